#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/unit-run.sh JOBS OUTDIR SOLO BIN...: run test binaries JOBS at a
# time (make unit-run, make valgrind-run), each with its own CF_TEST_TMP
# (OUTDIR/NAME) and its output captured in OUTDIR/NAME.out; afterwards every
# test's output in the order given, with its seconds. The names in SOLO (a
# space-separated list) run afterwards one at a time with nothing beside
# them: their checks time a server. UNIT_WRAP (optional) is put before each
# binary (valgrind). Any failure fails the run and shows that test's output;
# once one has failed, no new test starts.
set -eu
jobs=$1 out=$2 solo=$3
shift 3
mkdir -p "$out"
rm -rf "$out/.claim" "$out/.failed"
mkdir "$out/.claim"

one() { # one BIN: run it, its status and seconds beside its output
    n=$(basename "$1")
    rm -rf "${out:?}/$n"
    mkdir -p "$out/$n"
    s=$(date +%s)
    rc=0
    # shellcheck disable=SC2086 # UNIT_WRAP is a command and its options
    CF_TEST_TMP="$out/$n" ${UNIT_WRAP:-} "$1" >"$out/$n.out" 2>&1 || rc=$?
    echo "$rc $(($(date +%s) - s))" >"$out/$n.res"
    [ "$rc" -eq 0 ] || : >"$out/.failed"
}

is_solo() {
    case " $solo " in *" $(basename "$1") "*) return 0 ;; esac
    return 1
}

# A worker takes the next unclaimed test (mkdir is atomic: one worker wins).
worker() {
    i=0
    for b in "$@"; do
        i=$((i + 1))
        [ ! -e "$out/.failed" ] || return 0
        is_solo "$b" && continue
        mkdir "$out/.claim/$i" 2>/dev/null || continue
        one "$b"
    done
}

for n in "$@"; do rm -f "$out/$(basename "$n").res"; done
pids=
w=0
while [ "$w" -lt "$jobs" ]; do
    worker "$@" &
    pids="$pids $!"
    w=$((w + 1))
done
for p in $pids; do wait "$p"; done
for b in "$@"; do
    [ ! -e "$out/.failed" ] || break
    if is_solo "$b"; then one "$b"; fi
done

fail=0
for b in "$@"; do
    n=$(basename "$b")
    [ -e "$out/$n.res" ] || continue
    read -r rc secs <"$out/$n.res"
    echo "== $b ($secs s)"
    cat "$out/$n.out"
    if [ "$rc" -ne 0 ]; then
        echo "FAIL $b (exit $rc)"
        fail=1
    fi
done
rm -rf "$out/.claim"
if [ "$fail" -ne 0 ] || [ -e "$out/.failed" ]; then
    rm -f "$out/.failed"
    echo "unit-run: failed:$(for b in "$@"; do n=$(basename "$b"); [ -e "$out/$n.res" ] && read -r rc secs <"$out/$n.res" && [ "$rc" -ne 0 ] && printf ' %s' "$n"; done)"
    exit 1
fi
