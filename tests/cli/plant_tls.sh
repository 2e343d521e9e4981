#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/plant_tls.sh CELLFIT: results to the plant over TLS, with the
# real engines on 127.0.0.1 free ports: certificates made by openssl in
# the test's folder (a CA, the servers' certificate for 127.0.0.1, a
# client certificate, and a second CA that signed none of them);
# PostgreSQL with ssl = on that takes TCP connections over TLS alone
# (hostssl), Mosquitto with a TLS listener that requires a client
# certificate. `cellfit serve --sim` forwards with sslmode=verify-full
# (sslrootcert) and mqtts:// (mqtt_cafile, mqtt_certfile, mqtt_keyfile):
# its jobs arrive (psql, a mosquitto_sub over TLS; pg_stat_ssl says the
# forwarder's connection is encrypted). With the other CA both refuse the
# servers, the log says why (certificate verify failed), the jobs wait in
# the outbox; with the right CA again they arrive, every job once in
# PostgreSQL with the figures the PLC read. Everything started is stopped
# by PID (the database by its data folder).
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
HERE=$(cd "$(dirname "$0")" && pwd)
PY=/usr/bin/python3
for tool in openssl mosquitto mosquitto_sub psql sqlite3 runuser; do
    command -v $tool >/dev/null || { echo "plant_tls: $tool missing (scripts/deps.sh test)"; exit 1; }
