# SPDX-License-Identifier: MIT
# tests/cli/lib.sh: what every tests/cli/*.sh script shares, sourced after
# `set -u`: the pass/fail count and its ok/no lines, expect (exit code, with
# stdout and stderr kept in $T/out and $T/err), json (a field of a one-line
# JSON object), le (numeric <=), and stop_all (the PIDs in $PIDS stopped in
# reverse order: TERM, a short wait, KILL); for the scripts that serve:
# stop_servers, plc_setup, plc_part, serve_start, py_step. Not a test
# itself: the Makefile's test-cli leaves it out.
pass=0
fail=0
PIDS=""
ok() { pass=$((pass + 1)); echo "ok   $1"; }
no() { fail=$((fail + 1)); echo "FAIL $1"; }
# expect CODE NAME CMD...: run, check the exit code, keep stdout/stderr.
expect() {
    want=$1; name=$2; shift 2
    "$@" >"$T/out" 2>"$T/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok "$name"; else
        no "$name (exit $got, want $want)"; sed 's/^/     /' "$T/err" | head -5; fi
}
json() { # json FILE KEY: a number or string field of a one-line JSON object
    sed -n "s/.*\"$2\": \"\{0,1\}\([^,\"}]*\)\"\{0,1\}[,}].*/\1/p" "$1"
}
# le A B: A <= B as numbers
le() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 <= b + 0) }'; }
stop_all() { # reverse order: TERM, wait a little, KILL
    for p in $(echo $PIDS | tr ' ' '\n' | sed '1!G;h;$!d'); do kill -TERM "$p" 2>/dev/null; done
    for p in $PIDS; do
        i=0
        while kill -0 "$p" 2>/dev/null && [ $i -lt 20 ]; do sleep 0.1; i=$((i + 1)); done
        kill -KILL "$p" 2>/dev/null
        wait "$p" 2>/dev/null
    done
    PIDS=""
}
# The servers' scripts (plc*.sh, plant*.sh, trim.sh) keep their servers' PIDs
# in $pids and stop them with a longer wait (serve stops its cellsim child).
# stop_servers [TENTHS]: TERM to each, then up to TENTHS x 0.1 s (50) before
# KILL; by PID only.
# same_surface A.igs B.igs UV: 0 when the two surfaces agree within 1e-6 mm
# at every (u, v) of the file UV (cellfit eval of each, side by side).
same_surface() {
    "$CF" eval "$1" "$3" >"$T/same_a" && "$CF" eval "$2" "$3" >"$T/same_b" &&
        paste "$T/same_a" "$T/same_b" |
        awk '{ for (i = 1; i <= 3; i++) { d = $i - $(i + 3); if (d < 0) d = -d; if (d > m) m = d } }
            END { exit !(NR > 0 && m < 1e-6) }'
}

# fit_ready_s SERVE.LOG: the seconds from the last row to the streamed fit
# that serve logged ("fit: points from memory, ready S s after ..."), or "".
fit_ready_s() {
    sed -n 's/.*fit: points from memory, ready \([0-9.]*\) s after the last row.*/\1/p' "$1" | head -1
}

stop_servers() {
    for p in ${pids:-}; do kill -TERM "$p" 2>/dev/null; done
    for p in ${pids:-}; do
        i=0
        while kill -0 "$p" 2>/dev/null && [ $i -lt "${1:-50}" ]; do sleep 0.1; i=$((i + 1)); done
        kill -KILL "$p" 2>/dev/null
    done
    pids=""
}
# plc_setup NAME [rig] [TOOL...]: the preamble of the scripts that run
# serve with a Python PLC (plc*.sh, trim.sh), after CF=$(realpath "$1"):
# HERE, and PY (Debian's python3) with its pymodbus checked, and each TOOL
# (missing: exit 1); with rig, no cellsim beside $CF skips the script (exit
# 0, "NAME: 0 passed, 0 failed") and $T/part is the simulated rig's part;
# $T made, and at exit $plc_atexit (a command, if set), stop_servers and $T
# removed; INT and TERM exit 1. Its variables are plc_*: expect and
# serve_start set want, name and got (sh has only globals).
plc_setup() {
    plc_name=$1; shift
    plc_rig=; [ "${1:-}" = rig ] && { plc_rig=1; shift; }
    HERE=$(cd "$(dirname "$0")" && pwd)
    PY=/usr/bin/python3
    "$PY" -c "import sys; sys.path.insert(0, '$HERE'); import plc_cycle" 2>/dev/null ||
        { echo "$plc_name: $PY without pymodbus (scripts/deps.sh test)"; exit 1; }
    for plc_tool in "$@"; do
        command -v "$plc_tool" >/dev/null ||
            { echo "$plc_name: $plc_tool missing (scripts/deps.sh test)"; exit 1; }
    done
    if [ -n "$plc_rig" ] && [ ! -x "$(dirname "$CF")/cellsim" ]; then
        echo "skip $plc_name: no cellsim beside $CF"
        echo "$plc_name: 0 passed, 0 failed"
        exit 0
    fi
    T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-$plc_name.XXXXXX")
    pids=""
    trap 'eval "${plc_atexit:-}"; stop_servers; rm -rf "$T"' EXIT
    trap 'exit 1' INT TERM
    if [ -n "$plc_rig" ]; then # cellsim's part (--part): its nominal and check.uv
        "$CF" gen --dir "$T/part" --nu 40 --nv 30 --count 1000 >/dev/null
    fi
}
# plc_part DIR NU NV COUNT: a part for FIT (`cellfit gen`, noise 0.002 mm)
# in DIR, and its points as x y z in DIR/points.xyz.
plc_part() {
    "$CF" gen --dir "$1" --nu "$2" --nv "$3" --count "$4" --noise 0.002 >/dev/null
    grep -v '^#' "$1/points.uvxyz" | cut -d' ' -f3- >"$1/points.xyz"
}
# serve_start NAME ARGS...: `$CF serve` on 127.0.0.1, port 0, in the
# background, stderr in $T/NAME.log; sets $port and $pid, adds $pid to $pids.
serve_start() {
    name=$1; shift
    rm -f "$T/$name.port"
    "$CF" serve --plc tcp:127.0.0.1:0 --port-file "$T/$name.port" "$@" 2>"$T/$name.log" &
    pid=$!
    pids="$pid ${pids:-}"
    i=0
    while [ ! -s "$T/$name.port" ] && kill -0 "$pid" 2>/dev/null && [ $i -lt 100 ]; do
        sleep 0.1; i=$((i + 1))
    done
    port=$(sed -n 1p "$T/$name.port" 2>/dev/null) # line 2: serve's PID
    [ -n "$port" ] && ok "serve $name listening on 127.0.0.1:$port" ||
        { no "serve $name did not start"; sed 's/^/     /' "$T/$name.log" | head -5; }
}
# py_step SCRIPT SECONDS STEP ARGS...: a Python client step ($HERE/SCRIPT,
# under $PY) with a time limit; its ok/FAIL lines printed and counted.
py_step() {
    script=$1; secs=$2; shift 2
    timeout "$secs" "$PY" "${HERE:-$(dirname "$0")}/$script" "$@" >"$T/py.out" 2>&1
    rc=$?
    cat "$T/py.out"
    pass=$((pass + $(grep -c '^ok ' "$T/py.out")))
    fail=$((fail + $(grep -c '^FAIL' "$T/py.out")))
    [ $rc -eq 0 ] || [ "$(grep -c '^FAIL' "$T/py.out")" -gt 0 ] || no "$script $1 exited $rc"
}
