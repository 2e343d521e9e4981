# SPDX-License-Identifier: MIT
"""tests/cli/checks_check.py: the check points and zones of `cellfit report
--checks`, brute force in Python (not our C code): per check of CHECKS.txt
the deviation (deviations.csv) of the nearest point, or the mean over the
points within its radius, compared with the DFQ's K0001 after the five
figures (K0100 counts them all), a zone without a point as a value not
measured (K0002 255), and the report's --json "checks". Usage:
checks_check.py CHECKS.txt CSV DFQ REPORT.json; one "ok|FAIL <what>" line
per check."""
import csv
import json
import math
import re
import sys


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)


checks = []
for line in open(sys.argv[1]):
    t = line.split("#")[0].split()
    if t:
        checks.append((t[0], [float(v) for v in t[1:4]], float(t[4]) if len(t) > 4 else None))
with open(sys.argv[2], newline="") as f:
    rows = list(csv.DictReader(f))
pts = [((float(r["x"]), float(r["y"]), float(r["z"])), float(r["deviation"])) for r in rows]
k = {}
for line in open(sys.argv[3]):
    m = re.match(r"^K(\d{4})(?:/(\d+))? (.*)$", line.rstrip("\n"))
    if m:
        k[(m.group(1), int(m.group(2) or 0))] = m.group(3)
rep = json.load(open(sys.argv[4]))
tol = rep["tol"]
check(int(k[("0100", 0)]) == 5 + len(checks), "dfq K0100 %s = 5 figures + %d checks" % (k[("0100", 0)], len(checks)))
check(len(rep.get("checks", [])) == len(checks), "json has %d checks" % len(rep.get("checks", [])))
for i, (name, p, radius) in enumerate(checks):
    c = 6 + i
    d2 = [sum((q[a] - p[a]) ** 2 for a in range(3)) for q, _ in pts]
    if radius is None:
        order = sorted(range(len(pts)), key=lambda j: d2[j])
        # the nearest must be clear, or the check says nothing
        check(d2[order[1]] - d2[order[0]] > 1e-6, "%s: nearest point unambiguous" % name)
        want, count = pts[order[0]][1], 1
    else:
        inside = [j for j in range(len(pts)) if d2[j] <= radius * radius]
        check(all(abs(math.sqrt(x) - radius) > 1e-6 for x in d2), "%s: no point on the zone's edge" % name)
        count = len(inside)
        want = sum(pts[j][1] for j in inside) / count if count else None
    check(k.get(("2002", c)) == name, "dfq characteristic %d named %s" % (c, k.get(("2002", c))))
    check(float(k[("2110", c)]) == -tol and float(k[("2111", c)]) == tol and float(k[("2101", c)]) == 0,
          "%s: nominal 0, limits -tol, +tol" % name)
    js = rep["checks"][i]
    check(js["name"] == name and [js["x"], js["y"], js["z"]] == p and js["radius"] == radius,
          "%s: json name, x y z and radius as the file" % name)
    check(js["points"] == count, "%s: json points %s = %d" % (name, js["points"], count))
    if want is None:
        check(k.get(("0002", c)) == "255", "%s: no point within %g mm: dfq value not measured (K0002 255)" % (name, radius))
        check(js["deviation"] is None, "%s: json deviation null" % name)
    else:
        got = float(k[("0001", c)])
        check(abs(got - want) <= 1e-12 and ("0002", c) not in k,
              "%s: dfq %.17g = brute force %.17g (%d points)" % (name, got, want, count))
        check(abs(js["deviation"] - want) <= 1e-12, "%s: json deviation = brute force" % name)
