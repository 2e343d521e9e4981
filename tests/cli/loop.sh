#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/loop.sh CELLFIT: end-to-end checks of the fitting loop of
# `cellfit fit --tol` (fit, reparameterise, insert knots until the
# tolerance holds; Brujic et al. 2010, Section 2.2) and of `--robust`:
# on a panel with a narrow bump the start net misses the tolerance, both
# refinements reach it (checked independently with `cellfit report` and
# against the true part), residual-driven with fewer control points than
# uniform; a robust fit recovers the part under 1 % gross outliers where
# the plain fit is pulled; memory stays flat in the number of points.
# --refine auto (the default, nf_knotsel) reaches it too, and its pruning
# stage reports its trials honestly.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-loop.XXXXXX")
trap 'rm -rf "$T"' EXIT
json() { # json FILE KEY: the first number, string or boolean field KEY of a one-line JSON object
    sed -n "s/^{.*\"$2\": \"\{0,1\}\([^,\"}]*\)\"\{0,1\}[,}].*/\1/p" "$1" | head -1
}
# top FILE KEY: a top-level field (after the rounds array, or without one)
top() { sed 's/"rounds": \[[^]]*\]//' "$1" >"$T/top.json"; json "$T/top.json" "$2"; }
# maxdev FIT TRUTHDIR: largest normal distance of the true check points to FIT
maxdev() {
    "$CF" project "$1" "$2/check.xyz" | awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }'
}

# A 200 x 150 mm panel (dent, warp) with a narrow bump (0.5 mm high, radius
# 4 mm at the centre, on a check point); a 12 x 10 start net (20 mm spans).
"$CF" gen --dir "$T/b" --nu 12 --nv 10 --count 30000 --noise 0.005 --bump 0.5,100,75,4 >/dev/null
grep -v '^#' "$T/b/points.uvxyz" | cut -d' ' -f3- >"$T/b/points.xyz"
# The true part densely (noise-free, 10^5 points off the scan lines): a fit
# must not wiggle between the lines it was fitted to.
"$CF" gen --dir "$T/bt" --nu 12 --nv 10 --count 100000 --noise 0 --bump 0.5,100,75,4 >/dev/null
grep -v '^#' "$T/bt/points.uvxyz" | cut -d' ' -f3- >"$T/bt/check.xyz"
TOL=0.03
expect 1 "start net alone misses the tolerance (--max-rounds 1: exit 1)" "$CF" fit --base "$T/b/nominal.igs" \
    --points "$T/b/points.xyz" --tol $TOL --max-rounds 1 --out "$T/start.igs" --json
cp "$T/out" "$T/start.json"
[ "$(top "$T/start.json" tol_met)" = false ] && ok "start net: tol_met false" || no "start: $(cat "$T/start.json")"
[ -s "$T/start.igs" ] && ok "the best surface is written even when the tolerance is not met" || no "no surface written"
[ "$(wc -l <"$T/err")" -eq 1 ] && grep -q "not met" "$T/err" && ok "one line on stderr says the tolerance was not met" ||
    no "stderr: $(cat "$T/err")"
w0=$(top "$T/start.json" within_tol_pct)
e0=$(maxdev "$T/start.igs" "$T/b")
le 0.1 "$e0" && ok "start net misses the bump: $w0 % within $TOL mm, true part off by $e0 mm" || no "start net fits the bump ($e0)"

for r in uniform residual; do
    expect 0 "--refine $r reaches the tolerance" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" \
        --tol $TOL --refine $r --out "$T/$r.igs" --json
    cp "$T/out" "$T/$r.json"
    [ "$(top "$T/$r.json" tol_met)" = true ] && ok "$r: tol_met true" || no "$r: $(cat "$T/$r.json")"
    n=$(grep -o '"round": ' "$T/$r.json" | wc -l)
    le 2 "$n" && ok "$r: $n rounds reported" || no "$r: $n rounds"
    # Independently: cellfit report measures the written surface against the points.
    "$CF" report "$T/$r.igs" "$T/b/points.xyz" --tol $TOL --json >"$T/rep-$r.json"
    w=$(json "$T/rep-$r.json" within_tol_pct)
    [ "$w" = 100 ] && ok "$r: report confirms 100 % of the points within $TOL mm" || no "$r: report says $w %"
    e=$(maxdev "$T/$r.igs" "$T/b")
    le "$e" $TOL && ok "$r: fit within $TOL mm of the true part, bump included (max $e)" || no "$r: true part off by $e mm"
    e=$(maxdev "$T/$r.igs" "$T/bt")
    le "$e" $TOL && ok "$r: no wiggle between the scan lines: 10^5 true points within $TOL mm (max $e)" ||
        no "$r: dense true points off by $e mm"
