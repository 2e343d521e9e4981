#!/bin/sh
# SPDX-License-Identifier: MIT
# mk/fuzz-run.sh BUILD SECONDS JOBS NAME...: libFuzzer runs of the built
# targets (mk/fuzz.mk), JOBS at a time (each is one process on one core, so
# two cores halve make test's fuzz-short), every target for SECONDS from
# tests/fuzz/corpus/NAME; new inputs go to BUILD/work/NAME. A crash, leak or
# hang fails the run and leaves the input in BUILD/findings/; the figures of
# each run go to BUILD/summary.txt, in the order the names were given.
set -eu
build=$1 secs=$2 jobs=$3
shift 3
mkdir -p "$build/findings"
: >"$build/summary.txt"

one() { # one NAME: run it, then a line in BUILD/NAME.res (ok or FINDING)
    t=$1
    mkdir -p "$build/work/$t"
    if "$build/fuzz/fuzz_$t" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 \
        -close_fd_mask=3 -print_final_stats=1 -artifact_prefix="$build/findings/$t-" \
        "$build/work/$t" "tests/fuzz/corpus/$t" >"$build/$t.log" 2>&1; then
        runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/$t.log")
        eps=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$build/$t.log")
        cov=$(grep -o 'cov: [0-9]*' "$build/$t.log" | tail -1)
        echo "fuzz_$t: $runs runs in $secs s, $eps exec/s, $cov, no finding" >"$build/$t.res"
    else
        echo "FINDING" >"$build/$t.res"
    fi
}

queue= # the running targets' PIDs, oldest first
for t in "$@"; do
    rm -f "$build/$t.res"
    echo "== fuzz_$t: $secs s"
    one "$t" &
    queue="$queue $!"
    if [ "$(echo $queue | wc -w)" -ge "$jobs" ]; then
        wait "$(echo $queue | cut -d' ' -f1)" || true
        queue=$(echo $queue | cut -s -d' ' -f2-)
    fi
done
wait
bad=0
for t in "$@"; do
    if [ ! -f "$build/$t.res" ] || [ "$(cat "$build/$t.res")" = FINDING ]; then
        tail -40 "$build/$t.log"
        echo "fuzz_$t: FINDING (input in $build/findings/)"
        bad=1
    else
        tee -a "$build/summary.txt" <"$build/$t.res"
    fi
done
exit $bad
