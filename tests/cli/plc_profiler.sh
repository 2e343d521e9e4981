#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc_profiler.sh CELLFIT: the line profiler as a cell method
# (issue 19): `cellfit serve --sim --scan-method profiler` starts cellsim
# with --gev (Aravis's fake GigE Vision camera on 127.0.0.1, port 3956: one
# per machine, so this waits while another test holds it) and a SCAN_FIT
# over Modbus (tests/cli/plc_rig.py's otffit step) measures one pass of
# the profiler's 160 profiles of 256 points into a journal, streamed into
# the fit: DONE with results, the journal's points + dropouts = 160 x 256
# with no profile lost, POINTS = the journal's points, the exported fit =
# the journal replayed by `cellfit journal fit`, and from memory (log).
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup plc_profiler rig
py() { py_step plc_rig.py 120 "$@"; }

# The GigE Vision port free (another profiler test may hold it): up to 60 s.
i=0
while ! "$PY" -c 'import socket; s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("127.0.0.1", 3956))' 2>/dev/null &&
    [ $i -lt 60 ]; do
    sleep 1; i=$((i + 1))
done

mkdir -p "$T/res"
serve_start p --sim --scan-method profiler \
    --sim-args="--speed 5000 --seed 5 --part $T/part/nominal.igs --gev-width 256 --gev-height 16 --gev-profiles 160" \
    --nominal "$T/part/nominal.igs" --results "$T/res"
simport=$(sed -n 's/.*rig: cellsim pid [0-9]* on 127.0.0.1:\([0-9]*\)$/\1/p' "$T/p.log")
grep -q "rig: profiler gev:127.0.0.1:cfserve, cellsim: gev 127.0.0.1 cfserve width 256 height 16 profiles 160" "$T/p.log" &&
    ok "serve started cellsim --gev: profiler gev:127.0.0.1:cfserve, 160 profiles of 256 points" ||
    no "no profiler in serve's log: $(grep 'rig:' "$T/p.log")"
py otffit "$port" "${simport:-0}" "$T/res" "$T/prof.out" profiler
d=$(sed -n 1p "$T/prof.out" 2>/dev/null); jnl=$(sed -n 2p "$T/prof.out" 2>/dev/null)
np=$(sed -n 3p "$T/prof.out" 2>/dev/null)
if [ -f "$jnl" ] && "$CF" journal info "$jnl" --json >"$T/info.json"; then
    pts=$(json "$T/info.json" points)
    drop=$(sed -n 's/.*scan by the profiler: 160 profiles, [0-9]* points, [0-9]* points\/s; lost: 0 profiles (0 frames), 0 bad frames, \([0-9]*\) dropouts.*/\1/p' "$T/p.log")
    [ -n "$drop" ] && [ $((pts + drop)) -eq $((160 * 256)) ] && [ "$(json "$T/info.json" ended)" = 1 ] &&
        [ "$(json "$T/info.json" end_code)" = 0 ] &&
        ok "journal of profiles: $pts points + $drop dropouts = 160 x 256, no profile lost, ended 0" ||
        no "journal: $(cat "$T/info.json"); log: $(grep 'scan by the profiler' "$T/p.log")"
    [ "$pts" = "$np" ] && ok "POINTS $np = the journal's points" || no "POINTS $np, journal $pts"
    if "$CF" journal fit "$jnl" --nominal "$T/part/nominal.igs" --out "$T/replay.igs" >/dev/null 2>&1; then
        same_surface "$d/fitted.igs" "$T/replay.igs" "$T/part/check.uv" && ok "profiler SCAN_FIT: exported fit = the journal replayed" ||
            no "profiler SCAN_FIT: exported fit differs from the replayed journal"
    else
        no "cellfit journal fit on the profiler's journal"
    fi
else
    no "no journal from the profiler's SCAN_FIT ($jnl)"
fi
r=$(fit_ready_s "$T/p.log")
[ -n "$r" ] && ok "log: the profiler's points streamed, from memory, fit ready $r s after the last row" ||
    no "log lacks the profiler SCAN_FIT's streamed fit"
if grep -E "Sanitizer|runtime error" "$T"/*.log >/dev/null; then
    no "sanitizer reports in the server log"
else
    ok "no sanitizer report in the server log"
fi
stop_servers
echo "plc_profiler: $pass passed, $fail failed"
[ $fail -eq 0 ]
