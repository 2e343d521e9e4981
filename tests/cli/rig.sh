#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/rig.sh CELLFIT: the hal transports and drivers against cellsim
# (beside CELLFIT) on the real wire protocols: Modbus TCP on 127.0.0.1,
# Modbus RTU and the probe's ASCII protocol over socat pty pairs; each
# fault ends in a successful retry or a clear error; mbpoll and pymodbus
# read the simulated stage as third-party peers; the probe's readings
# agree with the part's truth computed here from the nominal (cellfit gen
# and eval) and cf_part's dent and warp formula.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
SIM=$(dirname "$CF")/cellsim
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-rig.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
# expect CODE NAME CMD...: run under timeout, check the exit code, keep stdout/stderr.
expect() {
    want=$1; name=$2; shift 2
    timeout 60 "$@" >"$T/out" 2>"$T/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok "$name"; else
        no "$name (exit $got, want $want)"; sed 's/^/     /' "$T/err" | head -5; fi
    ! grep -q "Sanitizer\|runtime error" "$T/err" || no "$name: sanitizer report"
}
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'; }
# wait_for FILE PATTERN: until a line matches (at most 10 s; a wait, not a timing assertion)
wait_for() {
    i=0
    while ! grep -q "$2" "$1" 2>/dev/null; do
        i=$((i + 1)); [ $i -gt 200 ] && return 1; sleep 0.05
    done
}
# wait_gone FILE: cellsim removes its control file once obeyed
wait_gone() {
    i=0
    while [ -e "$1" ]; do i=$((i + 1)); [ $i -gt 200 ] && return 1; sleep 0.05; done
}
# start_sim NAME ARGS...: cellsim in the background, waits for its ready line
start_sim() {
    n=$1; shift
    # The old ready line must not be seen before the new process truncates
    # the file (the redirection happens in the background child).
    rm -f "$T/$n.out"
    "$SIM" "$@" >"$T/$n.out" 2>"$T/$n.err" &
    PIDS="$PIDS $!"
    wait_for "$T/$n.out" "cellsim: ready" || { no "$n: cellsim did not come up"; cat "$T/$n.err"; }
}
# start_socat NAME: a pty pair $T/NAME.a <-> $T/NAME.b, waits for socat's loop
start_socat() {
    rm -f "$T/$1.a" "$T/$1.b"
    socat -d -d "pty,raw,echo=0,link=$T/$1.a" "pty,raw,echo=0,link=$T/$1.b" 2>"$T/$1.socat" &
    eval "SOCAT_$1=$!"
    PIDS="$PIDS $!"
    wait_for "$T/$1.socat" "starting data transfer loop" || no "socat $1 did not start"
    sleep 0.1 # socat is ready about 100 ms after the line (HARDWARE-TESTING.md)
}
ctl() { # ctl LINE...: tell cellsim through its control file, wait until obeyed
    printf '%s\n' "$@" >"$T/ctl.tmp" && mv "$T/ctl.tmp" "$T/ctl" && wait_gone "$T/ctl"
}

# The truth: the nominal as cellfit gen writes it (the simulator's built-in
# part), evaluated at u = x/200, v = y/150 (the panel's Greville placement
# reproduces x and y), plus the dent and warp of lib/cf_part.c.
"$CF" gen --dir "$T/part" --count 10 >/dev/null || no "cellfit gen"
truth_d() { # truth_d X Y Z0: the distance the probe must read at stage (X, Y)
    printf '%.17g %.17g\n' "$(awk -v x="$1" 'BEGIN { print x / 200 }')" \
        "$(awk -v y="$2" 'BEGIN { print y / 150 }')" >"$T/uv"
    "$CF" eval "$T/part/nominal.igs" "$T/uv" | awk -v z0="$3" '{ x = $1; y = $2;
        dx = x - 130; dy = y - 60; dent = -0.4 * exp(-2 * (dx * dx + dy * dy) / 225);
        warp = 0.3 * (x / 200 - 0.5) * (y / 150 - 0.5) * 4; printf "%.6f", z0 - ($3 + dent + warp) }'
}

