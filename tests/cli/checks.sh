#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/checks.sh CELLFIT: `cellfit report --checks`: named check points
# and zones, their deviations in the DFQ after the five figures and in
# --json, checked by a brute-force Python computation over the same
# report's deviations.csv (checks_check.py); a zone without a point is a
# value not measured with a warning; a malformed file is refused. Prints
# "checks: N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HERE=$(dirname "$0")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-checks.XXXXXX")
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM

"$CF" gen --dir "$T" --count 5000 --noise 0.01 >/dev/null || no "gen"
# Checks near measured points (rows 1234 and 2500 of the points, u v x y z),
# a zone around row 4000 and one far away from every point.
awk 'NR == 1235 { printf "P1 %.6f %.6f %.6f\n", $3 + 0.3, $4 - 0.2, $5 + 0.1 }
     NR == 2501 { printf "Z1 %.6f %.6f %.6f 6.5  # a zone\n", $3, $4, $5 }
     NR == 4001 { printf "# a comment line\nZ2 %.6f %.6f %.6f 3.1\n", $3 + 1, $4, $5 }' \
    "$T/points.uvxyz" >"$T/checks.txt"
echo "far 5000 5000 0 1" >>"$T/checks.txt"
expect 0 "report --dfq --checks --csv --json" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" \
    --tol 0.05 --dfq "$T/r.dfq" --csv "$T/d.csv" --checks "$T/checks.txt" --json
cp "$T/out" "$T/report.json"
grep -q "warning: check far: no point within 1 mm" "$T/err" && ok "warning for the empty zone" ||
    no "no warning: $(cat "$T/err")"
[ "$(grep -c warning "$T/err")" = 1 ] && ok "one warning only" || no "warnings: $(cat "$T/err")"
python3 "$HERE/checks_check.py" "$T/checks.txt" "$T/d.csv" "$T/r.dfq" "$T/report.json" >"$T/py" 2>&1 ||
    no "checks_check.py: $(tail -3 "$T/py")"
while read -r word rest; do
    case $word in ok) ok "$rest" ;; FAIL) no "$rest" ;; esac
done <"$T/py"
grep -q "^ok .*Z1: dfq" "$T/py" && grep -q "^ok .*P1: dfq" "$T/py" && ok "values checked" ||
    no "values not checked"
expect 0 "report --checks (text)" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 \
    --checks "$T/checks.txt"
grep -q "check Z1: .* mean of [0-9]* points within 6.5 mm" "$T/out" && ok "text names the zone" ||
    no "text: $(grep check "$T/out")"
printf 'A 1 2\n' >"$T/bad1.txt"
expect 2 "a check without Z refused" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 \
    --checks "$T/bad1.txt" --dfq "$T/bad.dfq"
grep -q "bad1.txt:1:" "$T/err" && ok "error names file and line" || no "error: $(cat "$T/err")"
[ ! -e "$T/bad.dfq" ] && ok "no DFQ on refusal" || no "bad.dfq written"
printf '# zones\nA 1 2 3 0\n' >"$T/bad2.txt"
expect 2 "radius 0 refused" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 --checks "$T/bad2.txt"
printf 'A 1 2 3\nA 4 5 6\n' >"$T/bad3.txt"
expect 2 "a name twice refused" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 --checks "$T/bad3.txt"
expect 2 "a missing checks file refused" "$CF" report "$T/nominal.igs" "$T/points.uvxyz" --tol 0.05 \
    --checks "$T/none.txt"
echo "checks: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
