/* SPDX-License-Identifier: MIT */
/* cf_resdb.c: the cell's results database (cf_resdb.h) on SQLite: schema
 * and migrations, the synced record of a job with its outbox entries, the
 * outbox's bound, and the queries behind `cellfit results`. */
#define _DEFAULT_SOURCE /* gmtime_r and clock_gettime beside C11 */
#if !CF_NO_PLANT        /* built only with SQLite, libpq and libmosquitto (mk/plant.mk) */
#include "cf_resdb.h"
#include "hal_dl.h"
#include "hal_dl_libs.h"
#include <math.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

/* SQLite, loaded by the first open (hal_dl.h): only commands that record
 * or read results map it. */
/* clang-format off */
#define SQ_SYMS(X) \
    X(sqlite3_bind_double) \
    X(sqlite3_bind_int64) \
    X(sqlite3_bind_null) \
    X(sqlite3_bind_parameter_count) \
    X(sqlite3_bind_text) \
    X(sqlite3_busy_timeout) \
    X(sqlite3_close) \
    X(sqlite3_column_double) \
    X(sqlite3_column_int) \
    X(sqlite3_column_int64) \
    X(sqlite3_column_text) \
    X(sqlite3_column_type) \
    X(sqlite3_errmsg) \
    X(sqlite3_exec) \
    X(sqlite3_finalize) \
    X(sqlite3_open_v2) \
    X(sqlite3_prepare_v2) \
    X(sqlite3_step)
/* clang-format on */
HAL_DL_TABLE(sq, SQ_SYMS)
static hal_dl_t sq_lib =
    HAL_DL_LIB(sq, HAL_DL_SONAME_SQLITE3, HAL_DL_PACKAGE_SQLITE3, "the results database");

/* SQLite there, or msg says which package to install. */
static int sq_ready(const char *path, char *msg, size_t ml)
{
    if (!hal_dl_load(&sq_lib))
        return 0;
    snprintf(msg, ml, "%s: %s", path, hal_dl_error(&sq_lib));
    return -1;
}

struct cf_resdb {
    sqlite3 *db;
};

const char *cf_resdb_strerror(int err)
{
    switch (err) {
    case CF_RESDB_OK: return "ok";
    case CF_RESDB_EOPEN: return "cannot open the results database";
    case CF_RESDB_ESCHEMA:
        return "results database schema newer than this cellfit, or migration failed";
    case CF_RESDB_EIO: return "results database statement failed";
    case CF_RESDB_ENOTFOUND: return "no such job";
    case CF_RESDB_ENOTDB: return "not a cellfit results database";
    case CF_RESDB_ENOLIB: return "the SQLite library cannot be loaded";
    default: return "unknown results database error";
    }
}

/* Version 1: the jobs table alone (as the first recorder wrote it).
 * Version 2: the PLC's part serial (part_id), the job's command, the
 * journal's path and checksum, the outbox and its counters. Each step
 * runs in the migration's transaction; a database at any older version
 * walks the steps from its own. */
static const char *const schema_v1 =
    "CREATE TABLE IF NOT EXISTS jobs ("
    " job_uuid TEXT PRIMARY KEY NOT NULL, cell_id TEXT, part_number INTEGER,"
    " program INTEGER, result_seq INTEGER, started_at TEXT, ended_at TEXT, state TEXT,"
    " error_code INTEGER, fit_status INTEGER, rms REAL, max_dev REAL, min_dev REAL,"
    " within_pct REAL, verdict INTEGER, points INTEGER, control_points INTEGER,"
    " surface_path TEXT, surface_sha256 TEXT, report_path TEXT, report_sha256 TEXT);"
    "CREATE INDEX IF NOT EXISTS jobs_ended ON jobs(ended_at);";

