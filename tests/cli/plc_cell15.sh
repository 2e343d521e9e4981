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
plc_atexit='umount "$T/small" 2>/dev/null' # the small journal folder (5.), before $T goes
plc_setup plc_cell15 rig
py() { py_step plc_cell15.py 120 "$@"; } # py STEP PORT ARGS...
stop_one() { kill -TERM "$1"; wait "$1"; pids=$(echo "$pids" | sed "s/\\b$1\\b//"); }
BOUND=${CELL15_ABORT_BOUND:-2.0}

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

# 4. No room for the scan's journal: refused at acceptance (108), before
# any motion. min_free_mb beyond any filesystem; then, where this user may
# mount one, a 64 KiB tmpfs as the journal folder with the default 1 MiB.
serve_start s --sim --nominal "$T/part/nominal.igs" --results "$T/ress" --min-free-mb 1000000000
py nospace "$port" 108
grep -q "scan refused: folder $T/ress: [0-9]* bytes free, the job needs [0-9]*" "$T/s.log" &&
    ok "log: the folder, the bytes free and the bytes needed" || no "log: no free-space refusal"
! grep -q "job SCAN" "$T/s.log" && ok "no scan job started" || no "a scan job started"
stop_one "$pid"
mkdir -p "$T/small"
if mount -t tmpfs -o size=64k tmpfs "$T/small" 2>/dev/null; then
    serve_start m --sim --nominal "$T/part/nominal.igs" --results "$T/resm" --journal-dir "$T/small"
    py nospace "$port" 108
    grep -q "scan refused: folder $T/small: [0-9]* bytes free" "$T/m.log" &&
        ok "64 KiB tmpfs: refused for want of 1 MiB free" || no "tmpfs: no refusal logged"
    stop_one "$pid"
    umount "$T/small"
else
    echo "skip: cannot mount a tmpfs here (the min_free_mb case above covers the check)"
fi
expect 2 "serve --min-free-mb -1: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --min-free-mb -1

# 5a. The outbox registers = `cellfit results outbox`, the broker down,
# then up (mosquitto on a free port of 127.0.0.1).
plc_part "$T/fp" 16 12 20000
if command -v mosquitto >/dev/null; then
    mq=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    serve_start o --nominal "$T/fp/nominal.igs" --points "$T/fp/points.xyz" --results "$T/reso" \
        --mqtt "mqtt://127.0.0.1:$mq/c15" --cell-id c15 --forward-backoff-max 1
    py outbox "$port" "$CF" "$T/reso/results.db" down
    mosquitto -p "$mq" >"$T/mq.log" 2>&1 &
    mqpid=$!; pids="$mqpid $pids"
    py outbox "$port" "$CF" "$T/reso/results.db" up
    stop_one "$pid"
    stop_one "$mqpid"
else
    no "mosquitto not installed (scripts/deps.sh installs it)"
fi

# 5b. The last scan's on-the-fly losses: cellsim's FIFO of 64 overflowing
# under slow replies (as tests/cli/scan_fast.sh's overrun case); the
# registers against the journal (cellfit journal info) and serve's log.
serve_start f --sim --nominal "$T/part/nominal.igs" --results "$T/resf" --scan-method otf \
    --scan-period-us 20 --sim-args="--speed 5000 --seed 1 --part $T/part/nominal.igs --fifo 64 --fault slow@tcp:e30:10"
