#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/binpoints.sh CELLFIT: raw little-endian float64 point files
# (.uvxyz.bin, .xyz.bin; docs/formats.md) through `cellfit fit`: the same
# points as the ASCII file (converted here by Python's float(), which
# rounds correctly like strtod, and struct.pack('<d')) give the same fit
# to the last digit, with and without given parameters; a file that ends
# inside a point or holds a NaN is refused with one line naming the point.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-binpoints.XXXXXX")
trap 'rm -rf "$T"' EXIT
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
"$CF" gen --dir "$T" --nu 12 --nv 9 --count 20000 >/dev/null
grep -v '^#' "$T/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"
# tobin IN OUT: every number of IN (text) as 8 little-endian bytes
tobin() {
    "$PY" -c 'import struct, sys
v = [float(t) for line in open(sys.argv[1]) if not line.startswith("#") for t in line.split()]
open(sys.argv[2], "wb").write(struct.pack("<%dd" % len(v), *v))' "$1" "$2"
}
tobin "$T/points.uvxyz" "$T/p.uvxyz.bin"
tobin "$T/points.xyz" "$T/p.xyz.bin"
[ "$(wc -c <"$T/p.uvxyz.bin")" -eq 800000 ] && ok "20,000 points x 5 x 8 bytes" ||
    no "binary file has $(wc -c <"$T/p.uvxyz.bin") bytes"
# same IN1 IN2 WHAT: the fits' JSON figures and the IGES data (the global
# section, with file name and time, left out) are the same
same() {
    for k in points rms max_abs iterations; do
        a=$(json "$T/$1.json" $k)
        b=$(json "$T/$2.json" $k)
        [ -n "$a" ] && [ "$a" = "$b" ] && ok "$3: $k $a in both" || no "$3: $k '$a' vs '$b'"
    done
    grep -v '^.\{72\}G' "$T/$1.igs" >"$T/a.dat"
    grep -v '^.\{72\}G' "$T/$2.igs" >"$T/b.dat"
    cmp -s "$T/a.dat" "$T/b.dat" && ok "$3: the same fitted surface" || no "$3: surfaces differ"
}
fit() { # fit NAME POINTS [--uv]
    n=$1 p=$2
    shift 2
    expect 0 "fit $(basename "$p") $*" "$CF" fit --base "$T/nominal.igs" --points "$p" "$@" \
        --out "$T/$n.igs" --json
    cp "$T/out" "$T/$n.json"
}
# One reader each: one order of summation (two threads split the text at a
# line start near its middle byte, the raw file at half its points: other
# groupings, the same sums to rounding, checked after).
fit ta "$T/points.uvxyz" --uv --threads 1
fit tb "$T/p.uvxyz.bin" --uv --threads 1
same ta tb "given parameters"
fit t2a "$T/points.uvxyz" --uv --threads 2
fit t2b "$T/p.uvxyz.bin" --uv --threads 2
for n in t2a t2b; do
    [ "$(json "$T/$n.json" threads)" = 2 ] && ok "$n: two threads" || no "$n: threads $(json "$T/$n.json" threads)"
done
for n in t2a t2b; do
    same_surface "$T/ta.igs" "$T/$n.igs" "$T/check.uv" && ok "$n: the one-thread surface" ||
        no "$n: differs from one thread's"
done
fit xa "$T/points.xyz"
fit xb "$T/p.xyz.bin"
same xa xb "projected"
# Refusals: a partial last point, a NaN (point 7).
head -c 799996 "$T/p.uvxyz.bin" >"$T/cut.uvxyz.bin"
expect 2 "a file ending inside a point" "$CF" fit --base "$T/nominal.igs" --points \
    "$T/cut.uvxyz.bin" --uv --out "$T/x.igs"
grep -q "ends inside point 20000" "$T/err" && ok "the message names point 20000" ||
    no "message: $(cat "$T/err")"
"$PY" -c 'import struct, sys
b = bytearray(open(sys.argv[1], "rb").read()); b[6*40+16:6*40+24] = struct.pack("<d", float("nan"))
open(sys.argv[2], "wb").write(b)' "$T/p.uvxyz.bin" "$T/nan.uvxyz.bin"
expect 2 "a NaN" "$CF" fit --base "$T/nominal.igs" --points "$T/nan.uvxyz.bin" --uv --out "$T/x.igs"
grep -q "point 7: non-finite" "$T/err" && ok "the message names point 7" || no "message: $(cat "$T/err")"
echo "binpoints: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