expect 0 "cellsim --help" "$SIM" --help
grep -q -- "--fault KIND" "$T/out" && ok "cellsim --help documents faults" || no "help lacks --fault"
expect 2 "cellsim without a server is bad usage" "$SIM"
expect 2 "cellsim bad fault spec" "$SIM" --tcp 0 --fault crc:x3
grep -q "fault 'crc:x3'" "$T/err" && ok "bad fault spec named" || no "bad fault spec message"
expect 2 "cellfit rig bad URI" "$CF" rig status --stage tcp:127.0.0.1:99999
grep -q "port not 1..65535" "$T/err" && ok "bad URI reason" || no "bad URI reason: $(cat "$T/err")"

# ---- Modbus TCP ----
start_sim tcp --tcp 0 --noise 0 --control "$T/ctl" --verbose
PORT=$(awk '/^cellsim: tcp/ { print $4 }' "$T/tcp.out")
S=tcp:127.0.0.1:$PORT
P=tcp:127.0.0.1:$PORT:2
expect 0 "tcp: status" "$CF" rig status --stage "$S" --probe "$P" --json
[ "$(json "$T/out" homed)" = 0 ] && ok "tcp: not homed at power-up" || no "tcp: homed at power-up"
expect 1 "tcp: move before homing fails" "$CF" rig move 10 10 --stage "$S"
grep -q "not homed.*-212" "$T/err" && ok "tcp: RIG_ENOTHOMED" || no "tcp: $(cat "$T/err")"
expect 0 "tcp: home" "$CF" rig home --stage "$S" --json
[ "$(json "$T/out" x)" = 0 ] && [ "$(json "$T/out" y)" = 0 ] && ok "tcp: homed at (0, 0)" ||
    no "tcp: home at $(cat "$T/out")"
expect 0 "tcp: move 123.456 78.9" "$CF" rig move 123.456 78.9 --stage "$S" --json
near "$(json "$T/out" x)" 123.456 1e-9 && near "$(json "$T/out" y)" 78.9 1e-9 &&
    ok "tcp: position read back" || no "tcp: position $(cat "$T/out")"
expect 1 "tcp: target outside the soft limits" "$CF" rig move 250 0 --stage "$S"
grep -q "soft limits.*-211" "$T/err" && ok "tcp: RIG_ELIMIT" || no "tcp: $(cat "$T/err")"
# Third-party peers read the registers by raw address (docs/rig-devices.md).
hi() { awk -v v="$1" 'BEGIN { u = int(v * 1000 + 0.5); print int(u / 65536) }'; }
lo() { awk -v v="$1" 'BEGIN { u = int(v * 1000 + 0.5); print u % 65536 }'; }
want="5 $(hi 123.456) $(lo 123.456) $(hi 78.9) $(lo 78.9)"
timeout 10 mbpoll -m tcp -p "$PORT" -0 -r 5 -c 5 -1 127.0.0.1 >"$T/mbpoll" 2>&1
got=$(sed -n 's/^\[\([0-9]*\)\]:[[:space:]]*\([0-9]*\).*/\2/p' "$T/mbpoll" | tr '\n' ' ' | sed 's/ $//')
[ "$got" = "$want" ] && ok "mbpoll: status and position registers ($got)" ||
    no "mbpoll read '$got', want '$want'"
timeout 10 /usr/bin/python3 - "$PORT" >"$T/py" 2>&1 <<'EOF'
import sys, types
try:
    import serial_asyncio  # noqa: F401 (pymodbus 3.0 imports it even for TCP)
except ImportError:
    m = types.ModuleType("serial_asyncio")
    m.create_serial_connection = None
    sys.modules["serial_asyncio"] = m
from pymodbus.client import ModbusTcpClient
c = ModbusTcpClient("127.0.0.1", port=int(sys.argv[1]))
c.connect()
r = c.read_holding_registers(5, 5, slave=1)
print(" ".join(str(v) for v in r.registers))
c.close()
EOF
[ "$(cat "$T/py")" = "$want" ] && ok "pymodbus: status and position registers" ||
    no "pymodbus read '$(cat "$T/py")', want '$want'"
d=$(truth_d 123.456 78.9 50)
expect 0 "tcp: probe (Modbus input registers)" "$CF" rig probe --probe "$P" --json
near "$(json "$T/out" last_mm)" "$d" 0.0006 && ok "tcp: probe reads the truth ($d mm)" ||
    no "tcp: probe read $(json "$T/out" last_mm), truth $d"
