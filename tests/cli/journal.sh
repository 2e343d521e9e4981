#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/journal.sh CELLFIT: the journal of measured points end to end:
# `cellfit journal export/info/recover/fit` on journals written through the
# real file store, exit codes and one-line errors naming the damaged record,
# the streaming fit of a journal against `cellfit fit` and the true part,
# and power cuts: a writer killed with kill -9 at seeded random moments,
# after which recovery keeps every acknowledged record and drops only a
# torn tail, many times over.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-journal.XXXXXX")
WPID=
cleanup() {
    if [ -n "$WPID" ]; then kill -TERM "$WPID" 2>/dev/null; wait "$WPID" 2>/dev/null; fi
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
expect() {
    want=$1; name=$2; shift 2
    timeout 60 "$@" >"$T/out" 2>"$T/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok "$name"; else
        no "$name (exit $got, want $want)"; sed 's/^/     /' "$T/err" | head -5; fi
}
one_line() { [ "$(wc -l <"$T/err")" -eq 1 ]; }
size() { wc -c <"$1" | tr -d ' '; }

# Known records: written, described, checked, exported.
expect 0 "selftest-write 1000 records" "$CF" journal selftest-write "$T/a.jnl" --records 1000 --sync-every 50
[ "$(tail -1 "$T/out")" = ended ] && grep -q '^acked 1001$' "$T/out" && ok "writer acknowledged all 1001 records" ||
    no "writer output: $(tail -2 "$T/out" | tr '\n' ' ')"
[ "$(size "$T/a.jnl")" = $((128 + 1001 * 80)) ] && ok "file is header + 1001 records of 80 bytes" ||
    no "file size $(size "$T/a.jnl")"
expect 0 "info --json" "$CF" journal info "$T/a.jnl" --json
cp "$T/out" "$T/info.json"
# Record i lacks a surface when i mod 97 = 13: 11 of 0..999.
[ "$(json "$T/info.json" records)" = 1001 ] && [ "$(json "$T/info.json" points)" = 989 ] &&
    [ "$(json "$T/info.json" flagged)" = 11 ] && ok "info: 1001 records, 989 points, 11 flagged" ||
    no "info counts: $(cat "$T/info.json")"
[ "$(json "$T/info.json" ended)" = 1 ] && [ "$(json "$T/info.json" torn_tail)" = 0 ] &&
    [ "$(json "$T/info.json" span_seconds)" = 1 ] && ok "info: ended, no torn tail, span 1 s" ||
    no "info state: $(cat "$T/info.json")"
expect 0 "info (text)" "$CF" journal info "$T/a.jnl"
expect 0 "selftest-check" "$CF" journal selftest-check "$T/a.jnl"
expect 0 "export" "$CF" journal export "$T/a.jnl" --out "$T/a.xyz"
[ "$(wc -l <"$T/a.xyz")" -eq 989 ] && ok "export: 989 points" || no "export: $(wc -l <"$T/a.xyz") lines"
# Record 1: stage (0.1, 0), z = 100 - (10 + sin 1) (the writer's formula).
awk 'NR == 2 { d = $3 - (90 - sin(1)); if (d < 0) d = -d; exit !($1 == 0.1 && $2 == 0 && d < 1e-12) }' "$T/a.xyz" &&
    ok "export: record 1 is (0.1, 0, 90 - sin 1)" || no "export line 2: $(sed -n 2p "$T/a.xyz")"

# A torn tail: reported by info, cut by recover, the records intact.
printf 'torn' >>"$T/a.jnl"
expect 0 "info on a torn tail" "$CF" journal info "$T/a.jnl" --json
[ "$(json "$T/out" torn_tail_bytes)" = 4 ] && [ "$(json "$T/out" records)" = 1001 ] &&
    ok "info: 4 bytes of torn tail, 1001 records" || no "torn info: $(cat "$T/out")"
expect 0 "recover" "$CF" journal recover "$T/a.jnl"
[ "$(size "$T/a.jnl")" = $((128 + 1001 * 80)) ] && ok "recover cut the 4 bytes" || no "size after recover $(size "$T/a.jnl")"
expect 0 "selftest-check after recover" "$CF" journal selftest-check "$T/a.jnl"

# Damage before the tail: exit 2, one line naming record 500.
cp "$T/a.jnl" "$T/bad.jnl"
printf '\377' | dd of="$T/bad.jnl" bs=1 seek=$((128 + 500 * 80 + 20)) conv=notrunc 2>/dev/null
for sub in info export recover; do
    expect 2 "$sub on a damaged record: exit 2" "$CF" journal $sub "$T/bad.jnl"
    grep -q "record 500 " "$T/err" && one_line && ok "$sub names record 500 in one line" ||
        no "$sub message: $(cat "$T/err")"
done
expect 2 "fit on a damaged record: exit 2" "$CF" journal fit "$T/bad.jnl" --nominal "$T/a.xyz" --out "$T/x.igs"
head -c 100 "$T/a.jnl" >"$T/short.jnl"
expect 2 "info on a torn header: exit 2" "$CF" journal info "$T/short.jnl"
grep -q "header" "$T/err" && one_line && ok "names the header" || no "header message: $(cat "$T/err")"
expect 2 "info on a missing file: exit 2" "$CF" journal info "$T/none.jnl"
expect 2 "unknown subcommand: exit 2" "$CF" journal frobnicate "$T/a.jnl"
expect 2 "selftest-write never overwrites" "$CF" journal selftest-write "$T/a.jnl" --records 3

# The streaming fit of a journal: a synthetic part's scattered points,
# journalled; the fit equals `cellfit fit` of the same points (same
# projection, same equations) and recovers the true part to the noise.
"$CF" gen --dir "$T/part" --nu 40 --nv 30 --count 60000 --noise 0.005 >/dev/null
grep -v '^#' "$T/part/points.uvxyz" | cut -d' ' -f3- >"$T/part/p.xyz"
expect 0 "journal the part's points" "$CF" journal selftest-write "$T/p.jnl" --points "$T/part/p.xyz" \
    --nominal "$T/part/nominal.igs"
expect 0 "export them" "$CF" journal export "$T/p.jnl" --out "$T/p.out"
paste "$T/part/p.xyz" "$T/p.out" | awk '$1 != $4 || $2 != $5 || $3 != $6 { bad++ } END { exit bad > 0 || NR != 60000 }' &&
    ok "export gives the 60000 points back exactly" || no "export differs from the points"
expect 0 "journal fit" "$CF" journal fit "$T/p.jnl" --nominal "$T/part/nominal.igs" --out "$T/jf.igs" --json
cp "$T/out" "$T/jf.json"
[ "$(json "$T/jf.json" points)" = 60000 ] && ok "journal fit: 60000 points" || no "journal fit: $(cat "$T/jf.json")"
"$CF" fit --base "$T/part/nominal.igs" --points "$T/part/p.xyz" --out "$T/ff.igs" >/dev/null
"$CF" eval "$T/jf.igs" "$T/part/check.uv" >"$T/e-jf"
"$CF" eval "$T/ff.igs" "$T/part/check.uv" >"$T/e-ff"
d=$(paste "$T/e-jf" "$T/e-ff" | awk '{ for (c = 1; c <= 3; c++) { a = $c - $(c+3); if (a < 0) a = -a; if (a > m) m = a } } END { printf "%.3g", m }')
le "$d" 1e-9 && ok "journal fit = cellfit fit of the same points (max diff $d mm)" || no "journal fit differs from fit by $d mm"
e=$(paste "$T/e-jf" "$T/part/check.xyz" | awk '{ d = $3 - $6; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }')
le "$e" 0.01 && ok "journal fit within 0.01 mm of the true part (max $e)" || no "journal fit misses the part by $e mm"
# A reparameterisation pass reads the journal again, projecting onto the first fit.
expect 0 "journal fit --reparam 1" "$CF" journal fit "$T/p.jnl" --nominal "$T/part/nominal.igs" --reparam 1 --out "$T/jf1.igs"
"$CF" fit --base "$T/part/nominal.igs" --points "$T/part/p.xyz" --reparam 1 --out "$T/ff1.igs" >/dev/null
"$CF" eval "$T/jf1.igs" "$T/part/check.uv" >"$T/e-jf1"
"$CF" eval "$T/ff1.igs" "$T/part/check.uv" >"$T/e-ff1"
d=$(paste "$T/e-jf1" "$T/e-ff1" | awk '{ for (c = 1; c <= 3; c++) { a = $c - $(c+3); if (a < 0) a = -a; if (a > m) m = a } } END { printf "%.3g", m }')
le "$d" 1e-9 && ok "journal fit --reparam 1 = cellfit fit --reparam 1 (max diff $d mm)" || no "reparam fits differ by $d mm"
cmp -s "$T/e-jf1" "$T/e-jf" && no "--reparam 1 changed nothing" || ok "--reparam 1 is a different fit from pass 0"
r=$(json "$T/jf.json" rms)
le "$r" 0.006 && ok "residual rms $r from the second pass over the journal (noise 0.005)" || no "rms $r"
# To a tolerance, with `cellfit fit`'s options: noise 0.005 mm along z, so
# 0.02 mm (4 sigma) holds for 99 % of the points on the first round;
# 0.01 mm (2 sigma) cannot hold for 99 % (a Gaussian keeps 95.4 % within
# 2 sigma, and knots do not remove noise): two rounds, the second on the
# uniform refinement of the 40 x 30 cubic net (every span halved: 40 + 37
# by 30 + 27), the best round written and reported, exit 1 as `cellfit fit`.
expect 0 "journal fit --tol 0.02 --within 99" "$CF" journal fit "$T/p.jnl" --nominal "$T/part/nominal.igs" \
    --tol 0.02 --within 99 --json --out "$T/jt.igs"
[ "$(json "$T/out" fit_status)" = met ] && grep -q '"tol_met": true' "$T/out" &&
    [ "$(grep -o '"round": ' "$T/out" | wc -l)" -eq 1 ] && ok "tol 0.02: fit_status met in one round" ||
    no "tol 0.02: $(cat "$T/out")"
awk -v p="$(json "$T/out" within_tol_pct)" 'BEGIN { exit !(p >= 99 && p <= 100) }' &&
    ok "tol 0.02: $(json "$T/out" within_tol_pct) % within" || no "tol 0.02: within $(json "$T/out" within_tol_pct)"
expect 1 "journal fit --tol 0.01 --within 99 --max-rounds 2 --refine uniform: not met, exit 1" "$CF" journal fit "$T/p.jnl" \
    --nominal "$T/part/nominal.igs" --tol 0.01 --within 99 --max-rounds 2 --refine uniform --json --out "$T/jt2.igs"
cp "$T/out" "$T/jt2.json"
grep -q "tolerance 0.01 mm not met" "$T/err" && one_line && [ -s "$T/jt2.igs" ] &&
    ok "says the tolerance was not met in one line, the best fit written" || no "not met: $(cat "$T/err")"
[ "$(json "$T/jt2.json" fit_status)" = not_met_no_progress ] && grep -q '"tol_met": false' "$T/jt2.json" &&
    grep -q '"stopped": "not_met_max_rounds: after 2 rounds' "$T/jt2.json" && ok "tol 0.01: fit_status not_met_no_progress after 2 rounds" ||
    no "tol 0.01: $(cat "$T/jt2.json")"
grep -q '"round": 0, "nu": 40, "nv": 30, ' "$T/jt2.json" && grep -q '"round": 1, "nu": 77, "nv": 57, ' "$T/jt2.json" &&
    [ "$(grep -o '"round": ' "$T/jt2.json" | wc -l)" -eq 2 ] && ok "tol 0.01: rounds 40 x 30, then 77 x 57" ||
    no "tol 0.01 rounds: $(cat "$T/jt2.json")"
awk -v p="$(sed 's/.*"round": 0,[^}]*"within_tol_pct": \([0-9.e+-]*\).*/\1/' "$T/jt2.json")" \
    'BEGIN { exit !(p > 94.5 && p < 99) }' && ok "tol 0.01: round 0 keeps about 95.4 % within 2 sigma" ||
    no "tol 0.01: round 0 within $(cat "$T/jt2.json")"
"$CF" fit --base "$T/part/nominal.igs" --points "$T/part/p.xyz" --tol 0.01 --within 99 --max-rounds 2 \
    --refine uniform --json --out "$T/ft2.igs" >"$T/ft2.json" 2>/dev/null
[ "$(sed 's/.*"rounds": \(\[[^]]*\]\).*/\1/; s/"seconds": [0-9.e+-]*//g' "$T/ft2.json")" = \
    "$(sed 's/.*"rounds": \(\[[^]]*\]\).*/\1/; s/"seconds": [0-9.e+-]*//g' "$T/jt2.json")" ] &&
    ok "journal fit rounds = cellfit fit rounds of the same points" || no "rounds differ from cellfit fit"
expect 2 "journal fit --within without --tol: exit 2" "$CF" journal fit "$T/p.jnl" --nominal "$T/part/nominal.igs" \
    --within 99 --out "$T/x.igs"
grep -q -- "need --tol" "$T/err" && one_line && ok "says --within needs --tol" || no "--within message: $(cat "$T/err")"
"$CF" gen --dir "$T/other" --nu 8 --nv 8 --count 100 >/dev/null
for sub in export info recover fit; do
    expect 0 "journal $sub --help: exit 0" "$CF" journal $sub --help
done
grep -q -- "--nominal N.igs" "$T/out" && ok "journal fit --help lists --nominal" || no "journal fit --help: $(head -3 "$T/out")"
expect 2 "journal fit against another nominal: exit 2" "$CF" journal fit "$T/p.jnl" --nominal "$T/other/nominal.igs" --out "$T/x.igs"
grep -q "measured against 'nominal.igs'" "$T/err" && one_line && ok "says which nominal it was measured against" ||
    no "nominal mismatch message: $(cat "$T/err")"

# cellfit scan: usage errors; without device drivers in the build it says so.
expect 2 "scan without --journal: exit 2" "$CF" scan --stage a --probe b --nominal "$T/part/nominal.igs"
expect 2 "scan --tol without --fit: exit 2" "$CF" scan --stage a --probe b --nominal "$T/part/nominal.igs" --journal "$T/s.jnl" --tol 0.1
grep -q -- "apply to --fit" "$T/err" && one_line && ok "says --tol applies to --fit" || no "scan --tol message: $(cat "$T/err")"
expect 2 "scan --step 0: exit 2" "$CF" scan --stage a --probe b --nominal "$T/part/nominal.igs" --journal "$T/s.jnl" --step 0
expect 2 "scan --region bad: exit 2" "$CF" scan --stage a --probe b --nominal "$T/part/nominal.igs" --journal "$T/s.jnl" --region 1:0:0:1
expect 2 "scan onto an existing journal: exit 2" "$CF" scan --stage a --probe b --nominal "$T/part/nominal.igs" --journal "$T/a.jnl"
timeout 60 "$CF" scan --stage tcp:127.0.0.1:1 --probe tcp:127.0.0.1:1 --nominal "$T/part/nominal.igs" --journal "$T/s.jnl" >"$T/out" 2>"$T/err"
rc=$?
if grep -q "not in this build" "$T/err"; then
    [ $rc -eq 1 ] && [ ! -e "$T/s.jnl" ] && ok "scan without drivers: exit 1, no journal left" || no "scan without drivers: exit $rc"
else
    [ $rc -ne 0 ] && [ ! -e "$T/s.jnl" ] && one_line && ok "scan with no device there: exit $rc, one line, no journal left" ||
        no "scan on closed ports: exit $rc, $(cat "$T/err")"
fi

# Power cuts: a writer (each record appended in two writes with a pause, so
# that a kill can tear one) killed with kill -9 after a seeded random delay.
# Recovery must keep every record the writer had acknowledged (printed after
# the fsync), drop nothing but a torn tail, and leave whole records only.
runs=30
lost=0
torn=0
for i in $(seq 1 $runs); do
    j="$T/cut$i.jnl"
    delay=$(awk -v s="$i" 'BEGIN { srand(s * 7919); printf "%.3f", 0.02 + 0.25 * rand() }')
    "$CF" journal selftest-write "$j" --records 10000000 --sync-every 16 --torn "$i" >"$T/w$i.out" 2>&1 &
    WPID=$!
    sleep "$delay"
    kill -KILL "$WPID" 2>/dev/null
    wait "$WPID" 2>/dev/null
    WPID=
    acked=$(sed -n 's/^acked //p' "$T/w$i.out" | tail -1)
    acked=${acked:-0}
    if ! grep -q '^header$' "$T/w$i.out"; then
        continue # killed before the header was durable: nothing was promised
    fi
    tb=$(timeout 60 "$CF" journal info "$j" --json 2>/dev/null | sed -n 's/.*"torn_tail_bytes": \([0-9]*\).*/\1/p')
    [ "${tb:-0}" -gt 0 ] && torn=$((torn + 1))
    out=$(timeout 60 "$CF" journal recover "$j" 2>&1) || { lost=$((lost + 1)); echo "     run $i: $out"; continue; }
    kept=$(echo "$out" | sed -n 's/.*: \([0-9]*\) records kept.*/\1/p')
    chk=$(timeout 60 "$CF" journal selftest-check "$j" 2>&1) || { lost=$((lost + 1)); echo "     run $i: $chk"; continue; }
    if [ "${kept:-0}" -lt "$acked" ] || [ "$(size "$j")" != $((128 + kept * 80)) ]; then
        lost=$((lost + 1))
        echo "     run $i: acked $acked, kept $kept, size $(size "$j")"
    fi
done
[ $lost -eq 0 ] && ok "power cut x $runs: every acknowledged record kept, whole records only ($torn torn tails cut)" ||
    no "power cut: $lost of $runs runs lost acknowledged records or left a bad journal"

echo "journal: $pass passed, $fail failed"
[ $fail -eq 0 ]
