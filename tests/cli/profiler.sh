#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/profiler.sh CELLFIT: the laser line profiler over GigE Vision,
# end to end on loopback: cellsim --gev hosts Aravis's fake camera on
# 127.0.0.1 (docs/rig-profiler.md) and build/gev-check (tests/gev_check.c)
# receives frames through hal_gev and checks them against the part itself
# (sim_part_z, not the simulator's map), the dropouts against the part's
# slope, and that every frame id is delivered or counted lost. Then with
# 1 % of the GVSP packets dropped: losses happen and each is counted, and no
# delivered profile is shifted. The fake camera listens on the GigE Vision
# control port 3956, one per machine: a start that finds it taken is
# retried for a minute. Processes are stopped by PID.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
BIN=$(dirname "$CF")
SIM=$BIN/cellsim
CHECK=$BIN/gev-check
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-profiler.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
SER="CF$$"
FLANK=8
NOISE=0.002

if [ ! -x "$CHECK" ] || [ ! -x "$SIM" ]; then
    no "gev-check or cellsim not found beside $CF (make all builds them)"
    echo "profiler: $pass passed, $fail failed"
    exit 1
fi

# sim_start NAME ARGS...: cellsim --gev in the background; sets $G (the
# geometry it prints) and adds its PID to $PIDS.
sim_start() {
    name=$1; shift
    tries=0
    while :; do
        : >"$T/$name.out" # there before the first grep (the job's redirection may come later)
        "$SIM" --gev "$SER" --gev-flank $FLANK --noise $NOISE "$@" >"$T/$name.out" 2>"$T/$name.err" &
        spid=$!
        i=0
        while ! grep -q '^cellsim: ready' "$T/$name.out" && kill -0 $spid 2>/dev/null && [ $i -lt 300 ]; do
            sleep 0.1; i=$((i + 1))
        done
        if grep -q '^cellsim: ready' "$T/$name.out"; then break; fi
        kill -TERM $spid 2>/dev/null; wait $spid 2>/dev/null
        tries=$((tries + 1))
        if ! grep -q 'port 3956' "$T/$name.err" || [ $tries -ge 12 ]; then
            no "cellsim $name did not start: $(cat "$T/$name.err")"
            return 1
        fi
        sleep 5 # another profiler test holds the port
    done
    PIDS="$PIDS $spid"
    G=$(sed -n "s/^cellsim: gev 127.0.0.1 $SER //p" "$T/$name.out")
    [ -n "$G" ] && ok "cellsim $name serves gev:127.0.0.1:$SER ($G)" || no "cellsim $name: no gev line"
}

# figure NAME: a number after NAME in gev-check's line
figure() { sed -n "s/.* $1 \([0-9.e+-]*\).*/\1/p" "$T/out"; }

# Clean stream: 200 frames of 64 profiles x 1024 points (past the 16-bit frame id
# wrap: the fake camera starts at 65400), 100 values of each checked.
sim_start clean || { echo "profiler: $pass passed, $fail failed"; exit 1; }
expect 0 "200 frames, range values match the part, none lost" \
    timeout 60 "$CHECK" "gev:127.0.0.1:$SER" 200 "$G" $NOISE $FLANK 50 100
cat "$T/out"
[ "$(figure 'lost')" = 0 ] && ok "0 frames lost at 0 % injected loss" || no "lost $(figure 'lost')"
c=$(figure 'checked'); d=$(figure 'dropouts')
le 1000 "$((c - d))" && ok "$((c - d)) range values compared" || no "only $((c - d)) values compared"
le 1 "$d" && ok "$d dropouts, each off the part, out of range or on a flank steeper than $FLANK deg" ||
    no "no dropout at all"
# The check can fail: the same frames against a part 0.5 mm higher.
G2=$(echo "$G" | awk '{ for (i = 1; i < NF; i++) if ($i == "z0") $(i + 1) += 0.5; print }')
expect 1 "a part 0.5 mm off is caught" timeout 60 "$CHECK" "gev:127.0.0.1:$SER" 5 "$G2" $NOISE $FLANK 100 300
w=$(figure 'wrong')
le 1 "${w:-0}" && ok "$w values wrong against the shifted part" || no "shifted part not caught: $(cat "$T/out")"
expect 1 "another serial number is refused" timeout 60 "$CHECK" "gev:127.0.0.1:X$SER" 1 "$G" $NOISE $FLANK
grep -q "serial $SER, not X$SER" "$T/err" && ok "the refusal names both serials" || no "$(cat "$T/err")"
stop_all

# 1 % of the GVSP packets dropped (the fake camera does not resend): frames
# are lost, each one counted as a gap, and no delivered profile is shifted.
sim_start loss --gev-loss 0.01 || { echo "profiler: $pass passed, $fail failed"; exit 1; }
expect 0 "1 % packet loss: every loss counted, no shifted profile" \
    timeout 60 "$CHECK" "gev:127.0.0.1:$SER" 40 "$G" $NOISE $FLANK 50 300 expect-loss
cat "$T/out"
l=$(figure 'lost')
le 1 "${l:-0}" && ok "$l frames lost and counted" || no "no loss seen at 1 %"
stop_all

# Nothing at the address: a clear failure, not a hang.
expect 1 "no profiler at the address" timeout 60 "$CHECK" "gev:127.0.0.1:$SER" 1 "$G" $NOISE $FLANK
echo "profiler: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
