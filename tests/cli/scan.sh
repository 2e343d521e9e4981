#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/scan.sh CELLFIT: `cellfit scan` end to end on the real simulator
# (cellsim beside CELLFIT, Modbus TCP on 127.0.0.1): the raster and the
# kinematic model against the simulator's offset and the nominal, the
# streamed fit equal to a fit replayed from the journal, and what the job
# does with faults: a probe seeing no surface (flagged, scan goes on), a
# drive fault, a lost line, an e-stop and an abort (job ends with the code,
# journal consistent and synced). Without cellsim (a build without sim/) there is nothing to run.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
SIM=$(dirname "$CF")/cellsim
if [ ! -x "$SIM" ]; then
    echo "skip scan: no cellsim beside $CF"
    echo "scan: 0 passed, 0 failed"
    exit 0
fi
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-scan.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
expect() {
    want=$1; name=$2; shift 2
    timeout 120 "$@" >"$T/out" 2>"$T/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok "$name"; else
        no "$name (exit $got, want $want)"; sed 's/^/     /' "$T/err" | head -5; fi
}
json() {
    sed -n "s/.*\"$2\": \"\{0,1\}\([^,\"}]*\)\"\{0,1\}[,}].*/\1/p" "$1"
}
wait_for() {
    i=0
    while ! grep -q "$2" "$1" 2>/dev/null; do
        i=$((i + 1)); [ $i -gt 200 ] && return 1; sleep 0.05
    done
}
# start_sim NAME ARGS...: cellsim on a free TCP port; sets PORT
start_sim() {
    n=$1; shift
    "$SIM" --tcp 0 --homed --part "$T/part/nominal.igs" "$@" >"$T/$n.out" 2>"$T/$n.err" &
    PIDS="$PIDS $!"
    wait_for "$T/$n.out" "cellsim: ready" || { no "$n: cellsim did not come up"; cat "$T/$n.err"; }
    PORT=$(sed -n 's/^cellsim: tcp 127.0.0.1 \([0-9]*\)$/\1/p' "$T/$n.out")
}
scan() { # scan JOURNAL ARGS...: the rig of the last start_sim
    j=$1; shift
    expect "$SCAN_WANT" "$SCAN_NAME" "$CF" scan --stage "tcp:127.0.0.1:$PORT:1" --probe "tcp:127.0.0.1:$PORT:2" \
        --nominal "$T/part/nominal.igs" --journal "$j" --region 0:100:0:50 --step 10 "$@"
}

"$CF" gen --dir "$T/part" --nu 40 --nv 30 --count 1000 >/dev/null

# A clean scan with a beam offset: 11 x 6 points, fitted as they arrive.
start_sim a --offset 1.5,2 --noise 0.002
SCAN_WANT=0 SCAN_NAME="scan 11 x 6 with --fit"
scan "$T/a.jnl" --cal 1.5:2:0 --fit "$T/a.igs" --report "$T/a.json" --json
cp "$T/out" "$T/a.out"
[ "$(json "$T/a.out" planned)" = 66 ] && [ "$(json "$T/a.out" points)" = 66 ] && [ "$(json "$T/a.out" flagged)" = 0 ] &&
    ok "66 points planned and measured" || no "scan counts: $(cat "$T/a.out")"
cmp -s "$T/a.out" "$T/a.json" && ok "--report holds the --json summary" || no "--report differs from --json"
expect 0 "scan --help: exit 0" "$CF" scan --help
grep -q -- "--region x0:x1:y0:y1" "$T/out" && ok "  ... lists --region" || no "scan --help: $(head -3 "$T/out")"
expect 0 "journal info" "$CF" journal info "$T/a.jnl" --json
[ "$(json "$T/out" records)" = 67 ] && [ "$(json "$T/out" ended)" = 1 ] && [ "$(json "$T/out" end_code)" = 0 ] &&
    [ "$(json "$T/out" z0)" = 50 ] && [ "$(json "$T/out" cx)" = 1.5 ] && ok "journal: 66 points + end record, kinematics in the header" ||
    no "journal info: $(cat "$T/out")"
