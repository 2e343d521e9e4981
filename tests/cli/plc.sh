#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc.sh CELLFIT: `cellfit serve` driven from third-party Modbus
# TCP clients through its registers only (docs/plc-register-map.md):
# pymodbus (tests/cli/plc_cycle.py) runs a full fit cycle, invalid commands
# in each state, an abort mid-job and a watchdog trip, while mbpoll reads
# identity and status as a second client; both word orders; usage errors;
# SIGTERM stops the server cleanly. Servers on 127.0.0.1, port 0.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup plc mbpoll
py() { py_step plc_cycle.py 300 "$@"; } # py STEP ARGS...
start() { serve_start "$@"; }          # start NAME ARGS...
mb() { timeout 10 mbpoll -m tcp -p "$port" -0 -1 "$@" 127.0.0.1 2>&1; }

# The part: 200000 x y z points (projected by the fit: a job of a few
# tenths of a second). The watchdog's cell gets 10^6 (a job of seconds,
# which must outlast WATCHDOG_MS = 300 ms on a fast machine too).
plc_part "$T" 16 12 200000
plc_part "$T/big" 16 12 1000000
# EXPORT's check points and zones (config checks): a point near row 5000, a
# zone around row 120000 and one far from every point (no value).
awk 'NR == 5000 { printf "P1 %.6f %.6f %.6f\n", $1 + 0.05, $2 - 0.03, $3 + 0.1 }
     NR == 120000 { printf "Z1 %.6f %.6f %.6f 2.3\nfar 5000 5000 0 1\n", $1, $2, $3 }' \
    "$T/points.xyz" >"$T/checks.txt"
mkdir -p "$T/results"

# Usage errors: exit 2, one line naming what.
expect 2 "serve without --plc: exit 2" "$CF" serve
expect 2 "serve --plc udp:...: exit 2" "$CF" serve --plc udp:127.0.0.1:0
expect 2 "serve --stage without --probe: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 \
    --stage tcp:127.0.0.1:1
grep -q "needs both --stage URI and --probe URI" "$T/err" && ok "  ... says the rig needs both" ||
    no "--stage message: $(cat "$T/err")"
expect 2 "serve --sim with --stage: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --sim \
    --stage tcp:127.0.0.1:1
expect 2 "serve --allow 300.1.1.1: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --allow 300.1.1.1
expect 2 "serve --stage rtu:... bad URI: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 \
    --stage modbus-rtu:/dev/null --probe tcp:127.0.0.1:1
expect 0 "serve --help: exit 0" "$CF" serve --help
grep -q -- "--fit-to-tol" "$T/out" && grep -q -- "--tol MM" "$T/out" && ok "  ... lists --tol and the fit settings" ||
    no "serve --help: $(head -3 "$T/out")"
expect 2 "serve --tolerance (now --tol): exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --tolerance 0.05
expect 2 "serve --refine bogus: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --refine bogus
grep -q "refine 'bogus': auto, uniform or residual" "$T/err" && ok "  ... says what refine takes" || no "refine: $(cat "$T/err")"
expect 2 "serve --board other: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --board nosuch
printf 'plc = tcp:127.0.0.1:0\n# comment\nnominal = %s\nwatchdog = 5\n' "$T/nominal.igs" >"$T/bad.conf"
expect 2 "config with an unknown key: exit 2" "$CF" serve --config "$T/bad.conf"
grep -q "bad.conf:4: unknown setting 'watchdog'" "$T/err" && ok "  ... names file:line" ||
    no "config error message: $(cat "$T/err")"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok "  ... in one line" || no "config error: $(wc -l <"$T/err") lines"
"$CF" serve --print-map >"$T/map.md"
grep -q '^| 0 | 40001 | MAGIC | u16 | R |' "$T/map.md" && ok "serve --print-map prints the map" ||
    no "serve --print-map"

# The cell, configured from a file (and options over it).
cat >"$T/cell.conf" <<CONF
# cellfit serve configuration (docs/plc-register-map.md)
plc = tcp:127.0.0.1:1
nominal = $T/nominal.igs
points = $T/points.xyz
results_dir = $T/results
results_dir.1 = $T/points.xyz/results
checks = $T/checks.txt
word_order = lo-hi
watchdog_ms = 0
log_level = info
CONF
start a --config "$T/cell.conf"
py identity "$port"
# mbpoll: identity in the default (low word first) order, no -B needed.
out=$(mb -r 0 -c 2)
echo "$out" | grep -q '^\[0\]:[[:space:]]*17222' && ok "mbpoll: magic 17222" || no "mbpoll magic: $out"
out=$(mb -r 2 -c 1 -t 4:float)
echo "$out" | grep -q '^\[2\]:[[:space:]]*123.456' && ok "mbpoll: test float 123.456 (lo-hi)" ||
    no "mbpoll float lo-hi: $out"
