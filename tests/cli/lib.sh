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
