#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/beside.sh LOG "BG" FG...: run the shell command BG at the lowest
# CPU and I/O priority in the background (output to LOG) while FG runs
# normally; then wait for BG and exit with FG's status (make test: the later
# stages' builds beside test-cli, which mostly waits on its simulated rigs).
# BG's own status is only reported: the stage that needs its output runs the
# same make again and fails there, with the compiler's message. If FG fails,
# BG is stopped.
set -eu
log=$1 bg=$2
shift 2
io=
if ionice -c 3 true 2>/dev/null; then io="ionice -c 3"; fi
# BG in a session of its own (setsid: a background child is no group
# leader, so setsid does not fork and BG's pid is its group), to be stopped
# as a whole.
sid=
if command -v setsid >/dev/null 2>&1; then sid=setsid; fi
t0=$(date +%s)
# shellcheck disable=SC2086 # sid and io are commands and their options, or nothing
$sid nice -n 19 $io sh -c "$bg" >"$log" 2>&1 &
pid=$!
stop() { [ -z "$sid" ] || kill -TERM "-$pid" 2>/dev/null || true; }
trap 'stop; exit 1' INT TERM
rc=0
"$@" || rc=$?
if [ "$rc" -ne 0 ]; then
    stop
    wait "$pid" 2>/dev/null || true
    exit "$rc"
fi
t1=$(date +%s)
brc=0
wait "$pid" || brc=$?
t2=$(date +%s)
echo "beside: $(tail -n 1 "$log" | cut -c1-120)"
echo "beside: background builds exit $brc after $((t2 - t0)) s (waited $((t2 - t1)) s; log $log)"
# make test's stage table: the background's own line (the stage that ran
# beside.sh counts both, the wait included).
[ ! -d build ] || printf 'stage %-12s %5d s (beside; %d s after the stage)\n' prebuild "$((t2 - t0))" \
    "$((t2 - t1))" >>build/stages.txt
exit 0