static const char *const schema_v2 =
    "ALTER TABLE jobs ADD COLUMN part_id TEXT;"
    "ALTER TABLE jobs ADD COLUMN command TEXT;"
    "ALTER TABLE jobs ADD COLUMN journal_path TEXT;"
    "ALTER TABLE jobs ADD COLUMN journal_sha256 TEXT;"
    "CREATE INDEX IF NOT EXISTS jobs_part ON jobs(part_number);"
    "CREATE TABLE outbox (id INTEGER PRIMARY KEY AUTOINCREMENT,"
    " job_uuid TEXT NOT NULL, target TEXT NOT NULL CHECK (target IN ('pg', 'mqtt')),"
    " attempts INTEGER NOT NULL DEFAULT 0, next_try REAL NOT NULL DEFAULT 0,"
    " created REAL NOT NULL, last_error TEXT, UNIQUE (job_uuid, target));"
    "CREATE INDEX outbox_due ON outbox(target, next_try);"
    "CREATE TABLE counters (name TEXT PRIMARY KEY, value INTEGER NOT NULL);"
    "INSERT INTO counters VALUES ('outbox_dropped', 0);"
    "INSERT INTO counters VALUES ('last_error_at', 0);"
    "CREATE TABLE last_error (id INTEGER PRIMARY KEY CHECK (id = 1), text TEXT);";

static const char *const *const steps[CF_RESDB_VERSION] = {&schema_v1, &schema_v2};

/* The columns in the order of cf_resdb_job_t's binding (put/get). */
#define COLS                                                                                       \
    "job_uuid, cell_id, part_number, part_id, program, result_seq, command, started_at, "          \
    "ended_at, state, error_code, fit_status, rms, max_dev, min_dev, within_pct, verdict, "        \
    "points, control_points, surface_path, surface_sha256, report_path, report_sha256, "           \
    "journal_path, journal_sha256"
#define NCOLS 25

static double now_unix(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

void cf_resdb_now_iso(char out[32])
{
    struct timespec ts;
    struct tm tm;
    clock_gettime(CLOCK_REALTIME, &ts);
    gmtime_r(&ts.tv_sec, &tm);
    size_t n = strftime(out, 32, "%Y-%m-%dT%H:%M:%S", &tm);
    int ms = (int)(ts.tv_nsec / 1000000L) % 1000;
    snprintf(out + n, 32 - n, ".%03dZ", ms);
}

static int exec(cf_resdb_t *d, const char *sql)
{
    return sq.sqlite3_exec(d->db, sql, NULL, NULL, NULL) == SQLITE_OK ? CF_RESDB_OK : CF_RESDB_EIO;
}

int cf_resdb_version(cf_resdb_t *d)
{
    sqlite3_stmt *st;
    int v = -1;
    if (sq.sqlite3_prepare_v2(d->db, "PRAGMA user_version", -1, &st, NULL) != SQLITE_OK)
        return -1;
    if (sq.sqlite3_step(st) == SQLITE_ROW)
        v = sq.sqlite3_column_int(st, 0);
    sq.sqlite3_finalize(st);
    return v;
}

static int migrate(cf_resdb_t *d, char *msg, size_t ml)
{
    if (exec(d, "BEGIN IMMEDIATE"))
        return snprintf(msg, ml, "migration: %s", sq.sqlite3_errmsg(d->db)), CF_RESDB_EIO;
    int v = cf_resdb_version(d);
    if (v > CF_RESDB_VERSION || v < 0) {
        exec(d, "ROLLBACK");
        snprintf(msg, ml, "schema version %d, this cellfit knows %d", v, CF_RESDB_VERSION);
        return CF_RESDB_ESCHEMA;
    }
    for (int k = v; k < CF_RESDB_VERSION; k++)
        if (exec(d, *steps[k])) {
            snprintf(msg, ml, "migration to version %d: %s", k + 1, sq.sqlite3_errmsg(d->db));
            exec(d, "ROLLBACK");
            return CF_RESDB_ESCHEMA;
        }
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA user_version = %d", CF_RESDB_VERSION);
    if (exec(d, sql) || exec(d, "COMMIT")) {
        snprintf(msg, ml, "migration: %s", sq.sqlite3_errmsg(d->db));
        exec(d, "ROLLBACK");
        return CF_RESDB_ESCHEMA;
    }
    return CF_RESDB_OK;
}

int cf_resdb_check(const char *path, char *msg, size_t ml)
{
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    int rc = CF_RESDB_OK, jobs = 0, v = 0;
    if (sq_ready(path, msg, ml))
        return CF_RESDB_ENOLIB;
    if (sq.sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) != SQLITE_OK) {
        snprintf(msg, ml, "%s: %s", path, db ? sq.sqlite3_errmsg(db) : "cannot open");
        rc = CF_RESDB_EOPEN;
        goto out;
    }
    sq.sqlite3_busy_timeout(db, 5000);
    int e =
        sq.sqlite3_prepare_v2(db,
                              "SELECT (SELECT count(*) FROM sqlite_master WHERE type = 'table' "
                              "AND name = 'jobs'), (SELECT user_version FROM pragma_user_version)",
                              -1, &st, NULL);
    if (e == SQLITE_OK && (e = sq.sqlite3_step(st)) == SQLITE_ROW) {
        jobs = sq.sqlite3_column_int(st, 0);
        v = sq.sqlite3_column_int(st, 1);
    }
    if (e == SQLITE_NOTADB) {
        snprintf(msg, ml, "%s: %s (not an SQLite database)", path,
                 cf_resdb_strerror(CF_RESDB_ENOTDB));
        rc = CF_RESDB_ENOTDB;
    } else if (e != SQLITE_ROW) {
        snprintf(msg, ml, "%s: %s", path, sq.sqlite3_errmsg(db));
        rc = CF_RESDB_EOPEN;
    } else if (!jobs || v < 1) { /* SQLite reads an empty file as an empty database */
        struct stat sb;
        snprintf(msg, ml, "%s: %s (%s)", path, cf_resdb_strerror(CF_RESDB_ENOTDB),
                 jobs                                  ? "schema version 0"
                 : !stat(path, &sb) && sb.st_size == 0 ? "an empty file"
                                                       : "an SQLite database without a jobs table");
        rc = CF_RESDB_ENOTDB;
    } else if (v > CF_RESDB_VERSION) {
        snprintf(msg, ml, "%s: schema version %d, this cellfit knows %d", path, v,
                 CF_RESDB_VERSION);
        rc = CF_RESDB_ESCHEMA;
    }
out:
    sq.sqlite3_finalize(st);
    sq.sqlite3_close(db);
    return rc;
}