done
# --refine auto (the default): met, confirmed by report; the true part at
# the check points within TOL; between the scan lines (10^5 noise-free true
# points) 99.99 % within TOL and none beyond 2 TOL (issue 14's held-out
# target): auto stops at the first net that holds the points, which may
# leave the bump's very top a little short (0.05 mm on 5 of 10^5).
expect 0 "--refine auto (default) reaches the tolerance" "$CF" fit --base "$T/b/nominal.igs" \
    --points "$T/b/points.xyz" --tol $TOL --out "$T/auto.igs" --json
cp "$T/out" "$T/auto.json"
[ "$(top "$T/auto.json" fit_status)" = met ] && [ "$(top "$T/auto.json" refine)" = auto ] &&
    ok "auto: fit_status met, refine auto by default" || no "auto: $(cat "$T/auto.json")"
"$CF" report "$T/auto.igs" "$T/b/points.xyz" --tol $TOL --json >"$T/rep-auto.json"
w=$(json "$T/rep-auto.json" within_tol_pct)
[ "$w" = 100 ] && ok "auto: report confirms 100 % of the points within $TOL mm" || no "auto: report says $w %"
e=$(maxdev "$T/auto.igs" "$T/b")
le "$e" $TOL && ok "auto: fit within $TOL mm of the true part at the check points (max $e)" || no "auto: true part off by $e mm"
"$CF" project "$T/auto.igs" "$T/bt/check.xyz" | awk -v t=$TOL '{ d = $3; if (d < 0) d = -d; n++; if (d > t) o++; if (d > m) m = d }
    END { printf "%d %d %.4g", n, o, m }' >"$T/dense"
read -r dn dout dmax <"$T/dense"
[ "$dn" -eq 100000 ] && le $((dout * 10000)) "$dn" && le "$dmax" "$(awk -v t=$TOL 'BEGIN { print 2 * t }')" &&
    ok "auto: between the scan lines $dout of $dn true points beyond $TOL mm, max $dmax" ||
    no "auto: dense true points: $dout of $dn beyond $TOL mm, max $dmax"
ca=$(top "$T/auto.json" control_points)
cu=$(top "$T/uniform.json" control_points)
cr=$(top "$T/residual.json" control_points)
echo "     control points to reach $TOL mm: uniform $cu, residual-driven $cr, auto $ca (start 120)"
# The pruning stage (auto, once met): its trials follow the loop's rounds
# in the JSON, each one knot line fewer than the fit it came from; the kept
# ones meet the tolerance, the undone ones not, top-level "pruned" counts
# the kept, and the result is the last kept trial's net. Against the same
# fit with --prune 0 (no stage): the loop's rounds alike, and no more
# control points with the stage than without.
expect 0 "--prune 0: the loop without the pruning stage" "$CF" fit --base "$T/b/nominal.igs" \
    --points "$T/b/points.xyz" --tol $TOL --prune 0 --out "$T/auto0.igs" --json
