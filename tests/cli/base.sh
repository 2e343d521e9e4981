#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/base.sh CELLFIT: `cellfit base` end to end (issue 3): the
# synthetic part's x y z points and its boundary curves (IGES 126), every
# kind of base surface built from them, a fit through each, and the fit
# checked against the true part; refusals with exit 2 and one line.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-base.XXXXXX")
trap 'rm -rf "$T"' EXIT
# maxdiff F G: largest coordinate difference between two x y z files
maxdiff() { paste "$1" "$2" | awk '{ for (c = 1; c <= 3; c++) { a = $c - $(c+3); if (a < 0) a = -a; if (a > m) m = a } } END { printf "%.4g", m }'; }
# oneline: the error is a single line on stderr
oneline() { [ "$(wc -l <"$T/err")" -eq 1 ] && ok "$1: one-line error" || no "$1: stderr has $(wc -l <"$T/err") lines"; }

# The part: a 40 x 30 bicubic nominal; the real part has a dent and a warp.
"$CF" gen --dir "$T" --nu 40 --nv 30 --count 60000 --noise 0.005 >/dev/null
grep -v '^#' "$T/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"
expect 0 "boundary curves of the nominal as IGES 126" "$CF" base --extract "$T/nominal.igs" --out "$T/curves.igs"
[ "$(grep -c '^     126' "$T/curves.igs")" -eq 8 ] && ok "four 126 entities (8 D lines)" || no "curves.igs: $(grep -c '^     126' "$T/curves.igs") 126 D lines"

# The nominal crown is a sum of univariate parts and a bilinear term, which
# a bilinear Coons patch reproduces: built from its boundary it is the nominal.
expect 0 "bilinear Coons base" "$CF" base --curves "$T/curves.igs" --out "$T/b-bilinear.igs" --json
[ "$(json "$T/out" method)" = bilinear ] && [ "$(json "$T/out" nu)" = 40 ] && [ "$(json "$T/out" nv)" = 30 ] &&
    ok "bilinear base: 40 x 30 (the curves' net)" || no "bilinear JSON: $(cat "$T/out")"
"$CF" eval "$T/b-bilinear.igs" "$T/check.uv" >"$T/e-bil"
"$CF" eval "$T/nominal.igs" "$T/check.uv" >"$T/e-nom"
d=$(maxdiff "$T/e-bil" "$T/e-nom")
le "$d" 1e-9 && ok "bilinear Coons of the nominal's boundary is the nominal ($d mm)" || no "bilinear Coons differs from the nominal by $d mm"

