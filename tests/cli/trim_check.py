# SPDX-License-Identifier: MIT
"""tests/cli/trim_check.py: compare what OpenCASCADE (tests/occt/occt_trim
read) sees of two trimmed faces: NOMINAL.occt and OURS.occt, and OURS's
surface against OURS.eval (cellfit eval at the same u v). Prints one
"ok|FAIL <what>" line per check; tolerance 1e-9 (uv and mm).
Usage: trim_check.py NOMINAL.occt OURS.occt OURS.eval NAME"""
import math
import sys


def load(path):
    head, wires, pts, xyz = {}, {}, {}, []
    for line in open(path):
        f = line.split()
        if not f:
            continue
        if f[0] in ("faces", "valid"):
            head[f[0]] = int(f[1])
        elif f[0] == "wire":
            wires[int(f[1])] = (int(f[3]), float(f[5]), [float(x) for x in f[7:11]])
        elif f[0] == "pt":
            pts.setdefault(int(f[1]), []).append((float(f[2]), float(f[3])))
        elif f[0] == "xyz":
            xyz.append([float(x) for x in f[1:4]])
    return head, wires, pts, xyz


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)


TOL = 1e-9
nom, ours = load(sys.argv[1]), load(sys.argv[2])
name = sys.argv[4]
check(ours[0].get("faces") == 1, "%s: OCCT reads one face (%s)" % (name, ours[0].get("faces")))
check(ours[0].get("valid") == 1, "%s: BRepCheck accepts it" % name)
check(sorted(ours[1]) == sorted(nom[1]), "%s: %d boundaries, as the nominal's %d" % (name, len(ours[1]), len(nom[1])))
for k in sorted(nom[1]):
    a, b = nom[1][k], ours[1].get(k)
    if b is None:
        check(False, "%s: boundary %d missing" % (name, k))
        continue
    dlen = abs(a[1] - b[1])
    dbox = max(abs(x - y) for x, y in zip(a[2], b[2]))
    # every sample of the nominal's boundary is on ours (nearest sample)
    dpts = max(min(math.hypot(p[0] - q[0], p[1] - q[1]) for q in ours[2][k]) for p in nom[2][k])
    check(a[0] == b[0] and dlen <= TOL and dbox <= TOL and dpts <= TOL,
          "%s: boundary %d in uv: %d edges (nominal %d), length %.3g, box %.3g, samples %.3g from the nominal's"
          % (name, k, b[0], a[0], dlen, dbox, dpts))
ev = [[float(x) for x in l.split()] for l in open(sys.argv[3]) if l.strip()]
n = len(ours[3])
d = max((abs(p - q) for a, b in zip(ours[3], ev) for p, q in zip(a, b)), default=float("inf"))
check(n == len(ev) and n > 0 and d <= TOL,
      "%s: OCCT's surface = cellfit eval at %d random (u, v): %.3g mm" % (name, n, d))
