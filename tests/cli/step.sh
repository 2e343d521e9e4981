#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/step.sh CELLFIT: STEP AP242 against OpenCASCADE. Synthetic parts
# from `cellfit gen` (IGES, degrees 1, 2, 3 and 5), made rational with
# pseudo-random weights, converted to STEP by build/surf-convert (cf_surfio,
# until `cellfit convert` exists); OCCT's STEPControl_Reader must find
# exactly one face with four edges that BRepCheck accepts, and its surface
# must equal the IGES original (evaluated by `cellfit eval`) at random
# parameters and on the check grid to 1e-9 mm. Then STEP back to IGES
# through our reader evaluates identically (bit for bit in the text), and
# the file OCCT's STEPControl_Writer makes of the shape reads (through our
# reader) as the same surface to 1e-9 mm.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
CONV="$(dirname "$CF")/surf-convert"
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-step.XXXXXX")
trap 'rm -rf "$T"' EXIT

if [ ! -x "$CONV" ]; then
    no "$CONV missing (make builds it: mk/step.mk)"
    echo "step: $pass passed, $fail failed"
    exit 1
fi
if ! sh tests/occt/build.sh "$T/occt" >"$T/occt.log" 2>&1; then
    if [ "${CI:-}" = true ]; then no "OpenCASCADE check could not be built: $(tail -2 "$T/occt.log")"; else
        echo "skip OpenCASCADE STEP check: $(tail -1 "$T/occt.log")"; fi
    echo "step: $pass passed, $fail failed"
    [ "$fail" -eq 0 ]
    exit
fi

# maxdiff A B: largest coordinate difference of two "x y z" files, and their
# line counts must match.
maxdiff() {
    paste "$1" "$2" | awk '{ if (NF != 6) bad = 1; for (c = 1; c <= 3; c++) { a = $c - $(c+3); if (a < 0) a = -a; if (a > m) m = a } }
        END { if (bad || NR == 0) print "mismatch"; else printf "%.3g", m }'
}

for deg in 1 2 3 5; do
    D="$T/d$deg"
    mkdir -p "$D"
    "$CF" gen --dir "$D" --nu 14 --nv 11 --degree $deg --count 1000 --seed $deg >/dev/null 2>&1 ||
        { no "gen degree $deg"; continue; }
    # 500 random parameters over the domain (gen's is [0, 1]^2), ends included.
    awk -v s=$deg 'BEGIN { srand(s); print "0 0"; print "1 1"; print "0 1"; print "1 0";
        for (i = 0; i < 496; i++) printf "%.17g %.17g\n", rand(), rand() }' >"$D/rand.uv"
    cat "$D/rand.uv" "$D/check.uv" >"$D/all.uv"
    nuv=$(wc -l <"$D/all.uv")
    "$CONV" "$D/nominal.igs" "$D/plain.igs" && "$CONV" "$D/nominal.igs" "$D/rational.igs" --rational $deg ||
        { no "degree $deg: conversions"; continue; }
    for kind in plain rational; do
        name="degree $deg $kind"
        if ! "$CF" convert "$D/$kind.igs" "$D/$kind.stp"; then
            no "$name: IGES -> STEP"; continue
        fi
        "$CF" eval "$D/$kind.igs" "$D/all.uv" >"$D/$kind.ours" || { no "$name: eval"; continue; }
        "$T/occt/occt_step" --write "$D/$kind.occ.stp" "$D/$kind.stp" <"$D/all.uv" >"$D/$kind.occt" 2>"$D/$kind.err"
        rc=$?
        if [ $rc -ne 0 ]; then
            no "$name: OpenCASCADE (exit $rc): $(tr '\n' ' ' <"$D/$kind.err" | cut -c1-200)"; continue
        fi
        grep -q "1 face(s)" "$D/$kind.err" && grep -q "4 edge(s)" "$D/$kind.err" &&
            grep -q "BRepCheck valid 1" "$D/$kind.err" &&
            ok "$name: OpenCASCADE reads one face, four edges, valid" ||
            no "$name: OpenCASCADE: $(tr '\n' ' ' <"$D/$kind.err")"
        want_rat=0
        [ $kind = rational ] && want_rat=1
        grep -q "degrees $deg $deg, poles 14 x 11, rational $want_rat $want_rat" "$D/$kind.err" &&
            ok "$name: OCCT sees degrees $deg, 14 x 11 poles, rational $want_rat" ||
            no "$name: OCCT's surface: $(grep degrees "$D/$kind.err")"
        d=$(maxdiff "$D/$kind.ours" "$D/$kind.occt")
        n=$(wc -l <"$D/$kind.occt")
        [ "$n" -eq "$nuv" ] && [ "$d" != mismatch ] && le "$d" 1e-9 &&
            ok "$name: OCCT's STEP surface = our IGES surface (max diff $d mm, $n points)" ||
            no "$name: OCCT's STEP surface differs: max diff $d over $n points"
        # Back through our STEP reader: the same numbers to the last digit.
        "$CF" convert "$D/$kind.stp" "$D/$kind.back.igs" && "$CF" eval "$D/$kind.back.igs" "$D/all.uv" >"$D/$kind.back" &&
            cmp -s "$D/$kind.back" "$D/$kind.ours" &&
            ok "$name: STEP -> IGES through our reader evaluates bit for bit" ||
            no "$name: STEP -> IGES round trip differs"
        # A file OCCT's STEPControl_Writer wrote (its own layout, its own
        # number format): our reader takes the same surface to 1e-9 mm.
        if "$CF" convert "$D/$kind.occ.stp" "$D/$kind.occ.igs" 2>"$D/$kind.cerr" &&
            "$CF" eval "$D/$kind.occ.igs" "$D/all.uv" >"$D/$kind.occ"; then
            d=$(maxdiff "$D/$kind.ours" "$D/$kind.occ")
            [ "$d" != mismatch ] && le "$d" 1e-9 &&
                ok "$name: our reader takes OCCT's STEP as the same surface (max diff $d mm)" ||
                no "$name: OCCT-written STEP read differently: max diff $d"
        else
            no "$name: our reader refused OCCT's STEP: $(cat "$D/$kind.cerr")"
        fi
    done
done
# The extension decides; an unknown one is refused.
"$CF" convert "$T/d3/nominal.igs" "$T/x.stl" 2>"$T/err" && no "unknown extension accepted" ||
    { grep -q "unknown surface format" "$T/err" && ok "unknown extension refused" ||
        no "unknown extension: $(cat "$T/err")"; }
echo "step: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
