#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/edges.sh CELLFIT: `cellfit base` without --curves (issue 3):
# boundary curves fitted to the points near the edges of their rectangle,
# a bilinear (and bicubic, tensor) Coons base from them, and a fit through
# it checked against the true part; refusals with exit 2 and one line.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-edges.XXXXXX")
trap 'rm -rf "$T"' EXIT
maxabs() { awk '{ d = $3; if (d < 0) d = -d; if (d > m) m = d } END { printf "%.4g", m }' "$1"; }
oneline() { [ "$(wc -l <"$T/err")" -eq 1 ] && ok "$1: one-line error" || no "$1: stderr has $(wc -l <"$T/err") lines"; }

# The part of base.sh: a 40 x 30 bicubic nominal, the real part dented and warped.
"$CF" gen --dir "$T" --nu 40 --nv 30 --count 60000 --noise 0.005 >/dev/null
grep -v '^#' "$T/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"

expect 0 "bilinear base from fitted edges (no --curves)" "$CF" base --points "$T/points.xyz" --method bilinear \
    --nu 40 --nv 30 --out "$T/B.igs" --json
[ "$(json "$T/out" curves)" = fitted ] && [ "$(json "$T/out" nu)" = 40 ] && [ "$(json "$T/out" nv)" = 30 ] &&
    ok "JSON says fitted curves, 40 x 30" || no "JSON: $(cat "$T/out")"
expect 0 "default net (--edge-cp 8)" "$CF" base --points "$T/points.xyz" --method bilinear --out "$T/B8.igs" --json
[ "$(json "$T/out" nu)" = 8 ] && [ "$(json "$T/out" nv)" = 8 ] && ok "net 8 x 8 from 8 control points per edge" || no "JSON: $(cat "$T/out")"

# The base only parameterises: a fit through it must land on the true part
# (check.xyz: true points; column 3 of project is the signed distance).
expect 0 "fit through the fitted-edge base" "$CF" fit --base "$T/B.igs" --points "$T/points.xyz" --out "$T/f.igs" --json
cl=$(json "$T/out" clamped)
[ "$cl" = 0 ] && ok "every point projects inside the base (clamped $cl)" || no "$cl points clamped to the base's boundary"
"$CF" project "$T/f.igs" "$T/check.xyz" >"$T/p-f"
e=$(maxabs "$T/p-f")
le "$e" 0.01 && ok "fit through the fitted-edge base within 0.01 mm of the true part (max $e)" ||
    no "fit through the fitted-edge base misses the true part by $e mm"
# The edges follow the part: the true points are nearer the base than to the
# points' plane (the base of the plane method).
"$CF" base --points "$T/points.xyz" --nu 40 --nv 30 --out "$T/P.igs" >/dev/null
"$CF" project "$T/B.igs" "$T/check.xyz" >"$T/p-b"
"$CF" project "$T/P.igs" "$T/check.xyz" >"$T/p-p"
eb=$(maxabs "$T/p-b")
ep=$(maxabs "$T/p-p")
le "$eb" "$(awk -v a="$ep" 'BEGIN { print a / 2 }')" && ok "fitted-edge base nearer the part than the plane ($eb vs $ep mm)" ||
    no "fitted-edge base $eb mm from the part, plane $ep"

for m in bicubic tensor; do
    expect 0 "$m base from fitted edges" "$CF" base --points "$T/points.xyz" --method $m --nu 40 --nv 30 --out "$T/B-$m.igs"
    "$CF" fit --base "$T/B-$m.igs" --points "$T/points.xyz" --out "$T/f-$m.igs" >/dev/null
    "$CF" project "$T/f-$m.igs" "$T/check.xyz" >"$T/p-$m"
    e=$(maxabs "$T/p-$m")
    le "$e" 0.01 && ok "fit through the $m base within 0.01 mm (max $e)" || no "fit through the $m base: $e mm"
done

# Refusals: exit 2, one line.
expect 2 "an edge with fewer points than control points" "$CF" base --points "$T/points.xyz" --method bilinear \
    --edge-band 0.1 --edge-cp 200 --out "$T/x.igs"
oneline "too few edge points"
grep -q "edge .* has [0-9]* points within --edge-band" "$T/err" && ok "message names the edge and the count" || no "message: $(cat "$T/err")"
[ ! -e "$T/x.igs" ] && ok "nothing written on refusal" || no "x.igs written"
expect 2 "--edge-cp below 4" "$CF" base --points "$T/points.xyz" --method bilinear --edge-cp 3 --out "$T/x.igs"
expect 2 "--edge-band 0" "$CF" base --points "$T/points.xyz" --method bilinear --edge-band 0 --out "$T/x.igs"
expect 2 "bilinear with neither curves nor points" "$CF" base --method bilinear --out "$T/x.igs"
oneline "nothing to build from"
echo "edges: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