# Faults, each from the next request on (control file).
ctl "fault crc@tcp:n1"
expect 0 "tcp: corrupted reply retried" "$CF" rig probe --probe "$P" --json
[ "$(json "$T/out" retries)" -ge 1 ] && ok "tcp: corrupted reply cost a retry" || no "tcp: no retry"
ctl "fault busy:n1"
expect 0 "tcp: busy exception retried" "$CF" rig status --stage "$S"
ctl "fault slow@tcp:n2:600"
expect 0 "tcp: slow reply: timeout, late reply dropped, retried" "$CF" rig probe --probe "$P" \
    --count 4 --timeout 300 --late 1200 --json
[ "$(json "$T/out" retries)" = 1 ] && ok "tcp: one retry for one slow reply" ||
    no "tcp: retries $(json "$T/out" retries)"
near "$(json "$T/out" mean_mm)" "$d" 0.0006 && ok "tcp: readings after the slow one are right" ||
    no "tcp: mean $(json "$T/out" mean_mm), truth $d"
ctl "fault disconnect@tcp:n2:400"
expect 0 "tcp: server gone 400 ms: reconnected" "$CF" rig probe --probe "$P" --count 3 --json
[ "$(json "$T/out" reconnects)" -ge 1 ] && ok "tcp: reconnect counted" || no "tcp: no reconnect"
ctl "fault disconnect@tcp:n2:1500"
expect 1 "tcp: server gone longer than --reconnect" "$CF" rig probe --probe "$P" --reconnect 300
grep -q -- "-206" "$T/err" && ok "tcp: RIG_EDISCONNECT" || no "tcp: $(cat "$T/err")"
sleep 1.5
ctl "fault silent@tcp:n1" "fault silent@tcp:n2" "fault silent@tcp:n3"
expect 1 "tcp: silent device" "$CF" rig status --stage "$S" --timeout 100 --retries 2
grep -q "Connection timed out.*attempt 3 of 3.*-202" "$T/err" && ok "tcp: RIG_ETIMEOUT after 3 attempts" ||
    no "tcp: $(cat "$T/err")"
ctl "fault nosurf:n1"
expect 1 "tcp: probe out of range" "$CF" rig probe --probe "$P"
grep -q -- "-208" "$T/err" && ok "tcp: RIG_ENOSURF" || no "tcp: $(cat "$T/err")"
ctl "fault stagefault:n1"
expect 1 "tcp: drive fault during the move" "$CF" rig move 10 10 --stage "$S"
grep -q "drive fault.*-209" "$T/err" && ok "tcp: RIG_EFAULT" || no "tcp: $(cat "$T/err")"
expect 1 "tcp: move refused while the fault is latched" "$CF" rig move 20 20 --stage "$S"
expect 0 "tcp: fault reset" "$CF" rig reset --stage "$S"
expect 0 "tcp: move after the reset" "$CF" rig move 20 20 --stage "$S"
ctl "estop on"
expect 1 "tcp: move under E-stop" "$CF" rig move 30 30 --stage "$S"
grep -q -- "-210" "$T/err" && ok "tcp: RIG_EESTOP" || no "tcp: $(cat "$T/err")"
ctl "estop off"
expect 0 "tcp: move after E-stop release" "$CF" rig move 30 30 --stage "$S"
# Several clients at once (one select() loop, a socket per client).
"$CF" rig probe --probe "$P" --count 300 --json >"$T/c1" 2>&1 &
c1=$!
"$CF" rig probe --probe "$P" --count 300 --json >"$T/c2" 2>&1 &
c2=$!
expect 0 "tcp: a third client meanwhile" "$CF" rig status --stage "$S"
wait $c1; r1=$?
wait $c2; r2=$?
[ $r1 -eq 0 ] && [ $r2 -eq 0 ] && [ "$(json "$T/c1" readings)" = 300 ] &&
    [ "$(json "$T/c2" readings)" = 300 ] && ok "tcp: two clients, 300 readings each" ||
    no "tcp: concurrent clients ($r1, $r2): $(cat "$T/c1" "$T/c2")"
# Faults with a probability (seeded): every reading still arrives.
ctl "fault crc@tcp:p0.2"
expect 0 "tcp: 20% corrupted replies -> all readings" "$CF" rig probe --probe "$P" --count 100 --json
[ "$(json "$T/out" readings)" = 100 ] && [ "$(json "$T/out" retries)" -ge 1 ] &&
    ok "tcp: 100 readings through p=0.2 faults ($(json "$T/out" retries) retries)" ||
    no "tcp: p0.2: $(cat "$T/out")"
