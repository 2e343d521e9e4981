#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/demo.sh CELLFIT: the cell's main job end to end on the simulated
# rig. cellsim (beside CELLFIT) plays the stage on Modbus RTU and the laser
# probe on its ASCII protocol, each over a socat pty pair (the wires a real
# cell has); the part on the table is the synthetic panel of lib/cf_part.h
# (nominal + a dent + a warp). `cellfit scan` rasters part of the panel,
# journals every point and streams it into the fit of the nominal's net,
# where beta (Eq. 7 of Brujic et al. 2010) keeps the unmeasured strip at
# nominal; `cellfit report` compares the measured part with the nominal
# (tolerance, colour map). Writes into DEMO_DIR (build/demo): fitted.igs and
# fitted.stp (STEP AP242), points.xyz, report.json, report.dfq (Q-DAS),
# deviations.csv and deviations.ply (per point), deviation-map.png (measured points vs nominal),
# fitted-vs-nominal.png (the updated surface over the whole panel, sampled
# in fitted-grid.xyz), scan.jnl, pids; prints a summary and stops every
# process it started, by PID, also on Ctrl-C or SIGTERM.
#
# Wire choice: RTU over a pty costs about 0.2 ms a request (socat relays,
# no baud-rate pacing), TCP about 0.1 ms; a point is about five requests
# and the 2.5 mm step takes 5 ms at 500 mm/s, so RTU adds about 1 ms a
# point to TCP's 0.5 ms: the realistic wire is kept (measured: 336 points
# at 100000 mm/s, RTU + ASCII 0.42 s, TCP 0.19 s).
#
# Settings (environment): DEMO_DIR, DEMO_REGION x0:x1:y0:y1 (60:200:0:150:
# the strip x < 60 is left unmeasured), DEMO_STEP mm (2.5), DEMO_SPEED
# stage mm/s (500), DEMO_NOISE probe sigma mm (0.002), DEMO_TOL mm (0.1),
# DEMO_BETA (0.03), DEMO_ALPHA (0.1), DEMO_SEED (1), DEMO_MARGIN mm (15:
# check points this far inside / outside the scanned rectangle count as
# measured / unmeasured).
#
# DEMO_METHOD (issue 19): otf (the default) scans on the fly: each raster
# row at constant speed, the probe streaming one reading per trigger over
# its ASCII protocol (cellsim simulates the trigger input), the readings
# paired with the positions latched at the same trigger number, journalled
# and streamed into the fit row by row: DEMO_STEP (0.1 mm between
# triggers), DEMO_PITCH (2 mm between rows), DEMO_PERIOD (50 us between
# triggers: the stage runs at step / period, 2000 mm/s) give 76 rows of
# 1401 points. stop keeps the stop-and-go probe (DEMO_STEP 2.5). profiler
# runs cellsim's GigE Vision line profiler (--gev, Aravis's fake camera on
# 127.0.0.1): DEMO_GEV_WIDTH (512) points a profile, DEMO_GEV_PROFILES
# (200) a pass over the whole part, DEMO_GEV_RATE (50) frames/s of 16
# profiles; the region is then the profiler's pass (no unmeasured strip).
set -u
CF=$1
SIM=$(dirname "$CF")/cellsim
D=${DEMO_DIR:-build/demo}
REGION=${DEMO_REGION:-60:200:0:150}
METHOD=${DEMO_METHOD:-otf}
case $METHOD in
otf) STEP=${DEMO_STEP:-0.1} ;;
stop | profiler) STEP=${DEMO_STEP:-2.5} ;;
*)
    echo "demo: DEMO_METHOD=$METHOD: want otf, stop or profiler" >&2
    exit 1
    ;;
esac
PITCH=${DEMO_PITCH:-2}
PERIOD=${DEMO_PERIOD:-50}
GEV_WIDTH=${DEMO_GEV_WIDTH:-512}
GEV_PROFILES=${DEMO_GEV_PROFILES:-200}
GEV_RATE=${DEMO_GEV_RATE:-50}
GEV_SERIAL=DEMO$$
SPEED=${DEMO_SPEED:-500}
NOISE=${DEMO_NOISE:-0.002}
TOL=${DEMO_TOL:-0.1}
BETA=${DEMO_BETA:-0.03}
ALPHA=${DEMO_ALPHA:-0.1}
SEED=${DEMO_SEED:-1}
MARGIN=${DEMO_MARGIN:-15}
BAUD=115200

die() {
    echo "demo: $*" >&2
    exit 1
}
[ -x "$CF" ] || die "$CF: no cellfit binary (make all)"
[ -x "$SIM" ] || die "$SIM: no cellsim beside $CF (make all)"
command -v socat >/dev/null 2>&1 || die "socat not found (apt-get install socat)"

