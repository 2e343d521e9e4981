#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc_cell15.sh CELLFIT: issue 15's leftovers on `cellfit serve
# --sim` with pymodbus as the PLC (tests/cli/plc_cell15.py): ABORT against
# a device that stopped answering (cellsim's 'silent' fault) reaches IDLE +
# ABORTED within the documented bound (2 s); cellsim killed mid-scan leaves
# a journal whose end record says the rig was lost (cellfit journal info);
# serve's port file after a SIGKILL is replaced at the next start (logged),
# and a second serve on a live one's port file is refused; a scan whose
# journal folder lacks the room is refused at acceptance (108) before any
# motion; the outbox and on-the-fly loss registers; FIT_REFINE 2 (auto).
# Servers on 127.0.0.1, port 0.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-cell15.XXXXXX")
pids=""
stop_all() { # TERM, wait, then KILL
    for p in $pids; do kill -TERM "$p" 2>/dev/null; done
    for p in $pids; do
        i=0
        while kill -0 "$p" 2>/dev/null && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
        kill -KILL "$p" 2>/dev/null
    done
    pids=""
}
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
py() { py_step plc_cell15.py 120 "$@"; } # py STEP PORT ARGS...
stop_one() { kill -TERM "$1"; wait "$1"; pids=$(echo "$pids" | sed "s/\\b$1\\b//"); }
BOUND=${CELL15_ABORT_BOUND:-2.0}

if [ ! -x "$(dirname "$CF")/cellsim" ]; then
    echo "skip: no cellsim beside $CF"; echo "plc_cell15: 0 passed, 0 failed"; exit 0
fi
"$CF" gen --dir "$T/part" --nu 40 --nv 30 --count 1000 >/dev/null

# 1. ABORT against a hung device: bounded.
serve_start h --sim --nominal "$T/part/nominal.igs" --results "$T/res" \
    --sim-args="--speed 5000 --seed 1 --part $T/part/nominal.igs --control $T/h.ctl"
py hung "$port" "$T/h.ctl" "$BOUND"
stop_one "$pid"

# 2. cellsim killed mid-scan: the journal's end record says the rig was lost.
serve_start g --sim --nominal "$T/part/nominal.igs" --results "$T/resg"
simpid=$(sed -n 's/.*rig: cellsim pid \([0-9]*\) on .*/\1/p' "$T/g.log")
if [ -n "$simpid" ]; then
    py lost "$port" "$simpid"
    jnl=$(ls "$T"/resg/*.jnl 2>/dev/null | head -1)
    if [ -n "$jnl" ] && "$CF" journal info "$jnl" --json >"$T/info.json"; then
        code=$(json "$T/info.json" end_code)
        why=$(json "$T/info.json" end_error)
        echo "     journal info: end_code $code ($why)"
        [ "$(json "$T/info.json" ended)" = 1 ] && [ "$code" = -219 ] &&
            [ "$why" = "rig lost (its process ended)" ] &&
            ok "lost: journal ended with -219, rig lost (not a PLC's abort)" ||
            no "lost: journal end: $(cat "$T/info.json")"
        "$CF" journal info "$jnl" >"$T/info.txt" 2>&1
        grep -q "ended: rig lost (its process ended) (-219)" "$T/info.txt" &&
            ok "lost: journal info says 'ended: rig lost'" || no "lost: $(grep ended "$T/info.txt")"
    else
        no "lost: no journal in $T/resg ($(ls "$T/resg"))"
    fi
else
    no "lost: no cellsim pid in g.log"
fi
stop_one "$pid"

# 3. The port file after SIGKILL: PORT and PID in it; replaced at the next
# start (logged); a live serve's is never taken over.
pf="$T/cell.port"
wait_pf() { # wait_pf PID: until the port file names PID on line 2
    i=0
    while [ "$(sed -n 2p "$pf" 2>/dev/null)" != "$1" ] && kill -0 "$1" 2>/dev/null && [ $i -lt 100 ]; do
        sleep 0.1; i=$((i + 1))
    done
}
"$CF" serve --plc tcp:127.0.0.1:0 --port-file "$pf" --nominal "$T/part/nominal.igs" 2>"$T/k1.log" &
k1=$!; pids="$k1 $pids"
wait_pf "$k1"
p1=$(sed -n 1p "$pf")
[ -n "$p1" ] && [ "$(sed -n 2p "$pf")" = "$k1" ] && ok "port file: port $p1 and serve's pid $k1" ||
    no "port file: $(cat "$pf")"
kill -KILL "$k1"; wait "$k1" 2>/dev/null
[ "$(sed -n 2p "$pf")" = "$k1" ] && ok "after SIGKILL the port file is left (pid $k1, no longer running)" ||
    no "port file after SIGKILL: $(cat "$pf" 2>&1)"
"$CF" serve --plc tcp:127.0.0.1:0 --port-file "$pf" --nominal "$T/part/nominal.igs" 2>"$T/k2.log" &
k2=$!; pids="$k2 $pids"
wait_pf "$k2"
p2=$(sed -n 1p "$pf")
[ "$(sed -n 2p "$pf")" = "$k2" ] && [ -n "$p2" ] &&
    grep -q "port file $pf: stale (port $p1, serve pid $k1 no longer holds it): replaced" "$T/k2.log" &&
    ok "restart: the stale port file replaced (port $p2, pid $k2), logged" ||
    { no "restart: port file $(cat "$pf" 2>&1)"; sed 's/^/     /' "$T/k2.log" | head -5; }
timeout 5 /usr/bin/python3 -c "import socket; socket.create_connection(('127.0.0.1', $p2), 2)" &&
    ok "restart: serve answers on the port the file names" || no "restart: port $p2 not served"
expect 1 "a second serve on a live serve's port file: exit 1" \
    "$CF" serve --plc tcp:127.0.0.1:0 --port-file "$pf" --nominal "$T/part/nominal.igs"
grep -q "port file $pf is held by a running serve (pid $k2, port $p2): not started" "$T/err" &&
    [ "$(sed -n 1p "$pf")" = "$p2" ] && [ "$(sed -n 2p "$pf")" = "$k2" ] &&
    ok "refused, naming pid $k2 and port $p2; the file unchanged" || no "second serve: $(cat "$T/err")"
stop_one "$k2"
[ ! -e "$pf" ] && ok "SIGTERM: the port file removed" || no "port file left after SIGTERM"