# A finer net on request (knot insertion): the same surface.
expect 0 "bilinear refined to 50 x 40" "$CF" base --curves "$T/curves.igs" --nu 50 --nv 40 --out "$T/b-fine.igs" --json
[ "$(json "$T/out" nu)" = 50 ] && [ "$(json "$T/out" nv)" = 40 ] && ok "refined net 50 x 40" || no "refined JSON: $(cat "$T/out")"
"$CF" eval "$T/b-fine.igs" "$T/check.uv" >"$T/e-fine"
d=$(maxdiff "$T/e-fine" "$T/e-bil")
le "$d" 1e-9 && ok "refined bilinear base is the same surface ($d mm)" || no "refined base differs by $d mm"
"$CF" info "$T/b-bilinear.igs" | grep -q "(polynomial)" && ok "polynomial curves give a polynomial base" || no "bilinear base not polynomial"
# box_check SURF NAME: `cellfit info`'s sampled box (inside the edges row
# by row, cf_surfrow) against `cellfit eval` (the basis at each point) at the
# same samples, 8 a knot span and direction, the edges included; at least
# one of the six bounds must lie inside the edges (where only cf_surfrow's
# samples reach it).
box_check() {
    if ! "$CF" info --json "$1" >"$T/info"; then no "$2: info failed"; return; fi
    for k in nu nv p q u0 u1 v0 v1 xmin xmax ymin ymax zmin zmax; do
        [ -n "$(json "$T/info" $k)" ] || { no "$2: info --json has no $k"; return; }
    done
    awk -v nu="$(json "$T/info" nu)" -v nv="$(json "$T/info" nv)" -v p="$(json "$T/info" p)" \
        -v q="$(json "$T/info" q)" -v u0="$(json "$T/info" u0)" -v u1="$(json "$T/info" u1)" \
        -v v0="$(json "$T/info" v0)" -v v1="$(json "$T/info" v1)" 'BEGIN {
        su = 8 * (nu - p); sv = 8 * (nv - q); if (su > 2000) su = 2000; if (sv > 2000) sv = 2000
        for (j = 0; j <= sv; j++) for (i = 0; i <= su; i++)
            printf "%.17g %.17g %d\n", u0 + (u1 - u0) * i / su, v0 + (v1 - v0) * j / sv,
                i == 0 || i == su || j == 0 || j == sv }' >"$T/box.uve"
    cut -d' ' -f1,2 "$T/box.uve" >"$T/box.uv"
    if ! "$CF" eval "$1" "$T/box.uv" >"$T/box.xyz"; then no "$2: eval failed"; return; fi
    r=$(cut -d' ' -f3 "$T/box.uve" | paste -d' ' "$T/box.xyz" - | awk \
        -v x0="$(json "$T/info" xmin)" -v x1="$(json "$T/info" xmax)" -v y0="$(json "$T/info" ymin)" \
        -v y1="$(json "$T/info" ymax)" -v z0="$(json "$T/info" zmin)" -v z1="$(json "$T/info" zmax)" '
        NR == 1 { for (c = 1; c <= 3; c++) { lo[c] = $c; hi[c] = $c; elo[c] = 1e300; ehi[c] = -1e300 } }
        { for (c = 1; c <= 3; c++) { if ($c < lo[c]) lo[c] = $c; if ($c > hi[c]) hi[c] = $c
              if ($4) { if ($c < elo[c]) elo[c] = $c; if ($c > ehi[c]) ehi[c] = $c } } }
        function off(s, t, w) { s -= t; if (s < 0) s = -s; return s > 1e-12 * w }
        END { w = (hi[1] - lo[1]) + (hi[2] - lo[2]) + (hi[3] - lo[3])
              if (off(lo[1], x0, w) || off(hi[1], x1, w) || off(lo[2], y0, w) || off(hi[2], y1, w) ||
                  off(lo[3], z0, w) || off(hi[3], z1, w)) {
                  printf "BAD info %s %s %s %s %s %s, eval %s %s %s %s %s %s", x0, x1, y0, y1, z0, z1,
                      lo[1], hi[1], lo[2], hi[2], lo[3], hi[3]; exit }
              n = 0; for (c = 1; c <= 3; c++) n += (elo[c] > lo[c]) + (ehi[c] < hi[c])
              print n }')
    case "$r" in
    [1-6]) ok "$2: info's sampled box is eval's at the same $(wc -l <"$T/box.xyz") samples ($r of 6 bounds inside the edges)" ;;
    0) no "$2: every bound on an edge: the check does not reach cf_surfrow" ;;
    *) no "$2: info's box: $r" ;;
    esac
}
box_check "$T/nominal.igs" "nominal"
expect 2 "--degree is refused for a Coons patch" "$CF" base --curves "$T/curves.igs" --degree 2 --out "$T/x.igs"