T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-demo.XXXXXX") || die "mktemp failed"
PIDS=""  # background servers, in start order
CHILD="" # the long foreground step, run in the background so a signal stops it
stop_pid() { # TERM, up to 3 s, KILL; reap it
    kill -TERM "$1" 2>/dev/null
    i=0
    while kill -0 "$1" 2>/dev/null && [ $i -lt 30 ]; do sleep 0.1; i=$((i + 1)); done
    kill -KILL "$1" 2>/dev/null
    wait "$1" 2>/dev/null
}
stop_all() { # the scan first (it stops the stage and syncs the journal), then the servers, last first
    [ -n "$CHILD" ] && stop_pid "$CHILD"
    CHILD=""
    for p in $(echo $PIDS | tr ' ' '\n' | sed '1!G;h;$!d'); do stop_pid "$p"; done
    PIDS=""
}
trap 'stop_all; rm -rf "$T"' EXIT
trap 'echo "demo: interrupted; stopping every process it started" >&2; exit 130' HUP INT TERM
# The servers in a session of their own: a Ctrl-C reaches the scan (which
# then stops the stage and ends the journal, on a rig still there) and this
# script, whose trap stops the servers after it. setsid keeps the PID (a
# background job is no process-group leader, so it does not fork).
DETACH=""
command -v setsid >/dev/null 2>&1 && DETACH=setsid

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
json() { # json FILE KEY: a number or string value of a flat JSON object
    sed -n "s/.*\"$2\": \"\{0,1\}\([^,\"}]*\)\"\{0,1\}[,}].*/\1/p" "$1"
}
wait_for() { # wait_for FILE PATTERN PID: until PATTERN is in FILE (10 s), PID alive
    i=0
    while ! grep -q "$2" "$1" 2>/dev/null; do
        kill -0 "$3" 2>/dev/null || return 1
        i=$((i + 1))
        [ $i -gt 200 ] && return 1
        sleep 0.05
    done
}
run() { # run OUT ERR CMD...: in the background, waited for (a trapped signal ends the wait)
    o=$1 e=$2
    shift 2
    "$@" >"$o" 2>"$e" &
    CHILD=$!
    wait "$CHILD"
    rc=$?
    CHILD=""
    return $rc
}

rm -rf "$D"
mkdir -p "$D" || die "$D: cannot create"
t_all=$(now)
IFS=: read -r X0 X1 Y0 Y1 <<EOF
$REGION
EOF

# 1. The CAD side: the nominal the cell fits against, and cellfit gen's
# check grid of the true part (the same lib/cf_part.c formula cellsim's
# built-in part uses; tests/cli/demo.sh checks that they agree).
"$CF" gen --dir "$D/part" --count 1 --noise 0 >/dev/null || die "cellfit gen failed"
NOM=$D/part/nominal.igs

# 2. The rig: two pty pairs, cellsim on one end of each; a second,
# noise-free cellsim on TCP answers "what is really there" for the summary.
t=$(now)
$DETACH socat -d -d "pty,raw,echo=0,link=$T/rtu.a" "pty,raw,echo=0,link=$T/rtu.b" 2>"$T/socat1.err" &
PIDS="$PIDS $!"
wait_for "$T/socat1.err" "starting data transfer loop" $! || die "socat (RTU pair) did not start: $(cat "$T/socat1.err")"
$DETACH socat -d -d "pty,raw,echo=0,link=$T/asc.a" "pty,raw,echo=0,link=$T/asc.b" 2>"$T/socat2.err" &
PIDS="$PIDS $!"
wait_for "$T/socat2.err" "starting data transfer loop" $! || die "socat (ASCII pair) did not start: $(cat "$T/socat2.err")"
GEV=""
[ "$METHOD" = profiler ] && GEV="--gev $GEV_SERIAL --gev-width $GEV_WIDTH --gev-height 16 --gev-profiles $GEV_PROFILES"
# shellcheck disable=SC2086
$DETACH "$SIM" --rtu "$T/rtu.b" --ascii "$T/asc.b" --homed --speed "$SPEED" --seed "$SEED" \
    --noise "$NOISE" $GEV >"$T/sim.out" 2>"$T/sim.err" &
