#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/help.sh CELLFIT: the command line from option tables (issue 13):
# every command and sub-command answers --help (exit 0, "usage:"), every
# option its --help lists is in its --help-man (roff) section too, an
# unknown option is named (exit 2), an option given last without its value
# "needs a value" (exit 2), --name=value works, `cellfit --version` prints
# the Makefile's version, `cellfit help CMD` is `CMD --help`, and cellsim
# answers --help from its own table.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
SIM=$(dirname "$CF")/cellsim
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-help.XXXXXX")
trap 'rm -rf "$T"' EXIT

# The option names a usage lists: its "  --name ..." lines, --help aside.
opt_names() { sed -n 's/^  \(--[a-z0-9][a-z0-9-]*\).*/\1/p' "$1" | grep -vx -- '--help'; }

# help_ok NAME CMD...: CMD --help exits 0 with "usage:" on stdout, and every
# option it lists appears in CMD --help-man (roff: "\-\-name" unescaped).
help_ok() {
    name=$1; shift
    "$@" --help >"$T/help" 2>"$T/err"
    rc=$?
    if [ $rc -ne 0 ]; then
        no "$name --help: exit $rc"; sed 's/^/     /' "$T/err" | head -3; return
    fi
    grep -q '^usage:' "$T/help" && ok "$name --help" || { no "$name --help: no usage line"; return; }
    "$@" --help-man >"$T/man" 2>"$T/err"
    rc=$?
    [ $rc -eq 0 ] || { no "$name --help-man: exit $rc"; return; }
    sed 's/\\-/-/g' "$T/man" >"$T/man.txt"
    missing=""
    for o in $(opt_names "$T/help"); do
        grep -q -- "^\.B $o\( \|$\)" "$T/man.txt" || missing="$missing $o"
    done
    [ -z "$missing" ] && ok "$name: the $(opt_names "$T/help" | wc -l) options of --help in --help-man" ||
        no "$name --help-man lacks$missing"
}

# Every command cellfit lists, and the sub-commands of rig, bench, journal
# (each must also be named by its parent's --help).
cmds=$("$CF" --commands)
[ -n "$cmds" ] && ok "cellfit --commands: $(echo $cmds)" || no "cellfit --commands lists nothing"
for c in $cmds; do
    help_ok "$c" "$CF" "$c"
done
for sub in "rig: status home move probe reset stop" "bench: accumulate solve fit export project" \
    "journal: export info recover fit"; do
    c=${sub%%:*}
    "$CF" "$c" --help >"$T/parent" 2>&1
    for s in ${sub#*:}; do
        grep -qw -- "$s" "$T/parent" && ok "$c --help names $s" || no "$c --help does not name $s"
        help_ok "$c $s" "$CF" "$c" "$s"
    done
done
help_ok "cellsim" "$SIM"

# cellfit --help, help CMD, --version.
expect 0 "cellfit --help" "$CF" --help
for c in $cmds; do
    grep -q "^  $c " "$T/out" || no "cellfit --help does not list $c"
done
"$CF" info --help >"$T/a" 2>&1
expect 0 "cellfit help info" "$CF" help info
cmp -s "$T/a" "$T/out" && ok "help info is info --help" || no "help info differs from info --help"
expect 0 "cellfit --version" "$CF" --version
want=$(sed -n 's/^CF_VERSION := //p' "$ROOT/Makefile")
grep -q "^cellfit $want (.*)" "$T/out" && ok "--version is $want (the Makefile's)" ||
    no "--version '$(head -1 "$T/out")', Makefile has '$want'"

# A small part for the commands that read one.
"$CF" gen --dir "$T/p" --nu 6 --nv 5 --count 200 >/dev/null || no "cellfit gen"
N="$T/p/nominal.igs"
grep -v '^#' "$T/p/points.uvxyz" | cut -d' ' -f3- >"$T/p/points.xyz"

# bad2 NAME PATTERN CMD...: exit 2, one line on stderr matching PATTERN.
bad2() {
    name=$1; pat=$2; shift 2
    "$@" >"$T/out" 2>"$T/err"
    rc=$?
    if [ $rc -ne 2 ]; then
        no "$name: exit $rc, want 2"; sed 's/^/     /' "$T/err" | head -3
    elif [ "$(wc -l <"$T/err")" -ne 1 ] || ! grep -qE -- "$pat" "$T/err"; then
        no "$name: stderr does not match '$pat'"; sed 's/^/     /' "$T/err" | head -3
    else
        ok "$name: $(cat "$T/err")"
    fi
}
bad2 "info: unknown option named" "unknown option '--bogus'" "$CF" info --bogus "$N"
bad2 "info: unknown option given last named" "unknown option '--bogus'" "$CF" info "$N" --bogus
bad2 "gen: unknown option named" "unknown option '--points'" "$CF" gen --dir "$T/q" --points 5
bad2 "rig move: unknown option named" "unknown option '--count'" "$CF" rig move 1 2 --stage x --count 3
bad2 "bench solve: unknown option named" "unknown option '--count'" "$CF" bench solve --count 5
bad2 "cellsim: unknown option named" "unknown option '--bogus'" "$SIM" --tcp 0 --bogus
bad2 "info --entity last: needs a value" "--entity needs a value" "$CF" info "$N" --entity
bad2 "report --tol last: needs a value" "--tol needs a value" "$CF" report "$N" "$T/p/points.xyz" --tol
bad2 "thin --out last: needs a value" "--out needs a value" "$CF" thin "$N" "$T/p/points.xyz" --quad-tol 0.01 --out
bad2 "ports --count last: needs a value" "--count needs a value" "$CF" ports --count
bad2 "rig probe --probe last: needs a value" "--probe needs a value" "$CF" rig probe --probe
bad2 "bench fit --cp last: needs a value" "--cp needs a value" "$CF" bench fit --cp
bad2 "cellsim --tcp last: needs a value" "--tcp needs a value" "$SIM" --tcp
bad2 "a flag takes no value" "--json takes no value" "$CF" info "$N" --json=1
bad2 "--entity=x names the option and what it takes" "--entity 'x': need an integer" "$CF" info --entity=x "$N"
bad2 "rig: unknown operation" "unknown operation 'jump'" "$CF" rig jump
bad2 "bench: unknown benchmark" "unknown benchmark 'sprint'" "$CF" bench sprint

# --name=value is --name value.
expect 0 "info --entity=0 FILE" "$CF" info --entity=0 "$N" --json
cp "$T/out" "$T/eq"
expect 0 "info --entity 0 FILE" "$CF" info --entity 0 "$N" --json
cmp -s "$T/eq" "$T/out" && ok "--entity=0 and --entity 0 agree" || no "--entity=0 differs"
expect 0 "report --tol=0.05" "$CF" report "$N" "$T/p/points.xyz" --tol=0.05 --json
awk -v t="$(json "$T/out" tol)" 'BEGIN { exit !(t == 0.05) }' && ok "report took --tol=0.05" ||
    no "report tol: $(head -c 200 "$T/out")"
expect 0 "gen --count=50 --dir=DIR" "$CF" gen --count=50 --dir="$T/g" --nu=5 --nv=4
[ "$(grep -vc '^#' "$T/g/points.uvxyz")" -eq 50 ] && ok "gen --count=50 wrote 50 points" ||
    no "gen --count=50 wrote $(grep -vc '^#' "$T/g/points.uvxyz")"

echo "help: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
