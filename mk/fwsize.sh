#!/bin/sh
# SPDX-License-Identifier: MIT
# mk/fwsize.sh: prove a linked image fits its board. Every allocated section
# must lie in a memory region of the linker map, and each region's use
# (.data counted twice: in RAM and as its load image in flash) within its
# length. The linker refuses overflows too; this also prints the figures.
# Usage: mk/fwsize.sh CROSS_PREFIX ELF MAP
set -eu
prefix=$1 elf=$2 map=$3

"${prefix}size" "$elf"
regions=$(awk '/^Memory Configuration/ { f = 1; next }
               /^Linker script and memory map/ { f = 0 }
               f && $2 ~ /^0x/ && $1 != "*default*" { print $1, $2, $3 }' "$map")
[ -n "$regions" ] || { echo "fwsize: no memory regions in $map" >&2; exit 1; }

"${prefix}objdump" -h -w "$elf" | awk -v regions="$regions" -v elf="$elf" '
function hex(s,    i, c, v) {
    sub(/^0x/, "", s); v = 0
    for (i = 1; i <= length(s); i++) {
        c = index("0123456789abcdef", tolower(substr(s, i, 1))) - 1
        v = v * 16 + c
    }
    return v
}
function region(addr,    r) {
    for (r = 1; r <= nr; r++)
        if (addr >= org[r] && addr < org[r] + len[r]) return r
    return 0
}
BEGIN {
    n = split(regions, w, /[ \n]+/)
    for (i = 1; i + 2 <= n; i += 3) { nr++; name[nr] = w[i]; org[nr] = hex(w[i+1]); len[nr] = hex(w[i+2]) }
}
$1 ~ /^[0-9]+$/ && /ALLOC/ {
    size = hex($3); vma = hex($4); lma = hex($5)
    if (size == 0) next
    r = region(vma)
    if (!r) { printf "fwsize: %s: section %s at 0x%s is in no region\n", elf, $2, $4; bad = 1; next }
    used[r] += size
    if (/LOAD/ && lma != vma) {
        r = region(lma)
        if (!r) { printf "fwsize: %s: load image of %s is in no region\n", elf, $2; bad = 1; next }
        used[r] += size
    }
}
END {
    printf "%-10s %10s %10s %10s %6s\n", "region", "origin", "used", "length", "use"
    for (r = 1; r <= nr; r++) {
        printf "%-10s 0x%08x %10d %10d %5.1f%%\n", name[r], org[r], used[r], len[r], len[r] ? 100 * used[r] / len[r] : 0
        if (used[r] > len[r]) { printf "fwsize: %s overflows %s\n", elf, name[r]; bad = 1 }
    }
    exit bad
}'