int cf_resdb_open(const char *path, cf_resdb_t **out, char *msg, size_t ml)
{
    *out = NULL;
    if (sq_ready(path, msg, ml))
        return CF_RESDB_ENOLIB;
    cf_resdb_t *d = calloc(1, sizeof *d);
    if (!d)
        return snprintf(msg, ml, "%s: out of memory", path), CF_RESDB_EOPEN;
    if (sq.sqlite3_open_v2(path, &d->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL) !=
        SQLITE_OK) {
        snprintf(msg, ml, "%s: %s", path, d->db ? sq.sqlite3_errmsg(d->db) : "cannot open");
        sq.sqlite3_close(d->db);
        free(d);
        return CF_RESDB_EOPEN;
    }
    /* WAL: readers (the forwarder, `cellfit results`) never block the job's
     * write; FULL: the commit is on disk when it returns. A 256 KiB page
     * cache: a row a job needs few pages, and serve holds three connections
     * (recorder, forwarder, outbox registers) for weeks; SQLite's default
     * lets each grow to 2 MB as the table does. */
    sq.sqlite3_busy_timeout(d->db, 5000);
    int rc = exec(d, "PRAGMA journal_mode=WAL") || exec(d, "PRAGMA synchronous=FULL") ||
                     exec(d, "PRAGMA cache_size=-256")
                 ? CF_RESDB_EOPEN
                 : migrate(d, msg, ml);
    if (rc) {
        if (rc == CF_RESDB_EOPEN)
            snprintf(msg, ml, "%s: %s", path, sq.sqlite3_errmsg(d->db));
        sq.sqlite3_close(d->db);
        free(d);
        return rc;
    }
    *out = d;
    return CF_RESDB_OK;
}

void cf_resdb_close(cf_resdb_t *d)
{
    if (!d)
        return;
    sq.sqlite3_close(d->db);
    free(d);
}

static void bind_text(sqlite3_stmt *st, int i, const char *s)
{
    if (s && *s)
        sq.sqlite3_bind_text(st, i, s, -1, SQLITE_TRANSIENT);
    else
        sq.sqlite3_bind_null(st, i);
}