cp "$T/out" "$T/auto0.json"
msg=$(python3 -c "
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
tr = [r for r in a['rounds'] if 'pruned' in r]
loop = a['rounds'][:len(a['rounds']) - len(tr)]
e = []
if any('pruned' in r for r in loop): e.append('a trial among the loop rounds')
if any('pruned' in r for r in b['rounds']) or b['pruned'] != 0: e.append('--prune 0 pruned')
if [(r['nu'], r['nv']) for r in loop] != [(r['nu'], r['nv']) for r in b['rounds']]: e.append('loop rounds differ')
cp = loop[-1]['control_points']
for r in tr:
    if r['removed_dir'] not in ('u', 'v') or r['control_points'] >= cp: e.append('trial net %d from %d' % (r['control_points'], cp))
    if r['pruned']:
        cp = r['control_points']
        if r['within_tol_pct'] < a['within']: e.append('kept trial below within')
    elif r['within_tol_pct'] >= a['within']: e.append('undone trial met')
if sum(r['pruned'] for r in tr) != a['pruned']: e.append('pruned count')
if a['control_points'] != cp or a['control_points'] > b['control_points']: e.append('result net %d' % a['control_points'])
if a['fit_status'] != 'met' or a['within_tol_pct'] < a['within']: e.append('status')
print('%s: %d trials, %d kept, %d -> %d control points' % ('; '.join(e) or 'ok', len(tr), a['pruned'], b['control_points'], a['control_points']))
" "$T/auto.json" "$T/auto0.json")
case "$msg" in
ok:*) ok "auto: pruning trials in the rounds, honest (${msg#ok: })" ;;
*) no "auto: pruning rounds: $msg" ;;
esac
[ -n "$cu" ] && [ -n "$cr" ] && [ "$cr" -lt "$cu" ] && ok "residual-driven needs fewer control points ($cr < $cu)" ||
    no "residual $cr vs uniform $cu control points"

# Limits: --max-cp below what the tolerance needs: best fit written, exit 1, why.
expect 1 "--max-cp too small: exit 1" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --tol $TOL \
    --max-cp 300 --out "$T/capped.igs" --json
cp "$T/out" "$T/capped.json"
c=$(top "$T/capped.json" control_points)
[ "$(top "$T/capped.json" tol_met)" = false ] && le "$c" 300 && [ -s "$T/capped.igs" ] &&
    ok "capped: best fit of $c control points written, tol_met false" || no "capped: $(cat "$T/capped.json")"
grep -q "max-cp" "$T/err" && ok "capped: stderr names --max-cp" || no "capped stderr: $(cat "$T/err")"
wc=$(top "$T/capped.json" within_tol_pct)
le "$w0" "$wc" && ok "capped: the best fit is no worse than the start ($w0 -> $wc %)" || no "capped $wc < start $w0"
# --within: a share of the points is enough.
expect 0 "--within 95 met by the start net" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --tol $TOL \
    --within 95 --out "$T/w.igs" --json
[ "$(grep -o '"round": ' "$T/out" | wc -l)" -eq 1 ] && ok "--within 95: one round" || no "--within: $(cat "$T/out")"
# --uv: refinement with the given parameters.
expect 0 "--uv --tol" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.uvxyz" --uv --tol $TOL --out "$T/uv.igs" --json
[ "$(top "$T/out" tol_met)" = true ] && ok "--uv: tolerance met" || no "--uv: $(cat "$T/out")"
# Bad usage.
expect 0 "fit --help: exit 0" "$CF" fit --help
grep -q -- "--tol MM" "$T/out" && grep -q -- "--robust-iters N" "$T/out" && grep -q "default: auto" "$T/out" &&
    ok "fit --help lists --tol, --robust-iters and the defaults" || no "fit --help: $(head -3 "$T/out")"
expect 2 "fit --bogus: exit 2" "$CF" fit --bogus
grep -q "unknown option '--bogus'" "$T/err" && ok "  ... named as unknown" || no "fit --bogus: $(cat "$T/err")"
expect 0 "fit --tol=VALUE accepted" "$CF" fit --base="$T/b/nominal.igs" --points="$T/b/points.uvxyz" --uv --tol=1 \
    --out="$T/eq.igs" --json
[ "$(json "$T/out" fit_status)" = met ] && ok "  ... fit_status met" || no "fit_status: $(cat "$T/out")"
expect 2 "--within without --tol" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --within 90 --out "$T/x.igs"
expect 2 "--tol 0" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --tol 0 --out "$T/x.igs"
expect 2 "--refine bogus" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --tol 1 --refine bogus --out "$T/x.igs"
expect 2 "--max-cp below the base net" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/points.xyz" --tol 1 --max-cp 50 --out "$T/x.igs"
[ "$(wc -l <"$T/err")" -eq 1 ] && ok "refusal is one line" || no "refusal: $(cat "$T/err")"

