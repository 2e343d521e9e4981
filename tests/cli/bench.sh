#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/bench.sh CELLFIT: `cellfit bench accumulate` on one and two
# cores: exit codes, the one-line errors, the JSON fields, and that the
# two-core accumulation, solved, gives the one-core residual (the shard's
# sums are the same sums). Prints figures only as fields; no timing checks.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-bench.XXXXXX")
trap 'rm -rf "$T"' EXIT

for t in 1 2; do
    for o in raster random; do
        expect 0 "accumulate --threads $t --order $o" "$CF" bench accumulate --count 50000 \
            --cp 2500 --order $o --threads $t --json
        [ "$(json "$T/out" threads)" = $t ] && ok "threads $t in JSON" || no "threads $t in JSON"
        [ "$(json "$T/out" points)" = 50000 ] && ok "50000 points" || no "points"
        [ -n "$(json "$T/out" points_per_s)" ] && [ -n "$(json "$T/out" merge_seconds)" ] &&
            ok "rate and merge fields" || no "rate and merge fields"
    done
done
# Two cores need a second store: the arena grows by the shard's bytes.
"$CF" bench accumulate --count 1000 --cp 2500 --json >"$T/one"
"$CF" bench accumulate --count 1000 --cp 2500 --threads 2 --json >"$T/two"
a1=$(json "$T/one" arena_bytes)
a2=$(json "$T/two" arena_bytes)
# 2,500 control points, bicubic: 8 N (25 + 3) + 256 bytes more
[ "$((a2 - a1))" = $((8 * 2500 * 28 + 256)) ] && ok "shard adds 8 N (K + 3) + 256 bytes" ||
    no "shard bytes: $a1 -> $a2"
# The same system from one core and from two: the same iterations, residual.
for t in 1 2; do
    expect 0 "bench fit --threads $t" "$CF" bench fit --count 100000 --cp 2500 --order random \
        --solver pcg --threads $t --json
    cp "$T/out" "$T/fit$t"
done
[ "$(json "$T/fit1" iterations)" = "$(json "$T/fit2" iterations)" ] &&
    ok "one and two cores: same PCG iterations" || no "iterations differ"
awk -v a="$(json "$T/fit1" rel_residual)" -v b="$(json "$T/fit2" rel_residual)" \
    'BEGIN { exit !(a > 0 && b > 0 && a / b < 1.01 && b / a < 1.01) }' &&
    ok "one and two cores: same residual" || no "residuals differ"
# Bad usage: exit 2, one line naming the option.
expect 2 "--threads 3 refused" "$CF" bench accumulate --threads 3
[ "$(wc -l <"$T/err")" -eq 1 ] && grep -q -- "--threads" "$T/err" && ok "one-line error" ||
    no "error message"
expect 2 "--threads 0 refused" "$CF" bench accumulate --threads 0

echo "bench: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