SIMPID=$!
PIDS="$PIDS $SIMPID"
wait_for "$T/sim.out" "^cellsim: ready pid $SIMPID\$" $SIMPID || die "cellsim did not come up: $(cat "$T/sim.err")"
$DETACH "$SIM" --tcp 0 --homed --speed 65535 --noise 0 >"$T/truth.out" 2>"$T/truth.err" &
TRUTHPID=$!
PIDS="$PIDS $TRUTHPID"
wait_for "$T/truth.out" "^cellsim: ready pid $TRUTHPID\$" $TRUTHPID || die "cellsim (truth) did not come up: $(cat "$T/truth.err")"
TRUTHPORT=$(sed -n 's/^cellsim: tcp 127.0.0.1 \([0-9]*\)$/\1/p' "$T/truth.out")
printf 'cellsim %s\nsocat %s\nsocat %s\ncellsim-truth %s\n' "$SIMPID" $(echo $PIDS | cut -d' ' -f1-2) \
    "$TRUTHPID" >"$D/pids"
t_rig=$(since "$t")
STAGE=rtu:$T/rtu.a:$BAUD:8N1:1
PROBE=tty:$T/asc.a:$BAUD

# 3. Scan and fit: the serpentine raster over the region (or the
# profiler's pass), every point journalled and streamed into the fit.
case $METHOD in
otf)
    HOW="on the fly, a trigger every $PERIOD us, rows $PITCH mm apart (stage on Modbus RTU, probe streaming ASCII)"
    set -- --method otf --stage "$STAGE" --probe "$PROBE" --region "$REGION" --step "$STEP" \
        --pitch "$PITCH" --period "$PERIOD"
    ;;
profiler)
    GEOM=$(sed -n 's/^cellsim: gev //p' "$T/sim.out")
    [ -n "$GEOM" ] || die "cellsim printed no profiler geometry: $(cat "$T/sim.err")"
    set -- $(echo "$GEOM" | awk '{ for (i = 1; i < NF; i++) g[$i] = $(i + 1)
        printf "%s %s %s %s", g["x0"], g["x0"] + (g["profiles"] - 1) * g["dx"], g["y0"], g["y0"] + (g["width"] - 1) * g["dy"] }')
    X0=$1 X1=$2 Y0=$3 Y1=$4
    REGION=$X0:$X1:$Y0:$Y1
    STEP=$(echo "$GEOM" | awk '{ for (i = 1; i < NF; i++) if ($i == "dx") printf "%.3f", $(i + 1) }')
    HOW="GigE Vision line profiler ($GEV_WIDTH points a profile, $GEV_RATE frames of 16 profiles/s, cellsim's fake camera on 127.0.0.1)"
    set -- --method profiler --probe "gev:127.0.0.1:$GEV_SERIAL" --geometry "$GEOM" --frame-rate "$GEV_RATE"
    ;;
*)
    HOW="stop and go, stage $SPEED mm/s on Modbus RTU, probe ASCII"
    set -- --method stop --stage "$STAGE" --probe "$PROBE" --region "$REGION" --step "$STEP"
    ;;
esac
echo "demo: scanning x $X0..$X1, y $Y0..$Y1 mm, step $STEP mm ($HOW)"
t=$(now)
if [ -t 2 ]; then SCANERR=/dev/stderr; else SCANERR=$T/scan.err; fi # the progress bar on a terminal
run "$T/scan.out" "$SCANERR" "$CF" scan "$@" --nominal "$NOM" \
    --journal "$D/scan.jnl" --alpha "$ALPHA" --beta "$BETA" \
    --fit "$D/fitted.igs" --job-id 1 --report "$T/scan.json" ||
    die "scan failed$([ -f "$T/scan.err" ] && echo ": $(tail -n 1 "$T/scan.err")")"
t_scan=$(since "$t")

# 4. Report: the measured points against the nominal (the inspection), the
# fitted surface against the nominal over the whole panel, the fitted
# surface against the true part, and the truth at the deepest point.
t=$(now)
"$CF" journal export "$D/scan.jnl" --out "$D/points.xyz" || die "journal export failed"
"$CF" report "$NOM" "$D/points.xyz" --tol "$TOL" --png "$D/deviation-map.png" --json \
    --csv "$D/deviations.csv" --ply "$D/deviations.ply" --dfq "$D/report.dfq" \
    --part-number "DEMO-PANEL" --part-name "cellfit demo panel" --part-id "demo-1" \
    >"$T/dev.json" 2>"$T/report.err" || die "report failed: $(cat "$T/report.err")"
"$CF" convert "$D/fitted.igs" "$D/fitted.stp" 2>"$T/report.err" ||
    die "convert to STEP failed: $(cat "$T/report.err")"
