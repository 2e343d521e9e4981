#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc_rig.sh CELLFIT: `cellfit serve --sim` (cellsim started as
# its child, beside CELLFIT) driven through its registers only by pymodbus
# and mbpoll (tests/cli/plc_rig.py): HOME, SCAN_FIT on the simulated rig
# (its points streamed into the fit, read from memory after the scan),
# results, EXPORT, ACK_RESULTS; an on-the-fly SCAN_FIT streamed likewise,
# equal to its journal's replay; a SCAN_FIT to a tolerance, robustly (the
# cell's fit_to_tol, within, robust), equal to the shell's fit; the journal checked by `cellfit journal`;
# invalid commands while scanning; an abort and a watchdog trip mid-scan
# (cellsim's stage seen stopped, journal consistent); a drive fault and an
# e-stop injected in cellsim (307, 311), RESET, HOME, next job; cellsim
# killed (203); SIGTERM stops serve and its child. Then the server's
# hardening: malformed frames, the rate limit, the allow-list, and a soak
# (tests/cli/plc_soak.py, PLC_SOAK_TX transactions, 20000 here).
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup plc_rig rig mbpoll
PYS=plc_rig.py
py() { py_step "$PYS" 120 "$@"; } # py STEP ARGS...: one client step
# start NAME ARGS...: serve_start, and with --sim $simport and $simpid (from
# its log).
start() {
    serve_start "$@"
    simport=$(sed -n 's/.*rig: cellsim pid [0-9]* on 127.0.0.1:\([0-9]*\)$/\1/p' "$T/$1.log")
    simpid=$(sed -n 's/.*rig: cellsim pid \([0-9]*\) on .*/\1/p' "$T/$1.log")
}

mkdir -p "$T/res"
SIMARGS="--speed 5000 --seed 1 --part $T/part/nominal.igs --control $T/a.ctl"
start a --sim --sim-args="$SIMARGS" --nominal "$T/part/nominal.igs" --results "$T/res"
[ -n "$simport" ] && kill -0 "$simpid" 2>/dev/null && ok "cellsim pid $simpid started by serve, port $simport" ||
    no "no cellsim child in the log"
py cycle "$port" "$simport" "$T/res" "$(command -v mbpoll)" "$T/cycle.out"
jnl=$(sed -n 2p "$T/cycle.out")
if [ -f "$jnl" ] && "$CF" journal info "$jnl" --json >"$T/info.json"; then
    [ "$(json "$T/info.json" records)" = 863 ] && [ "$(json "$T/info.json" points)" = 861 ] &&
        [ "$(json "$T/info.json" ended)" = 1 ] && [ "$(json "$T/info.json" end_code)" = 0 ] &&
        [ "$(json "$T/info.json" torn_tail)" = 0 ] && [ "$(json "$T/info.json" part_id)" = CYCLE-4711 ] &&
        ok "journal info: part ID CYCLE-4711 (the PLC's PART_ID), 861 points + end record, ended 0, no torn tail" ||
        no "journal info: $(cat "$T/info.json")"
    # The fit the cell exported = the journal replayed by `cellfit journal fit`
    # (alpha, beta as float32 in the registers: equal to 1e-6 mm).
    d=$(sed -n 1p "$T/cycle.out")
    if "$CF" journal fit "$jnl" --nominal "$T/part/nominal.igs" --out "$T/replay.igs" >/dev/null 2>&1; then
        same_surface "$d/fitted.igs" "$T/replay.igs" "$T/part/check.uv" && ok "exported fit = the journal replayed by cellfit journal fit" ||
            no "exported fit differs from the replayed journal"
    else
        no "cellfit journal fit on the cell's journal"
    fi
else
    no "no journal from the cycle ($jnl)"
fi
# SCAN_FIT streamed (issue 19): the points went into the fit as they
# arrived and the passes after the scan read them from memory (the fit equal
# to the journal's replay above); the time from the last row to the fit.
r=$(fit_ready_s "$T/a.log")
[ -n "$r" ] && ok "log: SCAN_FIT's points from memory, fit ready $r s after the last row" ||
    no "log lacks the streamed fit's source and time"
