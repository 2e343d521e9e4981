# SPDX-License-Identifier: MIT
"""tests/cli/terrain.py NAME NX NY OUT [NOISE]: a terrain-like height field
on a regular grid of NX columns by NY rows over [0, 100]^2 mm, written row
by row (lines of equal y) as x y z, with Gaussian noise of NOISE mm in z
(seeded: the same file every time) if given: "cliffs" (hills and a curved 15 mm cliff, tanh of width
3 mm), "narrow" (a panel with a 1 mm wide ridge and a 3 mm bump) or "coast"
(a sea floor and land, a 4-14 mm step over 0.7 mm along a wavy coastline),
the fields of bench/loop_bench.py. Prints the height range (max z - min z)."""
import math
import random
import sys


def height(name, x, y):
    hills = 6.0 * math.sin(x / 17.0) * math.cos(y / 23.0) + 3.0 * math.sin((x + 2 * y) / 31.0)
    if name == "cliffs":
        d = y - (45.0 + 10.0 * math.sin(x / 20.0))
        return hills + 15.0 * 0.5 * (1.0 + math.tanh(d / 3.0))
    if name == "narrow":
        ridge = 4.0 * math.exp(-(((x - 0.6 * y - 30.0) / 1.0) ** 2))
        bump = 8.0 * math.exp(-((x - 70.0) ** 2 + (y - 30.0) ** 2) / (2 * 3.0**2))
        return 0.3 * hills + ridge + bump
    if name == "coast":
        d = x - (55.0 + 12.0 * math.sin(y / 14.0) + 5.0 * math.cos(y / 5.0))
        sea = -18.0 * (1.0 - math.exp(-max(-d, 0.0) / 20.0)) - 1.5 * math.sin(x / 9.0) * math.cos(
            y / 11.0)
        land = 4.0 + 10.0 * math.exp(-((x - 80.0) ** 2 + (y - 40.0) ** 2) / (2 * 10.0**2)) + \
            3.0 * math.sin(x / 9.0) * math.sin(y / 13.0)
        return sea + (land - sea) * 0.5 * (1.0 + math.tanh(d / 0.7))
    raise SystemExit("terrain.py: unknown field " + name)


def main():
    name, nx, ny, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
    noise = float(sys.argv[5]) if len(sys.argv) > 5 else 0.0
    rng = random.Random(14)
    lo, hi = math.inf, -math.inf
    with open(out, "w") as f:
        for j in range(ny):
            y = (j + 0.5) * 100.0 / ny
            for i in range(nx):
                x = (i + 0.5) * 100.0 / nx
                z = height(name, x, y) + (rng.gauss(0.0, noise) if noise > 0 else 0.0)
                lo, hi = min(lo, z), max(hi, z)
                f.write("%.9f %.9f %.9f\n" % (x, y, z))
    print("%.9g" % (hi - lo))


main()
