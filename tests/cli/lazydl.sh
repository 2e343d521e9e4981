#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/lazydl.sh CELLFIT: the libraries loaded at first use (issue 20,
# hal/hal_dl.h; their sonames in BUILD/gen/hal_dl_libs.h). cellfit links
# none of them (readelf), and neither --version nor a fit maps one (the
# loader's own account, LD_DEBUG=files); fit --record maps SQLite, and only
# it. With each library unloadable (an empty file of its soname first in
# LD_LIBRARY_PATH: dlopen fails as for a missing one) a fit still works,
# while fit --record and a profiler scan fail with exit 1, as a database
# that cannot be opened does, naming the soname and the package to install.
# Prints "lazydl: N passed, N failed".
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HDR=$(dirname "$CF")/gen/hal_dl_libs.h
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-lazydl.XXXXXX")
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM

if [ ! -f "$HDR" ]; then
    no "no $HDR beside $CF (make builds it)"
    echo "lazydl: $pass passed, $fail failed"
    exit 1
fi
soname() { sed -n "s/^#define HAL_DL_SONAME_$1 \"\(.*\)\"/\1/p" "$HDR"; }
package() { sed -n "s/^#define HAL_DL_PACKAGE_$1 \"\(.*\)\"/\1/p" "$HDR"; }
SONAMES=$(sed -n 's/^#define HAL_DL_SONAME_[A-Z0-9]* "\(.*\)"/\1/p' "$HDR")
# Aravis brings GLib: none of it either.
HEAVY="$SONAMES libglib-2.0.so.0 libgobject-2.0.so.0 libgio-2.0.so.0"
[ -n "$SONAMES" ] && ok "loaded at first use: $(echo $SONAMES)" || no "$HDR lists no library"

# mapped LOG: the objects the loader mapped (LD_DEBUG=files, one file a process).
mapped() { sed -n 's/.*file=\([^ ]*\) \[[0-9]*\];  generating link map.*/\1/p' "$1".* | sort -u; }
heavy_in() { for s in $HEAVY; do grep -qx "$s" "$1" && echo "$s"; done; }

needed=$(readelf -d "$CF" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')
echo "$needed" >"$T/needed"
bad=$(heavy_in "$T/needed")
[ -z "$bad" ] && ok "cellfit links none of them (NEEDED: $(echo $needed))" || no "cellfit links $(echo $bad)"

rm -f "$T"/ld.*
expect 0 "cellfit --version" env LD_DEBUG=files LD_DEBUG_OUTPUT="$T/ld" "$CF" --version
mapped "$T/ld" >"$T/maps"
bad=$(heavy_in "$T/maps")
[ -s "$T/maps" ] && [ -z "$bad" ] && ok "--version maps $(wc -l <"$T/maps") objects, none of them" ||
    no "--version maps: $(echo $bad) (of $(wc -l <"$T/maps"))"

"$CF" gen --dir "$T/part" --nu 8 --nv 8 --count 20000 --noise 0.002 >/dev/null
P="--base $T/part/nominal.igs --points $T/part/points.uvxyz --uv"
rm -f "$T"/ld.*
# shellcheck disable=SC2086
expect 0 "fit" env LD_DEBUG=files LD_DEBUG_OUTPUT="$T/ld" "$CF" fit $P --out "$T/f.igs"
mapped "$T/ld" >"$T/maps"
bad=$(heavy_in "$T/maps")
[ -s "$T/maps" ] && [ -z "$bad" ] && ok "fit maps none of them" || no "fit maps: $(echo $bad)"

SQ=$(soname SQLITE3)
if [ -n "$SQ" ]; then
    rm -f "$T"/ld.*
    # shellcheck disable=SC2086
    expect 0 "fit --record" env LD_DEBUG=files LD_DEBUG_OUTPUT="$T/ld" "$CF" fit $P \
        --out "$T/f2.igs" --record --db "$T/results"
    mapped "$T/ld" >"$T/maps"
    bad=$(heavy_in "$T/maps")
    [ "$bad" = "$SQ" ] && grep -q "file=$SQ .*dynamically loaded by" "$T"/ld.* &&
        ok "fit --record loads $SQ, and only it, at its first use" || no "fit --record maps: $(echo $bad)"
    expect 0 "results list reads the row" "$CF" results list --db "$T/results"
    [ "$(wc -l <"$T/out")" -eq 1 ] && ok "  one row" || no "  rows: $(cat "$T/out")"
fi

# Every library unloadable: an empty file of its soname (dlopen: file too short).
mkdir "$T/gone"
for s in $SONAMES; do : >"$T/gone/$s"; done
G="env LD_LIBRARY_PATH=$T/gone"
expect 0 "without them: --version" $G "$CF" --version
# shellcheck disable=SC2086
expect 0 "without them: fit" $G "$CF" fit $P --out "$T/f3.igs"
grep -v '^#' "$T/part/points.uvxyz" | cut -d' ' -f1-2 | head -400 >"$T/uv"
same_surface "$T/f.igs" "$T/f3.igs" "$T/uv" && ok "  the same surface" ||
    no "  another surface"
if [ -n "$SQ" ]; then
    # The class of a results database that cannot be opened: exit 1, surface written.
    # shellcheck disable=SC2086
    expect 1 "fit --record --db in a folder that does not exist: exit 1" "$CF" fit $P \
        --out "$T/f4.igs" --record --db "$T/nowhere/results.db"
    # shellcheck disable=SC2086
    expect 1 "without SQLite: fit --record, exit 1" $G "$CF" fit $P --out "$T/f5.igs" \
        --record --db "$T/results"
    grep -q "$SQ" "$T/err" && grep -q "install the Debian package $(package SQLITE3)" "$T/err" &&
        [ -f "$T/f5.igs" ] && ! grep -q -e "--db:" "$T/err" &&
        ok "  names $SQ and $(package SQLITE3); the surface is written" ||
        no "  message: $(cat "$T/err")"
    expect 1 "without SQLite: results list, exit 1" $G "$CF" results list --db "$T/results"
    grep -q "needs $SQ" "$T/err" && ! grep -q -e "--db takes" "$T/err" &&
        ok "  names $SQ, without a hint about --db" || no "  message: $(cat "$T/err")"
fi
AR=$(soname ARAVIS)
if [ -n "$AR" ]; then
    # Fails at the probe's open, before any network (no camera is needed).
    expect 1 "without Aravis: scan --method profiler, exit 1" $G timeout 60 "$CF" scan \
        --stage tcp:127.0.0.1:1 --probe gev:127.0.0.1 --method profiler \
        --geometry 'width 64 height 8 profiles 10 x0 0 dx 1 y0 0 dy 1 z0 0 lo 0 scale 0.001' \
        --nominal "$T/part/nominal.igs" --journal "$T/s.jnl"
    grep -q "needs $AR: install the Debian package $(package ARAVIS)" "$T/err" &&
        ok "  names $AR and $(package ARAVIS)" || no "  message: $(cat "$T/err")"
fi
echo "lazydl: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
