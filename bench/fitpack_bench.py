# SPDX-License-Identifier: MIT
"""bench/fitpack_bench.py: FITPACK (scipy LSQBivariateSpline, surfit) on the
height field of `cellfit bench fit`, same points, same knots; one JSON line.

Usage: python3 bench/fitpack_bench.py --count M --cp N [--order random|raster]

The points are those host/cmd/cmd_bench.c generates (its xorshift64 generator and
seed, or its raster), x = 100u, y = 100v, z = height(u, v); the spline is
bicubic on side = round(sqrt(N)) coefficients a direction with uniform
interior knots 100 i/(side-3), i = 1..side-4. FITPACK fits the scalar z only.
Only the LSQBivariateSpline call is timed. Warnings (rank deficiency) and
errors are reported in "status" and "message" with scipy's own text.
"""

import argparse
import json
import math
import sys
import time
import warnings

import numpy as np
from scipy.interpolate import LSQBivariateSpline

MASK = (1 << 64) - 1


def points(m, order):
    """u, v of cmd_bench.c's gen_chunk: raster rows of constant v, or brand()."""
    if order == "raster":
        cols = math.ceil(math.sqrt(m))
        k = np.arange(m)
        return (k % cols + 0.5) / cols, (k // cols + 0.5) / cols
    s = 0x853C49E6748FEA9B
    out = np.empty(2 * m)
    for i in range(2 * m):
        s ^= (s << 13) & MASK
        s ^= s >> 7
        s ^= (s << 17) & MASK
        out[i] = (s >> 11) / 9007199254740992.0
    return out[0::2], out[1::2]


def height(u, v):
    return 10.0 * u * (1.0 - u) + 5.0 * v * v + 0.5 * np.sin(12.0 * u) * np.cos(9.0 * v)


def main():
    ap = argparse.ArgumentParser(description="FITPACK surfit on cellfit's bench data")
    ap.add_argument("--count", type=int, required=True)
    ap.add_argument("--cp", type=int, required=True)
    ap.add_argument("--order", choices=("random", "raster"), default="random")
    a = ap.parse_args()
    side = max(4, round(math.sqrt(a.cp)))
    u, v = points(a.count, a.order)
    x, y, z = 100.0 * u, 100.0 * v, height(u, v)
    knots = 100.0 * np.arange(1, side - 3) / (side - 3)
    res = {"bench": "fitpack", "points": a.count, "control_points": side * side,
           "degree": 3, "order": a.order, "values": "z"}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        t0 = time.perf_counter()
        try:
            spl = LSQBivariateSpline(x, y, z, knots, knots, bbox=[0.0, 100.0, 0.0, 100.0],
                                     kx=3, ky=3)
            err = None
        except Exception as e:  # scipy raises ValueError/MemoryError: report, do not die
            err = e
        res["seconds"] = time.perf_counter() - t0
    if err is not None:
        res["status"] = "error"
        res["message"] = "%s: %s" % (type(err).__name__, " ".join(str(err).split()))
    else:
        res["status"] = "warning" if caught else "ok"
        if caught:
            res["message"] = " ".join(" ".join(str(w.message) for w in caught).split())
        res["fp"] = float(spl.get_residual())
        res["rms"] = math.sqrt(res["fp"] / a.count)
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