static void bind_job(sqlite3_stmt *st, const cf_resdb_job_t *j)
{
    int f = j->has_fit;
    bind_text(st, 1, j->job_uuid);
    bind_text(st, 2, j->cell_id);
    sq.sqlite3_bind_int64(st, 3, j->part_number);
    bind_text(st, 4, j->part_id);
    sq.sqlite3_bind_int64(st, 5, j->program);
    sq.sqlite3_bind_int64(st, 6, j->result_seq);
    bind_text(st, 7, j->command);
    bind_text(st, 8, j->started_at);
    bind_text(st, 9, j->ended_at);
    bind_text(st, 10, j->state);
    sq.sqlite3_bind_int64(st, 11, j->error_code);
    for (int i = 12; i <= 19; i++)
        sq.sqlite3_bind_null(st, i);
    if (f) {
        sq.sqlite3_bind_int64(st, 12, j->fit_status);
        sq.sqlite3_bind_double(st, 13, j->rms);
        sq.sqlite3_bind_double(st, 14, j->max_dev);
        sq.sqlite3_bind_double(st, 15, j->min_dev);
        sq.sqlite3_bind_double(st, 16, j->within_pct);
        if (j->verdict > 0) /* 0: no verdict (a shell fit without a tolerance) */
            sq.sqlite3_bind_int64(st, 17, j->verdict);
        sq.sqlite3_bind_int64(st, 18, j->points);
        sq.sqlite3_bind_int64(st, 19, j->control_points);
    }
    bind_text(st, 20, j->surface_path);
    bind_text(st, 21, j->surface_sha256);
    bind_text(st, 22, j->report_path);
    bind_text(st, 23, j->report_sha256);
    bind_text(st, 24, j->journal_path);
    bind_text(st, 25, j->journal_sha256);
}

static void col_text(sqlite3_stmt *st, int i, char *out, size_t n)
{
    const unsigned char *s = sq.sqlite3_column_text(st, i);
    snprintf(out, n, "%s", s ? (const char *)s : "");
}

static double col_num(sqlite3_stmt *st, int i)
{
    return sq.sqlite3_column_type(st, i) == SQLITE_NULL ? NAN : sq.sqlite3_column_double(st, i);
}

static void get_job(sqlite3_stmt *st, cf_resdb_job_t *j)
{
    memset(j, 0, sizeof *j);
    col_text(st, 0, j->job_uuid, sizeof j->job_uuid);
    col_text(st, 1, j->cell_id, sizeof j->cell_id);
    j->part_number = (long)sq.sqlite3_column_int64(st, 2);
    col_text(st, 3, j->part_id, sizeof j->part_id);
    j->program = (long)sq.sqlite3_column_int64(st, 4);
    j->result_seq = (long)sq.sqlite3_column_int64(st, 5);
    col_text(st, 6, j->command, sizeof j->command);
    col_text(st, 7, j->started_at, sizeof j->started_at);
    col_text(st, 8, j->ended_at, sizeof j->ended_at);
    col_text(st, 9, j->state, sizeof j->state);
    j->error_code = (long)sq.sqlite3_column_int64(st, 10);
    j->has_fit = sq.sqlite3_column_type(st, 12) != SQLITE_NULL;
    j->fit_status = (long)sq.sqlite3_column_int64(st, 11);
    j->rms = sq.sqlite3_column_double(st, 12);
    /* A figure not known (a shell fit's signed deviations, its share within
     * without a tolerance) was bound as NaN, which SQLite stores as NULL. */
    j->max_dev = col_num(st, 13);
    j->min_dev = col_num(st, 14);
    j->within_pct = col_num(st, 15);
    j->verdict = (long)sq.sqlite3_column_int64(st, 16);
    j->points = (long)sq.sqlite3_column_int64(st, 17);
    j->control_points = (long)sq.sqlite3_column_int64(st, 18);
    col_text(st, 19, j->surface_path, sizeof j->surface_path);
    col_text(st, 20, j->surface_sha256, sizeof j->surface_sha256);
    col_text(st, 21, j->report_path, sizeof j->report_path);
    col_text(st, 22, j->report_sha256, sizeof j->report_sha256);
    col_text(st, 23, j->journal_path, sizeof j->journal_path);
    col_text(st, 24, j->journal_sha256, sizeof j->journal_sha256);
}

