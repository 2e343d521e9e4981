#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/badinput.sh CELLFIT: bad input is refused, never crashes, hangs
# or gives a wrong surface (issue 7): exit 2, exactly one line on stderr
# naming the file, the line or record where there is one, and what is
# wrong, and no output file left behind (neither --out nor a .tmp beside
# it). Covers point files, IGES surfaces and option values for fit, eval,
# info, report and base, and serve's configuration file.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-bad.XXXXXX")
trap 'rm -rf "$T"' EXIT
OUT="$T/out/result.igs"
mkdir -p "$T/out"
# bad NAME PATTERN CMD...: exit 2, one stderr line matching the extended
# regular expression PATTERN, nothing written to $T/out (run under timeout:
# a hang is a failure too).
bad() {
    name=$1; pat=$2; shift 2
    timeout 60 "$@" >"$T/stdout" 2>"$T/err"
    got=$?
    lines=$(wc -l <"$T/err")
    left=$(ls -A "$T/out")
    if [ "$got" -ne 2 ]; then
        no "$name: exit $got, want 2"; sed 's/^/     /' "$T/err" | head -3
    elif [ "$lines" -ne 1 ]; then
        no "$name: $lines lines on stderr, want 1"; sed 's/^/     /' "$T/err" | head -3
    elif ! grep -qE -- "$pat" "$T/err"; then
        no "$name: message does not match '$pat'"; sed 's/^/     /' "$T/err"
    elif [ -n "$left" ]; then
        no "$name: left $left behind"
    else
        ok "$name: $(cut -c1-150 "$T/err")"
    fi
    rm -rf "$T/out"; mkdir -p "$T/out"
}

# A valid part: the nominal (6 x 4, degree 3) and points on it.
"$CF" gen --dir "$T" --nu 6 --nv 4 --count 400 --noise 0.001 >/dev/null ||
    { echo "badinput: cellfit gen failed"; exit 1; }
N="$T/nominal.igs"
grep -v '^#' "$T/points.uvxyz" >"$T/good.uvxyz"
cut -d' ' -f3- "$T/good.uvxyz" >"$T/good.xyz"
# fitx NAME PATTERN BASE POINTS [OPTIONS]: cellfit fit with --out in $T/out.
fitx() {
    n=$1; p=$2; b=$3; q=$4; shift 4
    bad "$n" "$p" "$CF" fit --base "$b" --points "$q" --out "$OUT" "$@"
}
# The good inputs fit (so the refusals below are about the one thing changed).
"$CF" fit --base "$N" --points "$T/good.xyz" --out "$T/good.igs" >/dev/null 2>&1 &&
    ok "the unchanged inputs fit" || no "the unchanged inputs do not fit"

# --- point files
P="$T/pts"
mkdir -p "$P"
{ sed -n 1,2p "$T/good.xyz"; echo "1.0 nan 2.0"; sed -n 3,10p "$T/good.xyz"; } >"$P/nan.xyz"
fitx "NaN coordinate" "$P/nan.xyz:3: .*non-finite" "$N" "$P/nan.xyz"
{ sed -n 1p "$T/good.xyz"; echo "1.0 2.0 -inf"; } >"$P/inf.xyz"
fitx "Inf coordinate" "$P/inf.xyz:2: .*non-finite" "$N" "$P/inf.xyz"
{ sed -n 1,4p "$T/good.xyz"; echo "1e999 2 3"; } >"$P/huge.xyz"
fitx "coordinate beyond double range" "$P/huge.xyz:5: .*range" "$N" "$P/huge.xyz"
: >"$P/empty.xyz"
fitx "empty point file" "$P/empty.xyz.*no points" "$N" "$P/empty.xyz"
printf '# only a comment\n\n   \n' >"$P/nopoints.xyz"
fitx "point file with no points" "$P/nopoints.xyz.*no points" "$N" "$P/nopoints.xyz"
{ sed -n 1,6p "$T/good.xyz"; echo "1.0 2.0"; } >"$P/cols.xyz"
fitx "wrong column count" "$P/cols.xyz:7: 2 values, expected 3" "$N" "$P/cols.xyz"
{ sed -n 1,3p "$T/good.uvxyz"; echo "0.5 0.5 1 2 3 4"; } >"$P/cols.uvxyz"
fitx "wrong column count (--uv)" "$P/cols.uvxyz:4: 6 values, expected 5" "$N" "$P/cols.uvxyz" --uv
printf 'hello world\n' >"$P/junk.xyz"
fitx "junk text" "$P/junk.xyz:1: 'hello' is not a number" "$N" "$P/junk.xyz"
{ sed -n 1,2p "$T/good.xyz"; printf '1 2 3\001\377\000\n'; } >"$P/binary.xyz"
fitx "binary data" "$P/binary.xyz:3: .*binary" "$N" "$P/binary.xyz"
printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' >"$P/short.ply"
fitx "PLY with fewer vertices than its header" "$P/short.ply:.*file ends after 1 of 5" "$N" "$P/short.ply"
printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 nan 3\n' >"$P/nan.ply"
fitx "PLY NaN coordinate" "$P/nan.ply:8: .*non-finite" "$N" "$P/nan.ply"
printf 'ply\nformat binary_little_endian 1.0\nelement junk 1000000000000\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n' >"$P/empty-elements.ply"
fitx "PLY with 10^12 empty elements (no hang)" "$P/empty-elements.ply: file ends after 0 of 1 vertices" \
    "$N" "$P/empty-elements.ply"
