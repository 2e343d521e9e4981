/* SPDX-License-Identifier: MIT */
/* cf_resdb.h: the cell's results database (SQLite, results/results.db):
 * one row per job in `jobs`, and the durable `outbox` of deliveries to the
 * plant (PostgreSQL, MQTT) that cf_forward.h drains. A row and its outbox
 * entries are written in one transaction, synced (WAL, synchronous=FULL)
 * before the caller reports the job done, so a result survives a power cut
 * the moment the PLC can see it. The schema is versioned (PRAGMA
 * user_version) and migrated on open. Each connection belongs to one
 * thread; the forwarder opens its own. */
#ifndef CF_RESDB_H
#define CF_RESDB_H

#include <stddef.h>

#define CF_RESDB_VERSION 2 /* the schema this code writes */
#define CF_RESDB_PATH 4096 /* bytes of a stored path, its NUL included */

enum {
    CF_RESDB_OK = 0,
    CF_RESDB_EOPEN = -1,     /* cannot open or create the file */
    CF_RESDB_ESCHEMA = -2,   /* a newer schema, or a migration failed */
    CF_RESDB_EIO = -3,       /* a statement failed (disk full, locked too long) */
    CF_RESDB_ENOTFOUND = -4, /* no such job */
    CF_RESDB_ENOTDB = -5,    /* a file, but not a results database */
    CF_RESDB_ENOLIB = -6     /* SQLite is not installed (msg names the package) */
};
const char *cf_resdb_strerror(int err);

/* Outbox targets (bits). */
enum { CF_RESDB_PG = 1, CF_RESDB_MQTT = 2 };

/* One job's row. Text fields "" and has_fit 0 are stored as NULL; with a
 * fit, max_dev, min_dev, within_pct NaN and verdict 0 too (figures a shell
 * fit does not know, cmd_record.h), read back as NaN and 0. */
typedef struct cf_resdb_job {
    char job_uuid[37];
    char cell_id[64];
    long part_number;
    char part_id[64];
    long program, result_seq;
    char command[16];                  /* scan, fit, scan_fit, export */
    char started_at[32], ended_at[32]; /* UTC ISO 8601, milliseconds */
    char state[16];                    /* done, error, aborted */
    long error_code;                   /* the PLC's error code, 0 when done */
    int has_fit;                       /* the figures below are set */
    long fit_status;                   /* 0: fitted */
    double rms, max_dev, min_dev, within_pct;
    long verdict; /* 1 pass, 2 fail, 0 none */
    long points, control_points;
    char surface_path[CF_RESDB_PATH], surface_sha256[65];
    char report_path[CF_RESDB_PATH], report_sha256[65];
    char journal_path[CF_RESDB_PATH], journal_sha256[65];
} cf_resdb_job_t;

/* A delivery due. */
typedef struct cf_resdb_due {
    long long id;
    char job_uuid[37];
    int target; /* CF_RESDB_PG or CF_RESDB_MQTT */
    long attempts;
} cf_resdb_due_t;

typedef struct cf_resdb_obstat {
    long pending_pg, pending_mqtt; /* entries waiting */
    long long dropped;             /* entries dropped because the outbox was full */
    double oldest;                 /* enqueue time of the oldest entry (Unix s), 0: none */
    char last_error[256];          /* the most recent delivery error, "" none */
} cf_resdb_obstat_t;

typedef struct cf_resdb cf_resdb_t;

/* Whether an existing path is a results database (SQLite, a jobs table,
 * schema version 1 .. CF_RESDB_VERSION), looked at read-only, before
 * cf_resdb_open would migrate whatever it is given: CF_RESDB_OK;
 * CF_RESDB_ENOTDB (another file, another application's SQLite database, an
 * empty file) or CF_RESDB_ESCHEMA (a newer schema) with msg saying why;
 * CF_RESDB_EOPEN when it cannot be read. */
int cf_resdb_check(const char *path, char *msg, size_t ml);

/* Open (create) path and migrate it to CF_RESDB_VERSION. */
int cf_resdb_open(const char *path, cf_resdb_t **out, char *msg, size_t ml);
void cf_resdb_close(cf_resdb_t *db);
int cf_resdb_version(cf_resdb_t *db); /* PRAGMA user_version */

/* The row, and an outbox entry for each target bit, in one synced
 * transaction. The outbox holds at most outbox_max entries (<= 0: no
 * bound): beyond it the oldest are dropped and counted, never refused. */
int cf_resdb_record(cf_resdb_t *db, const cf_resdb_job_t *j, int targets, long outbox_max);

/* The oldest entry of one target due at now (Unix seconds): 1 found, 0
 * none, or an error. */
int cf_resdb_due(cf_resdb_t *db, int target, double now, cf_resdb_due_t *out);
/* Delivered: the entry goes. */
int cf_resdb_delivered(cf_resdb_t *db, long long id);
/* Not delivered: tried again at next_try; err kept for `results outbox`. */
int cf_resdb_retry(cf_resdb_t *db, long long id, double next_try, const char *err);
/* Every entry of target due now (after a reconnection). */
int cf_resdb_due_now(cf_resdb_t *db, int target);
int cf_resdb_outbox_stat(cf_resdb_t *db, cf_resdb_obstat_t *st);

int cf_resdb_get(cf_resdb_t *db, const char *uuid, cf_resdb_job_t *out);

/* Jobs by ended_at, oldest first; part < 0 any part, since NULL or "" any
 * time (an ISO 8601 prefix, compared as text: "2026-12-02" works). fn's
 * non-zero return stops the walk and is returned. */
typedef int (*cf_resdb_fn)(void *ctx, const cf_resdb_job_t *j);
int cf_resdb_query(cf_resdb_t *db, long part, const char *since, cf_resdb_fn fn, void *ctx);

/* The current UTC time as ISO 8601 with milliseconds ("...T..:..:..sssZ"). */
void cf_resdb_now_iso(char out[32]);

#endif
