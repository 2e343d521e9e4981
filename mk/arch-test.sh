#!/bin/sh
# SPDX-License-Identifier: MIT
# mk/arch-test.sh NAME "EMU" CELLFIT NATIVE_CELLFIT UNIT_TEST...: a build for
# another CPU run under an emulator (qemu-user), from mk/arch.mk:
#  - westmere only: the emulated CPU really lacks AVX (an AVX2 program built
#    here dies with SIGILL) and cellfit refuses CELLFIT_CPU=x86-64-v3 there;
#  - every UNIT_TEST binary under EMU (cmocka's counts summed);
#  - one end-to-end fit under EMU: cellfit gen (the synthetic part), fit,
#    eval against the part's true check points (0.01 mm, as tests/cli/run.sh)
#    and against the same fit by NATIVE_CELLFIT on this machine's CPU
#    (baseline path): bit for bit under westmere (same code), within 1e-9 mm
#    on aarch64 (another compiler's rounding);
#  - aarch64 only: its cellsim under EMU answers the native cellfit over
#    Modbus TCP on 127.0.0.1.
# Prints "arch-NAME: N passed, N failed"; fails on a failure.
set -u
. "$(dirname "$0")/../tests/cli/lib.sh"
[ $# -ge 4 ] || { echo "usage: $0 NAME EMU CELLFIT NATIVE_CELLFIT [UNIT_TEST...]" >&2; exit 2; }
NAME=$1 EMU=$2 CF=$(realpath "$3") NCF=$(realpath "$4")
shift 4
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-arch.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
start=$(date +%s)
echo "== arch-$NAME: under $EMU"

if [ "$NAME" = westmere ]; then
    # An AVX2 program: 4-wide vectors of doubles at -mavx2 are ymm registers.
    printf '%s\n' 'typedef double v4 __attribute__((vector_size(32)));' \
        'int main(int c, char **v) { (void)v; volatile v4 a = {c, c, c, c};' \
        '  v4 b = a; return (int)(b * b)[3] - 1; }' >"$T/avx2.c"
    if ${ARCH_CC:-cc} -O2 -mavx2 "$T/avx2.c" -o "$T/avx2" 2>"$T/cc.err"; then
        "$T/avx2" && ok "an AVX2 program runs natively" || no "the AVX2 program fails natively"
        $EMU "$T/avx2" 2>/dev/null
        rc=$?
        [ $rc -eq 132 ] && ok "the same program dies with SIGILL under $EMU (exit $rc): no AVX there" ||
            no "AVX2 program under $EMU: exit $rc, want 132 (SIGILL)"
    else
        no "cannot build the AVX2 probe: $(head -1 "$T/cc.err")"
    fi
    CELLFIT_CPU=x86-64-v3 $EMU "$CF" eval /dev/null /dev/null >/dev/null 2>"$T/err"
    grep -q "lacks AVX2/FMA" "$T/err" && ok "cellfit refuses CELLFIT_CPU=x86-64-v3 under $EMU" ||
        no "CELLFIT_CPU=x86-64-v3 not refused: $(cat "$T/err")"
fi

# Unit tests, ARCH_JOBS at a time (one emulator on each core; a lane takes
# the next unclaimed binary, mkdir being atomic), each in its own
# CF_TEST_TMP; their verdicts follow in the order given.
npass=0 nskip=0 nfail=0
mkdir -p "$T/tmp" "$T/claim"
lane() {
    i=0
    for t in "$@"; do
        i=$((i + 1))
        mkdir "$T/claim/$i" 2>/dev/null || continue
        b=$(basename "$t")
        s=$(date +%s)
        mkdir -p "$T/tmp/$b"
        CF_TEST_TMP="$T/tmp/$b" $EMU "$t" >"$T/$b.log" 2>&1
        echo "$? $(($(date +%s) - s))" >"$T/$b.rc"
    done
}
w=0
while [ $w -lt "${ARCH_JOBS:-$(nproc 2>/dev/null || echo 1)}" ]; do
    lane "$@" &
    PIDS="$PIDS $!"
    w=$((w + 1))
done
for p in $PIDS; do wait "$p"; done
PIDS=
for t in "$@"; do
    b=$(basename "$t")
    rc=1 secs=0
    [ -s "$T/$b.rc" ] && read -r rc secs <"$T/$b.rc"
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$T/$b.log")
    k=$(sed -n 's/^\[  SKIPPED \] \([0-9]*\) test.*/\1/p' "$T/$b.log")
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$T/$b.log")
    npass=$((npass + ${p:-0})) nskip=$((nskip + ${k:-0})) nfail=$((nfail + ${f:-0}))
    if [ $rc -eq 0 ] && [ -n "$p" ]; then
        ok "unit $b: ${p} passed${k:+, $k skipped} ($secs s)"
    else
        no "unit $b: exit $rc"
        grep -E 'FAILED|ERROR|LINE' "$T/$b.log" | head -10 | sed 's/^/     /'
    fi
done
[ $# -gt 0 ] && echo "arch-$NAME: unit tests under emulation: $npass passed, $nskip skipped, $nfail failed in $# binaries"

# One end-to-end fit: the part, 40 x 30 bicubic net, 60,000 noisy points.
P=$T/part
expect 0 "gen under $EMU" $EMU "$CF" gen --dir "$P" --nu 40 --nv 30 --count 60000 --noise 0.005
expect 0 "fit under $EMU" $EMU "$CF" fit --base "$P/nominal.igs" --points "$P/points.uvxyz" --uv \
    --out "$T/fit.igs" --json
[ "$(json "$T/out" points)" = 60000 ] && ok "fit took 60000 points (solver $(json "$T/out" solver))" ||
    no "fit: $(cat "$T/out")"
expect 0 "eval under $EMU" $EMU "$CF" eval "$T/fit.igs" "$P/check.uv"
cp "$T/out" "$T/e-emu"
e=$(paste "$T/e-emu" "$P/check.xyz" | awk '{ d = $3 - $6; if (d < 0) d = -d; if (d > m) m = d }
    END { printf "%.4g", m }')
[ "$(wc -l <"$T/e-emu")" -gt 100 ] && le "$e" 0.01 &&
    ok "fitted surface within 0.01 mm of the true part (max $e mm)" || no "fit misses the part by $e mm"
# The same fit natively, baseline path, on the emulated run's own input.
CELLFIT_CPU=baseline "$NCF" fit --base "$P/nominal.igs" --points "$P/points.uvxyz" --uv \
    --out "$T/fit-native.igs" >/dev/null 2>&1 &&
    CELLFIT_CPU=baseline "$NCF" eval "$T/fit-native.igs" "$P/check.uv" >"$T/e-native" ||
    no "native fit failed"
d=$(paste "$T/e-emu" "$T/e-native" | awk '{ for (c = 1; c <= 3; c++) { a = $c - $(c + 3);
    if (a < 0) a = -a; if (a > m) m = a } } END { printf "%.3g", m }')
if [ "$NAME" = westmere ]; then
    cmp -s "$T/e-emu" "$T/e-native" && ok "same surface as the native baseline fit, bit for bit" ||
        no "emulated and native baseline fits differ (max $d mm)"
else
    le "$d" 1e-9 && ok "surface within 1e-9 mm of the native x86-64 fit (max $d mm)" ||
        no "emulated and native fits differ by $d mm"
fi

# aarch64's cellsim: the simulated rig on the emulated CPU, the native
# cellfit as its client over loopback.
SIM=$(dirname "$CF")/cellsim
if [ "$NAME" != westmere ] && [ -x "$SIM" ]; then
    $EMU "$SIM" --tcp 0 --noise 0 >"$T/sim.out" 2>"$T/sim.err" &
    PIDS="$PIDS $!"
    i=0
    while ! grep -q "cellsim: ready" "$T/sim.out" 2>/dev/null && [ $i -lt 200 ]; do
        sleep 0.05; i=$((i + 1))
    done
    port=$(awk '/^cellsim: tcp/ { print $4 }' "$T/sim.out")
    if [ -n "$port" ]; then
        expect 0 "native cellfit rig home against $NAME cellsim" timeout 30 "$NCF" rig home \
            --stage "tcp:127.0.0.1:$port" --json
        expect 0 "native cellfit rig status against $NAME cellsim" timeout 30 "$NCF" rig status \
            --stage "tcp:127.0.0.1:$port" --probe "tcp:127.0.0.1:$port:2" --json
        [ "$(json "$T/out" homed)" = 1 ] && ok "$NAME cellsim: homed over Modbus TCP" ||
            no "$NAME cellsim status: $(cat "$T/out")"
    else
        no "$NAME cellsim did not come up: $(head -3 "$T/sim.err")"
    fi
    stop_all
fi

echo "arch-$NAME: $pass passed, $fail failed ($(($(date +%s) - start)) s)"
[ "$fail" -eq 0 ]
