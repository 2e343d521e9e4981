#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/trim.sh CELLFIT: trimmed faces in and out, against OpenCASCADE.
# OCCT makes the nominal (tests/occt/occt_trim make: a bicubic B-spline face
# cut by a circle, with a quadrilateral hole, written as IGES 144/142/102/
# 126). Points sampled from it (`cellfit eval` at random u v) with a bump
# added are fitted to a tolerance (knots inserted) by `cellfit fit --base
# nominal.igs`, written as IGES and as STEP; OCCT reads each as one valid
# face whose boundaries in (u, v) equal the nominal's (edge count, length,
# box and samples to 1e-9) and whose surface equals `cellfit eval` of the
# fit at 500 random (u, v) to 1e-9 mm (tests/cli/trim_check.py). `cellfit
# convert` keeps the trim: IGES read and written again is the same file, and
# our STEP reads back to the same trim as our IGES. OCCT's STEP of the
# nominal (ADVANCED_FACE bounds with PCURVEs) as the base keeps its bounds.
# `cellfit serve` (on 127.0.0.1, port 0, stopped by PID) exports the fit of
# the trimmed nominal as the same trimmed face, IGES and STEP.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup trim
if ! sh tests/occt/build.sh "$T/occt" >"$T/occt.log" 2>&1; then
    if [ "${CI:-}" = true ]; then no "OpenCASCADE check could not be built: $(tail -2 "$T/occt.log")"; else
        echo "skip OpenCASCADE trim check: $(tail -1 "$T/occt.log")"; fi
    echo "trim: $pass passed, $fail failed"
    [ "$fail" -eq 0 ]
    exit
fi
OT="$T/occt/occt_trim"
if "$OT" make "$T/nominal.igs" "$T/nominal.stp" 2>"$T/make.err" && [ -s "$T/nominal.igs" ]; then
    ok "OCCT writes the trimmed nominal"
else
    no "occt_trim make: $(tail -2 "$T/make.err")"
fi
# Points: 4000 random (u, v) over the whole domain, a 0.2 mm bump at (50, 40).
python3 -c "
import random
random.seed(17)
for i in range(4000): print('%.17g %.17g' % (random.random(), random.random()))" >"$T/pts.uv"
python3 -c "
import random
random.seed(71)
for i in range(500): print('%.17g %.17g' % (random.random(), random.random()))" >"$T/check.uv"
"$CF" eval "$T/nominal.igs" "$T/pts.uv" >"$T/nom.xyz"
awk '{ dx = $1 - 50; dy = $2 - 40; printf "%.17g %.17g %.17g\n", $1, $2, $3 + 0.2 * exp(-(dx * dx + dy * dy) / 300) }' \
    "$T/nom.xyz" >"$T/pts.xyz"
for ext in igs stp; do
    if "$CF" fit --base "$T/nominal.igs" --points "$T/pts.xyz" --out "$T/fit.$ext" --tol 0.005 \
        --within 99 >"$T/fit.$ext.out" 2>&1; then
        grep -q "trimmed face: 2 boundaries kept" "$T/fit.$ext.out" &&
            ok "fit -> .$ext: $(grep 'trimmed face' "$T/fit.$ext.out" | sed 's/^ *//')" ||
            no "fit -> .$ext: no trim said: $(tail -3 "$T/fit.$ext.out")"
    else
        no "fit -> .$ext: $(tail -3 "$T/fit.$ext.out")"
    fi
done
# The fit refined the net (so the test is not of the nominal itself) and
# kept the domain the trim curves live in.
"$CF" info "$T/nominal.igs" >"$T/nom.info"
"$CF" info "$T/fit.igs" >"$T/fit.info"
[ "$(grep '^domain' "$T/nom.info")" = "$(grep '^domain' "$T/fit.info")" ] &&
    ! grep -q "net 6 x 6" "$T/fit.info" &&
    ok "the fit: $(grep -o 'net [0-9]* x [0-9]*' "$T/fit.info"), the nominal's domain" ||
    no "fit info: $(head -2 "$T/fit.info")"
"$OT" read "$T/nominal.igs" <"$T/check.uv" >"$T/nominal.occt" 2>"$T/read.err" ||
    no "OCCT cannot read the nominal: $(tail -2 "$T/read.err")"
for ext in igs stp; do
    "$OT" read "$T/fit.$ext" <"$T/check.uv" >"$T/fit.$ext.occt" 2>"$T/read.err" ||
        no "OCCT cannot read fit.$ext: $(tail -2 "$T/read.err")"
    "$CF" eval "$T/fit.$ext" "$T/check.uv" >"$T/fit.$ext.eval"
    python3 "$HERE/trim_check.py" "$T/nominal.occt" "$T/fit.$ext.occt" "$T/fit.$ext.eval" \
        "fit.$ext" >"$T/check.out" 2>&1 || echo "FAIL trim_check.py: $(tail -2 "$T/check.out")" >>"$T/check.out"
    while read -r st rest; do
        if [ "$st" = ok ]; then ok "$rest"; else no "$rest"; fi
    done <"$T/check.out"
