#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/footprint.sh CELLFIT: honest edges (issue 14). Points on half
# of a part's domain only: where no point lies under a control point's
# support, `cellfit fit` pins it to the nominal (cf_edges), so the fitted
# surface there IS the nominal (checked against `cellfit eval` of the
# nominal itself), while `--free-edges` (the old behaviour) extrapolates;
# over the data both fits agree within the noise. The loop (--tol) pins to
# the nominal refined into each round's knots, not to the previous round.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-footprint.XXXXXX")
trap 'rm -rf "$T"' EXIT
# maxdev A B: largest distance between the x y z lines of A and B
maxdev() { paste "$1" "$2" | awk '{ d = sqrt(($1-$4)^2 + ($2-$5)^2 + ($3-$6)^2); if (d > m) m = d } END { printf "%.4g", m }'; }
# grid U0 U1 N: (N+1)^2 parameters u in [U0, U1], v in [0, 1]
grid() { awk -v a="$1" -v b="$2" -v n="$3" 'BEGIN { for (i = 0; i <= n; i++) for (k = 0; k <= n; k++) printf "%.17g %.17g\n", a + (b - a) * i / n, k / n }'; }

# A 16 x 16 bicubic nominal (13 uniform spans a side), the real part dented
# and warped, noise 0.002 mm; the points of u < 0.5 kept.
"$CF" gen --dir "$T" --nu 16 --nv 16 --count 20000 --noise 0.002 >/dev/null
grep -v '^#' "$T/points.uvxyz" | awk '$1 < 0.5' >"$T/half.uvxyz"
# Data reach span 6 (u < 0.5 < 7/13); a control point's support is 4 spans,
# so every control point of the spans from 10/13 = 0.77 on holds no point.
grid 0.8 1 40 >"$T/out.uv"
grid 0 0.45 40 >"$T/in.uv"
"$CF" eval "$T/nominal.igs" "$T/out.uv" >"$T/nom-out"

expect 0 "fit of half the domain (pinned edges)" "$CF" fit --base "$T/nominal.igs" --points "$T/half.uvxyz" --uv \
    --out "$T/pin.igs" --json
np=$(json "$T/out" pinned_cp)
# Control points with support in spans >= 7 (index >= 10 of 16): 6 columns.
[ "$np" = 96 ] && ok "96 control points without data pinned (6 columns of 16)" || no "pinned_cp $np, want 96"
expect 0 "the same with --free-edges" "$CF" fit --base "$T/nominal.igs" --points "$T/half.uvxyz" --uv \
    --out "$T/free.igs" --free-edges --json
[ "$(json "$T/out" pinned_cp)" = 0 ] && ok "--free-edges pins nothing" || no "--free-edges: $(cat "$T/out")"
"$CF" eval "$T/pin.igs" "$T/out.uv" >"$T/pin-out"
"$CF" eval "$T/free.igs" "$T/out.uv" >"$T/free-out"
ep=$(maxdev "$T/pin-out" "$T/nom-out")
ef=$(maxdev "$T/free-out" "$T/nom-out")
echo "     outside the footprint (u >= 0.8): max distance to the nominal $ef mm before (free), $ep mm after (pinned)"
le "$ep" 0.001 && ok "outside the footprint the fit is the nominal within 0.001 mm ($ep)" ||
    no "outside the footprint the fit is $ep mm from the nominal"
le 0.05 "$ef" && ok "without pins it extrapolates there ($ef mm off the nominal)" ||
    no "the free fit stays at the nominal ($ef): the test does not exercise the edge"
"$CF" eval "$T/pin.igs" "$T/in.uv" >"$T/pin-in"
"$CF" eval "$T/free.igs" "$T/in.uv" >"$T/free-in"
ei=$(maxdev "$T/pin-in" "$T/free-in")
le "$ei" 0.002 && ok "over the data (u <= 0.45) pinned and free fits agree within the noise sigma ($ei mm)" ||
    no "over the data the pins move the fit by $ei mm"
# Against the true part over the data: the pins do not spoil the fit.
awk '$1 <= 0.45' "$T/check.uv" >"$T/chk.uv"
paste -d' ' "$T/check.uv" "$T/check.xyz" | awk '$1 <= 0.45 { print $3, $4, $5 }' >"$T/chk.xyz"
"$CF" eval "$T/pin.igs" "$T/chk.uv" >"$T/pin-chk"
et=$(maxdev "$T/pin-chk" "$T/chk.xyz")
le "$et" 0.006 && ok "pinned fit within 3 sigma of the true part over the data ($et mm)" || no "pinned fit $et mm off the true part"

# The loop from a 4 x 4 nominal (one span: round 0 has data under every
# control point and extrapolates). --refine uniform halves the empty spans
# too, so later rounds have control points without data that round 0 had
# put off the nominal: they must follow the nominal refined into their
# knots, not P0 (the previous round's fit; pinned there the edge stays
# 1.7 mm off).
mkdir "$T/b"
"$CF" gen --dir "$T/b" --nu 4 --nv 4 --count 20000 --noise 0.002 --bump 0.5,30,50,8 >/dev/null
grep -v '^#' "$T/b/points.uvxyz" | awk '$1 < 0.5 { print $3, $4, $5 }' >"$T/b/half.xyz"
grid 1 1 40 | sort -u >"$T/b/edge.uv"
"$CF" eval "$T/b/nominal.igs" "$T/b/edge.uv" >"$T/b/nom"
expect 0 "loop on half the domain, pinned" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/half.xyz" --tol 0.01 --within 99 \
    --refine uniform --out "$T/b/pin.igs" --json
r=$(grep -o '"round":' "$T/out" | wc -l)
[ "$r" -ge 3 ] && ok "the loop ran $r rounds" || no "the loop ran $r rounds"
lp=$(json "$T/out" pinned_cp)
[ "${lp:-0}" -gt 0 ] && ok "the last round pinned $lp control points" || no "pinned_cp ${lp:-none}"
expect 0 "loop on half the domain, --free-edges" "$CF" fit --base "$T/b/nominal.igs" --points "$T/b/half.xyz" --tol 0.01 \
    --within 99 --refine uniform --out "$T/b/free.igs" --free-edges
"$CF" eval "$T/b/pin.igs" "$T/b/edge.uv" >"$T/b/pin"
"$CF" eval "$T/b/free.igs" "$T/b/edge.uv" >"$T/b/free"
ep=$(maxdev "$T/b/pin" "$T/b/nom")
ef=$(maxdev "$T/b/free" "$T/b/nom")
echo "     loop, edge u = 1: max distance to the nominal $ef mm before (free), $ep mm after (pinned)"
le "$ep" 0.001 && ok "loop: the far edge is the nominal within 0.001 mm ($ep)" || no "loop: far edge $ep mm off the nominal"
le 0.05 "$ef" && ok "loop without pins: the far edge extrapolated ($ef mm)" || no "loop without pins: far edge $ef"
echo "footprint: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
