#!/bin/sh
# SPDX-License-Identifier: MIT
# bench/scan.sh BUILD: the scan benchmark (make bench-scan; issue 19):
# on-the-fly pairing in process (build/scan-bench otf) and over cellsim's
# Modbus TCP (otf-rig: the probe's streaming FIFO), and the laser line
# profiler over GigE Vision on loopback (cellsim --gev, build/scan-bench
# gev) at 0 % and 1 % injected packet loss, every profile streamed into the
# fit; then the profiler through `cellfit scan --fit` at 10^6 and 10^7
# points (points/s, the result's time after the last profile, the peak
# RSS); prints Markdown tables and keeps the JSON lines in
# BUILD/bench/scan.jsonl and scan_cmd.jsonl. Measures, asserts nothing. Environment:
# SCAN_RATE (frames/s asked of the profiler, 20), SCAN_WIDTH (2048),
# SCAN_HEIGHT (64), SCAN_OTF_PERIOD_US (the on-the-fly trigger period over
# Modbus TCP, 25 us: 40,000 points/s offered; the points/s is 1/period, so
# the simulated rig's trigger is what bounds it). The fake camera takes port 3956 on 127.0.0.1: one
# profiler per machine at a time.
set -u
B=$1
OUT=$B/bench
mkdir -p "$OUT"
J=$OUT/scan.jsonl
: >"$J"
RATE=${SCAN_RATE:-20}
W=${SCAN_WIDTH:-2048}
H=${SCAN_HEIGHT:-64}
SER="BENCH$$"
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-scanbench.XXXXXX")
spid=""
cleanup() {
    [ -n "$spid" ] && kill -TERM "$spid" 2>/dev/null && wait "$spid" 2>/dev/null
    rm -rf "$T"
}
trap cleanup EXIT

sim_start() { # sim_start LOSS: cellsim --gev in the background, $G its geometry
    "$B/cellsim" --gev "$SER" --gev-width "$W" --gev-height "$H" --gev-profiles 512 \
        --gev-loss "$1" >"$T/sim.out" 2>"$T/sim.err" &
    spid=$!
    i=0
    while ! grep -q '^cellsim: ready' "$T/sim.out" && kill -0 $spid 2>/dev/null && [ $i -lt 300 ]; do
        sleep 0.1; i=$((i + 1))
    done
    G=$(sed -n "s/^cellsim: gev 127.0.0.1 $SER //p" "$T/sim.out")
    [ -n "$G" ] || { echo "scan bench: cellsim did not start: $(cat "$T/sim.err")" >&2; exit 1; }
}
sim_stop() { kill -TERM "$spid" 2>/dev/null; wait "$spid" 2>/dev/null; spid=""; }

for n in 100000 1000000; do
    timeout 300 "$B/scan-bench" otf $n | tee -a "$J"
done
# Over cellsim's Modbus TCP: 3 rows at 100 mm/s, triggers every SCAN_OTF_PERIOD_US.
"$B/cellsim" --tcp 0 --homed --speed 100 >"$T/mb.out" 2>"$T/mb.err" &
spid=$!
i=0
while ! grep -q '^cellsim: ready' "$T/mb.out" && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
P=$(sed -n 's/^cellsim: tcp 127.0.0.1 //p' "$T/mb.out")
timeout 300 "$B/scan-bench" otf-rig "tcp:127.0.0.1:$P:1" "tcp:127.0.0.1:$P:2" 3 "${SCAN_OTF_PERIOD_US:-25}" 0.002 |
    tee -a "$J"
kill -TERM "$spid" 2>/dev/null; wait "$spid" 2>/dev/null; spid=""
sim_start 0
for n in 1000000 10000000; do
    timeout 300 "$B/scan-bench" gev "gev:127.0.0.1:$SER" "$G" $n "$RATE" | tee -a "$J"
done
sim_stop
sim_start 0.01
timeout 300 "$B/scan-bench" gev "gev:127.0.0.1:$SER" "$G" 1000000 "$RATE" | tee -a "$J"
sim_stop