done
# Our reader keeps the trim bit for bit: OCCT's file converted, then ours
# converted again, give the same bytes (the 3-D edges are made again from
# the same curves on the same surface).
export SOURCE_DATE_EPOCH=1700000000
mkdir -p "$T/a" "$T/b" # one base name: the file's name is in its header
if "$CF" convert "$T/nominal.igs" "$T/a/x.igs" 2>"$T/err" && "$CF" convert "$T/a/x.igs" "$T/b/x.igs" 2>>"$T/err"; then
    cmp -s "$T/a/x.igs" "$T/b/x.igs" && grep -q "^     144 .*D " "$T/b/x.igs" &&
        ok "convert: IGES 144 read and written again, the same file" || no "convert: a.igs and b.igs differ"
else
    no "convert: $(tail -2 "$T/err")"
fi
"$OT" read "$T/a/x.igs" <"$T/check.uv" >"$T/a.occt" 2>/dev/null
"$CF" eval "$T/a/x.igs" "$T/check.uv" >"$T/a.eval"
python3 "$HERE/trim_check.py" "$T/nominal.occt" "$T/a.occt" "$T/a.eval" "convert nominal.igs" >"$T/check.out" 2>&1
while read -r st rest; do
    if [ "$st" = ok ]; then ok "$rest"; else no "$rest"; fi
done <"$T/check.out"
# STEP in: OCCT's own STEP of the nominal (its ADVANCED_FACE's bounds, PCURVEs
# on the B-spline surface) as the base; the fit written as IGES keeps them:
# OCCT sees the boundaries it wrote.
"$OT" read "$T/nominal.stp" <"$T/check.uv" >"$T/nominal.stp.occt" 2>/dev/null ||
    no "OCCT cannot read its nominal.stp"
if "$CF" fit --base "$T/nominal.stp" --points "$T/pts.xyz" --out "$T/fits.igs" --tol 0.005 \
    --within 99 >"$T/fits.out" 2>&1 && grep -q "trimmed face: 2 boundaries kept" "$T/fits.out"; then
    ok "fit --base nominal.stp -> .igs: the STEP face's 2 bounds kept"
else
    no "fit --base nominal.stp: $(tail -3 "$T/fits.out")"
fi
"$OT" read "$T/fits.igs" <"$T/check.uv" >"$T/fits.occt" 2>/dev/null
"$CF" eval "$T/fits.igs" "$T/check.uv" >"$T/fits.eval"
python3 "$HERE/trim_check.py" "$T/nominal.stp.occt" "$T/fits.occt" "$T/fits.eval" "fit of nominal.stp" >"$T/check.out" 2>&1
while read -r st rest; do
    if [ "$st" = ok ]; then ok "$rest"; else no "$rest"; fi
done <"$T/check.out"
# Our STEP reader keeps our STEP's trim bit for bit: fit.stp and fit.igs
# (one fit, two formats) converted to IGES give the same bytes.
mkdir -p "$T/c" "$T/d"
if "$CF" convert "$T/fit.stp" "$T/c/x.igs" 2>"$T/err" && "$CF" convert "$T/fit.igs" "$T/d/x.igs" 2>>"$T/err"; then
    cmp -s "$T/c/x.igs" "$T/d/x.igs" && ok "convert: fit.stp's trim and surface read back as fit.igs's, bit for bit" ||
        no "convert: fit.stp and fit.igs read back differently"
else
    no "convert fit.stp: $(tail -2 "$T/err")"
fi
# The cell: serve with the trimmed nominal, FIT and EXPORT from a Modbus
# client (pymodbus); the exported fitted.igs and fitted.stp are the same
# trimmed face for OCCT.
mkdir -p "$T/results"
serve_start cell --nominal "$T/nominal.igs" --points "$T/pts.xyz" --results "$T/results"
"$PY" - "$port" "$T/results" "$HERE" >"$T/cell.out" 2>&1 <<'PYEOF'
import glob, sys
sys.path.insert(0, sys.argv[3])
from plc_cycle import Cell, PART, FIT, EXPORT, ERROR
c = Cell(int(sys.argv[1]))
c.write(PART, c.words(17) + [1, 0] + c.fwords(0.01))
for cmd in (FIT, EXPORT):
    c.command(cmd)
    s = c.wait_done(c.seq)
    if s["status"] & ERROR:
        sys.exit("FAIL command %d: status 0x%x" % (cmd, s["status"]))
d = glob.glob(sys.argv[2] + "/17_*")
print(d[0] if len(d) == 1 else "FAIL %d folders" % len(d))
PYEOF
d=$(tail -1 "$T/cell.out")
if [ -f "$d/fitted.igs" ] && [ -f "$d/fitted.stp" ]; then
    ok "serve: FIT and EXPORT of the trimmed nominal"
    for f in fitted.igs fitted.stp; do
        "$OT" read "$d/$f" <"$T/check.uv" >"$T/cell.occt" 2>/dev/null
        "$CF" eval "$d/$f" "$T/check.uv" >"$T/cell.eval"
        python3 "$HERE/trim_check.py" "$T/nominal.occt" "$T/cell.occt" "$T/cell.eval" "serve's $f" >"$T/check.out" 2>&1
        while read -r st rest; do
            if [ "$st" = ok ]; then ok "$rest"; else no "$rest"; fi
        done <"$T/check.out"
    done
else
    no "serve: $(tail -3 "$T/cell.out"; tail -3 "$T/cell.log")"
fi
stop_servers
grep -q "Sanitizer\|runtime error" "$T/cell.log" && no "serve: a sanitizer report: $(grep -m1 "Sanitizer\|runtime error" "$T/cell.log")" ||
    ok "serve: no sanitizer report in its log"
echo "trim: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