# Curves given in another order (--de) and direction make the same patch.
expect 0 "bilinear with --de 7,5,3,1" "$CF" base --curves "$T/curves.igs" --de 7,5,3,1 --out "$T/b-de.igs"
"$CF" project "$T/b-de.igs" "$T/check.xyz" >"$T/p-de"
e=$(awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$T/p-de")
"$CF" project "$T/nominal.igs" "$T/check.xyz" >"$T/p-nom"
en=$(awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$T/p-nom")
le "$(awk -v a="$e" -v b="$en" 'BEGIN { d = a - b; if (d < 0) d = -d; print d }')" 1e-9 &&
    ok "reordered curves give the same surface (true points $e mm from it, $en from the nominal)" ||
    no "reordered curves: $e vs $en"

expect 0 "bicubic Coons base (30 % subset)" env SOURCE_DATE_EPOCH=0 "$CF" base --points "$T/points.xyz" --curves "$T/curves.igs" \
    --method bicubic --subset 30 --seed 7 --out "$T/b-bicubic.igs" --json
cp "$T/out" "$T/bicubic.json"
u=$(json "$T/bicubic.json" used)
le 15000 "$u" && le "$u" 21000 && ok "bicubic used about 30 % of 60000 points ($u)" || no "bicubic used $u points"
expect 0 "bicubic, same seed: same base" env SOURCE_DATE_EPOCH=0 "$CF" base --points "$T/points.xyz" --curves "$T/curves.igs" \
    --method bicubic --subset 30 --seed 7 --out "$T/b-bicubic2.igs"
pdata() { awk 'substr($0, 73, 1) == "P"' "$1"; } # parameter data (the G section names the file)
pdata "$T/b-bicubic.igs" >"$T/pd1"
pdata "$T/b-bicubic2.igs" >"$T/pd2"
cmp -s "$T/pd1" "$T/pd2" && [ -s "$T/pd1" ] && ok "seeded subset is reproducible (identical parameter data)" || no "same seed, different base"
expect 0 "bicubic, another seed" env SOURCE_DATE_EPOCH=0 "$CF" base --points "$T/points.xyz" --curves "$T/curves.igs" \
    --method bicubic --subset 30 --seed 8 --out "$T/b-bicubic3.igs"
pdata "$T/b-bicubic3.igs" >"$T/pd3"
cmp -s "$T/pd1" "$T/pd3" && no "another seed gives the same base" || ok "another seed, another subset"
# The bicubic patch's fitted cross derivatives carry interior detail the
# boundary lacks: the true part is nearer to it than to the bilinear patch.
rmsd() { awk '{ s += $3 * $3; n++ } END { printf "%.4g", sqrt(s / n) }' "$1"; }
"$CF" project "$T/b-bicubic.igs" "$T/check.xyz" >"$T/p-bic"
"$CF" project "$T/b-bilinear.igs" "$T/check.xyz" >"$T/p-bil"
rb=$(rmsd "$T/p-bic")
rl=$(rmsd "$T/p-bil")
le "$rb" "$(awk -v a="$rl" 'BEGIN { print a / 2 }')" && ok "bicubic base nearer the true part than bilinear (rms $rb vs $rl mm)" ||
    no "bicubic base rms $rb mm, bilinear $rl"
expect 0 "bicubic with the paper's derivative scaling" "$CF" base --points "$T/points.xyz" --curves "$T/curves.igs" \
    --method bicubic --scale --out "$T/b-scaled.igs"
"$CF" project "$T/b-scaled.igs" "$T/check.xyz" >"$T/p-sc"
rs=$(rmsd "$T/p-sc")
le "$rs" "$rl" && ok "scaled bicubic base still nearer than bilinear (rms $rs)" || no "scaled bicubic rms $rs, bilinear $rl"
expect 0 "tensor-product base (30 % subset, 40 x 30)" "$CF" base --points "$T/points.xyz" --curves "$T/curves.igs" \
    --method tensor --subset 30 --nu 40 --nv 30 --degree 3 --out "$T/b-tensor.igs" --json
expect 0 "plane base (40 x 30)" "$CF" base --points "$T/points.xyz" --nu 40 --nv 30 --out "$T/b-plane.igs" --json
cp "$T/out" "$T/plane.json"
nz=$(json "$T/plane.json" nz)
le 0.9999 "$nz" && ok "plane normal along z for a panel measured from above (nz $nz)" || no "plane normal nz = $nz"

# The tensor base follows the real part, so the true points are nearer to
# it than to the bilinear one (which is the nominal).
"$CF" project "$T/b-tensor.igs" "$T/check.xyz" >"$T/p-ten"
et=$(awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$T/p-ten")
le "$et" "$(awk -v a="$en" 'BEGIN { print a / 4 }')" && ok "tensor base within $et mm of the true part (bilinear: $en)" ||
    no "tensor base $et mm from the true part, bilinear $en"

# A fit through each base (parameters by projection onto it) recovers the
# true part to the noise.
for m in plane bilinear bicubic tensor; do
    expect 0 "fit through the $m base" "$CF" fit --base "$T/b-$m.igs" --points "$T/points.xyz" --out "$T/f-$m.igs" --json
    r=$(json "$T/out" rms)
    "$CF" project "$T/f-$m.igs" "$T/check.xyz" >"$T/p-$m"
    e=$(awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$T/p-$m")
    le "$e" 0.01 && ok "fit through the $m base within 0.01 mm of the true part (max $e, rms residual $r)" ||
        no "fit through the $m base misses the true part by $e mm"
done

# Refusals: exit 2, one line naming what is wrong.
expect 2 "curves that do not meet (--de 1,3,5,5)" "$CF" base --curves "$T/curves.igs" --de 1,3,5,5 --out "$T/x.igs"
oneline "corners"
grep -q "do not meet at corner" "$T/err" && ok "message names the corner" || no "corner message: $(cat "$T/err")"
[ ! -e "$T/x.igs" ] && ok "nothing written on refusal" || no "x.igs written"
expect 2 "a surface is not a curve (--de on a 128)" "$CF" base --curves "$T/nominal.igs" --out "$T/x.igs"
oneline "no curves"
expect 2 "--de needs four DE numbers" "$CF" base --curves "$T/curves.igs" --de 1,3,5 --out "$T/x.igs"
expect 2 "bicubic without curves or points" "$CF" base --method bicubic --out "$T/x.igs"
expect 2 "plane without points" "$CF" base --out "$T/x.igs"
expect 2 "unknown method" "$CF" base --points "$T/points.xyz" --method spline --out "$T/x.igs"
expect 2 "missing curves file" "$CF" base --curves "$T/none.igs" --out "$T/x.igs"
oneline "missing file"
printf '0 0 0\n1 1 1\n2 2 2\n3 3 3\n' >"$T/line.xyz"
expect 2 "collinear points: no plane" "$CF" base --points "$T/line.xyz" --out "$T/x.igs"
printf '1 2 3\n4 5\n' >"$T/bad.xyz"
expect 2 "malformed points file" "$CF" base --points "$T/bad.xyz" --out "$T/x.igs"
grep -q "bad.xyz:2" "$T/err" && ok "message names file:line" || no "points message: $(cat "$T/err")"
box_check "$T/b-tensor.igs" "tensor base"
echo "base: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
