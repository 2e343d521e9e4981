#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/quad.sh CELLFIT: end-to-end checks of the quadrilateral-based
# commands (Piegl & Tiller 2001, Section 3): `cellfit thin` (exit codes,
# one-line errors, JSON, kept points are input points, each once, a finer
# tolerance keeps more) and `cellfit bench project` (JSON fields, accuracy
# against the generator's true parameters).
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-quad.XXXXXX")
trap 'rm -rf "$T"' EXIT
one_line() { [ "$(wc -l <"$T/err")" -eq 1 ] && ok "$1: one-line error" || no "$1: error not one line"; }

expect 0 "gen part" "$CF" gen --dir "$T" --nu 16 --nv 12 --count 20000 --noise 0.002
awk '!/^#/ { print $3, $4, $5 }' "$T/points.uvxyz" >"$T/points.xyz"

expect 0 "thin --quad-tol 0.5%" "$CF" thin "$T/nominal.igs" "$T/points.xyz" --quad-tol 0.5% --out "$T/t1.xyz" --json
cp "$T/out" "$T/t1.json"
for k in points kept quads vertices rel_tol radius seconds; do
    [ -n "$(json "$T/t1.json" $k)" ] || no "thin: JSON field $k"
done
[ "$(json "$T/t1.json" points)" = 20000 ] && ok "thin read 20000 points" || no "thin points"
k1=$(json "$T/t1.json" kept)
[ "$(wc -l <"$T/t1.xyz")" -eq "$k1" ] && ok "thin wrote $k1 points" || no "thin output lines != kept"
le "$k1" "$(json "$T/t1.json" vertices)" && ok "at most one point per vertex" || no "kept > vertices"
# Every kept point is an input point (bit for bit through %.17g), each once.
n_in=$(awk 'NR == FNR { seen[$1 + 0, $2 + 0, $3 + 0] = 1; next }
    (($1 + 0, $2 + 0, $3 + 0) in seen) { n++ } END { print n + 0 }' "$T/points.xyz" "$T/t1.xyz")
[ "$n_in" -eq "$k1" ] && ok "kept points are input points" || no "$((k1 - n_in)) kept points not in the input"
[ "$(sort -u "$T/t1.xyz" | wc -l)" -eq "$k1" ] && ok "kept points distinct" || no "a point kept twice"

expect 0 "thin --quad-tol 0.0005" "$CF" thin "$T/nominal.igs" "$T/points.xyz" --quad-tol 0.0005 --out "$T/t2.xyz" --json
k2=$(json "$T/out" kept)
[ "$k2" -gt "$k1" ] && ok "finer tolerance keeps more ($k1 -> $k2)" || no "finer tolerance kept $k2 <= $k1"

# u v x y z input works too (the last three columns).
expect 0 "thin reads u v x y z" "$CF" thin "$T/nominal.igs" "$T/points.uvxyz" --quad-tol 0.5% --out "$T/t3.xyz"
cmp -s "$T/t1.xyz" "$T/t3.xyz" && ok "same points from x y z and u v x y z" || no "uvxyz differs"

expect 2 "thin: --quad-tol out of range" "$CF" thin "$T/nominal.igs" "$T/points.xyz" --quad-tol 2 --out "$T/x"
one_line "thin --quad-tol"
expect 2 "thin: no --out" "$CF" thin "$T/nominal.igs" "$T/points.xyz" --quad-tol 0.01
one_line "thin usage"
expect 2 "thin: missing points file" "$CF" thin "$T/nominal.igs" "$T/none.xyz" --quad-tol 0.01 --out "$T/x"
one_line "thin missing file"
expect 1 "thin: unwritable output" "$CF" thin "$T/nominal.igs" "$T/points.xyz" --quad-tol 0.01 --out "$T/no/dir/x"
one_line "thin unwritable"

expect 0 "bench project" "$CF" bench project --count 20000 --cp 2500 --json
cp "$T/out" "$T/bp.json"
for k in points control_points quads seconds points_per_s max_param_error slow_points; do
    [ -n "$(json "$T/bp.json" $k)" ] || no "bench project: JSON field $k"
done
e=$(json "$T/bp.json" max_param_error)
le "$e" 1e-9 && ok "bench project: parameters within 1e-9 of the truth ($e)" || no "bench project error $e"
expect 2 "bench project: bad option" "$CF" bench project --bogus 1

echo "quad: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