fitx "missing point file" "$T/nonexistent.xyz.*cannot open" "$N" "$T/nonexistent.xyz"
# --uv parameters outside the knot domain [0, 1]^2.
{ sed -n 1,4p "$T/good.uvxyz"; echo "1.5 0.5 10 20 3"; } >"$P/domain.uvxyz"
fitx "--uv parameters outside the knot domain" "$P/domain.uvxyz:5: parameters .*outside the knot domain" \
    "$N" "$P/domain.uvxyz" --uv
# Data on a corner only, no smoothing: the system cannot be determined.
awk '$1 < 0.3 && $2 < 0.3' "$T/good.uvxyz" >"$P/corner.uvxyz"
fitx "points that do not determine the surface" "$P/corner.uvxyz.*(no data|do not determine)" \
    "$N" "$P/corner.uvxyz" --uv --alpha 0 --beta 0

# --- IGES surfaces (the nominal edited in place, columns kept)
G="$T/iges"
mkdir -p "$G"
head -n 12 "$N" >"$G/truncated.igs"
fitx "truncated IGES" "$G/truncated.igs: line 12: .*(Terminate|truncated)" "$G/truncated.igs" "$T/good.xyz"
sed '/P      3$/s/^1\.0,/1.x,/' "$N" >"$G/garbled.igs"
fitx "garbled IGES number" "$G/garbled.igs: line 12 \(P record 3.*'1.x' is garbled" "$G/garbled.igs" \
    "$T/good.xyz"
sed '/D      2$/s/^     128/     126/' "$N" >"$G/dtype.igs"
fitx "garbled IGES directory" "$G/dtype.igs: line 9 .*entity type" "$G/dtype.igs" "$T/good.xyz"
sed '12d' "$N" >"$G/gap.igs"
fitx "IGES with a line missing" "$G/gap.igs: line 12: P sequence number 4, expected 3" "$G/gap.igs" \
    "$T/good.xyz"
head -c 3000 /dev/zero | tr '\0' '\001' >"$G/binary.igs"
fitx "binary junk as IGES" "$G/binary.igs: line 1: binary" "$G/binary.igs" "$T/good.xyz"
: >"$G/empty.igs"
fitx "empty IGES" "$G/empty.igs: line 1: empty" "$G/empty.igs" "$T/good.xyz"
# The 6 x 4 cubic's P records: 128,5,3,3,3,... then u knots
# 0,0,0,0,1/3,2/3,1,1,1,1 and v knots, weights, points.
hdr=$(sed -n '/P      1$/s/^\(128,[0-9]*,[0-9]*,[0-9]*,[0-9]*\),.*/\1/p' "$N")
[ "$hdr" = "128,5,3,3,3" ] && ok "nominal header is $hdr" || no "nominal header '$hdr'"
sed '/P      1$/s/^128,5,3,3,3,/128,5,3,9,3,/' "$N" >"$G/degree.igs"
fitx "degree above the board's maximum" "$G/degree.igs: line 10 \(P record 1.*degree.*takes 1 to" \
    "$G/degree.igs" "$T/good.xyz"
sed '/P      1$/s/^128,5,3,3,3,/128,9,3,3,3,/' "$N" >"$G/fewknots.igs"
fitx "too few knots for the counts" "$G/fewknots.igs: line 10 \(P record 1.*(truncated|wrong counts)" \
    "$G/fewknots.igs" "$T/good.xyz"
sed '/P      1$/s/0\.33333333333333331/0.93333333333333331/' "$N" >"$G/knots.igs"
fitx "knots that decrease" "$G/knots.igs: line 11 \(P record 2.*knot vector decreases" "$G/knots.igs" \
    "$T/good.xyz"
wl=$(grep -n 'P      [0-9]*$' "$N" | sed -n 's/^\([0-9]*\):.*1\.0,1\.0,1\.0,1\.0,1\.0,.*/\1/p' | head -1)
sed "${wl}s/1\.0,1\.0,1\.0,1\.0,1\.0,/1.0,1.0,1.0,0.0,1.0,/" "$N" >"$G/zeroweight.igs"
fitx "zero weight" "$G/zeroweight.igs: line [0-9]+ \(P record .*weight W.*not positive" \
    "$G/zeroweight.igs" "$T/good.xyz"
