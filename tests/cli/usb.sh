#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/usb.sh CELLFIT: the serial (libserialport) and usb (libusb)
# backends end to end, on simulated devices: sim-umock (built beside
# cellfit by make all) runs `cellfit ports` inside a umockdev testbed with
# an FTDI 0403:6001 adapter at /dev/ttyUSB0 (the laser probe behind it) and
# the trigger box 1209:cf01. Expected values come from what the simulator
# is told (its distance table; its encoder model x = 100 k, y = 1000 - 3 k
# for trigger k at k * period us, docs/rig-usb.md), never from cellfit.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
SIM=${SIM_UMOCK:-$(dirname "$CF")/sim-umock}
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-usb.XXXXXX")
trap 'rm -rf "$T"' EXIT
# field KEY WANT NAME: a JSON field of the last output
field() {
    v=$(json "$T/out" "$1")
    [ "$v" = "$2" ] && ok "$3 ($1 = $v)" || no "$3: $1 = '$v', want '$2'"
}
# sim OPTIONS... -- cellfit ARGS...: a client under timeout, in the testbed.
sim() { timeout 60 "$SIM" "$@"; }
if [ ! -x "$SIM" ]; then
    no "sim-umock not found at $SIM (make all builds it)"
    echo "usb: $pass passed, $fail failed"
    exit 1
fi
P=/dev/ttyUSB0

# Listing: libserialport finds the adapter through sysfs, with its USB ids.
expect 0 "ports lists the adapter" sim --no-usb -- "$CF" ports
grep -q "^$P usb 0403:6001 serial CFPROBE1" "$T/out" && ok "ports: $P is 0403:6001" ||
    no "ports: $(cat "$T/out")"
expect 0 "ports --json" sim --no-usb -- "$CF" ports --json
field count 1 "one port"
grep -q '"name": "/dev/ttyUSB0", "usb": "0403:6001"' "$T/out" && ok "ports --json: VID:PID" ||
    no "ports --json: $(cat "$T/out")"

# Probe readings are the simulator's table, in order, with out-of-range.
expect 0 "probe: 5 readings" sim --no-usb --table 1.5,-2.25,oor,3.125 -- "$CF" ports --probe $P --count 5
printf 'reading 1: 1.500 mm\nreading 2: -2.250 mm\nreading 3: out of range\nreading 4: 3.125 mm\nreading 5: 1.500 mm\n' >"$T/want"
cmp -s "$T/out" "$T/want" && ok "probe: the table, out of range included" ||
    no "probe readings: $(tr '\n' '|' <"$T/out")"
expect 0 "probe --baud 9600 --json" sim --no-usb --table 7.5 -- "$CF" ports --probe $P --baud 9600 --count 3 --json
field readings 3 "three readings at 9600 baud"
field mean_mm 7.5 "mean of the table"

# Garbled reply: RIG_EPROTO when not retried; with retries the next reply.
expect 1 "garbled reply, no retries: fails" sim --no-usb --garble 1 -- "$CF" ports --probe $P --retries 0
grep -q "reading 1: error -204" "$T/out" && ok "garbled reply is RIG_EPROTO (-204)" ||
    no "garbled: $(cat "$T/out")"
[ "$(wc -l <"$T/err")" -eq 1 ] && grep -q "malformed" "$T/err" && ok "one error line naming the reply" ||
    no "error line: $(cat "$T/err")"
expect 0 "garbled reply, retried: OK" sim --no-usb --garble 1 --table 1.234,2.5 -- "$CF" ports --probe $P --json
field retries 1 "one retry"
field last_error -204 "after RIG_EPROTO"
field first_mm 2.5 "the retry's reply"
# A probe error code is the device refusing, not retried.
expect 1 "ER,M0,07" sim --no-usb --error 2:07 -- "$CF" ports --probe $P --count 3
grep -q "reading 2: error -205" "$T/out" && grep -q "probe error 07" "$T/err" &&
    ok "ER,M0,07 is RIG_EEXCEPTION with the code" || no "ER: $(cat "$T/out" "$T/err")"
grep -q "reading 3: " "$T/out" && ok "readings go on after a probe error" || no "after ER"