py otfregs "$port" "$T/scan.regs"
read -r trig dropped noread notrig both dup ovr <"$T/scan.regs" 2>/dev/null
jnl=$(ls "$T"/resf/*.jnl 2>/dev/null | head -1)
if [ -n "$jnl" ] && [ -n "${trig:-}" ] && "$CF" journal info "$jnl" --json >"$T/finfo.json"; then
    pts=$(json "$T/finfo.json" points)
    echo "     SCAN_*: triggers $trig dropped $dropped no_reading $noread no_trigger $notrig both_lost $both dup $dup overruns $ovr; journal points $pts"
    [ "$trig" = "$pts" ] && ok "SCAN_TRIGGERS $trig = the journal's points" || no "SCAN_TRIGGERS $trig, journal $pts"
    le 1 "$dropped" && le 1 "$ovr" && le 1 "$both" && le "$both" "$dropped" && [ "$noread" = 0 ] &&
        [ "$notrig" = 0 ] && ok "losses counted: $dropped dropped by the probe, $ovr overruns, $both lost on both sides" ||
        no "losses: $(cat "$T/scan.regs")"
    grep -q "lost: $noread readings, $notrig triggers, $both on both sides ($dropped dropped by the probe), $ovr overrun" "$T/f.log" &&
        ok "the registers = serve's log line of the scan" || no "log: $(grep 'scan on the fly' "$T/f.log")"
else
    no "otfregs: no journal or registers ($(ls "$T/resf" 2>&1))"
fi
stop_one "$pid"

# 5c. FIT_REFINE 2 (auto): the default, and the cell's loop = the shell's
# `cellfit fit --refine auto` (1: --refine residual): a coarse 8 x 6
# nominal under the 40 x 30 part's points, fitted to 0.01 mm for 99 %.
"$CF" gen --dir "$T/coarse" --nu 8 --nv 6 --count 1000 >/dev/null
plc_part "$T/fine" 40 30 20000
serve_start r --nominal "$T/coarse/nominal.igs" --points "$T/fine/points.xyz" --results "$T/resr"
grep -q "fit defaults (FIT_TOL .. FIT_REPARAM): plain" "$T/r.log" && ok "serve starts with FIT_TOL 0" || no "fit defaults: $(grep 'fit defaults' "$T/r.log")"
py refine "$port" "$T/refine.cps"
read -r c_auto c_res <"$T/refine.cps" 2>/dev/null
for how in auto residual; do
    "$CF" fit --base "$T/coarse/nominal.igs" --points "$T/fine/points.xyz" --tol 0.01 --within 99 \
        --refine $how --json --out "$T/shell_$how.igs" >"$T/shell_$how.json" 2>"$T/err"
done
s_auto=$(json "$T/shell_auto.json" control_points)
s_res=$(json "$T/shell_residual.json" control_points)
echo "     control points: cell auto ${c_auto:-?} / shell auto ${s_auto:-?}; cell residual ${c_res:-?} / shell residual ${s_res:-?}"
[ -n "${c_auto:-}" ] && [ "$c_auto" = "$s_auto" ] && [ "$c_res" = "$s_res" ] &&
    ok "FIT_REFINE 2 = --refine auto ($c_auto), 1 = --refine residual ($c_res)" ||
    no "refine: cell $c_auto/$c_res, shell $s_auto/$s_res"
stop_one "$pid"
# The pruning stage's config key (prune): a cell with prune 0 keeps every
# inserted knot line, as `cellfit fit --prune 0` does (here more control
# points than with the default 4 trials).
serve_start p --nominal "$T/coarse/nominal.igs" --points "$T/fine/points.xyz" --results "$T/resp" --prune 0
py refine "$port" "$T/prune.cps"
read -r c_p0 c_p0res <"$T/prune.cps" 2>/dev/null
"$CF" fit --base "$T/coarse/nominal.igs" --points "$T/fine/points.xyz" --tol 0.01 --within 99 \
    --refine auto --prune 0 --json --out "$T/shell_p0.igs" >"$T/shell_p0.json" 2>"$T/err"
s_p0=$(json "$T/shell_p0.json" control_points)
[ -n "${c_p0:-}" ] && [ "$c_p0" = "$s_p0" ] && [ "$c_p0" != "$c_auto" ] &&
    ok "serve --prune 0 = cellfit fit --prune 0 ($c_p0 control points; $c_auto with the default)" ||
    no "prune 0: cell ${c_p0:-?}, shell ${s_p0:-?}, default ${c_auto:-?}"
stop_one "$pid"
expect 2 "serve --prune -1: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --prune -1
serve_start u --nominal "$T/coarse/nominal.igs" --refine uniform --fit-to-tol
grep -q "fit defaults (FIT_TOL .. FIT_REPARAM): loop to 0.05 mm (uniform)" "$T/u.log" &&
    ok "--refine uniform still taken (FIT_REFINE 0)" || no "refine uniform: $(grep 'fit defaults' "$T/u.log")"
stop_one "$pid"
expect 2 "serve --refine sideways: exit 2" "$CF" serve --plc tcp:127.0.0.1:0 --refine sideways

if grep -E "Sanitizer|runtime error" "$T"/*.log >/dev/null; then
    no "sanitizer reports in the server logs"; grep -hE "Sanitizer|runtime error" "$T"/*.log | head -5
else
    ok "no sanitizer report in the server logs"
fi
stop_servers
echo "plc_cell15: $pass passed, $fail failed"
[ $fail -eq 0 ]
