#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/pkg/install.sh BUILD: what a plant's IT does with cellfit: `make
# install DESTDIR=STAGE PREFIX=/usr` lays out the tree (debian-depends names
# the packages of the libraries cellfit loads at first use); the examples build
# against it with pkg-config and run (an exact fit from an array, a journal
# read back and compared with `cellfit journal info`); every man page
# renders with man -l; every option `--help` shows is in the man page;
# `make uninstall` leaves nothing behind. Prints "install: N passed, N failed".
set -u
. "$(dirname "$0")/../cli/lib.sh"
B=$(realpath "$1")
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-install.XXXXXX")
S=$T/stage
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
MK="make -s --no-print-directory BUILD=$B"

expect 0 "make install DESTDIR=STAGE PREFIX=/usr" $MK install DESTDIR="$S" PREFIX=/usr
for f in usr/bin/cellfit usr/bin/cellsim usr/lib/libcellfit.a usr/lib/pkgconfig/cellfit.pc \
    usr/include/cellfit.h usr/share/man/man1/cellfit.1 usr/share/man/man1/cellsim.1 \
    usr/share/man/man5/cellfit.conf.5 usr/share/doc/cellfit/README.md \
    usr/share/doc/cellfit/LICENSE usr/share/doc/cellfit/plc-register-map.md \
    usr/share/doc/cellfit/examples/cellfit.conf usr/share/bash-completion/completions/cellfit \
    usr/lib/systemd/system/cellfit.service etc/cellfit/cellfit.conf; do
    [ -f "$S/$f" ] && ok "installed /$f" || no "missing /$f"
done
U=$S/usr/lib/systemd/system/cellfit.service
grep -q '^ExecStart=/usr/bin/cellfit serve --config /etc/cellfit/cellfit.conf' "$U" &&
    ok "unit runs the installed cellfit with the installed config" || no "unit ExecStart: $(grep ExecStart "$U")"
grep -q '^SupplementaryGroups=.*dialout' "$U" && ok "unit's user is in dialout" || no "unit: no dialout"
# The results and journal folders the example config names, made by systemd.
for d in $(sed -n 's#^\(results_dir[.0-9]*\|journal_dir\) *= */var/lib/\(.*\)#\2#p' "$S/etc/cellfit/cellfit.conf"); do
    grep -q "^StateDirectory=.*\b$d\b" "$U" && ok "unit creates /var/lib/$d" || no "unit does not create /var/lib/$d"
done
doc=$(sed -n 's#^Documentation=.*file://\([^ ]*\).*#\1#p' "$U")
[ -n "$doc" ] && [ -f "$S$doc" ] && ok "unit's Documentation= is installed ($doc)" || no "Documentation= '$doc' not installed"
# The libraries loaded at first use (mk/dl.mk) are no ELF dependency: the
# installed debian-depends lists each one's package, and cellfit links none.
D=$S/usr/share/doc/cellfit/debian-depends
for p in $(sed -n 's/^#define HAL_DL_PACKAGE_[A-Z0-9]* "\(.*\)"/\1/p' "$B/gen/hal_dl_libs.h"); do
    grep -Eq "^(Depends|Recommends):(.*,)? $p(,|\$)" "$D" && ok "debian-depends lists $p" ||
        no "debian-depends lacks $p: $(grep -v '^#' "$D" 2>&1)"
done
for s in $(sed -n 's/^#define HAL_DL_SONAME_[A-Z0-9]* "\(.*\)"/\1/p' "$B/gen/hal_dl_libs.h"); do
    readelf -d "$S/usr/bin/cellfit" | grep -q "NEEDED.*\[$s\]" && no "installed cellfit links $s"
done
"$S/usr/bin/cellfit" --version >"$T/v" 2>&1 && grep -q '^cellfit [0-9]' "$T/v" &&
    ok "installed cellfit --version: $(head -1 "$T/v")" || no "installed cellfit --version"

