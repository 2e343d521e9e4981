# SPDX-License-Identifier: MIT
# tests/cli/lib.sh: what every tests/cli/*.sh script shares, sourced after
# `set -u`: the pass/fail count and its ok/no lines, expect (exit code, with
# stdout and stderr kept in $T/out and $T/err), json (a field of a one-line
# JSON object), le (numeric <=), and stop_all (the PIDs in $PIDS stopped in
# reverse order: TERM, a short wait, KILL). Not a test itself: the Makefile's
# test-cli leaves it out.
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
stop_servers() {
    for p in ${pids:-}; do kill -TERM "$p" 2>/dev/null; done
    for p in ${pids:-}; do
        i=0
        while kill -0 "$p" 2>/dev/null && [ $i -lt "${1:-50}" ]; do sleep 0.1; i=$((i + 1)); done
        kill -KILL "$p" 2>/dev/null
    done
    pids=""
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