# SCAN_FIT to a tolerance, robustly, on a cell configured so (fit_to_tol,
# with tol 0.01: FIT_TOL's default; within, robust): a coarse nominal (8 x 6) under cellsim's dented part, so
# the loop must insert knots. The cell's fit = the shell's `cellfit fit
# --tol --within --robust` on the journal's points, both with the shell's
# default refinement, auto, named (float32 registers: equal to 1e-6 mm).
a_port=$port; a_pid=$pid; a_simport=$simport; a_simpid=$simpid
"$CF" gen --dir "$T/coarse" --nu 8 --nv 6 --count 1000 >/dev/null
mkdir -p "$T/tres"
start t --sim --sim-args="--speed 5000 --seed 3 --part $T/coarse/nominal.igs" \
    --nominal "$T/coarse/nominal.igs" --results "$T/tres" --fit-to-tol --tol 0.01 --robust --within 99 --refine auto
py tolfit "$port" "$simport" "$T/tres" 48 "$T/tol.out"
d=$(sed -n 1p "$T/tol.out"); jnl=$(sed -n 2p "$T/tol.out")
if [ -f "$jnl" ] && "$CF" journal export "$jnl" --out "$T/tol.xyz" &&
    "$CF" fit --base "$T/coarse/nominal.igs" --points "$T/tol.xyz" --tol 0.01 --within 99 --robust --refine auto \
        --out "$T/tol_shell.igs" >/dev/null; then
    same_surface "$d/fitted.igs" "$T/tol_shell.igs" "$T/coarse/check.uv" && ok "SCAN_FIT to tolerance = cellfit fit --tol --robust on the journal" ||
        no "the cell's fit to tolerance differs from the shell's"
else
    no "no journal or shell fit from the tolerance SCAN_FIT ($jnl)"
fi
grep -q "fit: 861 points, [0-9]* x [0-9]* net, [0-9]* rounds, fit_status met" "$T/t.log" &&
    ok "log: the fit's rounds and fit_status" || no "log lacks the fit's rounds"
grep -q "fit: points from memory, ready [0-9.]* s after the last row" "$T/t.log" &&
    ok "log: the tolerance SCAN_FIT streamed, its points from memory" || no "log: tolerance SCAN_FIT not streamed"
kill -TERM "$pid"; wait "$pid"
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
# SCAN_FIT on the fly (scan_method otf), streamed into the fit: the
# exported fit = the journal replayed by `cellfit journal fit` (float32
# registers: equal to 1e-6 mm), all of the journal's points fitted, and from
# memory after the last row.
mkdir -p "$T/ores"
start o --sim --sim-args="--speed 5000 --seed 4 --part $T/part/nominal.igs" \
    --nominal "$T/part/nominal.igs" --results "$T/ores" --scan-method otf
py otffit "$port" "$simport" "$T/ores" "$T/otf.out"
d=$(sed -n 1p "$T/otf.out"); jnl=$(sed -n 2p "$T/otf.out"); np=$(sed -n 3p "$T/otf.out")
if [ -f "$jnl" ] && "$CF" journal info "$jnl" --json >"$T/oinfo.json" &&
    "$CF" journal fit "$jnl" --nominal "$T/part/nominal.igs" --out "$T/oreplay.igs" >/dev/null 2>&1; then
    [ "$(json "$T/oinfo.json" points)" = "$np" ] && ok "otf SCAN_FIT: POINTS $np = the journal's points" ||
        no "otf SCAN_FIT: POINTS $np, journal $(json "$T/oinfo.json" points)"
    same_surface "$d/fitted.igs" "$T/oreplay.igs" "$T/part/check.uv" && ok "otf SCAN_FIT streamed: exported fit = the journal replayed" ||
        no "otf SCAN_FIT: exported fit differs from the replayed journal"
else
    no "no journal or replay from the otf SCAN_FIT ($jnl)"
fi
r=$(fit_ready_s "$T/o.log")
[ -n "$r" ] && ok "log: otf SCAN_FIT's points from memory, fit ready $r s after the last row" ||
    no "log lacks the otf SCAN_FIT's streamed fit"