awk 'BEGIN { for (j = 0; j <= 150; j++) for (i = 0; i <= 200; i++) printf "%.6f %.6f\n", i / 200, j / 150 }' >"$T/grid.uv"
"$CF" eval "$D/fitted.igs" "$T/grid.uv" >"$D/fitted-grid.xyz" || die "eval failed"
"$CF" report "$NOM" "$D/fitted-grid.xyz" --tol "$TOL" --png "$D/fitted-vs-nominal.png" --json \
    >"$T/fdev.json" 2>"$T/report.err" || die "report (fitted) failed: $(cat "$T/report.err")"
"$CF" info "$D/fitted.igs" --json >"$T/info.json" || die "info failed"
# Fitted vs true part on the check grid: normal distances of the true points
# to the fitted surface where measured; fitted vs nominal (and true vs
# nominal, for contrast) where not.
"$CF" project "$D/fitted.igs" "$D/part/check.xyz" >"$T/ft.txt" || die "project failed"
"$CF" eval "$D/fitted.igs" "$D/part/check.uv" >"$T/fc.xyz" || die "eval failed"
"$CF" project "$NOM" "$T/fc.xyz" >"$T/fn.txt" || die "project failed"
"$CF" project "$NOM" "$D/part/check.xyz" >"$T/tn.txt" || die "project failed"
paste "$D/part/check.xyz" "$T/ft.txt" "$T/fn.txt" "$T/tn.txt" | awk -v x0="$X0" -v x1="$X1" \
    -v y0="$Y0" -v y1="$Y1" -v m="$MARGIN" '
    function abs(a) { return a < 0 ? -a : a }
    { x = $1; y = $2
      if (x >= x0 + m && x <= x1 - m && y >= y0 + m && y <= y1 - m) {
          d = abs($6); ss += d * d; n++; if (d > mx) mx = d }
      else if (x <= x0 - m || x >= x1 + m || y <= y0 - m || y >= y1 + m) {
          un++; if (abs($9) > fn) fn = abs($9); if (abs($12) > tn) tn = abs($12) } }
    END { printf "%d %.6f %.6f %d %.6f %.6f\n", n, n ? sqrt(ss / n) : 0, mx, un, fn, tn }' >"$T/check.txt"
read -r NCHK FT_RMS FT_MAX NUN UN_FN UN_TN <"$T/check.txt"
# The deepest point of the fitted surface below the nominal, and the
# noise-free simulator's reading there.
imin=$(json "$T/fdev.json" min_index | awk '{ printf "%d", $1 }')
set -- $(sed -n "$((imin + 1))p" "$D/fitted-grid.xyz")
DX=$(printf '%.3f' "$1")
DY=$(printf '%.3f' "$2")
"$CF" scan --stage "tcp:127.0.0.1:$TRUTHPORT:1" --probe "tcp:127.0.0.1:$TRUTHPORT:2" --nominal "$NOM" \
    --journal "$T/truth.jnl" --region "$DX:$DX:$DY:$DY" --step 1 >/dev/null 2>"$T/truth.err" ||
    die "truth reading failed: $(tail -n 1 "$T/truth.err")"
"$CF" journal export "$T/truth.jnl" --out "$T/truth.xyz" || die "journal export failed"
"$CF" report "$NOM" "$T/truth.xyz" --tol "$TOL" --json >"$T/tdev.json" || die "report (truth) failed"
t_report=$(since "$t")

