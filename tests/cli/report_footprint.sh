#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/report_footprint.sh CELLFIT: `cellfit report` counts and marks
# the data footprint (issue 14, honest edges). Points exactly on a nominal
# at known parameters, with a round hole and nothing beyond u = 0.85: the
# report's footprint_cells, footprint_filled, no_data_cells,
# footprint_outline and footprint_share against an independent count over
# the parameters (tests/cli/fpcount.py, from the knots `cellfit info`
# prints); the map hatches the "no data" cells and draws the outline, and
# a part measured all over has neither.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
D=$(dirname "$(realpath "$0")")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-rfp.XXXXXX")
trap 'rm -rf "$T"' EXIT

"$CF" gen --dir "$T" --nu 12 --nv 10 --count 100 >/dev/null
"$CF" info "$T/nominal.igs" >"$T/info"
# uvgen HOLE UMAX: 20,000 random parameters in [0.005, UMAX] x [0.005, 0.995],
# a hole of radius 0.2 round (0.45, 0.5) when HOLE is 1.
uvgen() {
    python3 -c "
import random, sys
random.seed(3)
n = 0
while n < 20000:
    u, v = random.uniform(0.005, $2), random.uniform(0.005, 0.995)
    if $1 and (u - 0.45) ** 2 + (v - 0.5) ** 2 < 0.04:
        continue
    print('%.17g %.17g' % (u, v))
    n += 1
"
}
uvgen 1 0.85 >"$T/hole.uv"
uvgen 0 0.995 >"$T/full.uv"
for c in hole full; do
    "$CF" eval "$T/nominal.igs" "$T/$c.uv" >"$T/$c.xyz"
done

expect 0 "report of a part with a hole and an unmeasured strip" "$CF" report "$T/nominal.igs" "$T/hole.xyz" --tol 0.01 \
    --png "$T/hole.png" --json
cp "$T/out" "$T/hole.json"
set -- $(python3 "$D/fpcount.py" "$T/info" "$T/hole.uv")
cells=$1 filled=$2 empty=$3 outline=$4
got="$(json "$T/hole.json" footprint_cells) $(json "$T/hole.json" footprint_filled) $(json "$T/hole.json" no_data_cells) $(json "$T/hole.json" footprint_outline)"
echo "     independent count: $cells cells, $filled with points, $empty no data, $outline on the outline; report: $got"
[ "$got" = "$cells $filled $empty $outline" ] && ok "footprint counts equal the independent count" ||
    no "report says $got, independent count $cells $filled $empty $outline"
[ "$empty" -gt 0 ] && [ "$outline" -gt 0 ] && ok "the data have no-data cells ($empty) and an outline ($outline)" ||
    no "test data without a hole"
share=$(json "$T/hole.json" footprint_share)
awk -v s="$share" -v f="$filled" -v c="$cells" 'BEGIN { d = s - f / c; exit !(d < 1e-12 && d > -1e-12) }' &&
    ok "footprint_share $share = $filled / $cells" || no "footprint_share $share, want $filled / $cells"
expect 0 "text report" "$CF" report "$T/nominal.igs" "$T/hole.xyz" --tol 0.01
grep -q "footprint: $filled of $cells cells of the surface with points (.*), $empty no data, $outline on its outline" "$T/out" &&
    ok "the text report gives the same counts" || no "text: $(grep footprint "$T/out")"

expect 0 "report of a part measured all over" "$CF" report "$T/nominal.igs" "$T/full.xyz" --tol 0.01 \
    --png "$T/full.png" --json
cp "$T/out" "$T/full.json"
set -- $(python3 "$D/fpcount.py" "$T/info" "$T/full.uv")
[ "$(json "$T/full.json" no_data_cells)" = 0 ] && [ "$3" = 0 ] && [ "$(json "$T/full.json" footprint_share)" = 1 ] &&
    ok "measured all over: no no-data cells, share 1" || no "full: $(cat "$T/full.json" | tr ',' '\n' | grep footprint)"

# The map: the hatch's pixels (0x5A5A5A) and black (the outline besides the
# title, scale bar and tolerance lines every map has).
set -- $(python3 "$D/fpcount.py" --png "$T/hole.png")
hh=$1 hb=$2
set -- $(python3 "$D/fpcount.py" --png "$T/full.png")
fh=$1 fb=$2
echo "     map pixels: hatch $hh with the hole, $fh without; black $hb with, $fb without"
[ "$fh" -eq 0 ] && ok "no hatch on a part measured all over" || no "$fh hatch pixels without a hole"
[ "$hh" -gt 2000 ] && ok "the hole's no-data cells hatched ($hh pixels)" || no "hatch pixels $hh"
[ "$hb" -gt $((fb + 400)) ] && ok "the footprint's outline drawn ($((hb - fb)) more black pixels)" ||
    no "outline: black $hb with the hole, $fb without"
echo "report_footprint: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