kill -TERM "$pid"; wait "$pid"
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
port=$a_port; pid=$a_pid; simport=$a_simport; simpid=$a_simpid
py abort "$port" "$simport" "$T/res" "$T/abort.out"
jnl=$(cat "$T/abort.out")
if [ -f "$jnl" ] && "$CF" journal info "$jnl" --json >"$T/info.json"; then
    n=$(json "$T/info.json" points); f=$(json "$T/info.json" flagged)
    m=$([ -n "$(json "$T/info.json" part_id)" ] && echo 1 || echo 0) # the part ID's meta record
    [ "$(json "$T/info.json" torn_tail)" = 0 ] && [ "$(json "$T/info.json" ended)" = 1 ] &&
        [ "$(json "$T/info.json" end_code)" = -217 ] && [ "$(json "$T/info.json" records)" = $((n + f + m + 1)) ] &&
        [ "$n" -gt 0 ] && [ "$n" -lt 7676 ] &&
        ok "aborted journal: $n of 7676 points + end record (RIG_EABORTED), no torn tail" ||
        no "aborted journal: $(cat "$T/info.json")"
else
    no "no journal from the abort ($jnl)"
fi
py watchdog "$port" "$simport"
py fault "$port" "$simport" "$T/a.ctl" stagefault 307
py fault "$port" "$simport" "$T/a.ctl" "estop on" 311
grep -q "error job SCAN_FIT seq [0-9]*: SCANNING failed: error 307" "$T/a.log" &&
    ok "log: the stage fault, with its code" || no "log lacks the stage fault"
# cellsim killed under the cell: the PLC sees 203.
kill -KILL "$simpid"
py gone "$port" "$simport"
grep -q "rig: cellsim (pid $simpid) killed by signal 9: error 203" "$T/a.log" && ok "log: cellsim's end" ||
    no "log lacks cellsim's end"
kill -TERM "$pid"; wait "$pid"; rc=$?
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
[ $rc -eq 0 ] && ok "SIGTERM: serve a exits 0" || no "SIGTERM: serve a exit $rc"

# SIGTERM to serve stops its cellsim.
start b --sim --sim-args="--speed 5000"
spid=$simpid
[ -n "$spid" ] && kill -0 "$spid" 2>/dev/null && ok "serve b: cellsim pid $spid running" || no "serve b: no cellsim"
kill -TERM "$pid"; wait "$pid"; rc=$?
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
i=0
while [ -n "$spid" ] && kill -0 "$spid" 2>/dev/null && [ $i -lt 30 ]; do sleep 0.1; i=$((i + 1)); done
[ $rc -eq 0 ] && [ -n "$spid" ] && ! kill -0 "$spid" 2>/dev/null && ok "SIGTERM: serve exits 0, cellsim stopped" ||
    no "SIGTERM: serve exit $rc, cellsim $spid still there"
grep -q "rig: cellsim pid $spid stopped" "$T/b.log" && ok "log: cellsim stopped" || no "log: cellsim stop"

# Hardening on a cell without a rig: malformed frames, rate, allow-list.
start c --max-rate 50
py garbage "$port" 0
py rate "$port" 0
grep -q "over 50 requests/s" "$T/c.log" && ok "log: the rate limit, once a second" || no "log: rate limit"
grep -q "malformed MBAP header" "$T/c.log" && ok "log: malformed headers" || no "log: malformed"
start d --allow 10.0.0.0/8,192.168.1.7
py allow "$port" 0 refused
grep -q "refused: not in the allow-list" "$T/d.log" && ok "log: allow-list refusal" || no "log: allow-list"
start e --allow 10.0.0.0/8,127.0.0.1
py allow "$port" 0 served

# The soak: transactions from several clients while scan jobs run.
PYS=plc_soak.py
start s --sim --sim-args="--speed 5000 --seed 2 --part $T/part/nominal.igs" --nominal "$T/part/nominal.igs" \
    --results "$T/res" --max-rate 0
py soak "$port" "$simport" "$pid" "${PLC_SOAK_TX:-20000}" "${PLC_SOAK_MAX_GAP_MS:-1000}"
kill -TERM "$pid"; wait "$pid"; rc=$?
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
[ $rc -eq 0 ] && ok "SIGTERM after the soak: serve exits 0" || no "SIGTERM after the soak: exit $rc"

if grep -E "Sanitizer|runtime error" "$T"/*.log >/dev/null; then
    no "sanitizer reports in the server logs"
else
    ok "no sanitizer report in the server logs"
fi
stop_servers
echo "plc_rig: $pass passed, $fail failed"
[ $fail -eq 0 ]
