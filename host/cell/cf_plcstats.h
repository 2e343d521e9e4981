/* SPDX-License-Identifier: MIT */
/* cf_plcstats.h: the figures of map version 3 that come from the rest of
 * the cell, for cf_plcsrv's stats hook: the plant outbox as `cellfit
 * results outbox` shows it (entries waiting per sink, the oldest's age,
 * entries dropped), and the last scan's on-the-fly counts, which the job
 * runner keeps (cf_plcrun_t.scan_counts). The outbox is read from
 * results.db by a thread of its own, on a connection of its own, every
 * CF_PLCSRV_STATS_MS; the hook only copies its last figures: a slow disk
 * or a locked database (SQLite waits up to 5 s) never holds up the Modbus
 * server's answers. */
#ifndef CF_PLCSTATS_H
#define CF_PLCSTATS_H

#include "cf_plcrun.h"
#include "cf_plcsrv.h"
#include "cf_resdb.h"
#include <pthread.h>

typedef struct cf_plcstats {
    const cf_plcrun_t *rr; /* the runner: the last scan's counts */
    const char *db_path;   /* results.db, NULL: no outbox */
    /* the reader thread's */
    cf_resdb_t *db; /* opened by the thread, again after a failure */
    int db_failed;  /* an open failed: logged once */
    pthread_t th;
    int th_live;
    /* shared with the thread */
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int stop;
    int have;      /* the figures below were read at least once */
    long pg, mqtt; /* entries waiting */
    long long dropped;
    double oldest; /* Unix s, 0: none */
} cf_plcstats_t;

/* Set up, and start the reader thread when db_path is not NULL (and the
 * build has results.db). 0, or -1 when the thread cannot start (logged:
 * the outbox registers then stay 0). */
int cf_plcstats_start(cf_plcstats_t *ps, const cf_plcrun_t *rr, const char *db_path);
/* The stats hook (ctx: cf_plcstats_t *): no I/O, a short lock. */
void cf_plcstats_read(void *ctx, cf_plc_stats_t *out);
/* Stop the thread (it may finish a read first: up to SQLite's 5 s), close. */
void cf_plcstats_close(cf_plcstats_t *ps);

#endif
