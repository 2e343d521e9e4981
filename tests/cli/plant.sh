#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plant.sh CELLFIT: results from the cell to the plant with the
# real engines: a Mosquitto broker and a PostgreSQL server of the test's
# own on 127.0.0.1 free ports, `cellfit serve --sim` driven by a PLC
# client (pymodbus, tests/cli/plant.py). The database is stopped during one
# job and stays down for the next, the broker likewise, then both and serve
# itself (the outbox is durable); once everything is back, independent
# clients check that every job is in results.db (sqlite3) and in
# PostgreSQL (psql) exactly once and reached the broker (mosquitto_sub,
# QoS 1, persistent session), each with the figures the PLC read; the
# cell's retained status and its Last Will. Everything started is stopped
# by PID.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
for tool in mosquitto mosquitto_sub psql sqlite3 runuser; do
    command -v $tool >/dev/null || { echo "plant: $tool missing (scripts/deps.sh test)"; exit 1; }
done
# A folder the postgres user can reach (its parents included): /tmp, 755.
T=$(mktemp -d /tmp/cellfit-plant.XXXXXX)
chmod 755 "$T"
. "$HERE/engines.sh" # pg_init, pg_start, pg_stop, psql_admin, mq_start, mq_stop, freeport
[ -x "$PGBIN/pg_ctl" ] || { echo "plant: no PostgreSQL server (scripts/deps.sh test)"; rm -rf "$T"; exit 1; }
pids=""
stop_serve() { stop_servers 100; }
cleanup() {
    stop_serve
    [ -n "${SUBPID:-}" ] && kill -TERM "$SUBPID" 2>/dev/null
    mq_stop
    pg_stop
    [ -n "${CF_KEEP:-}" ] && echo "plant: kept $T" || rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
py() { py_step plant.py 180 "$@"; }

PGPORT=$(freeport)
MQPORT=$(freeport)
# PostgreSQL: a cluster of the test's own, TCP on 127.0.0.1 with passwords
# (scram), the socket in its folder for the set-up.
echo "cellpw-$$-secret" >"$T/pw"
pg_init scram-sha-256 && ok "initdb: a cluster in $PGD" || { no "initdb"; tail -5 "$T/initdb.log"; exit 1; }
pg_start && ok "PostgreSQL on 127.0.0.1:$PGPORT" || { no "PostgreSQL start"; tail -5 "$T/pglog/pg.log"; exit 1; }
psql_admin -c "CREATE ROLE cell LOGIN PASSWORD '$(cat "$T/pw")'" -c "CREATE DATABASE plant OWNER cell" &&
    ok "role cell with a password, database plant" || no "create role and database"
PSQL="runuser -u postgres -- psql -h $PGD -p $PGPORT -U postgres -d plant"

# Mosquitto: loopback only; persistence, so that the checking subscriber's
# QoS 1 session (and what is queued for it) outlives the broker's restart.
cat >"$T/mosquitto.conf" <<CONF
listener $MQPORT 127.0.0.1
allow_anonymous true
persistence true
persistence_location $T/mq/
CONF
mkdir -p "$T/mq"
# Started as root, mosquitto drops to its own user: the folder is its.
id mosquitto >/dev/null 2>&1 && chown mosquitto "$T/mq"
mq_start "$T/mosquitto.conf" "$MQPORT" && ok "Mosquitto pid $MQPID on 127.0.0.1:$MQPORT" || { no "Mosquitto start"; exit 1; }
# The subscriber's persistent session first (-E: subscribe and leave), so
# that nothing published before it listens is lost to it.
SUB="mosquitto_sub -h 127.0.0.1 -p $MQPORT -q 1 -c -i plant-check -v -t plant/#"
$SUB -E && ok "checking subscriber's session (QoS 1, persistent)" || no "subscriber session"
$SUB >"$T/mqtt.out" 2>"$T/sub.err" &
SUBPID=$!

# The cell: a part of 200000 points, results into $T/results.
"$CF" gen --dir "$T" --nu 16 --nv 12 --count 200000 --noise 0.002 >/dev/null
grep -v '^#' "$T/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"
mkdir -p "$T/results"
cat >"$T/cell.conf" <<CONF
nominal = $T/nominal.igs
points = $T/points.xyz
results_dir = $T/results
cell_id = cellA
plant_db = postgresql://cell@127.0.0.1:$PGPORT/plant
plant_db_password = $(cat "$T/pw")
mqtt = mqtt://127.0.0.1:$MQPORT/plant
forward_backoff_max = 1
CONF
start() {
    serve_start "$1" --config "$T/cell.conf" --sim
    simpid=$(sed -n 's/.*rig: cellsim pid \([0-9]*\) on .*/\1/p' "$T/$1.log")
}
start a
J="$T/jobs.jsonl"
: >"$J"
py job "$port" 1001 "$J"
py job "$port" 1002 "$J" "runuser -u postgres -- $PGBIN/pg_ctl -D $PGD -m fast -w stop"
! [ -f "$PGD/postmaster.pid" ] && ok "PostgreSQL stopped during job 1002" || no "PostgreSQL still up"
py job "$port" 1003 "$J"
n=$(sqlite3 "$T/results/results.db" "SELECT count(*) FROM outbox WHERE target = 'pg'")
[ "$n" -ge 4 ] && ok "outbox holds $n PostgreSQL entries while it is down" || no "pg outbox $n"
"$CF" results outbox --db "$T/results/results.db" >"$T/ob.out" 2>&1 &&
    grep -q "pg  *$n" "$T/ob.out" && ok "cellfit results outbox: $n waiting for pg" ||
    no "results outbox: $(cat "$T/ob.out")"
pg_start && ok "PostgreSQL restarted" || no "PostgreSQL restart"
py job "$port" 1004 "$J" "kill -TERM $MQPID; sleep 0.3"
py job "$port" 1005 "$J"
n=$(sqlite3 "$T/results/results.db" "SELECT count(*) FROM outbox WHERE target = 'mqtt'")
[ "$n" -ge 4 ] && ok "outbox holds $n MQTT entries while the broker is down" || no "mqtt outbox $n"
wait "$MQPID" 2>/dev/null
mq_start "$T/mosquitto.conf" "$MQPORT" && ok "Mosquitto restarted (pid $MQPID)" || no "Mosquitto restart"
py job "$port" 1006 "$J"
# Both down, a job, serve stopped and started again: the outbox is durable.
pg_stop
mq_stop
py job "$port" 1007 "$J"
stop_serve
ok "serve stopped with both engines down"
start b
pg_start && mq_start "$T/mosquitto.conf" "$MQPORT" && ok "PostgreSQL and Mosquitto back" || no "engines back"
py job "$port" 1008 "$J"
i=0
while [ "$(sqlite3 "$T/results/results.db" 'SELECT count(*) FROM outbox')" != 0 ] && [ $i -lt 300 ]; do
    sleep 0.1; i=$((i + 1))
done
[ $i -lt 300 ] && ok "outbox drained $((i / 10)).$((i % 10)) s after the last job" ||
    no "outbox not drained: $(sqlite3 "$T/results/results.db" 'SELECT target, attempts, last_error FROM outbox' | head -3)"
sleep 1 # the last messages to the subscriber
kill -0 "$SUBPID" 2>/dev/null && ok "subscriber alive" || no "subscriber died: $(cat "$T/sub.err")"
py verify "$J" "$T/results/results.db" "$PSQL" "$T/mqtt.out"
# cellfit results against the sqlite3 CLI's own count.
DB="$T/results/results.db"
n=$("$CF" results list --db "$DB" --part 1002 | wc -l)
[ "$n" -eq 2 ] && ok "results list --part 1002: 2 jobs (FIT, EXPORT)" || no "results list --part: $n"
n=$("$CF" results export --db "$DB" | wc -l)
[ "$n" -eq "$(($(sqlite3 "$DB" 'SELECT count(*) FROM jobs') + 1))" ] &&
    ok "results export: a header and every row ($n lines)" || no "results export: $n lines"
u=$(sqlite3 "$DB" "SELECT job_uuid FROM jobs WHERE command = 'export' LIMIT 1")
"$CF" results show "$u" --db "$DB" --json >"$T/show.json"
[ "$(json "$T/show.json" job_uuid)" = "$u" ] && [ "$(json "$T/show.json" report_sha256)" = \
    "$(sqlite3 "$DB" "SELECT report_sha256 FROM jobs WHERE job_uuid = '$u'")" ] &&
    ok "results show UUID --json: the row" || no "results show: $(cat "$T/show.json")"
n=$("$CF" results list --db "$DB" --since 2999-01-01 | wc -l)
[ "$n" -eq 0 ] && ok "results list --since the future: nothing" || no "results --since: $n"
grep -q "cellpw-$$-secret" "$T"/a.log "$T"/b.log && no "the password appears in serve's log" ||
    ok "the password never appears in serve's log"
grep -q "plant database unavailable" "$T/a.log" && ok "the outage is logged (WARN)" || no "outage not logged"
grep '^plant/cellA/status' "$T/mqtt.out" | grep -q '"busy"' &&
    grep '^plant/cellA/status' "$T/mqtt.out" | grep -q '"idle"' &&
    ok "status topic: busy and idle seen" || no "status topic: $(grep status "$T/mqtt.out" | head -3)"
# The Last Will: serve killed (its cellsim child too, by PID).
kill -KILL $pids "$simpid" 2>/dev/null
pids=""
sleep 0.5
st=$(mosquitto_sub -h 127.0.0.1 -p "$MQPORT" -t plant/cellA/status -C 1 -W 5 2>/dev/null)
echo "$st" | grep -q '"offline"' && ok "retained status after a crash: offline (the Will)" ||
    no "retained status after a crash: $st"
sqlite3 "$T/results/results.db" 'PRAGMA user_version' | grep -qx 2 && ok "results.db schema version 2" ||
    no "schema version"
echo "plant: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
