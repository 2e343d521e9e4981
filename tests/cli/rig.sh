#!/bin/sh
# tests/cli/rig.sh CELLFIT: the hal transports and drivers against cellsim
# (beside CELLFIT) on the real wire protocols: Modbus TCP on 127.0.0.1,
# Modbus RTU and the probe's ASCII protocol over socat pty pairs; each
# fault ends in a successful retry or a clear error; mbpoll and pymodbus
# read the simulated stage as third-party peers; the probe's readings
# agree with the part's truth computed here from the nominal (cellfit gen
# and eval) and cf_part's dent and warp formula.
set -u
CF=$(realpath "$1")
SIM=$(dirname "$CF")/cellsim
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-rig.XXXXXX")
PIDS=""
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
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
pass=0
fail=0
ok() { pass=$((pass + 1)); echo "ok   $1"; }
no() { fail=$((fail + 1)); echo "FAIL $1"; }
# expect CODE NAME CMD...: run under timeout, check the exit code, keep stdout/stderr.
expect() {
    want=$1; name=$2; shift 2
    timeout 60 "$@" >"$T/out" 2>"$T/err"
    got=$?
    if [ "$got" -eq "$want" ]; then ok "$name"; else
        no "$name (exit $got, want $want)"; sed 's/^/     /' "$T/err" | head -5; fi
}
json() { # json FILE KEY: a number or string field of a one-line JSON object
    sed -n "s/.*\"$2\": \"\{0,1\}\([^,\"}]*\)\"\{0,1\}[,}].*/\1/p" "$1"
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
# reproduces x and y), plus the dent and warp of host/cf_part.c.
"$CF" gen --dir "$T/part" --points 10 >/dev/null || no "cellfit gen"
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
    --count 4 --timeout 200 --late 700 --json
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
stop_all

echo "rig: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