stop_all
start_sim tcp2 --tcp 0 --noise 0 --homed
PORT=$(awk '/^cellsim: tcp/ { print $4 }' "$T/tcp2.out")
S=tcp:127.0.0.1:$PORT
P=tcp:127.0.0.1:$PORT:2
# A third-party master moves the stage: slowly, so that it is busy when
# asked (a 100 mm move at 5 mm/s lasts 20 s); then stop.
timeout 10 mbpoll -m tcp -p "$PORT" -0 -t 4 -r 18 -1 127.0.0.1 5 >/dev/null 2>&1 &&
    timeout 10 mbpoll -m tcp -p "$PORT" -0 -t 4 -r 0 -1 127.0.0.1 $(hi 100) $(lo 100) 0 0 1 \
        >/dev/null 2>&1 && ok "mbpoll writes speed, target and the move command" ||
    no "mbpoll write failed"
expect 0 "status during a slow move" "$CF" rig status --stage "$S" --json
[ "$(json "$T/out" busy)" = 1 ] && [ "$(json "$T/out" inpos)" = 0 ] && ok "busy, not in position" ||
    no "during the move: $(cat "$T/out")"
expect 0 "stop" "$CF" rig stop --stage "$S"
expect 0 "status after stop" "$CF" rig status --stage "$S" --json
[ "$(json "$T/out" busy)" = 0 ] && [ "$(json "$T/out" inpos)" = 0 ] && ok "stopped short: idle, not in position" ||
    no "after stop: $(cat "$T/out")"
x=$(json "$T/out" x)
awk -v x="$x" 'BEGIN { exit !(x > 0 && x < 100) }' && ok "stopped between start and target (x = $x)" ||
    no "stopped at x = $x"
timeout 10 mbpoll -m tcp -p "$PORT" -0 -t 4 -r 18 -1 127.0.0.1 1000 >/dev/null 2>&1
# Off the part (inside the stage limits): out of range, a reading not a failure.
expect 0 "tcp: move off the part" "$CF" rig move 205 155 --stage "$S"
expect 1 "tcp: no surface below the probe" "$CF" rig probe --probe "$P"
grep -q -- "-208" "$T/err" && ok "tcp: RIG_ENOSURF off the part" || no "tcp: $(cat "$T/err")"
stop_all

# ---- Noise: Gaussian with the asked sigma around the truth, seeded ----
for seed in 7 7 8; do
    start_sim "noise$seed" --tcp 0 --noise 0.01 --seed $seed --homed
    PORT=$(awk '/^cellsim: tcp/ { print $4 }' "$T/noise$seed.out")
    "$CF" rig move 130 60 --stage "tcp:127.0.0.1:$PORT" >/dev/null 2>&1
    timeout 60 "$CF" rig probe --probe "tcp:127.0.0.1:$PORT:2" --count 400 >"$T/n$seed.$$" 2>&1
    mv "$T/n$seed.$$" "$T/n$seed.${seen:-a}"
    seen=b
    stop_all
done
d=$(truth_d 130 60 50)
awk -v d="$d" '{ s += $1; ss += ($1 - d) ^ 2; n++ } END { m = s / n; sd = sqrt(ss / n);
    printf "%.5f %.5f\n", m - d, sd; exit !(n == 400 && (m - d) ^ 2 < 0.0015 ^ 2 && sd > 0.008 && sd < 0.012) }' \
    "$T/n7.a" >"$T/stat" && ok "noise: mean - truth, sigma = $(cat "$T/stat") (sigma 0.01 asked)" ||
    no "noise: mean - truth, sigma = $(cat "$T/stat")"
cmp -s "$T/n7.a" "$T/n7.b" && ok "noise: the same seed, the same readings" || no "noise: seed 7 not reproduced"
cmp -s "$T/n7.a" "$T/n8.b" && no "noise: seeds 7 and 8 gave the same readings" || ok "noise: another seed, other readings"