/* Run sql (no result rows) with up to two text and one real parameter. */
static int run(cf_resdb_t *d, const char *sql, const char *t1, const char *t2, double r3)
{
    sqlite3_stmt *st;
    if (sq.sqlite3_prepare_v2(d->db, sql, -1, &st, NULL) != SQLITE_OK)
        return CF_RESDB_EIO;
    int np = sq.sqlite3_bind_parameter_count(st);
    if (np >= 1)
        bind_text(st, 1, t1);
    if (np >= 2)
        bind_text(st, 2, t2);
    if (np >= 3)
        sq.sqlite3_bind_double(st, 3, r3);
    int rc = sq.sqlite3_step(st);
    sq.sqlite3_finalize(st);
    return rc == SQLITE_DONE ? CF_RESDB_OK : CF_RESDB_EIO;
}

int cf_resdb_record(cf_resdb_t *d, const cf_resdb_job_t *j, int targets, long outbox_max)
{
    if (exec(d, "BEGIN IMMEDIATE"))
        return CF_RESDB_EIO;
    sqlite3_stmt *st;
    int rc = CF_RESDB_EIO;
    if (sq.sqlite3_prepare_v2(d->db,
                              "INSERT OR REPLACE INTO jobs (" COLS
                              ") VALUES (?,?,?,?,?,?,?,?,?,?,?,"
                              "?,?,?,?,?,?,?,?,?,?,?,?,?,?)",
                              -1, &st, NULL) != SQLITE_OK)
        goto fail;
    bind_job(st, j);
    rc = sq.sqlite3_step(st) == SQLITE_DONE ? CF_RESDB_OK : CF_RESDB_EIO;
    sq.sqlite3_finalize(st);
    double now = now_unix();
    static const char *const names[2] = {"pg", "mqtt"};
    for (int k = 0; k < 2 && !rc; k++)
        if (targets & (1 << k))
            rc = run(d,
                     "INSERT OR IGNORE INTO outbox (job_uuid, target, next_try, created) "
                     "VALUES (?, ?, ?3, ?3)",
                     j->job_uuid, names[k], now);
    if (!rc && outbox_max > 0) {
        /* Full: the oldest go, counted (a job is never refused or held). */
        char lim[32];
        snprintf(lim, sizeof lim, "%ld", outbox_max);
        rc = run(d,
                 "UPDATE counters SET value = value + max(0, (SELECT count(*) FROM outbox) - "
                 "CAST(?1 AS INTEGER)) WHERE name = 'outbox_dropped'",
                 lim, NULL, 0);
        if (!rc)
            rc = run(d,
                     "DELETE FROM outbox WHERE id IN (SELECT id FROM outbox ORDER BY id LIMIT "
                     "max(0, (SELECT count(*) FROM outbox) - CAST(?1 AS INTEGER)))",
                     lim, NULL, 0);
    }
    if (!rc && exec(d, "COMMIT") == CF_RESDB_OK)
        return CF_RESDB_OK;
fail:
    exec(d, "ROLLBACK");
    return CF_RESDB_EIO;
}

int cf_resdb_due(cf_resdb_t *d, int target, double now, cf_resdb_due_t *out)
{
    sqlite3_stmt *st;
    if (sq.sqlite3_prepare_v2(d->db,
                              "SELECT id, job_uuid, attempts FROM outbox WHERE target = ?1 AND "
                              "next_try <= ?3 ORDER BY id LIMIT 1",
                              -1, &st, NULL) != SQLITE_OK)
        return CF_RESDB_EIO;
    bind_text(st, 1, target == CF_RESDB_PG ? "pg" : "mqtt");
    sq.sqlite3_bind_double(st, 3, now);
    int rc = sq.sqlite3_step(st), found = 0;
    if (rc == SQLITE_ROW) {
        out->id = sq.sqlite3_column_int64(st, 0);
        col_text(st, 1, out->job_uuid, sizeof out->job_uuid);
        out->attempts = (long)sq.sqlite3_column_int64(st, 2);
        out->target = target;
        found = 1;
    }
    sq.sqlite3_finalize(st);
    return rc == SQLITE_ROW || rc == SQLITE_DONE ? found : CF_RESDB_EIO;
}