# Wall-clock dates (issue 16): the start in UTC, every point's time.
su=$(json "$T/out" started_utc)
now=$(date -u +%s)
st=$(date -u -d "$(echo "$su" | sed 's/T/ /; s/Z$//')" +%s 2>/dev/null || echo 0)
[ $((now - st)) -ge 0 ] && [ $((now - st)) -le 600 ] && ok "journal: started $su, within minutes of the clock" ||
    no "journal started_utc '$su' against now $now"
"$CF" journal export "$T/a.jnl" --times >"$T/a.csv"
head -1 "$T/a.csv" | grep -qx 'utc,x,y,z' && [ "$(($(wc -l <"$T/a.csv") - 1))" = 66 ] &&
    awk -F, -v s="$st" 'NR > 1 { if ($1 < s - 1 || $1 > s + 600 || $1 < prev) bad = 1; prev = $1 } END { exit bad }' "$T/a.csv" &&
    ok "journal export --times: 66 points with their UTC, in order" || no "export --times: $(head -3 "$T/a.csv")"
"$CF" journal export "$T/a.jnl" >"$T/a.xyz"
# Serpentine raster, offset by the beam: point k at x = 1.5 + 10 i, y = 2 + 10 j.
awk '{ k = NR - 1; j = int(k / 11); c = k % 11; i = (j % 2) ? 10 - c : c;
       dx = $1 - (1.5 + 10 * i); dy = $2 - (2 + 10 * j); if (dx < 0) dx = -dx; if (dy < 0) dy = -dy;
       if (dx > m) m = dx; if (dy > m) m = dy } END { exit !(NR == 66 && m < 0.002) }' "$T/a.xyz" &&
    ok "points on the serpentine raster, shifted by the beam offset" || no "raster/offset: $(head -3 "$T/a.xyz" | tr '\n' ' ')"
