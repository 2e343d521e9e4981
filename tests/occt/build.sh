#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/occt/build.sh OUTDIR: build OUTDIR/occt_eval (IGES),
# OUTDIR/occt_step (STEP) and OUTDIR/occt_trim (trimmed faces) against Debian's OpenCASCADE packages. Exits 3 with "occt: not available" when the headers
# or libraries are missing, so callers can skip the check. The three share
# occt_shape.hxx (reading a file into a shape, evaluating its surface).
set -u
out="${1:?usage: build.sh OUTDIR}"
here=$(dirname "$0")
inc="${OCCT_INC:-/usr/include/opencascade}" # OCCT_INC: another install
if [ ! -f "$inc/IGESControl_Reader.hxx" ] || ! command -v g++ >/dev/null 2>&1; then
    echo "occt: not available"
    exit 3
fi
# Libraries in dependency order (IGES reader down to the kernel).
libs="-lTKIGES -lTKXSBase -lTKShHealing -lTKTopAlgo -lTKGeomAlgo -lTKBRep \
-lTKGeomBase -lTKG3d -lTKG2d -lTKMath -lTKernel"
mkdir -p "$out" || exit 1
if ! g++ -std=c++11 -O2 -w -I"$inc" "$here/occt_eval.cpp" -o "$out/occt_eval" $libs 2>"$out/occt_build.log"; then
    if grep -q "cannot find -lTK\|No such file" "$out/occt_build.log"; then
        echo "occt: not available"
        exit 3
    fi
    cat "$out/occt_build.log" >&2
    exit 1
fi
# The STEP reader: same package (libocct-data-exchange-dev), more libraries.
slibs="-lTKSTEP -lTKSTEPAttr -lTKSTEP209 -lTKSTEPBase $libs"
if ! g++ -std=c++11 -O2 -w -I"$inc" "$here/occt_step.cpp" -o "$out/occt_step" $slibs 2>"$out/occt_build.log"; then
    if grep -q "cannot find -lTK\|No such file" "$out/occt_build.log"; then
        echo "occt: not available"
        exit 3
    fi
    cat "$out/occt_build.log" >&2
    exit 1
fi
# Trimmed faces, made and read (IGES and STEP): the same libraries.
if ! g++ -std=c++11 -O1 -w -I"$inc" "$here/occt_trim.cpp" -o "$out/occt_trim" $slibs 2>"$out/occt_build.log"; then
    if grep -q "cannot find -lTK\|No such file" "$out/occt_build.log"; then
        echo "occt: not available"
        exit 3
    fi
    cat "$out/occt_build.log" >&2
    exit 1
fi
rm -f "$out/occt_build.log"
exit 0
