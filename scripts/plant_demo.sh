#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/plant_demo.sh CELLFIT [SECONDS]: `make plant-demo`: a plant on one
# machine: one PostgreSQL server and one Mosquitto broker of its own on
# 127.0.0.1 free ports, 4 cells (`cellfit serve --sim`, each with a PLC
# client looping FIT, EXPORT, ACK_RESULTS) for SECONDS (default 120); the
# database is stopped for a fifth of the run a third of the way in, the
# broker likewise half way. Then the figures: per-cell jobs, latency from a
# job's end to its PostgreSQL row and to its MQTT message (median, p99),
# lost and duplicated counts. Everything started is stopped by PID (the
# database by its data folder): the engines' helpers are tests/cli/engines.sh,
# which tests/cli/plant.sh uses too.
set -u
CF=$(realpath "$1")
SECS=${2:-120}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PY=/usr/bin/python3
NCELL=4
T=$(mktemp -d /tmp/cellfit-plantdemo.XXXXXX)
chmod 755 "$T"
. "$ROOT/tests/cli/engines.sh" # pg_init, pg_start, pg_stop, mq_start, mq_stop, freeport
[ -x "$PGBIN/pg_ctl" ] || { echo "plant-demo: no PostgreSQL server (scripts/deps.sh demo)"; rm -rf "$T"; exit 1; }
pids=""
SUBPID=""
cleanup() {
    for p in $pids; do kill -TERM "$p" 2>/dev/null; done
    for p in $pids; do
        i=0
        while kill -0 "$p" 2>/dev/null && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
        kill -KILL "$p" 2>/dev/null
    done
    [ -n "$SUBPID" ] && kill -TERM "$SUBPID" 2>/dev/null
    mq_stop
    pg_stop
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
now() { date +%s.%N; }
PGPORT=$(freeport)
MQPORT=$(freeport)

mkdir -p "$T/mq"
id mosquitto >/dev/null 2>&1 && chown mosquitto "$T/mq"
pg_init trust || { cat "$T/initdb.log"; exit 1; }
pg_start || { echo "plant-demo: PostgreSQL did not start"; exit 1; }
psql_admin -c "CREATE DATABASE plant" || exit 1
PSQL="runuser -u postgres -- psql -h $PGD -p $PGPORT -U postgres -d plant"
printf 'listener %s 127.0.0.1\nallow_anonymous true\npersistence true\npersistence_location %s/mq/\n' \
    "$MQPORT" "$T" >"$T/mosquitto.conf"
mq_start "$T/mosquitto.conf" "$MQPORT" || { echo "plant-demo: Mosquitto did not start"; exit 1; }
SUB="mosquitto_sub -h 127.0.0.1 -p $MQPORT -q 1 -c -i plant-demo -t plant/#"
$SUB -E
$SUB -F '%U %t %p' >"$T/mqtt.out" 2>/dev/null &
SUBPID=$!
echo "plant-demo: PostgreSQL 127.0.0.1:$PGPORT, Mosquitto 127.0.0.1:$MQPORT, $NCELL cells, ${SECS} s"

"$CF" gen --dir "$T/part" --nu 16 --nv 12 --count 50000 --noise 0.002 >/dev/null
grep -v '^#' "$T/part/points.uvxyz" | cut -d' ' -f3- >"$T/part/points.xyz"
drivers=""
for k in $(seq 1 $NCELL); do
    d="$T/cell$k"
    mkdir -p "$d/results"
    cat >"$d/cell.conf" <<CONF
nominal = $T/part/nominal.igs
points = $T/part/points.xyz
results_dir = $d/results
cell_id = cell$k
plant_db = postgresql://postgres@127.0.0.1:$PGPORT/plant
mqtt = mqtt://127.0.0.1:$MQPORT/plant
forward_backoff_max = 2
log_level = warn
CONF
    "$CF" serve --plc tcp:127.0.0.1:0 --port-file "$d/port" --config "$d/cell.conf" --sim \
        2>"$d/serve.log" &
    pids="$! $pids"
    i=0
    while [ ! -s "$d/port" ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
    timeout $((SECS + 120)) "$PY" "$ROOT/scripts/plant_demo.py" drive "$(sed -n 1p "$d/port")" "$SECS" \
        $((k * 100000)) >"$d/drive.log" 2>&1 &
    drivers="$drivers $!"
done
# The outages: the database for SECS/5 from SECS/3, the broker for SECS/5
# from SECS/2 (overlapping: both down for a while; SECS >= 30).
t0=$(now)
P0=$((SECS / 3)); P1=$((P0 + SECS / 5)); M0=$((SECS / 2)); M1=$((M0 + SECS / 5))
at() { awk -v a="$1" -v b="$t0" 'BEGIN { printf "+%.1f s", a - b }'; }
sleep $P0
a=$(now); pg_stop; echo "plant-demo: PostgreSQL stopped at $(at "$a")"
sleep $((M0 - P0))
c=$(now); mq_stop; echo "plant-demo: Mosquitto stopped at $(at "$c")"
sleep $((P1 - M0))
pg_start; b=$(now); echo "plant-demo: PostgreSQL back at $(at "$b")"
sleep $((M1 - P1))
mq_start "$T/mosquitto.conf" "$MQPORT"; d2=$(now); echo "plant-demo: Mosquitto back at $(at "$d2")"
for p in $drivers; do wait "$p"; done
# Drained: every cell's outbox empty (60 s at most).
i=0
while [ $i -lt 600 ]; do
    left=0
    for k in $(seq 1 $NCELL); do
        n=$(sqlite3 "$T/cell$k/results/results.db" 'SELECT count(*) FROM outbox' 2>/dev/null || echo 1)
        left=$((left + n))
    done
    [ "$left" -eq 0 ] && break
    sleep 0.1; i=$((i + 1))
done
sleep 1
echo "plant-demo: outboxes drained $((i / 10)).$((i % 10)) s after the last job (left: $left)"
"$PY" "$ROOT/scripts/plant_demo.py" report "$T" "$PSQL" "$T/mqtt.out" "$a:$b,$c:$d2"
