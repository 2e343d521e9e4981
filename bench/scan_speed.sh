#!/bin/sh
# SPDX-License-Identifier: MIT
# bench/scan_speed.sh CELLFIT: how fast `cellfit scan` measures on cellsim
# (beside CELLFIT): a 21 x 16 raster (step 10 mm, 336 points) over the
# panel, per wire (Modbus TCP for stage and probe; Modbus RTU stage and
# ASCII probe over socat pty pairs) and stage speed. Prints points/s, ms per
# point, the simulated travel per point (step / speed) and what is left:
# the driver's and the wires' overhead. Measures, asserts nothing; about
# 45 s (the 200 mm/s rows are travel-bound, 17 s each). Environment:
# SCAN_SPEEDS ("200 5000 100000"), SCAN_WIRES ("tcp rtu").
set -u
CF=$1
SIM=$(dirname "$CF")/cellsim
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-scanbench.XXXXXX")
PIDS=""
stop_all() {
    for p in $PIDS; do kill -TERM "$p" 2>/dev/null; done
    for p in $PIDS; do wait "$p" 2>/dev/null; done
    PIDS=""
}
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 130' INT TERM
wait_for() {
    i=0
    while ! grep -q "$2" "$1" 2>/dev/null; do
        i=$((i + 1)); [ $i -gt 200 ] && return 1; sleep 0.05
    done
}
"$CF" gen --dir "$T/part" --count 1 >/dev/null
echo "| wire | speed mm/s | points | s | points/s | ms/point | travel ms/point | overhead ms/point |"
echo "|---|---|---|---|---|---|---|---|"
for w in ${SCAN_WIRES:-tcp rtu}; do
    for sp in ${SCAN_SPEEDS:-200 5000 100000}; do
        rm -f "$T"/*.out "$T"/*.err "$T/a.jnl"
        if [ "$w" = tcp ]; then
            "$SIM" --tcp 0 --homed --speed "$sp" --seed 1 >"$T/sim.out" 2>"$T/sim.err" &
            PIDS="$!"
            wait_for "$T/sim.out" "cellsim: ready" || { echo "cellsim did not start"; exit 1; }
            port=$(sed -n 's/^cellsim: tcp 127.0.0.1 \([0-9]*\)$/\1/p' "$T/sim.out")
            st=tcp:127.0.0.1:$port:1 pr=tcp:127.0.0.1:$port:2 name="Modbus TCP"
        else
            socat -d -d "pty,raw,echo=0,link=$T/rtu.a" "pty,raw,echo=0,link=$T/rtu.b" 2>"$T/s1.err" &
            PIDS="$!"
            socat -d -d "pty,raw,echo=0,link=$T/asc.a" "pty,raw,echo=0,link=$T/asc.b" 2>"$T/s2.err" &
            PIDS="$PIDS $!"
            wait_for "$T/s1.err" "starting data transfer loop" && wait_for "$T/s2.err" "starting data transfer loop" ||
                { echo "socat did not start"; exit 1; }
            "$SIM" --rtu "$T/rtu.b" --ascii "$T/asc.b" --homed --speed "$sp" --seed 1 >"$T/sim.out" 2>"$T/sim.err" &
            PIDS="$!$( [ -n "$PIDS" ] && echo " $PIDS")"
            wait_for "$T/sim.out" "cellsim: ready" || { echo "cellsim did not start"; exit 1; }
            st=rtu:$T/rtu.a:115200:8N1:1 pr=tty:$T/asc.a:115200 name="RTU stage + ASCII probe (ptys)"
        fi
        timeout 120 "$CF" scan --stage "$st" --probe "$pr" --nominal "$T/part/nominal.igs" \
            --journal "$T/a.jnl" --step 10 --json >"$T/scan.out" 2>/dev/null
        stop_all
        n=$(sed -n 's/.*"done": \([0-9]*\).*/\1/p' "$T/scan.out")
        s=$(sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p' "$T/scan.out")
        awk -v w="$name" -v sp="$sp" -v n="${n:-0}" -v s="${s:-0}" 'BEGIN {
            if (n == 0 || s == 0) { printf "| %s | %s | scan failed |||||\n", w, sp; exit }
            ms = 1e3 * s / n; tr = 1e3 * 10 / sp
            printf "| %s | %s | %d | %.2f | %.0f | %.2f | %.2f | %.2f |\n", w, sp, n, s, n / s, ms, tr, ms - tr }'
    done
done