# Adapter pulled: reads fail, reopening by name fails: RIG_EDISCONNECT.
expect 1 "adapter pulled" sim --no-usb --serial-unplug 2 -- "$CF" ports --probe $P --count 5 --reconnect 300 --json
field readings 2 "two readings before the pull"
field last_error -206 "then RIG_EDISCONNECT"
grep -q "reopening for 300 ms failed" "$T/err" && ok "the error says reconnect was tried" ||
    no "unplug error: $(cat "$T/err")"
expect 1 "no such port" sim --no-usb -- "$CF" ports --probe /dev/ttyUSB7
grep -q "cannot open" "$T/err" && ok "no such port: RIG_EOPEN" || no "no port: $(cat "$T/err")"
expect 2 "bad option" "$CF" ports --probe $P --count 0

# Trigger box: identity by control IN, period and arm by control OUT,
# encoder packets by bulk IN, checked against the simulator's model.
expect 0 "trigger box: 12 packets" sim --no-serial -- "$CF" ports --trig 1209:cf01 --count 12 --period 2000
grep -q "firmware 1.2.3, serial 42, 2 axes" "$T/out" && ok "identity via control IN" ||
    no "identity: $(head -1 "$T/out")"
bad=$(awk '/^trigger [0-9]/ { k = n++; if ($2 != k || $4 != 2000 * k || $7 != 100 * k || $8 != 1000 - 3 * k) b++ }
    END { print (n == 12 ? b + 0 : "count " n) }' "$T/out")
[ "$bad" = 0 ] && ok "12 packets: seq, time and encoders as the model" || no "packets: $bad"
expect 0 "trigger box by serial number" sim --no-serial -- "$CF" ports --trig 1209:cf01:TB000042 --json
field serial 42 "serial TB000042 found"
expect 1 "wrong serial number" sim --no-serial -- "$CF" ports --trig 1209:cf01:TB000099
grep -q "no device with that serial number" "$T/err" && ok "wrong serial: says so" ||
    no "serial: $(cat "$T/err")"
expect 1 "no trigger box" sim --no-usb -- "$CF" ports --trig 1209:cf01
grep -q "no such device" "$T/err" && ok "absent box: RIG_EOPEN, no such device" || no "absent: $(cat "$T/err")"

# Faults: silence (timeout), bad CRC, a gap, a pull with and without replug.
expect 1 "box goes silent" sim --no-serial --usb-silent 5 -- "$CF" ports --trig 1209:cf01 --count 10 --timeout 200 --json
field error -202 "silence is RIG_ETIMEOUT"
field packets 5 "after the 5 packets sent"
grep -q "LIBUSB_ERROR_TIMEOUT" "$T/err" && ok "detail names LIBUSB_ERROR_TIMEOUT" || no "timeout: $(cat "$T/err")"
expect 0 "bad CRC" sim --no-serial --usb-badcrc 3 -- "$CF" ports --trig 1209:cf01 --count 10 --json
field crc_errors 1 "one CRC error"
l=$(json "$T/out" lost)
[ "${l:-0}" -ge 1 ] && ok "the bad packet shows as a gap (lost $l)" || no "lost $l"
expect 0 "skipped trigger" sim --no-serial --usb-skip 4 -- "$CF" ports --trig 1209:cf01 --count 10 --json
field lost 1 "one trigger lost"
field crc_errors 0 "no CRC errors"
expect 1 "box pulled" sim --no-serial --usb-unplug 6 -- "$CF" ports --trig 1209:cf01 --count 10 --reconnect 300 --json
field error -206 "pull is RIG_EDISCONNECT"
field packets 6 "after the 6 packets sent"
grep -q "LIBUSB_ERROR_NO_DEVICE" "$T/err" && ok "detail names LIBUSB_ERROR_NO_DEVICE" || no "unplug: $(cat "$T/err")"
expect 0 "box pulled and plugged back" sim --no-serial --usb-unplug 4 --usb-replug 200 -- "$CF" ports --trig 1209:cf01 --count 10 --reconnect 3000 --json
field reconnects 1 "found again"
field rearmed 1 "set up again"
field packets 10 "all packets"

echo "usb: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