# ---- The same part from an IGES file: the same readings ----
start_sim iges --tcp 0 --noise 0 --homed --part "$T/part/nominal.igs"
PORT=$(awk '/^cellsim: tcp/ { print $4 }' "$T/iges.out")
"$CF" rig move 60.5 110.25 --stage "tcp:127.0.0.1:$PORT" >/dev/null 2>&1
expect 0 "iges part: probe" "$CF" rig probe --probe "tcp:127.0.0.1:$PORT:2" --json
d=$(truth_d 60.5 110.25 50)
near "$(json "$T/out" last_mm)" "$d" 0.0006 && ok "iges part: reads the truth ($d mm)" ||
    no "iges part: read $(json "$T/out" last_mm), truth $d"
stop_all

# ---- Modbus RTU and the ASCII probe over socat pty pairs ----
start_socat rtu
start_socat asc
start_sim pty --rtu "$T/rtu.b" --ascii "$T/asc.b" --noise 0 --control "$T/ctl" --verbose
S=rtu:$T/rtu.a:115200:8N1:1
P=rtu:$T/rtu.a:115200:8N1:2
A=tty:$T/asc.a:115200
expect 0 "rtu: home" "$CF" rig home --stage "$S"
expect 0 "rtu: move 150.25 33.5" "$CF" rig move 150.25 33.5 --stage "$S" --json
near "$(json "$T/out" x)" 150.25 1e-9 && near "$(json "$T/out" y)" 33.5 1e-9 &&
    ok "rtu: position read back" || no "rtu: position $(cat "$T/out")"
want="5 $(hi 150.25) $(lo 150.25) $(hi 33.5) $(lo 33.5)"
timeout 10 mbpoll -m rtu -b 115200 -P none -a 1 -0 -r 5 -c 5 -1 "$T/rtu.a" >"$T/mbpoll" 2>&1
got=$(sed -n 's/^\[\([0-9]*\)\]:[[:space:]]*\([0-9]*\).*/\2/p' "$T/mbpoll" | tr '\n' ' ' | sed 's/ $//')
[ "$got" = "$want" ] && ok "mbpoll over RTU: status and position ($got)" ||
    no "mbpoll over RTU read '$got', want '$want'"
d=$(truth_d 150.25 33.5 50)
expect 0 "rtu: probe (input registers, slave 2 on the same line)" "$CF" rig probe --probe "$P" --json
near "$(json "$T/out" last_mm)" "$d" 0.0006 && ok "rtu: probe reads the truth ($d mm)" ||
    no "rtu: probe read $(json "$T/out" last_mm), truth $d"
expect 0 "ascii: probe" "$CF" rig probe --probe "$A" --count 3 --json
near "$(json "$T/out" mean_mm)" "$d" 0.0006 && ok "ascii: probe reads the truth ($d mm)" ||
    no "ascii: probe read $(json "$T/out" mean_mm), truth $d"
for f in crc garble drop; do
    ctl "fault $f@rtu:n2"
    expect 0 "rtu: $f -> retried" "$CF" rig probe --probe "$P" --count 3 --timeout 500 --json
    [ "$(json "$T/out" retries)" = 1 ] && near "$(json "$T/out" mean_mm)" "$d" 0.0006 &&
        ok "rtu: $f cost one retry, readings right" || no "rtu: $f: $(cat "$T/out")"
done
# A reply later than the timeout: waited out and dropped, never taken as
# the answer to the next request (all later readings right, one retry).
ctl "fault slow@rtu:n2:500"
expect 0 "rtu: slow reply -> timeout, recovery" "$CF" rig probe --probe "$P" --count 5 \
    --timeout 300 --late 1200 --json
[ "$(json "$T/out" retries)" = 1 ] && near "$(json "$T/out" mean_mm)" "$d" 0.0006 &&
    ok "rtu: slow reply: one retry, no reply off by one" || no "rtu: slow: $(cat "$T/out")"
ctl "fault slow@rtu:n3:500"
expect 0 "rtu: slow reply between stage requests" "$CF" rig move 150.25 40 --stage "$S" \
    --timeout 300 --late 1200 --json
near "$(json "$T/out" y)" 40 1e-9 && ok "rtu: the move after a slow reply is right" ||
    no "rtu: move after slow reply: $(cat "$T/out")"
