/* SPDX-License-Identifier: MIT */
/* cf_forward.h: the forwarder: a thread beside the cell's job loop, with its
 * own connection to results.db, that drains the outbox (cf_resdb.h) to the
 * plant: each job row into PostgreSQL's `jobs` table (created if missing;
 * INSERT ... ON CONFLICT (job_uuid) DO NOTHING: exactly once) and as one
 * JSON message on PREFIX/CELL/result over MQTT (QoS 1; the entry goes when
 * the broker's PUBACK arrives: at least once, consumers dedupe by
 * job_uuid). The cell's state is retained on PREFIX/CELL/status (changes
 * only), with a Last Will that marks it offline. A target that is down is
 * retried with exponential backoff (capped); a job never waits for it:
 * the job's only cost is the outbox rows written with its own record.
 * Credentials come from the config (plant_db_password, mqtt_password) or
 * the environment (PGPASSWORD, ~/.pgpass; CELLFIT_MQTT_USERNAME and
 * CELLFIT_MQTT_PASSWORD), never from a logged URL: a password in a URL is
 * masked in every log line. TLS: PostgreSQL's sslmode, sslrootcert, ...
 * in the URL's query (libpq passes them through); MQTT with mqtts:// and
 * mqtt_cafile, mqtt_certfile, mqtt_keyfile. */
#ifndef CF_FORWARD_H
#define CF_FORWARD_H

#include <stddef.h>

enum {
    CF_FORWARD_OK = 0,
    CF_FORWARD_EARG = -1,   /* a URL or setting that cannot be used */
    CF_FORWARD_ESTART = -2, /* the database or the thread could not start */
};
const char *cf_forward_strerror(int err);

typedef struct cf_forward_opts {
    const char *db_path;     /* the cell's results.db */
    const char *cell_id;     /* topic level and column; NULL: the host name */
    const char *plant_db;    /* postgresql://USER@HOST:PORT/DB[?sslmode=...], NULL: none */
    const char *pg_password; /* NULL: libpq's own (PGPASSWORD, ~/.pgpass) */
    const char *mqtt;        /* mqtt[s]://HOST:PORT/PREFIX, NULL: none */
    const char *mqtt_user, *mqtt_password;
    const char *mqtt_cafile, *mqtt_certfile, *mqtt_keyfile;
    double backoff_max; /* seconds between retries at most; <= 0: 30 */
} cf_forward_opts_t;

typedef struct cf_forward cf_forward_t;

/* Check the URLs (0 or CF_FORWARD_EARG with msg): before anything starts. */
int cf_forward_check(const cf_forward_opts_t *o, char *msg, size_t ml);
/* The outbox targets (CF_RESDB_PG | CF_RESDB_MQTT) o configures. */
int cf_forward_targets(const cf_forward_opts_t *o);

/* Start the thread (with signals blocked). Connection failures are not
 * errors: they are retried. */
int cf_forward_start(const cf_forward_opts_t *o, cf_forward_t **out, char *msg, size_t ml);
/* A new outbox entry: look now rather than at the next poll. */
void cf_forward_kick(cf_forward_t *f);
/* The cell's state for PREFIX/CELL/status ("idle", "busy", "error"). */
void cf_forward_state(cf_forward_t *f, const char *state);
/* Publish "offline" (a clean stop sends no Will), stop and free. */
void cf_forward_stop(cf_forward_t *f);

/* url with a password (user:PASS@) replaced by "***", for logs. */
void cf_forward_mask(const char *url, char *out, size_t n);

#endif
