#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plc_slots.sh CELLFIT: `cellfit serve` against dead connections
# and PLC programs as they are written (issue 15, tests/cli/plc_slots.py):
# every slot held by a silent connection plus a slowloris, yet a fresh
# client is served within 3 s, 10 times of 10; TCP keepalive on the
# server's sockets; COMMAND + sequence +
# heartbeat in one request aborts a running job; the sequence rules (0,
# reuse, retransmission); register map version 2 (PART_ID, fit settings,
# JOB_TIME, counters, function 04); a client sending 2,000 refused
# commands gets a handful of log lines, not 2,000. Servers on 127.0.0.1,
# port 0, stopped by PID.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup plc_slots
py() { py_step plc_slots.py 120 "$@"; } # py STEP ARGS...

# A FIT of 200,000 projected points: a job of a few tenths of a second.
plc_part "$T" 16 12 200000
mkdir -p "$T/results"

serve_start a --nominal "$T/nominal.igs" --points "$T/points.xyz" --results "$T/results" \
    --max-clients 8
py slots "$port" 8
py keepalive "$port"
py abortblock "$port"
py seq "$port"
py v2 "$port"
grep -q "evicted (never a request" "$T/a.log" && ok "log: evictions say whom and why" ||
    no "log: no eviction line"

# The log limiter: 2,000 refused commands from one client.
serve_start s --max-rate 0
py spam "$port" 2000
sleep 0.3
n=$(grep -c "command RESET seq .*: refused" "$T/s.log")
m=$(grep -c "more like \"command RESET refused, 109\"" "$T/s.log")
[ "$n" -ge 1 ] && [ "$n" -le 5 ] && ok "log: 2000 refused commands: $n lines, not 2000" ||
    no "log: 2000 refused commands gave $n lines"
kill -TERM "$pid"
wait "$pid"
pids=$(echo "$pids" | sed "s/\\b$pid\\b//")
m=$(grep -c "more like \"command RESET refused, 109\"" "$T/s.log")
total=$(sed -n 's/.* \([0-9]*\) more like "command RESET refused, 109".*/\1/p' "$T/s.log" |
    awk '{ s += $1 } END { print s + 0 }')
[ "$m" -ge 1 ] && [ $((total + n)) -eq 2000 ] &&
    ok "log: the held-back lines counted ($total in $m count lines + $n = 2000)" ||
    no "log: held-back count $total in $m lines + $n lines, want 2000"

if grep -E "Sanitizer|runtime error" "$T/a.log" "$T/s.log" >/dev/null; then
    no "sanitizer reports in the server logs"
    grep -hE "Sanitizer|runtime error" "$T/a.log" "$T/s.log" | head -5
else
    ok "no sanitizer report in the server logs"
fi
stop_servers
echo "plc_slots: $pass passed, $fail failed"
[ $fail -eq 0 ]
