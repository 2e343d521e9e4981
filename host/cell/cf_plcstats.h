/* SPDX-License-Identifier: MIT */
/* cf_plcstats.h: the figures of map version 3 that come from the rest of
 * the cell, for cf_plcsrv's stats hook: the plant outbox as `cellfit
 * results outbox` shows it (entries waiting per sink, the oldest's age,
 * entries dropped; read from results.db on a connection of its own, WAL:
 * it never waits for the job's writes), and the last scan's on-the-fly
 * counts, which the job runner keeps (cf_plcrun_t.scan_counts). */
#ifndef CF_PLCSTATS_H
#define CF_PLCSTATS_H

#include "cf_plcrun.h"
#include "cf_plcsrv.h"
#include "cf_resdb.h"

typedef struct cf_plcstats {
    const cf_plcrun_t *rr; /* the runner: the last scan's counts */
    const char *db_path;   /* results.db, NULL: no outbox */
    cf_resdb_t *db;        /* opened at the first call */
    int db_failed;         /* logged once */
} cf_plcstats_t;

/* The stats hook (ctx: cf_plcstats_t *). */
void cf_plcstats_read(void *ctx, cf_plc_stats_t *out);
void cf_plcstats_close(cf_plcstats_t *ps);

#endif
