# SPDX-License-Identifier: MIT
# tests/cli/engines.sh: the plant's engines for tests/cli/plant.sh,
# tests/cli/plant_tls.sh and scripts/plant_demo.sh, sourced after T (a
# temporary folder the postgres user can reach: under /tmp, mode 755) is
# set: a PostgreSQL cluster of the caller's own (initdb in $T/pg, run as
# the postgres user, on 127.0.0.1:$PGPORT) and a Mosquitto broker started
# from the caller's own config file, each stopped by its data folder or
# its PID, never by name. Not a test itself: test-cli leaves it out.
ENG_PY=${PY:-/usr/bin/python3}
PGBIN=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
PGD="$T/pg"
MQPID=""

# A free TCP port on 127.0.0.1 (bound to port 0, read back).
freeport() { "$ENG_PY" -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

# eng_listening PORT: 0 once something accepts on 127.0.0.1:PORT.
eng_listening() {
    "$ENG_PY" -c 'import socket,sys; socket.create_connection(("127.0.0.1", int(sys.argv[1])), 0.5).close()' \
        "$1" 2>/dev/null
}

# pg_init AUTH: a cluster in $PGD, local connections trusted (the set-up,
# over its socket in $PGD), TCP with AUTH (trust, scram-sha-256); initdb's
# output in $T/initdb.log.
pg_init() {
    mkdir -p "$PGD" "$T/pglog" && chown postgres "$PGD" "$T/pglog" &&
        runuser -u postgres -- "$PGBIN/initdb" -D "$PGD" -U postgres --auth-local=trust \
            --auth-host="$1" >"$T/initdb.log" 2>&1
}

# pg_start [SETTING...]: the server on 127.0.0.1:$PGPORT, its socket in
# $PGD, each SETTING a "-c name=value" of its own; waits until it accepts.
pg_start() {
    runuser -u postgres -- "$PGBIN/pg_ctl" -D "$PGD" -l "$T/pglog/pg.log" -w \
        -o "-p $PGPORT -k $PGD -c listen_addresses=127.0.0.1 $*" start >/dev/null 2>&1
}

# pg_stop: a fast shutdown (an outage); the postmaster's PID as the last resort.
pg_stop() {
    [ -f "$PGD/postmaster.pid" ] || return 0
    pp=$(head -1 "$PGD/postmaster.pid")
    runuser -u postgres -- "$PGBIN/pg_ctl" -D "$PGD" -m fast -w stop >/dev/null 2>&1 ||
        kill -KILL "$pp" 2>/dev/null
}

# psql_admin ARGS...: psql as the superuser over the cluster's socket.
psql_admin() { runuser -u postgres -- psql -h "$PGD" -p "$PGPORT" -U postgres -v ON_ERROR_STOP=1 -qAt "$@"; }

# mq_start CONF PORT: mosquitto -c CONF in the background (its output
# appended to $T/mq.log), PID in $MQPID; 0 once PORT accepts connections
# (a plain TCP probe: it works for a TLS listener too), 1 after 5 s.
mq_start() {
    mosquitto -c "$1" >>"$T/mq.log" 2>&1 &
    MQPID=$!
    i=0
    while ! eng_listening "$2" && [ $i -lt 50 ]; do
        kill -0 "$MQPID" 2>/dev/null || return 1
        sleep 0.1; i=$((i + 1))
    done
    [ $i -lt 50 ]
}

# mq_stop: the broker stopped by its PID (TERM, then waited for).
mq_stop() {
    [ -n "$MQPID" ] || return 0
    kill -TERM "$MQPID" 2>/dev/null
    wait "$MQPID" 2>/dev/null
    MQPID=""
}
