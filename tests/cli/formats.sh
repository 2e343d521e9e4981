#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/formats.sh CELLFIT: the formats a plant uses, read by independent
# readers: `cellfit report --csv --ply --dfq` (Python's csv and struct,
# formats_check.py), `cellfit convert` to STEP and back (the surface the
# same to the last bit), report --scale. Prints "formats: N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HERE=$(dirname "$0")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-formats.XXXXXX")
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM

"$CF" gen --dir "$T" --count 5000 --noise 0.01 >/dev/null || no "gen"
expect 0 "report --csv --ply --dfq --png" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 \
    --csv "$T/d.csv" --ply "$T/d.ply" --dfq "$T/r.dfq" --png "$T/m.png" --part-number PN-7 --part-id SN42 --json
cp "$T/out" "$T/report.json"
python3 "$HERE/formats_check.py" "$T/report.json" "$T/d.csv" "$T/d.ply" "$T/r.dfq" >"$T/py" 2>&1 ||
    no "formats_check.py: $(tail -3 "$T/py")"
while read -r word rest; do
    case $word in ok) ok "$rest" ;; FAIL) no "$rest" ;; esac
done <"$T/py"
s=$(wc -c <"$T/m.png")
[ "$s" -le 204800 ] && ok "map is $s bytes (<= 200 KB)" || no "map is $s bytes"
expect 0 "report --ply --scale 1 (no map)" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 \
    --ply "$T/s.ply" --scale 1 --json
[ "$(json "$T/out" scale_end)" = 1 ] && ok "fixed scale end 1 mm" || no "scale_end $(json "$T/out" scale_end)"
expect 2 "report --ply from standard input refused" sh -c "\"$CF\" report \"$T/nominal.igs\" - --tol 0.05 --ply \"$T/x.ply\" <\"$T/points.uvxyz\""
[ ! -e "$T/x.ply" ] && ok "nothing written on refusal" || no "x.ply left behind"
# STEP and back: the same surface to the last bit.
expect 0 "convert to STEP" "$CF" convert "$T/nominal.igs" "$T/n.stp"
head -c 300 "$T/n.stp" | grep -q "AP242" && ok "STEP names AP242" || no "no AP242 in the header"
expect 0 "convert back to IGES" "$CF" convert "$T/n.stp" "$T/n2.igs"
"$CF" eval "$T/nominal.igs" "$T/check.uv" >"$T/e1" && "$CF" eval "$T/n2.igs" "$T/check.uv" >"$T/e2" &&
    cmp -s "$T/e1" "$T/e2" && ok "IGES -> STEP -> IGES evaluates bit for bit" || no "round trip differs"
expect 0 "fit writes STEP by extension" "$CF" fit --base "$T/n.stp" --points "$T/points.uvxyz" --uv --out "$T/f.stp"
expect 0 "info reads it" "$CF" info "$T/f.stp" --json
[ "$(json "$T/out" control_points)" = 1200 ] && ok "fitted STEP has the nominal's 1200 control points" ||
    no "info: $(head -c 200 "$T/out")"
echo "formats: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