# Through the command (issue 19): `cellfit scan --method profiler` with the
# streamed fit, 10^6 and 10^7 points (SCAN_CMD_POINTS): points/s, the
# result's time after the last profile, where the passes after the scan
# read the points (held in the job up to 2^20, else the journal read back)
# and the command's peak RSS (getrusage). The nominal is cellfit gen's part.
"$B/cellfit" gen --dir "$T/part" --count 1 --noise 0 >/dev/null
C=$OUT/scan_cmd.jsonl
: >"$C"
sim_start 0
for n in ${SCAN_CMD_POINTS:-1000000 10000000}; do
    rm -f "$T/c.jnl"
    timeout 900 "$B/cellfit" scan --probe "gev:127.0.0.1:$SER" --geometry "$G" --frame-rate "$RATE" \
        --profiles $(((n + W - 1) / W)) --nominal "$T/part/nominal.igs" --journal "$T/c.jnl" \
        --fit "$T/c.igs" --json >>"$C" 2>"$T/c.err" || echo "{\"failed\": \"$(head -1 "$T/c.err")\"}" >>"$C"
done
rm -f "$T/c.jnl"
sim_stop

echo
echo "| method | points | points/s | lost (counted) | fit ready after last | peak RSS |"
echo "|---|---|---|---|---|---|"
awk -v rate="$RATE" -v w="$W" -v h="$H" '
function f(k,   m) { m = $0; if (!match(m, "\"" k "\": [^,}]*")) return ""; m = substr(m, RSTART, RLENGTH); sub(/.*: /, "", m); return m }
f("mode") == "\"otf\"" {
    printf "| on the fly, in process (pairing + fit; part model %.2f s apart) | %s | %s | %s readings, %s triggers, %s duplicates (all injected ones: %s) | %s s | %s kB |\n",
        f("sim_seconds"), f("paired"), f("points_per_s"), f("lost_readings"), f("lost_triggers"), f("dup"),
        f("accounted") == 1 ? "yes" : "NO", f("fit_ready_s"), f("maxrss_kb") }
f("mode") == "\"otf-rig\"" {
    printf "| on the fly over Modbus TCP (cellsim, %s us triggers) | %s | %s | %s dropped by the probe = %s lost on both sides; %s readings, %s triggers | %s s | %s kB |\n",
        f("period_us"), f("paired"), f("points_per_s"), f("dropped_by_probe"), f("both_lost"),
        f("lost_readings"), f("lost_triggers"), f("fit_ready_s"), f("maxrss_kb") }
f("mode") == "\"gev\"" {
    n++; loss = n == 3 ? "1 %" : "0 %"
    printf "| profiler %s x %s at %s frames/s, %s packet loss | %s | %s | %s profiles (%s frames; %s arrived bad) | %s s | %s kB |\n",
        w, h, rate, loss, f("points"), f("points_per_s"), f("lost_profiles"), f("lost_frames"),
        f("bad_frames"), f("fit_ready_s"), f("maxrss_kb") }
' "$J"
echo
echo "| cellfit scan --method profiler --fit | points | points/s | fit ready after the last profile | passes after the scan read | peak RSS |"
echo "|---|---|---|---|---|---|"
awk -v rate="$RATE" '
function f(k,   m) { m = $0; if (!match(m, "\"" k "\": [^,}]*")) return ""; m = substr(m, RSTART, RLENGTH); sub(/.*: /, "", m); gsub(/"/, "", m); return m }
f("failed") != "" { printf "| failed: %s |||||\n", f("failed"); next }
{ printf "| %s profiles of %s points at %s frames/s (%s lost) | %s | %.0f | %.3f s | %s | %s kB |\n",
    f("rows"), f("ny"), rate, f("profiles_lost"), f("points"), f("points_per_s"), f("fit_ready_s"),
    f("fit_points_from"), f("peak_rss_kb") }' "$C"
