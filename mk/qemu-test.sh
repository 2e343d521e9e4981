#!/bin/sh
# SPDX-License-Identifier: MIT
# mk/qemu-test.sh: run a board image under QEMU with semihosting and check
# what it prints against the properties of its built-in fits
# (boards/common/bd_selftest.h), independently of the image's own verdict.
#   mk/qemu-test.sh run MACHINE ELF TIMEOUT BUDGET_TOOL
#   mk/qemu-test.sh check LOG STATUS BUDGET_TOOL   (re-check a saved log)
# Fails on a timeout, a non-zero QEMU exit, a missing case or a number off.
set -u
EXACT_TOL=1e-9   # BD_EXACT_TOL: reproduction of the true control points
EXACT_RESID=1e-14 # the image's stop for the exact cases
DEFAULT_RESID=1e-12 # NF_SOLVE_OPTS_DEFAULT

check() { # LOG STATUS BUDGET_TOOL
    log=$1 status=$2 tool=$3
    if [ "$status" -eq 124 ]; then
        echo "boards-test: QEMU timed out"; return 1
    fi
    keys=$("$tool" --keys) || return 1
    awk -v status="$status" -v keys="$keys" -v etol="$EXACT_TOL" -v eres="$EXACT_RESID" \
        -v dres="$DEFAULT_RESID" '
    function fail(msg) { print "boards-test: " msg; bad = 1 }
    function val(k,    i, kv) {
        for (i = 1; i <= NF; i++) { split($i, kv, "="); if (kv[1] == k) return kv[2] }
        return ""
    }
    BEGIN {
        n = split(keys, w, " ")
        for (i = 1; i <= n; i++) { split(w[i], kv, "="); host[kv[1]] = kv[2] }
        want["exact-gs"] = want["exact-chol"] = want["exact-pcg"] = "exact"
        want["largest"] = "exact"; want["default"] = want["default-pcg"] = "default"
        want["over"] = "over"
    }
    { sub(/\r$/, "") }
    /^board=/ {
        board = 1; arena = val("arena") + 0
        for (k in host)
            if (val(k) != host[k]) fail(k " is " val(k) " on the target, " host[k] " on the host")
    }
    /^case=/ {
        c = val("case"); seen[c] = 1; kind = want[c]
        if (kind == "") { fail("unexpected case " c); next }
        if (kind == "over") {
            if (val("rc") + 0 != -2) fail(c ": rc " val("rc") ", want -2 (NF_EBUDGET)")
            if (val("need") + 0 <= arena) fail(c ": need " val("need") " within the arena")
            next
        }
        if (val("rc") + 0 != 0 || val("rc") == "") fail(c ": rc " val("rc"))
        if (val("used") + 0 > val("need") + 0) fail(c ": used " val("used") " > formula " val("need"))
        if (kind == "exact") {
            if (!(val("maxerr") + 0 <= etol + 0)) fail(c ": maxerr " val("maxerr") " > " etol)
            if (!(val("resid") + 0 <= eres + 0)) fail(c ": resid " val("resid") " > " eres)
        } else {
            if (!(val("resid") + 0 <= dres + 0)) fail(c ": resid " val("resid") " > " dres)
            if (!(val("maxerr") + 0 < val("dev0") + 0)) fail(c ": maxerr " val("maxerr") " not below the nominal " val("dev0"))
        }
        if (c == "largest") {
            split(val("net"), s, "x")
            if (s[1] * s[2] != host["max_square_pcg"]) fail("largest net " val("net") " is not the budget max " host["max_square_pcg"])
        }
        if (val("ok") + 0 != 1) fail(c ": the image says ok=" val("ok"))
    }
    /^result=pass$/ { pass = 1 }
    /^fault/ { fail($0) }
    END {
        if (!board) fail("no board line")
        for (c in want) if (!seen[c]) fail("case " c " missing")
        if (!pass) fail("no result=pass")
        if (status != 0) fail("QEMU exit status " status)
        exit bad
    }' "$log"
}

case "${1:-}" in
run)
    machine=$2 elf=$3 limit=$4 tool=$5
    log=${elf%.elf}.qemu.log
    t0=$(date +%s.%N)
    timeout "$limit" qemu-system-arm -M "$machine" -nographic \
        -semihosting-config enable=on,target=native -kernel "$elf" </dev/null >"$log" 2>&1
    status=$?
    t1=$(date +%s.%N)
    cat "$log"
    if check "$log" "$status" "$tool"; then
        echo "boards-test: $machine passed ($(grep -c '^case=' "$log") cases, QEMU exit $status," \
            "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s)"
    else
        echo "boards-test: $machine FAILED (log $log)"; exit 1
    fi
    ;;
check)
    check "$2" "$3" "$4" && echo "boards-test: $2 passes"
    ;;
*)
    echo "usage: $0 run MACHINE ELF TIMEOUT BUDGET_TOOL | check LOG STATUS BUDGET_TOOL" >&2
    exit 2
    ;;
esac