done
T=$(mktemp -d /tmp/cellfit-plantls.XXXXXX)
chmod 755 "$T"
. "$HERE/engines.sh"
[ -x "$PGBIN/pg_ctl" ] || { echo "plant_tls: no PostgreSQL server (scripts/deps.sh test)"; rm -rf "$T"; exit 1; }
pids=""
SUBPID=""
stop_serve() { stop_servers 100; }
cleanup() {
    stop_serve
    [ -n "$SUBPID" ] && kill -TERM "$SUBPID" 2>/dev/null
    mq_stop
    pg_stop
    [ -n "${CF_KEEP:-}" ] && echo "plant_tls: kept $T" || rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM
py() { py_step plant.py 180 "$@"; }
PGPORT=$(freeport)
MQPORT=$(freeport)

# Certificates (P-256 keys, two days): ca signs the servers' (127.0.0.1 as
# an IP address and localhost) and the client's; other signs nothing here.
C="$T/tls"
mkdir -p "$C" && chmod 755 "$C"
key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$C/$1.key" 2>>"$C/log"; }
ca() { key "$1" && openssl req -x509 -key "$C/$1.key" -out "$C/$1.pem" -days 2 -subj "/CN=cellfit test CA $1" 2>>"$C/log"; }
leaf() { # leaf NAME CA EXTENSIONS
    key "$1" && openssl req -new -key "$C/$1.key" -out "$C/$1.csr" -subj "/CN=$1" 2>>"$C/log" &&
        printf '%s\n' "$3" >"$C/$1.ext" &&
        openssl x509 -req -in "$C/$1.csr" -CA "$C/$2.pem" -CAkey "$C/$2.key" -CAcreateserial \
            -days 2 -extfile "$C/$1.ext" -out "$C/$1.pem" 2>>"$C/log"
}
ca ca && ca other && leaf server ca "subjectAltName=IP:127.0.0.1,DNS:localhost" &&
    leaf client ca "extendedKeyUsage=clientAuth" &&
    ok "openssl: a CA, the servers' and a client's certificates, another CA" ||
    { no "certificates: $(tail -3 "$C/log")"; exit 1; }
openssl verify -CAfile "$C/ca.pem" "$C/server.pem" >/dev/null 2>&1 &&
    ! openssl verify -CAfile "$C/other.pem" "$C/server.pem" >/dev/null 2>&1 &&
    ok "openssl verify: the servers' certificate is ca's, not other's" || no "openssl verify"
# Each server reads its own copy of the key (PostgreSQL: its owner, 0600).
cp "$C/server.key" "$C/pg.key" && chown postgres "$C/pg.key" && chmod 600 "$C/pg.key"
cp "$C/server.key" "$C/mq.key" && chmod 600 "$C/mq.key"
id mosquitto >/dev/null 2>&1 && chown mosquitto "$C/mq.key"

# PostgreSQL: ssl on, TCP only over TLS (hostssl), scram passwords.
echo "tlspw-$$-secret" >"$T/pw"
pg_init scram-sha-256 && sed -i 's/^host /hostssl /' "$PGD/pg_hba.conf" &&
    ok "initdb; pg_hba.conf: hostssl only" || { no "initdb"; tail -5 "$T/initdb.log"; exit 1; }
pg_start "-c ssl=on -c ssl_cert_file=$C/server.pem -c ssl_key_file=$C/pg.key" &&
    ok "PostgreSQL with ssl = on, 127.0.0.1:$PGPORT" || { no "PostgreSQL start"; tail -5 "$T/pglog/pg.log"; exit 1; }
psql_admin -c "CREATE ROLE cell LOGIN PASSWORD '$(cat "$T/pw")'" -c "CREATE DATABASE plant OWNER cell" &&
    ok "role cell, database plant" || no "role and database"
URL="postgresql://cell@127.0.0.1:$PGPORT/plant"
PGPASSWORD=$(cat "$T/pw") psql "$URL?sslmode=disable" -qAt -c 'SELECT 1' >/dev/null 2>"$T/nossl.err" &&
    no "psql without TLS got in" || ok "psql without TLS: refused ($(grep -o 'no encryption' "$T/nossl.err" | head -1))"
PGPASSWORD=$(cat "$T/pw") psql "$URL?sslmode=verify-full&sslrootcert=$C/ca.pem" -qAt \
    -c 'SELECT ssl FROM pg_stat_ssl WHERE pid = pg_backend_pid()' >"$T/ssl.out" 2>&1 &&
    grep -qx t "$T/ssl.out" && ok "psql sslmode=verify-full with ca: in, encrypted" || no "psql verify-full: $(cat "$T/ssl.out")"

# Mosquitto: a TLS listener on loopback that wants a client certificate.
cat >"$T/mosquitto.conf" <<CONF
listener $MQPORT 127.0.0.1
allow_anonymous true
cafile $C/ca.pem
certfile $C/server.pem
keyfile $C/mq.key
require_certificate true
CONF
mq_start "$T/mosquitto.conf" "$MQPORT" && ok "Mosquitto with a TLS listener, pid $MQPID, 127.0.0.1:$MQPORT" ||
    { no "Mosquitto start: $(tail -3 "$T/mq.log")"; exit 1; }
SUBTLS="--cafile $C/ca.pem --cert $C/client.pem --key $C/client.key"
# shellcheck disable=SC2086
mosquitto_sub -h 127.0.0.1 -p "$MQPORT" $SUBTLS -t x -C 1 -W 1 -i tls-probe >/dev/null 2>"$T/probe.err"
rc=$?
[ $rc -eq 27 ] && ok "mosquitto_sub over TLS with the client certificate: connected (then its -W timeout)" ||
    no "mosquitto_sub over TLS: exit $rc $(cat "$T/probe.err")"
# shellcheck disable=SC2086
mosquitto_sub -h 127.0.0.1 -p "$MQPORT" --cafile "$C/other.pem" --cert "$C/client.pem" --key "$C/client.key" \
    -t x -C 1 -W 2 -i other-probe >/dev/null 2>"$T/probe.err"
rc=$?
[ $rc -ne 27 ] && [ $rc -ne 0 ] && ok "mosquitto_sub trusting the other CA: refused (exit $rc)" ||
    no "mosquitto_sub with the other CA got in (exit $rc)"
# shellcheck disable=SC2086
SUB="mosquitto_sub -h 127.0.0.1 -p $MQPORT $SUBTLS -q 1 -c -i tls-check -v -t plant/#"
$SUB -E && ok "checking subscriber's session over TLS" || no "subscriber session"
$SUB >"$T/mqtt.out" 2>"$T/sub.err" &
SUBPID=$!

"$CF" gen --dir "$T" --nu 16 --nv 12 --count 20000 --noise 0.002 >/dev/null
grep -v '^#' "$T/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"
mkdir -p "$T/results"
DB="$T/results/results.db"
conf() { # conf FILE CA: the cell with TLS towards both engines, trusting CA
    cat >"$1" <<CONF
nominal = $T/nominal.igs
points = $T/points.xyz
results_dir = $T/results
cell_id = cellS
plant_db = $URL?sslmode=verify-full&sslrootcert=$C/$2.pem
plant_db_password = $(cat "$T/pw")
mqtt = mqtts://127.0.0.1:$MQPORT/plant
mqtt_cafile = $C/$2.pem
mqtt_certfile = $C/client.pem
mqtt_keyfile = $C/client.key
forward_backoff_max = 1
CONF
}
conf "$T/good.conf" ca
conf "$T/bad.conf" other
drained() { # drained SECONDS: the outbox empty within them
    i=0
    while [ "$(sqlite3 "$DB" 'SELECT count(*) FROM outbox')" != 0 ] && [ $i -lt $(($1 * 10)) ]; do
        sleep 0.1; i=$((i + 1))
    done
    [ "$(sqlite3 "$DB" 'SELECT count(*) FROM outbox')" = 0 ]
}
pgrows() { psql_admin -d plant -c 'SELECT count(*) FROM jobs' 2>/dev/null || echo 0; }
J="$T/jobs.jsonl"
: >"$J"

serve_start a --config "$T/good.conf" --sim
py job "$port" 2001 "$J"
py job "$port" 2002 "$J"
drained 20 && ok "outbox drained over TLS" ||
    no "outbox not drained: $(sqlite3 "$DB" 'SELECT target, attempts, last_error FROM outbox' | head -2); $(grep forward "$T/a.log" | tail -2)"
[ "$(pgrows)" = 4 ] && ok "PostgreSQL: 4 rows (2 jobs, FIT and EXPORT)" || no "PostgreSQL rows $(pgrows)"
n=$(psql_admin -d plant -c "SELECT count(*) FROM pg_stat_ssl JOIN pg_stat_activity USING (pid) WHERE application_name = 'cellfit' AND ssl")
[ "$n" = 1 ] && ok "pg_stat_ssl: the forwarder's connection is encrypted" || no "pg_stat_ssl: $n"
sleep 0.5
n=$(grep -c '^plant/cellS/result ' "$T/mqtt.out")
[ "$n" -ge 4 ] && ok "the TLS subscriber got $n result messages" || no "TLS subscriber: $n results"
grep -q "broker 127.0.0.1:$MQPORT connected" "$T/a.log" && ok "serve: broker connected (mqtts://)" || no "no broker connection logged"
stop_serve

# The other CA: both servers refused, the reason in the log, jobs kept.
serve_start b --config "$T/bad.conf" --sim
py job "$port" 2003 "$J"
i=0 # both refusals logged (the first attempts come at once; 10 s at most)
while [ "$(grep -c 'unavailable' "$T/b.log")" -lt 2 ] && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
grep "plant database unavailable" "$T/b.log" | grep -q "certificate verify failed" &&
    ok "wrong CA, PostgreSQL: refused, 'certificate verify failed' in the log" ||
    no "PostgreSQL wrong CA: $(grep forward "$T/b.log" | head -3)"
grep "broker 127.0.0.1:$MQPORT unavailable" "$T/b.log" | grep -q "TLS handshake failed.*certificate verify failed" &&
    ok "wrong CA, broker: refused, 'TLS handshake failed: ... certificate verify failed' in the log" ||
    no "broker wrong CA: $(grep forward "$T/b.log" | head -3)"
grep "unavailable" "$T/b.log" | sed 's/^/     /' | cut -c1-220
[ "$(sqlite3 "$DB" "SELECT count(*) FROM outbox WHERE target = 'pg'")" = 2 ] &&
    [ "$(sqlite3 "$DB" "SELECT count(*) FROM outbox WHERE target = 'mqtt'")" = 2 ] &&
    [ "$(pgrows)" = 4 ] && ok "the job waits in the outbox (2 + 2 entries); PostgreSQL still 4 rows" ||
    no "outbox $(sqlite3 "$DB" 'SELECT target, count(*) FROM outbox GROUP BY target'), pg $(pgrows)"
grep -q "tlspw-$$-secret" "$T"/a.log "$T"/b.log && no "the password appears in serve's log" ||
    ok "the password never appears in serve's log"
stop_serve

# The right CA again: the backlog arrives, every job once.
serve_start c --config "$T/good.conf" --sim
py job "$port" 2004 "$J"
drained 30 && ok "backlog and new job drained over TLS" || no "not drained: $(sqlite3 "$DB" 'SELECT target, last_error FROM outbox' | head -2)"
sleep 1
stop_serve
kill -0 "$SUBPID" 2>/dev/null && ok "TLS subscriber alive" || no "subscriber died: $(cat "$T/sub.err")"
# A CA file that is not there: serve does not start, and names it.
sed "s|^mqtt_cafile = .*|mqtt_cafile = $T/missing.pem|" "$T/good.conf" >"$T/missing.conf"
timeout 60 "$CF" serve --plc tcp:127.0.0.1:0 --config "$T/missing.conf" --sim >/dev/null 2>"$T/missing.log"
rc=$?
[ $rc -ne 0 ] && [ $rc -ne 124 ] && grep -q "mqtt TLS: mqtt_cafile $T/missing.pem" "$T/missing.log" &&
    ok "mqtt_cafile missing: serve refuses to start (exit $rc), naming the file" ||
    no "missing CA file: exit $rc, $(tail -2 "$T/missing.log")"
py verify "$J" "$DB" "runuser -u postgres -- psql -h $PGD -p $PGPORT -U postgres -d plant" "$T/mqtt.out"
echo "plant_tls: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