out=$(mb -r 4 -c 1 -t 4:int)
echo "$out" | grep -q '^\[4\]:[[:space:]]*305419896' && ok "mbpoll: test uint32 305419896 (lo-hi)" ||
    no "mbpoll int lo-hi: $out"
# A write to a read-only register: exception 02 ("Illegal data address").
out=$(timeout 10 mbpoll -m tcp -p "$port" -0 -1 -r 0 127.0.0.1 1 2>&1)
echo "$out" | grep -qi "illegal data address" && ok "mbpoll: write to MAGIC: exception 02" ||
    no "mbpoll write to MAGIC: $out"
npts=$(grep -c . "$T/points.xyz")
py cycle "$port" "$T/results" "$npts" "$(command -v mbpoll)" "$T/exported"
d=$(cat "$T/exported" 2>/dev/null)
# The exported report against `cellfit report` on the exported surface.
if [ -n "$d" ] && "$CF" report "$d/fitted.igs" "$T/points.xyz" --tol 0.02 --json >"$T/ref.json"; then
    "$PY" - "$d/report.json" "$T/ref.json" <<'PYEOF' && ok "report.json agrees with cellfit report on fitted.igs" || no "report.json differs from cellfit report"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
keys = ("points", "rms", "min", "max", "within_tol", "p95_abs")
ok = all(a[k] == b[k] or abs(a[k] - b[k]) <= 1e-12 * abs(b[k]) for k in keys)
# The edges the data does not reach (issue 14): pinned control points
# counted, and the footprint's cells, when reported, add up.
fp = a.get("footprint", {"cells": 0, "filled": 0, "empty": 0})
ok = ok and isinstance(a.get("pinned_cp"), int) and 0 <= a["pinned_cp"] <= a["control_points"]
ok = ok and fp["filled"] + fp["empty"] == fp["cells"]
sys.exit(0 if ok else 1)
PYEOF
else
    no "cellfit report on the exported fitted.igs"
fi
# Beside them, what `make demo` writes: the STEP (the IGES's surface to the
# last bit), the per-point CSV and the DFQ (read here with Python's csv and
# plain text, not our code, against report.json's figures).
grep -v '^#' "$T/points.uvxyz" | head -300 | cut -d' ' -f1-2 >"$T/check.uv"
if [ -n "$d" ] && "$CF" eval "$d/fitted.igs" "$T/check.uv" >"$T/e1" && "$CF" eval "$d/fitted.stp" "$T/check.uv" >"$T/e2" &&
    cmp -s "$T/e1" "$T/e2"; then
    ok "export: fitted.stp is fitted.igs's surface to the last bit"
else
    no "export: fitted.stp missing or not fitted.igs's surface"
fi
[ -n "$d" ] && "$PY" - "$d/report.json" "$d/deviations.csv" "$d/report.dfq" <<'PYEOF' >"$T/files.out" 2>&1 &&
import csv, json, math, sys
rep = json.load(open(sys.argv[1]))
rows = list(csv.reader(open(sys.argv[2], newline="")))
bad = []
if rows[0] != ["x", "y", "z", "u", "v", "deviation", "in_tolerance"]: bad.append("csv header")
if len(rows) - 1 != rep["points"]: bad.append("csv rows %d for %d points" % (len(rows) - 1, rep["points"]))
dev = [float(r[5]) for r in rows[1:]]
rms = math.sqrt(sum(x * x for x in dev) / max(1, len(dev)))
if abs(rms - rep["rms"]) > 1e-12 * rep["rms"]: bad.append("csv rms %.17g, report %.17g" % (rms, rep["rms"]))
if sum(r[6] == "1" for r in rows[1:]) != rep["within_tol"]: bad.append("csv in_tolerance count")
k = dict(l.rstrip("\n").split(" ", 1) for l in open(sys.argv[3]) if l.strip())
want = {"K0100": "8", "K1001/1": str(rep["part"]), "K2002/1": "RMS deviation", "K2002/5": "Points within tolerance"}
bad += ["dfq %s=%r" % (f, k.get(f)) for f, v in want.items() if k.get(f) != v]
for c, key in ((1, "rms"), (2, "max"), (3, "min")):
    if float(k.get("K0001/%d" % c, "nan")) != rep[key]: bad.append("dfq K0001/%d vs %s" % (c, key))
