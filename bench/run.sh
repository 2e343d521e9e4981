#!/bin/sh
# SPDX-License-Identifier: MIT
# bench/run.sh CELLFIT: issue 6's benchmarks (`make bench`): accumulation,
# solvers, CHOLMOD and FITPACK on the same problems, end to end, and the
# machine's memory bandwidth; prints Markdown tables beside the paper's
# Tables 2-4 (bench/tables.py), projection, and keeps every raw JSON line in
# BUILD/bench/*.jsonl (BUILD: CELLFIT's directory). Measures, asserts nothing.
# About 3 minutes on 2 quiet cores (the end-to-end peers add about a minute),
# plus the fitting loop's section (a few minutes: surfit's search).
# BENCH_LONG=1 adds the 10^8-point runs (docs/performance.md). Environment:
# BENCH_REPS (3) runs per cell,
# the fastest kept, while one run takes less than BENCH_REPEAT_S (5) seconds
# of wall time; BENCH_CHOL_MAX_S (20): banded Cholesky is skipped ("-") where
# its estimate from N = 10^4 exceeds this; CC (gcc) builds the C helpers;
# BENCH_SECTIONS (all): some of stream accumulate solve cholmod fitpack e2e
# project loop.
set -eu

if [ $# -ne 1 ] || [ ! -x "$1" ]; then
    echo "usage: sh bench/run.sh CELLFIT (e.g. build/cellfit)" >&2
    exit 2
fi
CF=$1
case $CF in /*) ;; *) CF=./$CF ;; esac
HERE=$(dirname "$0")
OUT=$(dirname "$CF")/bench
REPS=${BENCH_REPS:-3}
REPEAT_S=${BENCH_REPEAT_S:-5}
CHOL_MAX_S=${BENCH_CHOL_MAX_S:-20}
CC=${CC:-gcc}
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3

mkdir -p "$OUT"
rm -f "$OUT"/*.jsonl "$OUT"/*.cfne "$OUT"/out.txt "$OUT"/stderr.txt
rm -rf "$OUT/e2e"
child=
cleanup() {
    if [ -n "$child" ]; then kill "$child" 2>/dev/null || true; fi
    rm -f "$OUT"/*.cfne "$OUT"/out.txt "$OUT"/stderr.txt
    rm -rf "$OUT/e2e"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

now_ns() { date +%s%N; }
start=$(now_ns)
say() { echo "bench: $*" >&2; }
# errmsg: the failed command's stderr as one JSON-safe line
errmsg() { sed 's/[\\"]/ /g' "$OUT/stderr.txt" | tr '\t\n' '  ' | cut -c1-300; }
# side N: round(sqrt(N)), the side of cellfit's square bench nets
side() { awk -v n="$1" 'BEGIN { printf "%d", int(sqrt(n) + 0.5) }'; }
# run CMD...: CMD's stdout to OUT/out.txt, stderr to OUT/stderr.txt; in the
# background and waited for, so that a signal to this script ends it too.
run() {
    "$@" >"$OUT/out.txt" 2>"$OUT/stderr.txt" &
    child=$!
    rc=0
    wait "$child" || rc=$?
    child=
    return "$rc"
}

# cell_n R FILE CMD...: run CMD (one JSON line on stdout) up to R times,
# appending each line to FILE (tables.py keeps the fastest); a run of
# REPEAT_S seconds or more (wall) is not repeated. A failure is recorded.
cell_n() {
    reps=$1
    file=$2
    shift 2
    i=0
    while [ "$i" -lt "$reps" ]; do
        i=$((i + 1))
        t0=$(now_ns)
        if ! run "$@"; then
            msg=$(errmsg)
            printf '{"bench": "error", "command": "%s", "message": "%s"}\n' "$*" "$msg" >>"$file"
            say "FAILED: $* ($msg)"
            return 0
        fi
        t1=$(now_ns)
        head -n 1 "$OUT/out.txt" >>"$file"
        awk -v a="$t0" -v b="$t1" -v lim="$REPEAT_S" 'BEGIN { exit !((b - a) / 1e9 >= lim) }' &&
            break
    done
    return 0
}
cell() { cell_n "$REPS" "$@"; }
# want SECTION: BENCH_SECTIONS (all) names it; BENCH_SECTIONS=e2e refreshes
# the end-to-end table alone (the machine's table always runs). The
# sections' bodies are left unindented.
want() { case " ${BENCH_SECTIONS:-all} " in *" all "* | *" $1 "*) return 0 ;; esac; return 1; }
table() { "$PY" "$HERE/tables.py" "$OUT" "$1" || say "tables.py failed on section $1"; }

# --- the machine, the tools -------------------------------------------------
say "building bench/stream.c and bench/cholmod_bench.c with $CC"
"$CC" -std=c11 -D_POSIX_C_SOURCE=200809L -O3 -march=x86-64-v3 -ffp-contract=fast \
    -fassociative-math -fno-signed-zeros -fno-trapping-math -Wall -Wextra -Werror \
    "$HERE/stream.c" -o "$OUT/stream" -lm
"$CC" -std=c11 -D_POSIX_C_SOURCE=200809L -O2 -march=x86-64-v3 -Wall -Wextra -Werror \
    -I/usr/include/suitesparse "$HERE/cholmod_bench.c" -o "$OUT/cholmod_bench" \
    -lcholmod -lsuitesparseconfig -lm

cpuinfo() { sed -n "s/^$1[[:space:]]*: *//p" /proc/cpuinfo | head -n 1; }
cpu="$(cpuinfo 'model name') (family $(cpuinfo 'cpu family') model $(cpuinfo model),"
cpu="$cpu $(cpuinfo 'cpu MHz') MHz, cache $(cpuinfo 'cache size'))"
blas=$(readlink -f /usr/lib/x86_64-linux-gnu/libblas.so.3 2>/dev/null || echo unknown)
rev=$(git -C "$HERE/.." rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ "$rev" != unknown ] &&
    [ -n "$(git -C "$HERE/.." status --porcelain -- firmware host boards 2>/dev/null)" ]; then
    rev="$rev+local changes"
fi
{
    printf '{"bench": "machine", "date": "%s", "nproc": %s, "cpu": "%s", ' \
        "$(date -u '+%Y-%m-%d %H:%M UTC')" "$(nproc)" "$cpu"
    printf '"mem_total_kb": %s, "kernel": "%s", "compiler": "%s", ' \
        "$(awk '/^MemTotal/ { print $2 }' /proc/meminfo)" "$(uname -r)" \
        "$("$CC" --version | head -n 1)"
    printf '"cellfit_cflags": "%s", "cellfit_rev": "%s", "blas": "%s", "python": "%s", ' \
        "$(sed -n 's/^BOARD_CFLAGS *:= *//p' "$HERE/../boards/linux-cell/board.mk")" "$rev" \
        "$blas" "$("$PY" --version 2>&1)"
    printf '"scipy": "%s", "reps": %s, "repeat_below_s": %s, "command": "sh %s %s"}\n' \
        "$("$PY" -c 'import scipy; print(scipy.__version__)')" "$REPS" "$REPEAT_S" "$0" "$1"
} >"$OUT/machine.jsonl"
table machine

if want stream; then
say "memory bandwidth (bench/stream.c)"
cell_n 1 "$OUT/stream.jsonl" "$OUT/stream" # best of 3-5 inside
table stream
fi

# --- accumulation: the paper's Table 2 grid, raster and random ---------------
if want accumulate; then
say "accumulation: M x N grid, raster and random order"
for m in 10000 100000 1000000; do
    for n in 100 1000 10000 100000; do
        for o in raster random; do
            cell "$OUT/accumulate.jsonl" "$CF" bench accumulate --count "$m" --cp "$n" \
                --order "$o" --json
        done
    done
done
for o in raster random; do
    cell "$OUT/accumulate.jsonl" "$CF" bench accumulate --count 1000000 --cp 1000000 \
        --order "$o" --json
done
say "accumulation on two cores (a shard each, merged at the end), M = 10^6"
for n in 100 1000 10000 100000 1000000; do
    for o in raster random; do
        cell "$OUT/accumulate.jsonl" "$CF" bench accumulate --count 1000000 --cp "$n" \
            --order "$o" --threads 2 --json
    done
done
table accumulate
fi

# --- solvers: Tables 3 and 4 -------------------------------------------------
if want solve; then
say "solve: gs, pcg, chol on M = 10 N random points"
for n in 100 1000 10000 100000; do
    for s in gs pcg; do
        cell "$OUT/solve.jsonl" "$CF" bench solve --cp "$n" --solver "$s" --json
    done
done
chol4=
for n in 100 1000 10000 100000; do
    if [ "$n" -eq 100000 ]; then
        # cost N (q Nu + p)^2 of a square bicubic net, scaled from N = 10^4
        est=null
        if [ -n "$chol4" ]; then
            est=$(awk -v t="$chol4" -v a="$(side 10000)" -v b="$(side 100000)" 'BEGIN {
                printf "%.3g", t * (b * b) / (a * a) * ((3 * b + 3) / (3 * a + 3)) ^ 2 }')
        fi
        if [ "$est" = null ] ||
            awk -v e="$est" -v lim="$CHOL_MAX_S" 'BEGIN { exit !(e > lim) }'; then
            printf '{"bench": "solve", "control_points": %s, "solver": "chol", ' \
                "$(($(side 100000) * $(side 100000)))" >>"$OUT/solve.jsonl"
            printf '"skipped": true, "estimate_seconds": %s}\n' "$est" >>"$OUT/solve.jsonl"
            say "chol at N = 10^5 skipped (estimate $est s, limit $CHOL_MAX_S s)"
            continue
        fi
    fi
    cell "$OUT/solve.jsonl" "$CF" bench solve --cp "$n" --solver chol --json
    if [ "$n" -eq 10000 ]; then
        chol4=$(grep '"solver": "chol"' "$OUT/solve.jsonl" | grep '"control_points": 10000,' |
            sed -n 's/.*"solve_seconds": \([-0-9.eE+]*\),.*/\1/p' | sort -g | head -n 1)
    fi
done
say "solve: pcg at N = 10^6 (10^7 random points to accumulate first)"
cell "$OUT/solve.jsonl" "$CF" bench solve --cp 1000000 --solver pcg --json
table solve
fi

# --- CHOLMOD on the same normal equations ------------------------------------
if want cholmod; then
say "CHOLMOD on the exported normal equations"
for n in 1000 10000 100000; do
    if ! run "$CF" bench export --cp "$n" --out "$OUT/ne_$n.cfne"; then
        printf '{"bench": "error", "command": "bench export --cp %s", "message": "%s"}\n' \
            "$n" "$(errmsg)" >>"$OUT/cholmod.jsonl"
        continue
    fi
    cell "$OUT/cholmod.jsonl" "$OUT/cholmod_bench" "$OUT/ne_$n.cfne"
    rm -f "$OUT/ne_$n.cfne"
done
table cholmod
fi

# --- FITPACK (scipy LSQBivariateSpline) against our fit ----------------------
if want fitpack; then
say "FITPACK (scipy) and cellfit on the same random points"
# N = 961 (31 x 31) beside 1024 (32 x 32): FITPACK slows down several times
# when the coefficient count is a power of two (its band array's stride).
for mn in 10000:100 10000:1000 10000:10000 100000:100 100000:961 100000:1000 100000:10000; do
    m=${mn%:*}
    n=${mn#*:}
    cell "$OUT/fitpack.jsonl" "$PY" "$HERE/fitpack_bench.py" --count "$m" --cp "$n"
    cell "$OUT/fit.jsonl" "$CF" bench fit --count "$m" --cp "$n" --order random --json
done
table fitpack
fi

# --- end to end: 10^6 points, ASCII and binary, beside the peers (issue 20) --
if want e2e; then
# Per net: `cellfit gen` (not timed), bench/genbin converts its points to
# .uvxyz.bin (not timed), then the wall time of `cellfit fit --uv` on each
# file, best of REPS; the peers (bench/peers_e2e.py: scipy CG, and CHOLMOD
# through bench/cholmod_bench) once each on the same points, file I/O not
# timed. Then 10^8 binary points onto N = 10^4 (the 10^6-point raster
# written 100 times, 4 GB, deleted after); BENCH_LONG=1 adds the same onto
# N = 10^5 and N = 10^6 from 10^7 points.
# The wall time by bench/walltime (fork to wait of the fit itself): timing
# with date +%s%N around it would add the second date's fork and exec,
# about 8 ms here (/bin/true: 11.5-13 ms that way, 3.6-4.6 ms by walltime).
e2e_fit() { # e2e_fit DIR FILE INPUT: one timed fit, its JSON line to e2e.jsonl
    if ! run "$OUT/walltime" "$OUT/wall.txt" "$CF" fit --base "$1/nominal.igs" --points "$2" \
        --uv --out "$1/fitted.igs" --json; then
        printf '{"bench": "error", "command": "fit %s", "message": "%s"}\n' "$2" "$(errmsg)" \
            >>"$OUT/e2e.jsonl"
        return 1
    fi
    wall=$(awk '{ printf "%.4f", $1 }' "$OUT/wall.txt")
    head -n 1 "$OUT/out.txt" |
        sed "s/^{/{\"bench\": \"e2e\", \"input\": \"$3\", \"wall_seconds\": $wall, /" \
            >>"$OUT/e2e.jsonl"
}
"$CC" -std=c11 -O2 -Wall -Wextra -Werror "$HERE/genbin.c" -o "$OUT/genbin"
"$CC" -std=c11 -O2 -Wall -Wextra -Werror "$HERE/walltime.c" -o "$OUT/walltime"
mkdir -p "$OUT/e2e"
for nside in 10 32 100 316; do
    say "end to end: N = $nside x $nside, 10^6 points, ASCII and binary, and the peers"
    d=$OUT/e2e/n$nside
    if ! run "$CF" gen --dir "$d" --nu "$nside" --nv "$nside" --count 1000000 ||
        ! run "$OUT/genbin" "$d/points.uvxyz" "$d/points.uvxyz.bin"; then
        printf '{"bench": "error", "command": "gen %s", "message": "%s"}\n' "$nside" \
            "$(errmsg)" >>"$OUT/e2e.jsonl"
        continue
    fi
    i=0
    while [ "$i" -lt "$REPS" ]; do
        i=$((i + 1))
        e2e_fit "$d" "$d/points.uvxyz" ascii || break
        e2e_fit "$d" "$d/points.uvxyz.bin" bin || break
    done
    if run "$PY" "$HERE/peers_e2e.py" --points "$d/points.uvxyz.bin" --nu "$nside" \
        --nv "$nside" --cfne "$d/ne.cfne"; then
        cat "$OUT/out.txt" >>"$OUT/e2e_peers.jsonl"
        if run "$OUT/cholmod_bench" "$d/ne.cfne"; then
            head -n 1 "$OUT/out.txt" | sed 's/^{/{"e2e": true, /' >>"$OUT/e2e_peers.jsonl"
        fi
    else
        printf '{"bench": "error", "command": "peers %s", "message": "%s"}\n' "$nside" \
            "$(errmsg)" >>"$OUT/e2e_peers.jsonl"
    fi
    rm -f "$d/ne.cfne"
    case $nside in 10 | 32) rm -rf "$d" ;; esac # the long runs reuse 100 and 316
done
# 10^8 binary points onto N = 10^4 always (issue 20's flat-memory run);
# BENCH_LONG=1 adds N = 10^5 and the 10^7 points onto N = 10^6.
longs=100
[ "${BENCH_LONG:-0}" = 1 ] && longs="100 316"
for nside in $longs; do
    d=$OUT/e2e/n$nside
    [ -f "$d/points.uvxyz" ] || continue
    say "end to end, long: 10^8 binary points onto $nside x $nside (4 GB in $d)"
    if run "$OUT/genbin" "$d/points.uvxyz" "$d/big.uvxyz.bin" 100; then
        e2e_fit "$d" "$d/big.uvxyz.bin" bin || true
    fi
    rm -f "$d/big.uvxyz.bin"
done
if [ "${BENCH_LONG:-0}" = 1 ]; then
    say "end to end, long: 10^7 points onto 1000 x 1000"
    d=$OUT/e2e/n1000
    if run "$CF" gen --dir "$d" --nu 1000 --nv 1000 --count 10000000 &&
        run "$OUT/genbin" "$d/points.uvxyz" "$d/points.uvxyz.bin"; then
        e2e_fit "$d" "$d/points.uvxyz.bin" bin || true
        e2e_fit "$d" "$d/points.uvxyz" ascii || true
    fi
    rm -rf "$d"
fi
rm -rf "$OUT/e2e"
table e2e
fi

# --- projection: closest points on a curved bicubic part, truth known --------
if want project; then
say "projection: cellfit bench project (random and raster order)"
for n in 1000 10000 100000; do
    for o in random raster; do
        cell "$OUT/project.jsonl" "$CF" bench project --count 200000 --cp "$n" --order "$o" --json
    done
done
table project
fi

# --- the fitting loop to a tolerance beside FITPACK surfit (issue 14) ---------
if want loop; then
# bench/loop_bench.py (also `make bench-loop`, with the firmware-level
# chooser): `cellfit fit --tol T --within 99` (--refine auto) and surfit on
# terrain-like fields, every 5th row held out; its own Markdown table.
# BENCH_LOOP=0 skips it; BENCH_LOOP_SIZES (5000,20000), BENCH_LOOP_SURFIT_S
# (60) the time surfit's search may take per data set.
if [ "${BENCH_LOOP:-1}" != 0 ]; then
    say "fitting loop: cellfit fit --tol (auto) and FITPACK surfit (bench/loop_bench.py)"
    "$PY" "$HERE/loop_bench.py" --cellfit "$CF" --no-knotsel --sizes "${BENCH_LOOP_SIZES:-5000,20000}" \
        --surfit-s "${BENCH_LOOP_SURFIT_S:-60}" --json "$OUT/loop.jsonl" ||
        say "loop_bench.py failed"
fi
fi

table targets
secs=$(awk -v a="$start" -v b="$(now_ns)" 'BEGIN { printf "%.0f", (b - a) / 1e9 }')
say "done in $secs s; raw JSON in $OUT/*.jsonl"