sed "${wl}s/1\.0,1\.0,1\.0,1\.0,1\.0,/1.0,1.0,1.0,-1.,1.0,/" "$N" >"$G/negweight.igs"
fitx "negative weight" "$G/negweight.igs: line [0-9]+ \(P record .*weight W.*not positive" \
    "$G/negweight.igs" "$T/good.xyz"
fitx "missing IGES" "$T/none.igs: cannot open" "$T/none.igs" "$T/good.xyz"

# --- a net over the board's budget
bad "base: net over the board's control-point budget" "3000 x 3000 exceeds" \
    "$CF" base --points "$T/good.xyz" --nu 3000 --nv 3000 --degree 3 --out "$OUT"

# --- option values
fitx "--alpha not a number" "--alpha 'x'" "$N" "$T/good.xyz" --alpha x
fitx "--beta negative" "--beta '-1'" "$N" "$T/good.xyz" --beta -1
fitx "--solver unknown" "--solver 'fast'" "$N" "$T/good.xyz" --solver fast
fitx "--max-iter zero" "--max-iter '0'" "$N" "$T/good.xyz" --max-iter 0
fitx "--entity not a DE number" "--entity 'two'" "$N" "$T/good.xyz" --entity two
fitx "--entity not in the file" "$N: .*(Directory Entry|DE) 7" "$N" "$T/good.xyz" --entity 7
fitx "--reparam with --uv" "--reparam" "$N" "$T/good.uvxyz" --uv --reparam 2
bad "base --degree 9" "--degree '9'" "$CF" base --points "$T/good.xyz" --degree 9 --out "$OUT"
bad "base --method unknown" "--method" "$CF" base --points "$T/good.xyz" --method cubic --out "$OUT"
bad "base: empty point file" "$P/empty.xyz" "$CF" base --points "$P/empty.xyz" --out "$OUT"
bad "base: NaN coordinate" "$P/nan.xyz:3: .*non-finite" "$CF" base --points "$P/nan.xyz" --out "$OUT"

# --- the other readers of the same files
printf '0.5 0.5\n0.5 nan\n' >"$P/nan.uv"
bad "eval: NaN parameter" "$P/nan.uv:2: .*non-finite" "$CF" eval "$N" "$P/nan.uv"
printf '0.5 0.5\n2.0 0.5\n' >"$P/out.uv"
bad "eval: parameter outside the domain" "$P/out.uv:2: .*(outside|domain)" "$CF" eval "$N" "$P/out.uv"
bad "eval: truncated IGES" "$G/truncated.igs: line 12" "$CF" eval "$G/truncated.igs" "$P/out.uv"
bad "info: knots that decrease" "$G/knots.igs: line 11 \(P record 2.*decreases" "$CF" info "$G/knots.igs"
bad "info: binary junk" "$G/binary.igs: line 1: binary" "$CF" info "$G/binary.igs"
bad "report: NaN coordinate" "$P/nan.xyz:3: .*non-finite" \
    "$CF" report "$N" "$P/nan.xyz" --tol 0.1 --png "$T/out/map.png"
bad "report: --tol negative" "--tol '-1'" "$CF" report "$N" "$T/good.xyz" --tol -1
bad "report: zero weight" "$G/zeroweight.igs: line [0-9]+ .*weight" \
    "$CF" report "$G/zeroweight.igs" "$T/good.xyz" --tol 0.1 --png "$T/out/map.png"

# --- serve's configuration file (--print-map: parse, print, never serve)
S="$T/conf"
mkdir -p "$S"
printf 'plc = tcp:127.0.0.1:0\nwatchdog_ms = -5\n' >"$S/value.conf"
bad "serve config: bad value" "$S/value.conf:2: watchdog_ms '-5'" \
    "$CF" serve --config "$S/value.conf" --print-map
printf '# cell\n\nspeed = 3\n' >"$S/unknown.conf"
bad "serve config: unknown setting" "$S/unknown.conf:3: unknown setting 'speed'" \
    "$CF" serve --config "$S/unknown.conf" --print-map
printf 'plc tcp:127.0.0.1:0\n' >"$S/noeq.conf"
bad "serve config: no '='" "$S/noeq.conf:1: expected key = value" \
    "$CF" serve --config "$S/noeq.conf" --print-map
head -c 5000 /dev/zero | tr '\0' 'x' >"$S/long.conf"
bad "serve config: a 5000-byte line" "$S/long.conf:1: line longer than" \
    "$CF" serve --config "$S/long.conf" --print-map
for i in $(seq 1 33); do echo "results_dir.$((i % 8)) = /data/r$i"; done >"$S/many.conf"
bad "serve config: settings beyond its storage are refused, not dropped" \
    "$S/many.conf:33: results_dir.1: more than 32" "$CF" serve --config "$S/many.conf" --print-map
printf 'plc = tcp:localhost:502\n' >"$S/plc.conf"
bad "serve config: plc not an IPv4 address" "$S/plc.conf:1: plc 'tcp:localhost:502'" \
    "$CF" serve --config "$S/plc.conf" --print-map

echo "badinput: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
