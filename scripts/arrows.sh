#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/arrows.sh [ROOT]: the include arrows between folders, and none
# running up. Layers (README, Layout): host/cmd and host/api on top, then
# host/cell, host/jobs, host/report, lib, firmware; hal on firmware; sim
# on lib, hal, firmware. An arrow is a distinct (file, project header)
# pair whose header lives in another folder; it is upward when it points
# from a lower layer to a higher one: lib/ to host/, host/report to
# host/jobs|cell|cmd|api, host/jobs to host/cell|cmd|api, host/cell to
# host/cmd|api, hal/ or firmware/ to lib/ or host/, sim/ to host/. The
# per-layer include paths make most of these fail to compile already; this
# also covers what a path would let through (e.g. a header copied across).
# Prints every upward arrow, then "arrows: N between folders, U upward";
# exits 1 when U > 0. ARROWS_PAIRS=1 also prints the count per pair of
# folders. `make lint` runs it (scripts/lint.sh).
set -eu
cd "${1:-.}"
dirs="firmware lib host host/report host/jobs host/cell host/cmd host/api hal sim include"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/arrows.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
# header base name -> its folder (the first found; a same-named header in
# the includer's own folder wins below)
for d in $dirs; do
    [ -d "$d" ] || continue
    for h in "$d"/*.h; do
        [ -f "$h" ] && printf '%s %s\n' "${h##*/}" "$d"
    done
done >"$tmp/headers"
# (folder, file, included header) for every quoted include
for d in $dirs; do
    [ -d "$d" ] || continue
    for f in "$d"/*.c "$d"/*.h; do
        [ -f "$f" ] || continue
        sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f" |
            while read -r inc; do printf '%s %s %s\n' "$d" "$f" "${inc##*/}"; done
    done
done >"$tmp/includes"
awk '
    NR == FNR { if (!($1 in where)) where[$1] = $2; all[$1 " " $2] = 1; next }
    {
        from = $1; file = $2; h = $3
        if ((h " " from) in all) next          # a header of its own folder
        if (!(h in where)) next                # system, board or generated header
        to = where[h]
        if (seen[file " " h]++) next
        n++
        pair[from " -> " to]++
        up = 0
        if (from == "lib" && to ~ /^host\//) up = 1
        if (from == "host/report" && to ~ /^host\/(jobs|cell|cmd|api)$/) up = 1
        if (from == "host/jobs" && to ~ /^host\/(cell|cmd|api)$/) up = 1
        if (from == "host/cell" && to ~ /^host\/(cmd|api)$/) up = 1
        if ((from == "hal" || from == "firmware") && (to == "lib" || to ~ /^host/)) up = 1
        if (from == "firmware" && (to == "hal" || to == "sim")) up = 1
        if (from == "sim" && to ~ /^host/) up = 1
        if (up) { u++; printf "arrows: upward: %s includes %s (%s)\n", file, h, to }
    }
    END {
        if (pairs) for (p in pair) printf "arrows: %5d %s\n", pair[p], p | "sort -k3"
        close("sort -k3")
        printf "arrows: %d between folders, %d upward\n", n, u
        exit u > 0
    }
' pairs="${ARROWS_PAIRS:-0}" "$tmp/headers" "$tmp/includes"
