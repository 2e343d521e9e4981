/* SPDX-License-Identifier: MIT */
/* cf_forward.c: the forwarder (cf_forward.h): one thread, its own SQLite
 * connection, one libpq connection and one libmosquitto client driven from
 * that thread (mosquitto_loop: no library thread, no locks around it). */
#define _DEFAULT_SOURCE /* gethostname, clock_gettime beside C11 */
#if !CF_NO_PLANT        /* built only with SQLite, libpq and libmosquitto (mk/plant.mk) */
#include "cf_forward.h"
#include "cf_log.h"
#include "cf_resdb.h"
#include "cf_resfmt.h"
#include "cf_thread.h"
#include "hal_dl.h"
#include "hal_dl_libs.h"
#include <libpq-fe.h>
#include <math.h>
#include <mosquitto.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* libpq and libmosquitto, loaded when serve forwards to a plant database or
 * a broker (hal_dl.h): no other command maps them. */
/* clang-format off */
#define PQ_SYMS(X) \
    X(PQclear) \
    X(PQconnectdbParams) \
    X(PQerrorMessage) \
    X(PQexec) \
    X(PQexecParams) \
    X(PQfinish) \
    X(PQresultErrorMessage) \
    X(PQresultStatus) \
    X(PQstatus)
#define MOSQ_SYMS(X) \
    X(mosquitto_connect) \
    X(mosquitto_connect_callback_set) \
    X(mosquitto_destroy) \
    X(mosquitto_disconnect) \
    X(mosquitto_disconnect_callback_set) \
    X(mosquitto_lib_cleanup) \
    X(mosquitto_lib_init) \
    X(mosquitto_log_callback_set) \
    X(mosquitto_loop) \
    X(mosquitto_new) \
    X(mosquitto_publish) \
    X(mosquitto_publish_callback_set) \
    X(mosquitto_reconnect) \
    X(mosquitto_strerror) \
    X(mosquitto_tls_set) \
    X(mosquitto_username_pw_set) \
    X(mosquitto_will_set)
/* clang-format on */
HAL_DL_TABLE(pq, PQ_SYMS)
HAL_DL_TABLE(mosq, MOSQ_SYMS)
static hal_dl_t pq_lib =
    HAL_DL_LIB(pq, HAL_DL_SONAME_PQ, HAL_DL_PACKAGE_PQ, "forwarding to plant_db (PostgreSQL)");
static hal_dl_t mosq_lib = HAL_DL_LIB(mosq, HAL_DL_SONAME_MOSQUITTO, HAL_DL_PACKAGE_MOSQUITTO,
                                      "forwarding to mqtt (the broker)");

#define FWD_POLL_MS 50    /* outbox poll and MQTT loop period */
#define FWD_ACK_S 10.0    /* a QoS 1 message without PUBACK is sent again after this */
#define FWD_INFLIGHT 32   /* QoS 1 messages awaiting PUBACK */
#define FWD_BACKOFF0 0.25 /* first retry delay (s), doubled each time */

typedef struct inflight {
    int mid;
    long long id;
} inflight_t;

struct cf_forward {
    cf_forward_opts_t o;
    char cell[64];
    pthread_t th;
    atomic_int stop;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int kicked;
    char state[32]; /* under mu */
    cf_resdb_t *db;
    /* PostgreSQL */
    PGconn *pg;
    double pg_next, pg_delay;
    int pg_down_logged;
    /* MQTT */
    struct mosquitto *mq;
    char mq_host[256], prefix[256], topic_res[384], topic_st[384];
    int mq_port, mq_tls, mq_connected, mq_ever;
    double mq_next, mq_delay;
    int mq_down_logged;
    char mq_err[256]; /* the library's last error line (OpenSSL's, for TLS) */
    char sent_state[32];
    inflight_t fl[FWD_INFLIGHT];
    int nfl;
};

const char *cf_forward_strerror(int err)
{
    switch (err) {
    case CF_FORWARD_OK: return "ok";
    case CF_FORWARD_EARG: return "bad plant database or broker setting";
    case CF_FORWARD_ESTART: return "forwarder could not start";
    default: return "unknown forwarder error";
    }
}

