#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc_v2.sh CELLFIT: the registers of map version 2 as `cellfit
# serve`'s jobs use them (tests/cli/plc_v2.py, pymodbus as the PLC): fit
# settings and FIT_STATUS, RECIPE (nominal.N, 114), FIT_MAX_CP (110),
# PART_ID and JOB_TIME in report.json (seq: RESULT_SEQ), two exports of one
# part within one second into two folders, a results folder made at start,
# one that cannot be made refused at EXPORT (108), a bad nominal (301),
# WD_ARMED with WATCHDOG_MS 0, the idle timeout (--idle-ms), the config's
# fit settings as the registers' defaults, --sim's default sim_args, and
# ERROR_CODE 203 at once when cellsim dies mid-scan. Servers on 127.0.0.1, port 0.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup plc_v2
py() { py_step plc_v2.py 120 "$@"; }  # py STEP PORT ARGS...
py1() { py_step plc_cycle.py 120 "$@"; }

plc_part "$T" 16 12 20000
mkdir -p "$T/n2" && cp "$T/nominal.igs" "$T/n2/nominal.igs"
printf 'not IGES\n' >"$T/bad.igs"

# The results folder does not exist yet: serve makes it (README's "Try").
cat >"$T/cell.conf" <<CONF
plc = tcp:127.0.0.1:1
nominal = $T/nominal.igs
nominal.2 = $T/n2/nominal.igs
points = $T/points.xyz
results_dir = $T/new/results
results_dir.1 = $T/points.xyz/results
CONF
serve_start a --config "$T/cell.conf"
[ -d "$T/new/results" ] && grep -q "created the folder $T/new/results" "$T/a.log" &&
    ok "a missing results folder is made at start" || no "results folder not made: $(ls "$T")"
grep -q "warn cannot create the folder $T/points.xyz/results" "$T/a.log" &&
    ok "a folder that cannot be made: a warning at start" || no "no warning for results_dir.1"
py defaults "$port" 0 100 0 2 0 0
py export2 "$port" "$T/new/results"
py recipe "$port" "$T/new/results" "$T/n2/nominal.igs"
py fitset "$port" 192
py partid "$port" "$T/new/results"
py wdarm "$port"
py1 errors "$port" folder 108
kill -TERM "$pid"; wait "$pid"; pids=$(echo "$pids" | sed "s/\\b$pid\\b//")

# The config's fit settings are the registers' defaults; the idle timeout.
serve_start d --nominal "$T/nominal.igs" --points "$T/points.xyz" --results "$T/new/results" \
    --tol 0.04 --fit-to-tol --within 95 --max-cp 4000 --refine uniform --robust --reparam 2 \
    --idle-ms 1500
py defaults "$port" 0.04 95 4000 0 1 2
py idle "$port" 1500
grep -q "idle timeout 1500 ms" "$T/d.log" && ok "log: idle timeout 1500 ms" || no "idle_ms not logged"
expect 2 "serve --idle-ms 999: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --idle-ms 999
# results_db naming another application's SQLite database: refused at
# start, the file left as it was (serve migrated it into one before).
/usr/bin/python3 -c 'import sqlite3, sys; c = sqlite3.connect(sys.argv[1]); c.execute("CREATE TABLE t (x)"); c.commit()' \
    "$T/other.db"
cp "$T/other.db" "$T/other.orig"
expect 1 "serve --results-db on another application's SQLite file: refused" timeout 10 "$CF" serve \
    --plc tcp:127.0.0.1:0 --results-db "$T/other.db"
cmp -s "$T/other.db" "$T/other.orig" && ok "that file is left byte for byte as it was" ||
    no "serve changed another application's database"
kill -TERM "$pid"; wait "$pid"; pids=$(echo "$pids" | sed "s/\\b$pid\\b//")

# A nominal that is not IGES: FIT ends in ERROR 301 (the doc's code).
serve_start e --nominal "$T/bad.igs" --points "$T/points.xyz" --results "$T/new/results"
py1 errors "$port" fit 301

# cellsim killed mid-scan: ERROR_CODE 203 at once (the job still aborting).
if [ -x "$(dirname "$CF")/cellsim" ]; then
    "$CF" gen --dir "$T/part" --nu 40 --nv 30 --count 1000 >/dev/null
    serve_start g --sim --nominal "$T/part/nominal.igs" --results "$T/new/results"
    simpid=$(sed -n 's/.*rig: cellsim pid \([0-9]*\) on .*/\1/p' "$T/g.log")
    grep -q 'default sim_args "--speed 5000 --seed 1 --part' "$T/g.log" &&
        ok "--sim without --sim-args: cellsim at 5000 mm/s, the nominal as its part" ||
        no "sim_args default not logged"
    [ -n "$simpid" ] && py gonescan "$port" "$simpid" || no "no cellsim pid in g.log"
else
    echo "skip gonescan: no cellsim beside $CF"
fi

# No cell_id in the config: results.db's rows carry the host's name, as the
# MQTT topics and `fit --record` do (it was "" in the rows).
if command -v sqlite3 >/dev/null && [ -f "$T/new/results/results.db" ]; then
    ids=$(sqlite3 "$T/new/results/results.db" "SELECT DISTINCT cell_id FROM jobs")
    [ -n "$ids" ] && [ "$ids" = "$(hostname)" ] && ok "results.db: cell_id '$ids' = the host's name" ||
        no "results.db: cell_id '$ids', host $(hostname)"
else
    no "no results.db in $T/new/results (or no sqlite3)"
fi

if grep -E "Sanitizer|runtime error" "$T"/[adeg].log >/dev/null; then
    no "sanitizer reports in the server logs"; grep -hE "Sanitizer|runtime error" "$T"/[adeg].log | head -5
else
    ok "no sanitizer report in the server logs"
fi
stop_servers
echo "plc_v2: $pass passed, $fail failed"
[ $fail -eq 0 ]