int cf_resdb_delivered(cf_resdb_t *d, long long id)
{
    char ids[32];
    snprintf(ids, sizeof ids, "%lld", id);
    return run(d, "DELETE FROM outbox WHERE id = CAST(?1 AS INTEGER)", ids, NULL, 0);
}

int cf_resdb_retry(cf_resdb_t *d, long long id, double next_try, const char *err)
{
    char ids[32];
    snprintf(ids, sizeof ids, "%lld", id);
    int rc = run(d,
                 "UPDATE outbox SET attempts = attempts + 1, next_try = ?3, last_error = ?2 "
                 "WHERE id = CAST(?1 AS INTEGER)",
                 ids, err, next_try);
    if (!rc && err && *err)
        rc = run(d, "INSERT OR REPLACE INTO last_error (id, text) VALUES (1, ?1)", err, NULL, 0);
    return rc;
}

int cf_resdb_due_now(cf_resdb_t *d, int target)
{
    return run(d, "UPDATE outbox SET next_try = 0 WHERE target = ?1",
               target == CF_RESDB_PG ? "pg" : "mqtt", NULL, 0);
}

int cf_resdb_outbox_stat(cf_resdb_t *d, cf_resdb_obstat_t *o)
{
    memset(o, 0, sizeof *o);
    sqlite3_stmt *st;
    if (sq.sqlite3_prepare_v2(d->db,
                              "SELECT (SELECT count(*) FROM outbox WHERE target = 'pg'),"
                              " (SELECT count(*) FROM outbox WHERE target = 'mqtt'),"
                              " (SELECT value FROM counters WHERE name = 'outbox_dropped'),"
                              " (SELECT coalesce(min(created), 0) FROM outbox),"
                              " (SELECT text FROM last_error WHERE id = 1)",
                              -1, &st, NULL) != SQLITE_OK)
        return CF_RESDB_EIO;
    int rc = sq.sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        o->pending_pg = (long)sq.sqlite3_column_int64(st, 0);
        o->pending_mqtt = (long)sq.sqlite3_column_int64(st, 1);
        o->dropped = sq.sqlite3_column_int64(st, 2);
        o->oldest = sq.sqlite3_column_double(st, 3);
        col_text(st, 4, o->last_error, sizeof o->last_error);
    }
    sq.sqlite3_finalize(st);
    return rc == SQLITE_ROW ? CF_RESDB_OK : CF_RESDB_EIO;
}

int cf_resdb_get(cf_resdb_t *d, const char *uuid, cf_resdb_job_t *out)
{
    sqlite3_stmt *st;
    if (sq.sqlite3_prepare_v2(d->db, "SELECT " COLS " FROM jobs WHERE job_uuid = ?1", -1, &st,
                              NULL) != SQLITE_OK)
        return CF_RESDB_EIO;
    bind_text(st, 1, uuid);
    int rc = sq.sqlite3_step(st);
    if (rc == SQLITE_ROW)
        get_job(st, out);
    sq.sqlite3_finalize(st);
    return rc == SQLITE_ROW ? CF_RESDB_OK : rc == SQLITE_DONE ? CF_RESDB_ENOTFOUND : CF_RESDB_EIO;
}

int cf_resdb_query(cf_resdb_t *d, long part, const char *since, cf_resdb_fn fn, void *ctx)
{
    sqlite3_stmt *st;
    if (sq.sqlite3_prepare_v2(d->db,
                              "SELECT " COLS " FROM jobs WHERE (?1 < 0 OR part_number = ?1) AND "
                              "(?2 IS NULL OR ended_at >= ?2) ORDER BY ended_at, job_uuid",
                              -1, &st, NULL) != SQLITE_OK)
        return CF_RESDB_EIO;
    sq.sqlite3_bind_int64(st, 1, part);
    bind_text(st, 2, since);
    int rc, stop = 0;
    cf_resdb_job_t *j = malloc(sizeof *j);
    if (!j) {
        sq.sqlite3_finalize(st);
        return CF_RESDB_EIO;
    }
    while (!stop && (rc = sq.sqlite3_step(st)) == SQLITE_ROW) {
        get_job(st, j);
        stop = fn(ctx, j);
    }
    free(j);
    sq.sqlite3_finalize(st);
    if (stop)
        return stop;
    return rc == SQLITE_DONE ? CF_RESDB_OK : CF_RESDB_EIO;
}
#endif