ctl "fault disconnect@rtu:n2:300"
expect 0 "rtu: line silent 300 ms -> recovered" "$CF" rig probe --probe "$P" --count 3 --json
[ "$(json "$T/out" retries)" -ge 1 ] && ok "rtu: silent line cost retries" || no "rtu: no retry"
ctl "fault busy@rtu:n1"
expect 0 "rtu: busy exception retried" "$CF" rig status --stage "$S"
ctl "fault stagefault:n1"
expect 1 "rtu: drive fault" "$CF" rig move 10 10 --stage "$S"
grep -q -- "-209" "$T/err" && ok "rtu: RIG_EFAULT" || no "rtu: $(cat "$T/err")"
expect 0 "rtu: fault reset" "$CF" rig reset --stage "$S"
for f in garble drop; do
    ctl "fault $f@ascii:n2"
    expect 0 "ascii: $f -> retried" "$CF" rig probe --probe "$A" --count 3 --timeout 500 --json
    [ "$(json "$T/out" retries)" = 1 ] && ok "ascii: $f cost one retry" ||
        no "ascii: $f: $(cat "$T/out")"
done
expect 0 "rtu: move back" "$CF" rig move 150.25 33.5 --stage "$S"
ctl "fault slow@ascii:n2:500"
expect 0 "ascii: slow reply -> timeout, recovery" "$CF" rig probe --probe "$A" --count 5 \
    --timeout 300 --late 1200 --json
[ "$(json "$T/out" retries)" = 1 ] && near "$(json "$T/out" mean_mm)" "$d" 0.0006 &&
    ok "ascii: slow reply: one retry, readings right" || no "ascii: slow: $(cat "$T/out")"
ctl "fault nosurf@ascii:n1"
expect 1 "ascii: out of range" "$CF" rig probe --probe "$A"
grep -q "M0,FFFFFFF.*-208" "$T/err" && ok "ascii: RIG_ENOSURF" || no "ascii: $(cat "$T/err")"
ctl "fault proberr@ascii:n1"
expect 1 "ascii: sensor error" "$CF" rig probe --probe "$A"
grep -q "ER,M0,01.*-205" "$T/err" && ok "ascii: ER,M0,01 is RIG_EEXCEPTION" || no "ascii: $(cat "$T/err")"
# The cable pulled by hand: socat killed and started again with the same
# links while a client reads; both ends reopen their paths.
pull() { # pull NAME URI: kill NAME's socat mid-run, restart it, the client must recover
    # Request 5's reply is held 1 s: the client is surely mid-run when the
    # mark shows in cellsim's log and socat goes.
    ctl "fault slow@$3:n5:1000"
    n0=$(grep -c "fault slow" "$T/pty.err")
    "$CF" rig probe --probe "$2" --count 400 --reconnect 5000 --json >"$T/pull" 2>&1 &
    cl=$!
    i=0
    while [ "$(grep -c "fault slow" "$T/pty.err")" -le "$n0" ] && [ $i -lt 200 ]; do
        sleep 0.05; i=$((i + 1)); done
    eval "kill \$SOCAT_$1"
    eval "wait \$SOCAT_$1" 2>/dev/null
    start_socat "$1"
    wait $cl
    rc=$?
    [ $rc -eq 0 ] && [ "$(json "$T/pull" readings)" = 400 ] && [ "$(json "$T/pull" reconnects)" -ge 1 ] &&
        ok "$3: socat restarted mid-run: reconnected, 400 readings" ||
        no "$3: cable pull: exit $rc, $(cat "$T/pull")"
}
pull rtu "$P" rtu
pull asc "$A" ascii
# Gone for good: a clear error once reconnect_ms is spent.
ctl "fault slow@rtu:n5:1000"
n0=$(grep -c "fault slow" "$T/pty.err")
"$CF" rig probe --probe "$P" --count 400 --reconnect 500 >"$T/gone" 2>&1 &
cl=$!
i=0
while [ "$(grep -c "fault slow" "$T/pty.err")" -le "$n0" ] && [ $i -lt 200 ]; do
    sleep 0.05; i=$((i + 1)); done
kill $SOCAT_rtu
wait $cl
rc=$?
[ $rc -eq 1 ] && grep -q "line lost, reopening failed for 500 ms.*-206" "$T/gone" &&
    ok "rtu: line gone: RIG_EDISCONNECT after reconnect_ms" || no "rtu: gone: exit $rc, $(cat "$T/gone")"
stop_all

# A sanitized build's reports from cellsim (it exits through main on TERM).
for e in "$T"/*.err; do
    ! grep -q "Sanitizer\|runtime error" "$e" || { no "$(basename "$e"): sanitizer report"; head -20 "$e"; }
done
echo "rig: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