# The examples against the installed tree, through pkg-config alone.
PC="env PKG_CONFIG_PATH= PKG_CONFIG_LIBDIR=$S/usr/lib/pkgconfig PKG_CONFIG_SYSROOT_DIR=$S pkg-config"
flags=$($PC --cflags --libs cellfit 2>"$T/err")
[ -n "$flags" ] && ok "pkg-config --cflags --libs cellfit: $flags" || no "pkg-config: $(cat "$T/err")"
for e in fit_array read_journal; do
    # shellcheck disable=SC2086
    expect 0 "example $e builds against the installed tree" \
        ${CC:-cc} -std=c11 -Wall -Wextra -Werror -o "$T/$e" "examples/$e.c" $flags
done
expect 0 "fit_array fits and reproduces the part exactly" "$T/fit_array" "$T/fitted.igs"
grep -q 'max control point error' "$T/out" && ok "fit_array: $(cat "$T/out")" || no "fit_array output"
expect 0 "the installed cellfit reads fit_array's IGES" "$S/usr/bin/cellfit" info "$T/fitted.igs" --json
[ "$(json "$T/out" control_points)" = 42 ] && ok "its net is the nominal's 7 x 6" ||
    no "info: $(cat "$T/out")"
expect 0 "a journal to read" "$S/usr/bin/cellfit" journal selftest-write "$T/j.jnl" --records 700
expect 0 "cellfit journal info" "$S/usr/bin/cellfit" journal info "$T/j.jnl" --json
npts=$(json "$T/out" points) nflag=$(json "$T/out" flagged)
expect 0 "read_journal reads it" "$T/read_journal" "$T/j.jnl"
[ "$(sed -n "s/^points //p" "$T/out")" = "$npts" ] && [ "$(sed -n "s/^flagged //p" "$T/out")" = "$nflag" ] &&
    ok "read_journal: $npts points and $nflag flagged, as journal info" ||
    no "read_journal: $(tr "\n" " " <"$T/out") against info $npts/$nflag"
expect 2 "read_journal refuses a file that is no journal" "$T/read_journal" "$T/fitted.igs"

# Every page renders; every option of every command's --help is in cellfit(1).
for p in man1/cellfit.1 man1/cellsim.1 man5/cellfit.conf.5; do
    MANWIDTH=100 man -l "$S/usr/share/man/$p" >"$T/page" 2>"$T/err"
    [ $? -eq 0 ] && [ ! -s "$T/err" ] && grep -q '^NAME' "$T/page" &&
        ok "man -l $p renders ($(wc -l <"$T/page") lines)" || no "man -l $p: $(head -3 "$T/err")"
done
src=$(sed 's/\\-/-/g' "$S/usr/share/man/man1/cellfit.1")
missing=0 count=0
for c in $("$S/usr/bin/cellfit" --commands); do
    for s in "" $("$S/usr/bin/cellfit" "$c" --subcommands 2>/dev/null); do
        for o in $("$S/usr/bin/cellfit" "$c" $s --help | sed -n 's/^  \(--[a-z0-9-]*\).*/\1/p'); do
            [ "$o" = --help ] && continue
            count=$((count + 1))
            echo "$src" | grep -q -- "$o\b" || { missing=$((missing + 1)); echo "     not in cellfit.1: $c $s $o"; }
        done
    done
done
[ $count -gt 50 ] && [ $missing -eq 0 ] && ok "all $count options of every --help are in cellfit(1)" ||
    no "$missing of $count options missing from cellfit(1)"
src=$(sed 's/\\-/-/g' "$S/usr/share/man/man1/cellsim.1")
missing=0 count=0
for o in $("$S/usr/bin/cellsim" --help | sed -n 's/^  \(--[a-z0-9-]*\).*/\1/p'); do
    [ "$o" = --help ] && continue
    count=$((count + 1))
    echo "$src" | grep -q -- "$o\b" || { missing=$((missing + 1)); echo "     not in cellsim.1: $o"; }
done
[ $count -gt 3 ] && [ $missing -eq 0 ] && ok "all $count options of cellsim --help are in cellsim(1)" ||
    no "$missing of $count cellsim options missing from cellsim(1)"

expect 0 "make uninstall" $MK uninstall DESTDIR="$S" PREFIX=/usr
left=$(find "$S" -type f | sed "s#^$S##")
[ -x "$S/../fit_array" ] || no "uninstall check needs a successful install first"
[ -z "$left" ] && ok "uninstall leaves no file" || no "left after uninstall: $left"
echo "install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
