# SPDX-License-Identifier: MIT
"""tests/cli/formats_check.py: independent readers for cellfit report's
per-point CSV, binary PLY and Q-DAS DFQ (Python's csv and struct, not our
C code). Usage: formats_check.py REPORT.json CSV PLY DFQ; prints one
"ok|FAIL <what>" line per check."""
import csv
import json
import math
import re
import struct
import sys

rep = json.load(open(sys.argv[1]))
n, tol = rep["points"], rep["tol"]


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)


# CSV: a header, one row per point, RMS and in/out as the report says.
with open(sys.argv[2], newline="") as f:
    rows = list(csv.reader(f))
check(rows[0] == ["x", "y", "z", "u", "v", "deviation", "in_tolerance"], "csv header " + ",".join(rows[0]))
check(len(rows) - 1 == n, "csv has %d rows for %d points" % (len(rows) - 1, n))
dev = [float(r[5]) for r in rows[1:]]
rms = math.sqrt(sum(d * d for d in dev) / len(dev))
check(abs(rms - rep["rms"]) <= 1e-12 * max(1.0, rep["rms"]), "csv rms %.17g = report %.17g" % (rms, rep["rms"]))
inside = sum(1 for r in rows[1:] if r[6] == "1")
check(inside == rep["within_tol"], "csv in_tolerance count %d = report %d" % (inside, rep["within_tol"]))
check(all((r[6] == "1") == (abs(float(r[5])) <= tol) for r in rows[1:]), "csv in_tolerance agrees with |deviation| <= tol")

# PLY: the header, the count, x y z equal to the CSV's, colours from a palette
# that orders the deviations (a colour never stands for two separate ranges).
data = open(sys.argv[3], "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
head = data[:end].decode()
m = re.search(r"element vertex (\d+)", head)
check(head.startswith("ply\nformat binary_little_endian 1.0\n"), "ply magic and format")
check(m and int(m.group(1)) == n, "ply vertex count %s" % (m and m.group(1)))
rec = struct.Struct("<dddBBBd")
check(len(data) - end == n * rec.size, "ply body is %d records of %d bytes" % (n, rec.size))
spans = {}
same = True
for i in range(n):
    x, y, z, r, g, b, d = rec.unpack_from(data, end + i * rec.size)
    cx, cy, cz = (float(v) for v in rows[1 + i][:3])
    same &= (x, y, z) == (cx, cy, cz) and d == dev[i]
    lo, hi = spans.get((r, g, b), (d, d))
    spans[(r, g, b)] = (min(lo, d), max(hi, d))
check(same, "ply points and deviations equal the csv's")
ordered = sorted(spans.values())
check(all(a[1] <= b[0] for a, b in zip(ordered, ordered[1:])), "ply: %d colours, each a separate deviation band" % len(spans))
check(len(spans) >= 3, "ply uses %d colours" % len(spans))

# DFQ: K-fields, the count, each characteristic complete, values as the report.
k = {}
for line in open(sys.argv[4]):
    line = line.rstrip("\n")
    mm = re.match(r"^K(\d{4})(?:/(\d+))? (.*)$", line)
    check(mm is not None, "dfq line is a K-field: " + line[:40]) if mm is None else None
    if mm:
        k[(mm.group(1), int(mm.group(2) or 0))] = mm.group(3)
cnt = int(k[("0100", 0)])
check(cnt == 5, "dfq K0100 %d characteristics" % cnt)
for c in range(1, cnt + 1):
    check(all(("%s" % f, c) in k for f in ("2001", "2002", "2142", "0001", "0004")), "dfq characteristic %d complete" % c)
    check(re.match(r"^\d\d\.\d\d\.\d{4}/\d\d:\d\d:\d\d$", k[("0004", c)]) is not None, "dfq date/time " + k[("0004", c)])
names = {k[("2002", c)]: c for c in range(1, cnt + 1)}
c = names["RMS deviation"]
check(float(k[("0001", c)]) == rep["rms"], "dfq RMS value = report")
check(float(k[("2111", c)]) == tol, "dfq RMS upper limit = tol")
c = names["Max deviation"]
check(float(k[("0001", c)]) == rep["max"] and float(k[("2110", c)]) == -tol, "dfq max value and lower limit")
c = names["Points within tolerance"]
check(abs(float(k[("0001", c)]) - rep["within_tol_pct"]) < 1e-9 and k[("2142", c)] == "%", "dfq within share in %")
check(k.get(("1001", 1)) == "PN-7" and k.get(("0014", 1)) == "SN42", "dfq part number and ident")