# Robust: 1 % gross outliers (+/- 5 mm spikes) on a net fine enough for the part.
"$CF" gen --dir "$T/o" --nu 40 --nv 30 --count 40000 --noise 0.005 --outliers 0.01 --spike 5 >/dev/null
grep -v '^#' "$T/o/points.uvxyz" | cut -d' ' -f3- >"$T/o/points.xyz"
spikes=$(grep -v '^#' "$T/o/points.uvxyz" | wc -l)
expect 0 "plain fit with spikes" "$CF" fit --base "$T/o/nominal.igs" --points "$T/o/points.xyz" --out "$T/plain.igs"
expect 0 "--robust fit with spikes" "$CF" fit --base "$T/o/nominal.igs" --points "$T/o/points.xyz" --robust --out "$T/robust.igs" --json
cp "$T/out" "$T/robust.json"
ep=$(maxdev "$T/plain.igs" "$T/o")
er=$(maxdev "$T/robust.igs" "$T/o")
le 0.05 "$ep" && ok "plain fit pulled by the spikes: true part off by $ep mm" || no "plain fit not pulled ($ep)"
le "$er" 0.01 && ok "robust fit recovers the true part within 0.01 mm (max $er)" || no "robust fit off by $er mm"
out=$(top "$T/robust.json" outliers)
sig=$(top "$T/robust.json" robust_sigma)
le 300 "$out" && le "$out" 600 && ok "robust: $out of $spikes points rejected (400 spikes)" || no "robust rejected $out"
le 0.004 "$sig" && le "$sig" 0.006 && ok "robust scale $sig mm (noise sigma 0.005)" || no "robust sigma $sig"
# Robust and refined together: spikes on the bump panel. The start net
# cannot follow the bump, whose points the robust pass rejects too; their
# misfit sits in one place (unlike the spikes) and still drives the knots.
"$CF" gen --dir "$T/bo" --nu 12 --nv 10 --count 40000 --noise 0.005 --bump 0.5,100,75,4 --outliers 0.01 >/dev/null
grep -v '^#' "$T/bo/points.uvxyz" | cut -d' ' -f3- >"$T/bo/points.xyz"
expect 0 "--robust --tol $TOL --within 98.9 with spikes and a bump" "$CF" fit --base "$T/bo/nominal.igs" \
    --points "$T/bo/points.xyz" --robust --tol $TOL --within 98.9 --refine residual --out "$T/bo.igs" --json
cp "$T/out" "$T/bo.json"
out=$(top "$T/bo.json" outliers)
e=$(maxdev "$T/bo.igs" "$T/bt")
[ "$(top "$T/bo.json" tol_met)" = true ] && le "$e" $TOL && le 300 "$out" && le "$out" 600 &&
    ok "robust + refined: bump recovered (dense true points within $e mm), $out points rejected (400 spikes)" ||
    no "robust + refined: tol_met $(top "$T/bo.json" tol_met), dense truth $e, rejected $out"

# The same with --refine auto (the default): the rejected points of a cell
# whose rejected share is 4 times the surface's (the bump, not the spikes)
# count as misfit for the knot chooser (cf_loop_fold_auto), so the bump is
# refined and not flagged. The last rounds gain 0.01-0.02 points each:
# --min-gain 0.005 lets them.
expect 0 "--robust --tol $TOL --within 98.9, auto, spikes and a bump" "$CF" fit --base "$T/bo/nominal.igs" \
    --points "$T/bo/points.xyz" --robust --tol $TOL --within 98.9 --min-gain 0.005 --out "$T/boa.igs" --json
cp "$T/out" "$T/boa.json"
out=$(top "$T/boa.json" outliers)
e=$(maxdev "$T/boa.igs" "$T/bt")
[ "$(top "$T/boa.json" tol_met)" = true ] && le "$e" $TOL && le 300 "$out" && le "$out" 600 &&
    ok "robust + auto: bump recovered (dense true points within $e mm), $out points rejected (400 spikes)" ||
    no "robust + auto: tol_met $(top "$T/boa.json" tol_met), dense truth $e, rejected $out"