# z = z0 - d: the part is the nominal plus a dent and a warp of at most ~0.7 mm.
"$CF" project "$T/part/nominal.igs" "$T/a.xyz" >"$T/a.proj"
dmax=$(awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$T/a.proj")
le "$dmax" 0.8 && ok "measured points within $dmax mm of the nominal (kinematics agree with the simulator)" ||
    no "points $dmax mm off the nominal: kinematic model disagrees"
# The fit streamed during the scan equals a fit replayed from the journal.
expect 0 "journal fit of the scan" "$CF" journal fit "$T/a.jnl" --nominal "$T/part/nominal.igs" --out "$T/a2.igs"
"$CF" eval "$T/a.igs" "$T/part/check.uv" >"$T/e1"
"$CF" eval "$T/a2.igs" "$T/part/check.uv" >"$T/e2"
cmp -s "$T/e1" "$T/e2" && ok "streamed fit = fit replayed from the journal" || no "streamed and replayed fits differ"
# scan --fit takes the fit job's options (as `cellfit fit`): to a
# tolerance, robustly, with a reprojection pass; the same options replayed
# from the journal give the same rounds and the same surface. 66 points
# under a 40 x 30 net: 80 % of them come within 0.05 mm.
SCAN_WANT=0 SCAN_NAME="scan --fit --tol 0.05 --within 75 --robust --reparam 1"
scan "$T/t.jnl" --cal 1.5:2:0 --fit "$T/t.igs" --tol 0.05 --within 75 --robust --reparam 1 --json
cp "$T/out" "$T/t.out"
[ "$(json "$T/t.out" fit_status)" = met ] && grep -q '"rounds": \[{"round": 0, ' "$T/t.out" &&
    [ "$(json "$T/t.out" robust_iters)" = 3 ] && [ "$(json "$T/t.out" reparam)" = 1 ] &&
    ok "scan --fit JSON: fit_status met, rounds, robust_iters 3, reparam 1" || no "scan --fit --tol: $(cat "$T/t.out")"
expect 0 "journal fit of it with the same options" "$CF" journal fit "$T/t.jnl" --nominal "$T/part/nominal.igs" \
    --tol 0.05 --within 75 --robust --reparam 1 --json --out "$T/t2.igs"
[ "$(sed 's/.*"rounds": \(\[[^]]*\]\).*/\1/; s/"seconds": [0-9.e+-]*//g' "$T/out")" = \
    "$(sed 's/.*"rounds": \(\[[^]]*\]\).*/\1/; s/"seconds": [0-9.e+-]*//g' "$T/t.out")" ] &&
    ok "the same rounds from the scan and from its journal" || no "rounds differ: $(cat "$T/out")"
"$CF" eval "$T/t.igs" "$T/part/check.uv" >"$T/e3"
"$CF" eval "$T/t2.igs" "$T/part/check.uv" >"$T/e4"
cmp -s "$T/e3" "$T/e4" && ok "streamed robust fit to a tolerance = replayed from the journal" ||
    no "streamed and replayed robust fits differ"

# The probe sees no surface at every 10th reading: flagged, the scan goes on.
SCAN_NAME="scan with no surface every 10th reading" SCAN_WANT=0
start_sim b --fault nosurf:e10
scan "$T/b.jnl" --json
cp "$T/out" "$T/b.out"
[ "$(json "$T/b.out" flagged)" = 6 ] && [ "$(json "$T/b.out" points)" = 60 ] &&
    ok "6 readings flagged, 60 points, scan completed" || no "nosurf counts: $(cat "$T/b.out")"
[ "$("$CF" journal export "$T/b.jnl" | wc -l)" -eq 60 ] && ok "export leaves the flagged readings out" || no "export of flagged journal"

# A drive fault at the 20th move: the job ends with RIG_EFAULT (-209), the
# journal holds the 19 points before it, the end record, nothing torn.
SCAN_NAME="scan with a drive fault: exit 1" SCAN_WANT=1
start_sim c --fault stagefault:n20
scan "$T/c.jnl"
# stderr: progress lines, then the error as one line.
tail -1 "$T/err" | grep -q "^cellfit scan: job ended at grid point 19 (x 20, y 10): stage: " &&
    [ "$(grep -c '^cellfit scan:' "$T/err")" -eq 1 ] && ok "one line naming the grid point and the stage" ||
    no "fault message: $(tail -1 "$T/err")"
"$CF" journal info "$T/c.jnl" --json >"$T/c.info"
[ "$(json "$T/c.info" end_code)" = -209 ] && [ "$(json "$T/c.info" torn_tail)" = 0 ] &&
    [ "$(json "$T/c.info" records)" = $(($(json "$T/c.info" points) + 1)) ] && le "$(json "$T/c.info" points)" 20 &&
    ok "journal ended with RIG_EFAULT after $(json "$T/c.info" points) points, synced, no torn tail" ||
    no "fault journal: $(cat "$T/c.info")"

# The line is lost for longer than the HAL reconnects (3 s): the job ends
# RIG_EDISCONNECT (-206), the journal consistent and synced.
SCAN_NAME="scan with the line lost: exit 1" SCAN_WANT=1
start_sim e --fault disconnect@tcp:n60:6000
scan "$T/e.jnl"
tail -1 "$T/err" | grep -q "line or connection lost" && ok "says the line was lost" || no "disconnect message: $(tail -1 "$T/err")"
"$CF" journal info "$T/e.jnl" --json >"$T/e.info"
[ "$(json "$T/e.info" end_code)" = -206 ] && [ "$(json "$T/e.info" torn_tail)" = 0 ] &&
    [ "$(json "$T/e.info" records)" = $(($(json "$T/e.info" points) + 1)) ] &&
    ok "journal ended RIG_EDISCONNECT after $(json "$T/e.info" points) points, no torn tail" ||
    no "disconnect journal: $(cat "$T/e.info")"

# E-stop pressed during the scan (cellsim's control file): RIG_EESTOP (-210).
start_sim f --control "$T/f.ctl"
timeout 120 "$CF" scan --stage "tcp:127.0.0.1:$PORT:1" --probe "tcp:127.0.0.1:$PORT:2" --nominal "$T/part/nominal.igs" \
    --journal "$T/f.jnl" --region 0:100:0:50 --step 10 >"$T/f.out" 2>"$T/f.err" &
spid=$!
wait_for "$T/f.err" "scan: [0-9]*/[0-9]* points (10%)" || no "scan made no progress"
echo "estop on" >"$T/f.ctl"
wait "$spid"
rc=$?
[ $rc -eq 1 ] && tail -1 "$T/f.err" | grep -q "emergency stop active" && ok "e-stop: exit 1, says so" ||
    no "e-stop: exit $rc, $(tail -1 "$T/f.err")"
"$CF" journal info "$T/f.jnl" --json >"$T/f.info"
[ "$(json "$T/f.info" end_code)" = -210 ] && [ "$(json "$T/f.info" torn_tail)" = 0 ] &&
    ok "journal ended RIG_EESTOP after $(json "$T/f.info" points) points" || no "e-stop journal: $(cat "$T/f.info")"

# SIGTERM during a scan: the stage is stopped, the job ends RIG_EABORTED (-217).
start_sim d
timeout 120 "$CF" scan --stage "tcp:127.0.0.1:$PORT:1" --probe "tcp:127.0.0.1:$PORT:2" --nominal "$T/part/nominal.igs" \
    --journal "$T/d.jnl" --step 5 >"$T/d.out" 2>"$T/d.err" &
spid=$!
wait_for "$T/d.err" "scan: [0-9]*/[0-9]* points (10%)" || no "scan made no progress"
kill -TERM "$spid"
wait "$spid"
rc=$?
[ $rc -eq 1 ] && grep -q "job stopped on request" "$T/d.err" && ok "SIGTERM: exit 1, job stopped on request" ||
    no "SIGTERM: exit $rc, $(tail -1 "$T/d.err")"
"$CF" journal info "$T/d.jnl" --json >"$T/d.info"
[ "$(json "$T/d.info" end_code)" = -217 ] && [ "$(json "$T/d.info" torn_tail)" = 0 ] &&
    ok "journal ended RIG_EABORTED after $(json "$T/d.info" points) of $(json "$T/d.info" planned) points" ||
    no "abort journal: $(cat "$T/d.info")"

# Ctrl-C while the rig has stopped answering (cellsim's 'silent' fault):
# the lines' stop check (hal_set_stop) ends the retries, late-reply waits
# and reconnects at once, so the scan exits within 2 s (serve's ABORT
# bound), not after the transports' timeouts (before: about 8 s).
start_sim s --control "$T/s.ctl"
timeout 120 "$CF" scan --stage "tcp:127.0.0.1:$PORT:1" --probe "tcp:127.0.0.1:$PORT:2" --nominal "$T/part/nominal.igs" \
    --journal "$T/s.jnl" --step 5 >"$T/s.out" 2>"$T/s.err" &
spid=$!
wait_for "$T/s.err" "scan: [0-9]*/[0-9]* points (10%)" || no "scan made no progress"
echo "fault silent:e1" >"$T/s.ctl"
i=0
while [ -e "$T/s.ctl" ] && [ $i -lt 100 ]; do sleep 0.05; i=$((i + 1)); done
sleep 0.3 # a request or two meets the silence
t0=$(date +%s.%N)
kill -INT "$spid"
wait "$spid"
rc=$?
dt=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
echo "     $(tail -1 "$T/s.err")"
[ $rc -eq 1 ] && le "$dt" 2 && grep -q "job stopped on request" "$T/s.err" && ok "Ctrl-C against a silent rig: exit 1 after $dt s (bound 2 s)" ||
    no "Ctrl-C against a silent rig: exit $rc after $dt s; $(tail -1 "$T/s.err")"

stop_all
echo "scan: $pass passed, $fail failed"
[ $fail -eq 0 ]
