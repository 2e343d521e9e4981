#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/otf.sh CELLFIT: on-the-fly scanning over cellsim's wires (the
# probe's streaming mode on Modbus TCP, then on its ASCII protocol over a
# socat pty pair), end to end: build/scan-bench otf-rig sends the stage across each row
# without waiting, arms the probe's streaming mode (one reading per trigger
# of the trigger input cellsim simulates, docs/rig-devices.md), pops the
# FIFO while the stage moves, pairs readings and latched positions by
# trigger number (firmware/scan_otf.c) and streams the points into a fit.
# Checked: every 37th point against the part itself (sim_part_z), the
# number of points against the row's length over the trigger spacing, and
# that nothing is lost or, when the FIFO overflows, that the probe's count
# of dropped entries equals the pairing's count of numbers lost on both
# sides. At 0.01 mm between triggers a reading paired with its neighbour's
# position would move a point by about 1 um, below the noise: the pairing
# by number is proven exactly by tests/test_scan_otf.c; this checks the
# chain. Processes stopped by PID.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
BIN=$(dirname "$CF")
SIM=$BIN/cellsim
BENCH=$BIN/scan-bench
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-otf.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
if [ ! -x "$BENCH" ] || [ ! -x "$SIM" ]; then
    no "scan-bench or cellsim not found beside $CF (make all builds them)"
    echo "otf: $pass passed, $fail failed"
    exit 1
fi

# The stage at 100 mm/s, a trigger every 100 us: 0.01 mm apart, 18,000 a
# 180 mm row.
"$SIM" --tcp 0 --homed --speed 100 --noise 0.002 >"$T/sim.out" 2>"$T/sim.err" &
PIDS="$PIDS $!"
i=0
while ! grep -q '^cellsim: ready' "$T/sim.out" && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
P=$(sed -n 's/^cellsim: tcp 127.0.0.1 //p' "$T/sim.out")
[ -n "$P" ] && ok "cellsim on 127.0.0.1:$P" || { no "cellsim did not start: $(cat "$T/sim.err")"; echo "otf: $pass passed, $fail failed"; exit 1; }

expect 0 "3 rows on the fly: every point right, nothing lost" \
    timeout 120 "$BENCH" otf-rig "tcp:127.0.0.1:$P:1" "tcp:127.0.0.1:$P:2" 3 100 0.002
cat "$T/out"
f() { sed -n "s/.*\"$1\": \([0-9.e+-]*\).*/\1/p" "$T/out"; }
paired=$(f paired)
# 3 rows of 1.8 s at 10 kHz: 54,000 triggers, fewer by the time it takes to
# arm the probe once the stage is sent off, more by the time the host takes
# to see it stopped (bounds allow 100-250 ms of each a row on a busy host).
le 52000 "${paired:-0}" && le "${paired:-0}" 62000 && ok "$paired points paired (about 54,000 due)" ||
    no "$paired points paired, about 54,000 due"
[ "$(f both_lost)" = 0 ] && [ "$(f lost_readings)" = 0 ] && [ "$(f dup)" = 0 ] &&
    ok "no reading lost, none duplicated" || no "losses: $(cat "$T/out")"
le 500 "$(f checked)" && ok "$(f checked) points checked against the part, worst $(f worst_mm) mm" ||
    no "too few points checked"
[ "$(f fitted)" = "$paired" ] && ok "every paired point went into the fit" || no "fitted $(f fitted)"
stop_all

# The same over the ASCII protocol on a pty pair (socat): the probe's lines
# on the tty, the stage on Modbus TCP, triggers every 50 us (20 kHz).
rm -f "$T/A" "$T/B"
socat -d -d "pty,raw,echo=0,link=$T/A" "pty,raw,echo=0,link=$T/B" 2>"$T/socat.log" &
PIDS="$PIDS $!"
i=0
while ! grep -q 'starting data transfer' "$T/socat.log" && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
sleep 0.2
"$SIM" --tcp 0 --ascii "$T/A" --homed --speed 100 --noise 0.002 >"$T/sim2.out" 2>"$T/sim2.err" &
PIDS="$PIDS $!"
i=0
while ! grep -q '^cellsim: ready' "$T/sim2.out" && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
P=$(sed -n 's/^cellsim: tcp 127.0.0.1 //p' "$T/sim2.out")
expect 0 "ASCII streaming, 2 rows at 20 kHz: every point right, nothing lost" \
    timeout 120 "$BENCH" otf-rig "tcp:127.0.0.1:$P:1" "tty:$T/B:115200" 2 50 0.002
cat "$T/out"
paired=$(f paired)
le 68000 "${paired:-0}" && le "${paired:-0}" 84000 && ok "$paired points paired (about 72,000 due)" ||
    no "$paired points paired, about 72,000 due"
[ "$(f both_lost)" = 0 ] && [ "$(f lost_readings)" = 0 ] && [ "$(f accounted)" = 1 ] &&
    ok "ASCII: no reading lost" || no "ASCII losses: $(cat "$T/out")"
stop_all
echo "otf: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