# 5. report.json: the figures of the summary, one flat object.
S=$T/scan.json
NPTS=$(json "$S" points)
RATE=$(awk -v n="$(json "$S" done)" -v s="$(json "$S" seconds)" 'BEGIN { printf "%.0f", n / s }')
# The fast methods' own figures: the points/s of the scan alone, the fit's
# readiness after the last row, and every loss counted (0 when not asked).
jn() { v=$(json "$S" "$1"); echo "${v:-0}"; }
SCANRATE=$(jn points_per_s | awk '{ printf "%.0f", $1 }')
[ "$METHOD" = stop ] && SCANRATE=$RATE
cat >"$D/report.json" <<EOF
{"points": $NPTS, "planned": $(json "$S" planned), "flagged": $(json "$S" flagged), "nx": $(json "$S" nx), "ny": $(json "$S" ny), "step": $STEP, "region": "$REGION", "control_points": $(json "$T/info.json" control_points), "nu": $(json "$T/info.json" nu), "nv": $(json "$T/info.json" nv), "alpha": $ALPHA, "beta": $BETA, "rms": $(json "$S" rms), "max_abs": $(json "$S" max_abs), "nominal_rms": $(json "$S" nominal_rms), "nominal_max_abs": $(json "$S" nominal_max_abs), "tol": $TOL, "within_tol_pct": $(json "$T/dev.json" within_tol_pct), "deviation_rms": $(json "$T/dev.json" rms), "deviation_min": $(json "$T/dev.json" min), "deviation_max": $(json "$T/dev.json" max), "dent_x": $DX, "dent_y": $DY, "dent_found": $(json "$T/fdev.json" min), "dent_true": $(json "$T/tdev.json" min), "noise": $NOISE, "check_measured": $NCHK, "fit_vs_true_rms": $FT_RMS, "fit_vs_true_max_abs": $FT_MAX, "check_unmeasured": $NUN, "unmeasured_fit_vs_nominal_max_abs": $UN_FN, "unmeasured_true_vs_nominal_max_abs": $UN_TN, "margin": $MARGIN, "speed": $SPEED, "points_per_s": $RATE, "method": "$METHOD", "scan_points_per_s": $SCANRATE, "fit_ready_s": $(jn fit_ready_s), "fit_solve_s": $(jn fit_solve_s), "lost_readings": $(jn lost_readings), "lost_triggers": $(jn lost_triggers), "both_lost": $(jn both_lost), "overrun": $(jn overrun), "dropped_by_probe": $(jn dropped_by_probe), "rows_cut": $(jn rows_cut), "profiles_lost": $(jn profiles_lost), "frames_lost": $(jn frames_lost), "dropouts": $(jn dropouts), "seconds_rig": $t_rig, "seconds_scan_fit": $t_scan, "seconds_report": $t_report, "fitted": "$D/fitted.igs", "points_file": "$D/points.xyz", "png": "$D/deviation-map.png", "png_fitted": "$D/fitted-vs-nominal.png", "journal": "$D/scan.jnl", "step_file": "$D/fitted.stp", "csv": "$D/deviations.csv", "ply": "$D/deviations.ply", "dfq": "$D/report.dfq"}
EOF

# 6. The summary.
R=$D/report.json
f() { awk -v v="$(json "$R" "$1")" -v fmt="$2" 'BEGIN { printf fmt, v }'; }
echo "== cellfit demo: the cell's job on the simulated rig"
echo "rig:     stage Modbus RTU $BAUD 8N1 (pty), probe ASCII (pty), cellsim pid $SIMPID; probe noise sigma $NOISE mm"
echo "scan:    $METHOD: x $X0..$X1 y $Y0..$Y1 mm, step $STEP mm: $NPTS points ($(json "$R" nx) x $(json "$R" ny)), $(json "$R" flagged) without surface; $SCANRATE points/s scanning, $RATE points/s with the fit"
[ "$METHOD" = stop ] || echo "losses:  readings $(json "$R" lost_readings), triggers $(json "$R" lost_triggers), both sides $(json "$R" both_lost), overrun $(json "$R" overrun), dropped by the probe $(json "$R" dropped_by_probe), rows cut $(json "$R" rows_cut), profiles $(json "$R" profiles_lost) ($(json "$R" frames_lost) frames); fit solved $(f fit_solve_s %.3f) s after the last row, checked against every point $(f fit_ready_s %.2f) s after it"
echo "fit:     $(json "$R" control_points) control points ($(json "$R" nu) x $(json "$R" nv)), alpha $ALPHA beta $BETA: residual rms $(f rms %.4f) mm, max $(f max_abs %.4f) mm"
echo "part:    vs nominal, tol +-$TOL mm: $(f within_tol_pct %.1f) % of points within; deviation rms $(f deviation_rms %.4f), min $(f deviation_min %+.4f), max $(f deviation_max %+.4f) mm"
echo "dent:    deepest $(f dent_found %+.4f) mm at ($DX, $DY) on the fitted surface; simulator's true part there $(f dent_true %+.4f) mm"
echo "truth:   fitted vs true part at $NCHK check points >= $MARGIN mm inside the scan: rms $(f fit_vs_true_rms %.4f) mm, max $(f fit_vs_true_max_abs %.4f) mm (noise sigma $NOISE)"
echo "beta:    unmeasured area ($NUN check points >= $MARGIN mm outside the scan): fitted vs nominal max $(f unmeasured_fit_vs_nominal_max_abs %.4f) mm (the true part is up to $(f unmeasured_true_vs_nominal_max_abs %.4f) mm off there: kept at nominal)"
echo "time:    rig up $t_rig s, scan + streamed fit $t_scan s, report $t_report s, total $(since "$t_all") s"
echo "files:   $D/: fitted.igs fitted.stp points.xyz report.json report.dfq deviations.csv deviations.ply"
echo "         deviation-map.png fitted-vs-nominal.png scan.jnl"
stop_all
echo "stopped: cellsim $SIMPID, socat $(sed -n 's/^socat //p' "$D/pids" | tr '\n' ' ')and cellsim $TRUTHPID (truth)"