if rep.get("part_id") and k.get("K0014/1") != rep["part_id"]: bad.append("dfq K0014/1")
print("\n".join(bad))
sys.exit(1 if bad else 0)
PYEOF
    ok "export: deviations.csv (a row per point, report.json's RMS) and report.dfq (its figures)" ||
    no "export: deviations.csv / report.dfq: $(cat "$T/files.out" 2>/dev/null | head -3)"
# The checks (config checks) in report.dfq and report.json: brute force in
# Python over the export's deviations.csv (checks_check.py).
if [ -n "$d" ] && "$PY" "$HERE/checks_check.py" "$T/checks.txt" "$d/deviations.csv" "$d/report.dfq" \
    "$d/report.json" >"$T/checks.out" 2>&1 && ! grep -q '^FAIL' "$T/checks.out" &&
    grep -q '^ok .*Z1: dfq' "$T/checks.out"; then
    ok "export: report.dfq and report.json's checks = brute force over deviations.csv ($(grep -c '^ok' "$T/checks.out") items of checks_check.py)"
else
    no "export: checks: $(grep -v '^ok' "$T/checks.out" 2>/dev/null | head -3)"
fi
grep -q "check far: no point within 1 mm" "$T/a.log" && ok "export: the empty zone logged" ||
    no "export: no log line for the empty zone"
py abort "$port"
# The watchdog trips mid-job on a cell of its own (the long job above).
a_port=$port
a_pid=$pid
start w --nominal "$T/big/nominal.igs" --points "$T/big/points.xyz"
py watchdog "$port"
kill -TERM "$pid"
wait "$pid"
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
port=$a_port
pid=$a_pid
py net "$port"
py errors "$port" folder 108
grep -q "info command FIT seq" "$T/a.log" && grep -q "error watchdog: PLC heartbeat" "$T/w.log" &&
    ok "log: levelled lines for commands and the watchdog" || no "log lines missing"
# A job keeps running while clients come and go: mbpoll connects and
# leaves during the jobs above; the server saw them.
[ "$(grep -c 'client .* connected' "$T/a.log")" -ge 8 ] && ok "log: clients came and went" ||
    no "log: few client connections"

# SIGTERM after all that: exit 0 (with ASan: no leak, no error).
kill -TERM "$pid"
wait "$pid"
rc=$?
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
[ $rc -eq 0 ] && ok "SIGTERM after the jobs: serve exits 0" || no "SIGTERM: serve a exit $rc"

# High word first: mbpoll needs -B, and the identity values say so.
start b --nominal "$T/nominal.igs" --points "$T/points.xyz" --word-order hi-lo --max-clients 2
out=$(mb -r 7 -c 1)
echo "$out" | grep -q '^\[7\]:[[:space:]]*1' && ok "hi-lo: WORD_ORDER reads 1" || no "hi-lo order: $out"
out=$(mb -r 2 -c 1 -t 4:float -B)
echo "$out" | grep -q '^\[2\]:[[:space:]]*123.456' && ok "mbpoll -B: test float 123.456 (hi-lo)" ||
    no "mbpoll -B float: $out"
out=$(mb -r 4 -c 1 -t 4:int -B)
echo "$out" | grep -q '^\[4\]:[[:space:]]*305419896' && ok "mbpoll -B: test uint32 (hi-lo)" ||
    no "mbpoll -B int: $out"
py identity "$port"
py limit "$port" 2 "$(command -v mbpoll)"

# A points file that is not there: the job fails with 302.
start c --nominal "$T/nominal.igs" --points "$T/no-such-points.xyz"
py errors "$port" fit 302
grep -q "no-such-points.xyz" "$T/c.log" && ok "log names the missing points file" ||
    no "log lacks the points file"

# SIGTERM: exit 0, port file removed.
kill -TERM "$pid"
wait "$pid"
rc=$?
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
[ $rc -eq 0 ] && ok "SIGTERM: serve exits 0" || no "SIGTERM: exit $rc"
[ ! -e "$T/$name.port" ] && ok "SIGTERM: port file removed" || no "port file left"
grep -q "info stopping" "$T/$name.log" && ok "SIGTERM: logged" || no "SIGTERM not logged"

if grep -E "Sanitizer|runtime error" "$T/a.log" "$T/b.log" "$T/c.log" "$T/w.log" >/dev/null; then
    no "sanitizer reports in the server logs"; grep -hE "Sanitizer|runtime error" "$T"/[abcw].log | head -5
else
    ok "no sanitizer report in the server logs"
fi
stop_servers
echo "plc: $pass passed, $fail failed"
[ $fail -eq 0 ]