# On clean data the robust fit is the plain fit to the noise.
"$CF" gen --dir "$T/c" --nu 40 --nv 30 --count 40000 --noise 0.005 >/dev/null
expect 0 "--robust on clean data" "$CF" fit --base "$T/c/nominal.igs" --points "$T/c/points.uvxyz" --uv --robust --out "$T/rc.igs"
"$CF" fit --base "$T/c/nominal.igs" --points "$T/c/points.uvxyz" --uv --out "$T/pc.igs" >/dev/null
"$CF" eval "$T/rc.igs" "$T/c/check.uv" >"$T/e-rc"
"$CF" eval "$T/pc.igs" "$T/c/check.uv" >"$T/e-pc"
d=$(paste "$T/e-rc" "$T/e-pc" | awk '{ a = $3 - $6; if (a < 0) a = -a; if (a > m) m = a } END { printf "%.3g", m }')
le "$d" 0.002 && ok "robust and plain fits agree on data without outliers ($d mm)" || no "robust vs plain on clean data: $d"

# Memory flat in the number of points with --tol (at most 1 MiB apart: less
# than one byte per added point; identical runs differ by a few hundred kB): same nets (uniform, two
# rounds, a tolerance below the noise: never met, the finer fit the best),
# 3 x 10^4 and 10^6 points (3 x 10^4: the second net, 10,179 control
# points, within half the points). Two threads on any machine: every pass
# reads the file's halves, so the points cache (one thread's whole passes,
# up to 64 MiB) stays out; its cost is checked after.
"$CF" gen --dir "$T/m4" --nu 60 --nv 45 --count 30000 >/dev/null &&
    "$CF" gen --dir "$T/m6" --nu 60 --nv 45 --count 1000000 >/dev/null
for m in m4 m6; do
    "$CF" fit --base "$T/$m/nominal.igs" --points "$T/$m/points.uvxyz" --uv --threads 2 --tol 0.004 \
        --refine uniform --max-rounds 2 --out "$T/$m.igs" --json >"$T/$m.json" 2>/dev/null
done
r4=$(top "$T/m4.json" peak_rss_bytes)
r6=$(top "$T/m6.json" peak_rss_bytes)
nets() { sed -n 's/.*"rounds": \[\([^]]*\)\].*/\1/p' "$1" | grep -o '"nu": [0-9]*, "nv": [0-9]*' | tr -d '"a-z:,' | tr -s ' \n' ' '; }
n4="$(nets "$T/m4.json") best $(top "$T/m4.json" control_points)"
n6="$(nets "$T/m6.json") best $(top "$T/m6.json" control_points)"
diff=$(awk -v a="$r4" -v b="$r6" 'BEGIN { d = b - a; if (d < 0) d = -d; print d }')
if [ -n "$r4" ] && [ -n "$r6" ] && [ "$n4" = "$n6" ] && le "$diff" 1048576; then
    ok "--tol loop: peak RSS flat in points over the nets ($n4): 3 x 10^4 -> $r4 B, 10^6 -> $r6 B"
else
    no "--tol loop: peak RSS 3 x 10^4 -> $r4 (nets $n4), 10^6 -> $r6 (nets $n6)"
fi
# One thread: the loop's passes from the points cache, which holds the rows
# of 5 doubles (within its 64 MiB): 40 B a point more (within the same
# 1 MiB), the same fits.
for m in m4 m6; do
    "$CF" fit --base "$T/$m/nominal.igs" --points "$T/$m/points.uvxyz" --uv --threads 1 --tol 0.004 \
        --refine uniform --max-rounds 2 --out "$T/${m}c.igs" --json >"$T/${m}c.json" 2>/dev/null
done
r4c=$(top "$T/m4c.json" peak_rss_bytes)
r6c=$(top "$T/m6c.json" peak_rss_bytes)
more=$(awk -v a="$r4c" -v b="$r6c" 'BEGIN { print b - a - 40 * 970000 }')
if [ -n "$r4c" ] && [ -n "$r6c" ] && [ "$(top "$T/m6c.json" control_points)" = "$(top "$T/m6.json" control_points)" ] &&
    le -1048576 "$more" && le "$more" 1048576; then
    ok "--tol loop, one thread: peak RSS 40 B a point more, the points cache (3 x 10^4 -> $r4c B, 10^6 -> $r6c B)"
else
    no "--tol loop, one thread: peak RSS 3 x 10^4 -> $r4c B, 10^6 -> $r6c B ($more B off 40 B a point)"
fi
echo "loop: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