static double wall(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

void cf_forward_mask(const char *url, char *out, size_t n)
{
    const char *s = strstr(url, "://"), *at, *colon;
    snprintf(out, n, "%s", url);
    if (!s)
        return;
    s += 3;
    at = strchr(s, '@');
    colon = strchr(s, ':');
    const char *slash = strchr(s, '/');
    if (at && colon && colon < at && (!slash || at < slash))
        snprintf(out, n, "%.*s***%s", (int)(colon + 1 - url), url, at);
}

/* mqtt[s]://HOST[:PORT]/PREFIX */
static int parse_mqtt(const char *u, char *host, size_t hn, int *port, int *tls, char *prefix,
                      size_t pn)
{
    const char *s;
    if (!strncmp(u, "mqtt://", 7))
        s = u + 7, *tls = 0, *port = 1883;
    else if (!strncmp(u, "mqtts://", 8))
        s = u + 8, *tls = 1, *port = 8883;
    else
        return -1;
    const char *slash = strchr(s, '/'), *colon = strchr(s, ':');
    if (!slash || !slash[1] || slash == s)
        return -1;
    const char *hend = colon && colon < slash ? colon : slash;
    if ((size_t)(hend - s) >= hn || strlen(slash + 1) >= pn || strchr(s, '@'))
        return -1;
    memcpy(host, s, (size_t)(hend - s));
    host[hend - s] = 0;
    if (colon && colon < slash) {
        char *e;
        long p = strtol(colon + 1, &e, 10);
        if (e != slash || p < 1 || p > 65535)
            return -1;
        *port = (int)p;
    }
    snprintf(prefix, pn, "%s", slash + 1);
    size_t l = strlen(prefix);
    if (prefix[l - 1] == '/')
        prefix[l - 1] = 0;
    return strpbrk(prefix, "+#") || !*prefix ? -1 : 0;
}

int cf_forward_check(const cf_forward_opts_t *o, char *msg, size_t ml)
{
    char h[256], p[256];
    int port, tls;
    if (o->mqtt && parse_mqtt(o->mqtt, h, sizeof h, &port, &tls, p, sizeof p)) {
        snprintf(msg, ml, "mqtt '%s': need mqtt://HOST:PORT/PREFIX (or mqtts://)", o->mqtt);
        return CF_FORWARD_EARG;
    }
    if (o->plant_db && strncmp(o->plant_db, "postgresql://", 13) &&
        strncmp(o->plant_db, "postgres://", 11)) {
        char m[512];
        cf_forward_mask(o->plant_db, m, sizeof m);
        snprintf(msg, ml, "plant_db '%s': need postgresql://USER@HOST:PORT/DB", m);
        return CF_FORWARD_EARG;
    }
    if (o->cell_id && (!*o->cell_id || strpbrk(o->cell_id, "/+#") || strlen(o->cell_id) >= 64)) {
        snprintf(msg, ml, "cell_id '%s': 1 to 63 characters, no '/', '+' or '#'", o->cell_id);
        return CF_FORWARD_EARG;
    }
    return CF_FORWARD_OK;
}

int cf_forward_targets(const cf_forward_opts_t *o)
{
    return (o->plant_db ? CF_RESDB_PG : 0) | (o->mqtt ? CF_RESDB_MQTT : 0);
}

static double backoff(double *delay, double cap)
{
    double d = *delay <= 0 ? FWD_BACKOFF0 : *delay;
    *delay = fmin(d * 2, cap);
    return d;
}

static double entry_delay(long attempts, double cap)
{
    return fmin(cap, FWD_BACKOFF0 * pow(2.0, (double)(attempts < 30 ? attempts : 30)));
}

/* ---- PostgreSQL ---- */

static const char *const pg_create =
    "CREATE TABLE IF NOT EXISTS jobs ("
    " job_uuid uuid PRIMARY KEY, cell_id text, part_number bigint, part_id text,"
    " program integer, result_seq integer, command text, started_at timestamptz,"
    " ended_at timestamptz, state text, error_code integer, fit_status integer,"
    " rms double precision, max_dev double precision, min_dev double precision,"
    " within_pct double precision, verdict integer, points bigint, control_points bigint,"
    " surface_path text, surface_sha256 text, report_path text, report_sha256 text,"
    " journal_path text, journal_sha256 text, received_at timestamptz NOT NULL DEFAULT now())";

static void pg_close(cf_forward_t *f)
{
    if (f->pg)
        pq.PQfinish(f->pg);
    f->pg = NULL;
}

static void pg_down(cf_forward_t *f, const char *why, double now)
{
    double d = backoff(&f->pg_delay, f->o.backoff_max);
    if (!f->pg_down_logged)
        cf_log(CF_LOG_WARN, "forward: plant database unavailable (%s): retrying, up to every %gs",
               why, f->o.backoff_max);
    f->pg_down_logged = 1;
    f->pg_next = now + d;
    pg_close(f);
}

static int pg_connect(cf_forward_t *f, double now)
{
    const char *kw[] = {"dbname", "connect_timeout", "application_name", "password", NULL};
    const char *val[] = {f->o.plant_db, "5", "cellfit", f->o.pg_password, NULL};
    if (!f->o.pg_password)
        kw[3] = NULL;
    f->pg = pq.PQconnectdbParams(kw, val, 1);
    if (!f->pg || pq.PQstatus(f->pg) != CONNECTION_OK) {
        char why[256];
        snprintf(why, sizeof why, "%s", f->pg ? pq.PQerrorMessage(f->pg) : "out of memory");
        why[strcspn(why, "\n")] = 0;
        pg_down(f, why, now);
        return -1;
    }
    PGresult *r = pq.PQexec(f->pg, pg_create);
    if (pq.PQresultStatus(r) != PGRES_COMMAND_OK) /* another cell may be creating it: go on */
        cf_log(CF_LOG_DEBUG, "forward: create jobs: %s", pq.PQresultErrorMessage(r));
    pq.PQclear(r);
    char m[512];
    cf_forward_mask(f->o.plant_db, m, sizeof m);
    cf_log(CF_LOG_INFO, "forward: plant database %s connected", m);
    f->pg_down_logged = 0;
    f->pg_delay = 0;
    cf_resdb_due_now(f->db, CF_RESDB_PG); /* the backlog, now */
    return 0;
}

static int pg_insert(cf_forward_t *f, const cf_resdb_job_t *j, char *err, size_t el)
{
    char num[12][32];
    const char *v[25];
    int k = 0;
#define TXT(s) (v[k++] = (s)[0] ? (s) : NULL)
    TXT(j->job_uuid);
    TXT(j->cell_id);
    v[k] = num[0], snprintf(num[0], 32, "%ld", j->part_number), k++;
    TXT(j->part_id);
    v[k] = num[1], snprintf(num[1], 32, "%ld", j->program), k++;
    v[k] = num[2], snprintf(num[2], 32, "%ld", j->result_seq), k++;
    TXT(j->command);
    TXT(j->started_at);
    TXT(j->ended_at);
    TXT(j->state);
    v[k] = num[3], snprintf(num[3], 32, "%ld", j->error_code), k++;
    int h = j->has_fit;
    v[k++] = h ? (snprintf(num[4], 32, "%ld", j->fit_status), num[4]) : NULL;
    /* A figure not known (NaN, verdict 0: cf_resdb.h) is NULL. */
    v[k++] = h ? (snprintf(num[5], 32, "%.17g", j->rms), num[5]) : NULL;
    v[k++] = h && isfinite(j->max_dev) ? (snprintf(num[6], 32, "%.17g", j->max_dev), num[6]) : NULL;
    v[k++] = h && isfinite(j->min_dev) ? (snprintf(num[7], 32, "%.17g", j->min_dev), num[7]) : NULL;
    v[k++] = h && isfinite(j->within_pct) ? (snprintf(num[8], 32, "%.17g", j->within_pct), num[8])
                                          : NULL;
    v[k++] = h && j->verdict > 0 ? (snprintf(num[9], 32, "%ld", j->verdict), num[9]) : NULL;
    v[k++] = h ? (snprintf(num[10], 32, "%ld", j->points), num[10]) : NULL;
    v[k++] = h ? (snprintf(num[11], 32, "%ld", j->control_points), num[11]) : NULL;
    TXT(j->surface_path);
    TXT(j->surface_sha256);
    TXT(j->report_path);
    TXT(j->report_sha256);
    TXT(j->journal_path);
    TXT(j->journal_sha256);
#undef TXT
    PGresult *r = pq.PQexecParams(
        f->pg,
        "INSERT INTO jobs (job_uuid, cell_id, part_number, part_id, program, result_seq, "
        "command, started_at, ended_at, state, error_code, fit_status, rms, max_dev, min_dev, "
        "within_pct, verdict, points, control_points, surface_path, surface_sha256, "
        "report_path, report_sha256, journal_path, journal_sha256) VALUES ($1, $2, $3, $4, $5, "
        "$6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17, $18, $19, $20, $21, $22, $23, "
        "$24, $25) ON CONFLICT (job_uuid) DO NOTHING",
        k, NULL, v, NULL, NULL, 0);
    int ok = pq.PQresultStatus(r) == PGRES_COMMAND_OK;
    if (!ok) {
        snprintf(err, el, "%s", pq.PQresultErrorMessage(r));
        err[strcspn(err, "\n")] = 0;
    }
    pq.PQclear(r);
    return ok ? 0 : -1;
}

static void pg_step(cf_forward_t *f, double now)
{
    if (!f->pg && (now < f->pg_next || pg_connect(f, now)))
        return;
    cf_resdb_due_t e;
    cf_resdb_job_t *j = malloc(sizeof *j);
    if (!j)
        return;
    for (int n = 0;
         n < 64 && !atomic_load(&f->stop) && cf_resdb_due(f->db, CF_RESDB_PG, now, &e) == 1; n++) {
        char err[256];
        if (cf_resdb_get(f->db, e.job_uuid, j)) { /* the row is gone: nothing to send */
            cf_resdb_delivered(f->db, e.id);
            continue;
        }
        if (!pg_insert(f, j, err, sizeof err)) {
            cf_resdb_delivered(f->db, e.id);
            continue;
        }
        if (pq.PQstatus(f->pg) != CONNECTION_OK) {
            pg_down(f, err, now); /* the entry waits for the reconnection */
            break;
        }
        cf_log(CF_LOG_WARN, "forward: job %s into the plant database: %s", e.job_uuid, err);
        cf_resdb_retry(f->db, e.id, now + entry_delay(e.attempts, f->o.backoff_max), err);
    }
    free(j);
}

/* ---- MQTT ---- */

static void status_payload(const cf_forward_t *f, const char *state, char *buf, size_t n)
{
    char ts[32];
    cf_resdb_now_iso(ts);
    snprintf(buf, n, "{\"cell_id\": \"%s\", \"state\": \"%s\", \"at\": \"%s\"}", f->cell, state,
             ts);
}

static void on_connect(struct mosquitto *m, void *ctx, int rc)
{
    cf_forward_t *f = ctx;
    (void)m;
    if (rc == 0)
        f->mq_connected = 1;
}

static void on_disconnect(struct mosquitto *m, void *ctx, int rc)
{
    cf_forward_t *f = ctx;
    (void)m, (void)rc;
    f->mq_connected = 0;
}

static void on_publish(struct mosquitto *m, void *ctx, int mid)
{
    cf_forward_t *f = ctx;
    (void)m;
    for (int i = 0; i < f->nfl; i++)
        if (f->fl[i].mid == mid) {
            if (f->fl[i].id > 0)
                cf_resdb_delivered(f->db, f->fl[i].id);
            f->fl[i] = f->fl[--f->nfl];
            return;
        }
}

/* The library's error lines (OpenSSL's among them when a TLS handshake
 * fails): the last kept for the reason mq_connect logs. */
static void on_log(struct mosquitto *m, void *ctx, int level, const char *line)
{
    cf_forward_t *f = ctx;
    (void)m;
    if (level == MOSQ_LOG_ERR)
        snprintf(f->mq_err, sizeof f->mq_err, "%s", line);
}

static void mq_down(cf_forward_t *f, const char *why, double now)
{
    double d = backoff(&f->mq_delay, f->o.backoff_max);
    if (!f->mq_down_logged)
        cf_log(CF_LOG_WARN, "forward: broker %s:%d unavailable (%s): retrying, up to every %gs",
               f->mq_host, f->mq_port, why, f->o.backoff_max);
    f->mq_down_logged = 1;
    f->mq_connected = 0;
    f->mq_next = now + d;
    /* Messages without PUBACK are sent again after the reconnection. */
    f->nfl = 0;
}

/* Why a connection failed or went, for the log: a TLS handshake fails in
 * mosquitto_connect or, the socket being non-blocking, in the loop after
 * it; either way OpenSSL's own line (on_log) says which check failed. */
static void mq_why(const cf_forward_t *f, int rc, const char *what, char *why, size_t n)
{
    if (rc == MOSQ_ERR_TLS || strstr(f->mq_err, "OpenSSL"))
        snprintf(why, n,
                 "TLS handshake failed: %s (is the broker's certificate signed by mqtt_cafile, "
                 "for this host name?)",
                 *f->mq_err ? f->mq_err : mosq.mosquitto_strerror(rc));
    else if (rc == MOSQ_ERR_ERRNO)
        snprintf(why, n, "connection refused or unreachable");
    else
        snprintf(why, n, "%s", rc ? mosq.mosquitto_strerror(rc) : what);
}

static int mq_connect(cf_forward_t *f, double now)
{
    char why[400];
    f->mq_err[0] = 0;
    int rc = f->mq_ever ? mosq.mosquitto_reconnect(f->mq)
                        : mosq.mosquitto_connect(f->mq, f->mq_host, f->mq_port, 30);
    if (rc != MOSQ_ERR_SUCCESS) {
        mq_why(f, rc, "", why, sizeof why);
        mq_down(f, why, now);
        return -1;
    }
    f->mq_ever = 1;
    /* CONNACK arrives in the loop; until then publishing is queued by the
     * library, which is fine, but wait for it to know the broker is up. */
    for (int i = 0; i < 40 && !f->mq_connected && rc == MOSQ_ERR_SUCCESS; i++)
        rc = mosq.mosquitto_loop(f->mq, FWD_POLL_MS, 1);
    if (!f->mq_connected) {
        mq_why(f, rc, "no CONNACK", why, sizeof why);
        mq_down(f, why, now);
        return -1;
    }
    cf_log(CF_LOG_INFO, "forward: broker %s:%d connected, topics %s/%s/...", f->mq_host, f->mq_port,
           f->prefix, f->cell);
    f->mq_down_logged = 0;
    f->mq_delay = 0;
    f->sent_state[0] = 0; /* the status again: the broker may have lost it */
    cf_resdb_due_now(f->db, CF_RESDB_MQTT);
    return 0;
}

static void mq_status(cf_forward_t *f)
{
    char st[32], buf[256];
    pthread_mutex_lock(&f->mu);
    snprintf(st, sizeof st, "%s", f->state);
    pthread_mutex_unlock(&f->mu);
    if (!strcmp(st, f->sent_state) || f->nfl >= FWD_INFLIGHT)
        return;
    status_payload(f, st, buf, sizeof buf);
    int mid;
    if (mosq.mosquitto_publish(f->mq, &mid, f->topic_st, (int)strlen(buf), buf, 1, true) ==
        MOSQ_ERR_SUCCESS) {
        f->fl[f->nfl++] = (inflight_t){mid, 0};
        snprintf(f->sent_state, sizeof f->sent_state, "%s", st);
    }
}

static int in_flight(const cf_forward_t *f, long long id)
{
    for (int i = 0; i < f->nfl; i++)
        if (f->fl[i].id == id)
            return 1;
    return 0;
}

static void mq_step(cf_forward_t *f, double now)
{
    if (!f->mq_connected && (now < f->mq_next || mq_connect(f, now)))
        return;
    mq_status(f);
    cf_resdb_due_t e;
    cf_resdb_job_t *j = malloc(sizeof *j);
    char *buf = malloc(8192);
    while (j && buf && f->nfl < FWD_INFLIGHT && !atomic_load(&f->stop) &&
           cf_resdb_due(f->db, CF_RESDB_MQTT, now, &e) == 1 && !in_flight(f, e.id)) {
        int mid, len;
        if (cf_resdb_get(f->db, e.job_uuid, j) || (len = cf_resfmt_json_buf(j, buf, 8192)) < 0) {
            cf_resdb_delivered(f->db, e.id);
            continue;
        }
        int rc = mosq.mosquitto_publish(f->mq, &mid, f->topic_res, len, buf, 1, false);
        if (rc != MOSQ_ERR_SUCCESS) {
            mq_down(f, mosq.mosquitto_strerror(rc), now);
            break;
        }
        f->fl[f->nfl++] = (inflight_t){mid, e.id};
        /* Not due again unless the PUBACK fails to come. */
        cf_resdb_retry(f->db, e.id, now + FWD_ACK_S, NULL);
    }
    free(j);
    free(buf);
}

/* ---- the thread ---- */

static void *fwd_main(void *arg)
{
    cf_forward_t *f = arg;
    while (!atomic_load(&f->stop)) {
        double now = wall();
        if (f->o.plant_db)
            pg_step(f, now);
        if (f->mq) {
            mq_step(f, now);
            if (f->mq_connected) {
                int rc = mosq.mosquitto_loop(f->mq, FWD_POLL_MS, 1);
                if (rc != MOSQ_ERR_SUCCESS || !f->mq_connected) {
                    char why[400];
                    mq_why(f, rc, "disconnected", why, sizeof why);
                    mq_down(f, why, wall());
                }
                continue;
            }
        }
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += FWD_POLL_MS * 1000000L;
        if (ts.tv_nsec >= 1000000000L)
            ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        pthread_mutex_lock(&f->mu);
        if (!f->kicked)
            pthread_cond_timedwait(&f->cv, &f->mu, &ts);
        f->kicked = 0;
        pthread_mutex_unlock(&f->mu);
    }
    return NULL;
}

static void mq_free(cf_forward_t *f)
{
    if (!f->mq)
        return;
    if (f->mq_connected) { /* a clean stop sends no Will: say offline ourselves */
        pthread_mutex_lock(&f->mu);
        snprintf(f->state, sizeof f->state, "offline");
        pthread_mutex_unlock(&f->mu);
        mq_status(f);
        for (int i = 0; i < 20 && f->nfl > 0; i++)
            if (mosq.mosquitto_loop(f->mq, FWD_POLL_MS, 1) != MOSQ_ERR_SUCCESS)
                break;
        mosq.mosquitto_disconnect(f->mq);
        mosq.mosquitto_loop(f->mq, FWD_POLL_MS, 1);
    }
    mosq.mosquitto_destroy(f->mq);
    mosq.mosquitto_lib_cleanup();
    f->mq = NULL;
}

static int mq_setup(cf_forward_t *f, char *msg, size_t ml)
{
    parse_mqtt(f->o.mqtt, f->mq_host, sizeof f->mq_host, &f->mq_port, &f->mq_tls, f->prefix,
               sizeof f->prefix);
    snprintf(f->topic_res, sizeof f->topic_res, "%s/%s/result", f->prefix, f->cell);
    snprintf(f->topic_st, sizeof f->topic_st, "%s/%s/status", f->prefix, f->cell);
    mosq.mosquitto_lib_init();
    char id[96];
    snprintf(id, sizeof id, "cellfit-%s", f->cell);
    f->mq = mosq.mosquitto_new(id, true, f);
    if (!f->mq)
        return snprintf(msg, ml, "mqtt: cannot create the client"), -1;
    mosq.mosquitto_connect_callback_set(f->mq, on_connect);
    mosq.mosquitto_disconnect_callback_set(f->mq, on_disconnect);
    mosq.mosquitto_publish_callback_set(f->mq, on_publish);
    mosq.mosquitto_log_callback_set(f->mq, on_log);
    char will[256];
    status_payload(f, "offline", will, sizeof will);
    mosq.mosquitto_will_set(f->mq, f->topic_st, (int)strlen(will), will, 1, true);
    const char *user = f->o.mqtt_user ? f->o.mqtt_user : getenv("CELLFIT_MQTT_USERNAME");
    const char *pw = f->o.mqtt_password ? f->o.mqtt_password : getenv("CELLFIT_MQTT_PASSWORD");
    if (user)
        mosq.mosquitto_username_pw_set(f->mq, user, pw);
    if (f->mq_tls || f->o.mqtt_cafile) {
        int rc = mosq.mosquitto_tls_set(f->mq, f->o.mqtt_cafile,
                                        f->o.mqtt_cafile ? NULL : "/etc/ssl/certs",
                                        f->o.mqtt_certfile, f->o.mqtt_keyfile, NULL);
        if (rc != MOSQ_ERR_SUCCESS) /* a file that cannot be read, or a key without its cert */
            return snprintf(msg, ml,
                            "mqtt TLS: mqtt_cafile %s, mqtt_certfile %s, mqtt_keyfile %s: %s "
                            "(each must be readable; a certificate and its key go together)",
                            f->o.mqtt_cafile ? f->o.mqtt_cafile : "(system: /etc/ssl/certs)",
                            f->o.mqtt_certfile ? f->o.mqtt_certfile : "(none)",
                            f->o.mqtt_keyfile ? f->o.mqtt_keyfile : "(none)",
                            mosq.mosquitto_strerror(rc)),
                   -1;
    }
    return 0;
}

int cf_forward_start(const cf_forward_opts_t *o, cf_forward_t **out, char *msg, size_t ml)
{
    *out = NULL;
    if (cf_forward_check(o, msg, ml))
        return CF_FORWARD_EARG;
    /* The libraries first: a missing one says what to install, nothing started. */
    hal_dl_t *need[2] = {o->plant_db ? &pq_lib : NULL, o->mqtt ? &mosq_lib : NULL};
    for (int i = 0; i < 2; i++)
        if (need[i] && hal_dl_load(need[i]))
            return snprintf(msg, ml, "%s", hal_dl_error(need[i])), CF_FORWARD_ESTART;
    cf_forward_t *f = calloc(1, sizeof *f);
    if (!f)
        return snprintf(msg, ml, "forwarder: out of memory"), CF_FORWARD_ESTART;
    f->o = *o;
    if (f->o.backoff_max <= 0)
        f->o.backoff_max = 30;
    if (o->cell_id)
        snprintf(f->cell, sizeof f->cell, "%s", o->cell_id);
    else if (gethostname(f->cell, sizeof f->cell - 1) || !*f->cell)
        snprintf(f->cell, sizeof f->cell, "cell");
    snprintf(f->state, sizeof f->state, "idle");
    pthread_mutex_init(&f->mu, NULL);
    pthread_cond_init(&f->cv, NULL);
    int rc = cf_resdb_open(o->db_path, &f->db, msg, ml);
    if (!rc && o->mqtt && mq_setup(f, msg, ml))
        rc = -1;
    if (!rc) {
        rc = cf_thread_start(&f->th, fwd_main, f); /* signals stay with the main thread */
        if (rc)
            snprintf(msg, ml, "forwarder: cannot start its thread");
    }
    if (rc) {
        mq_free(f);
        cf_resdb_close(f->db);
        pthread_mutex_destroy(&f->mu);
        pthread_cond_destroy(&f->cv);
        free(f);
        return CF_FORWARD_ESTART;
    }
    *out = f;
    return CF_FORWARD_OK;
}

void cf_forward_kick(cf_forward_t *f)
{
    if (!f)
        return;
    pthread_mutex_lock(&f->mu);
    f->kicked = 1;
    pthread_cond_signal(&f->cv);
    pthread_mutex_unlock(&f->mu);
}

void cf_forward_state(cf_forward_t *f, const char *state)
{
    if (!f)
        return;
    pthread_mutex_lock(&f->mu);
    snprintf(f->state, sizeof f->state, "%s", state);
    f->kicked = 1;
    pthread_cond_signal(&f->cv);
    pthread_mutex_unlock(&f->mu);
}

void cf_forward_stop(cf_forward_t *f)
{
    if (!f)
        return;
    atomic_store(&f->stop, 1);
    cf_forward_kick(f);
    pthread_join(f->th, NULL);
    mq_free(f);
    pg_close(f);
    cf_resdb_close(f->db);
    pthread_mutex_destroy(&f->mu);
    pthread_cond_destroy(&f->cv);
    free(f);
}
#endif
