/* SPDX-License-Identifier: MIT */
/* cf_record.h: every job of `cellfit serve` (HOME aside) recorded in the
 * cell's results.db (cf_resdb.h), by a runner table (cf_plcsrv.h) wrapped
 * around the job runner's (cf_plcrun.h): a job's UUID and start time when
 * its first phase begins (the worker starts it as the command is
 * accepted); when its last phase returns (done, failed or aborted) the row
 * and its outbox entries are written and synced before the phase's result
 * goes back to the state machine, so the PLC never sees DONE for a job
 * that is not on disk. The forwarder (cf_forward.h) is then kicked. A
 * database error is logged and counted, never turned into a job error:
 * the part is measured either way. */
#ifndef CF_RECORD_H
#define CF_RECORD_H

#include "cf_forward.h"
#include "cf_plcrun.h"
#include "cf_resdb.h"

typedef struct cf_record {
    cf_runner_t inner; /* the wrapped table */
    cf_plcrun_t *rr;   /* its context: paths of the journal and the export */
    cf_resdb_t *db;    /* the job thread's connection */
    cf_forward_t *fwd; /* NULL: nothing forwarded (no outbox entries) */
    const char *cell_id;
    int targets;     /* outbox targets (cf_forward_targets) */
    long outbox_max; /* cf_resdb_record's bound */
    /* the running job (the worker thread's only) */
    int active, cmd;
    unsigned seq;
    char uuid[37], started[32];
    plc_results_t fit; /* the latched fit's figures, for EXPORT rows */
    int have_fit;
    long recorded, failed; /* rows written, rows lost to database errors */
} cf_record_t;

/* Fill rec's inner, rr, db, fwd, cell_id, targets, outbox_max, then wrap:
 * out gets the table serve hands to cf_plcsrv_run. */
void cf_record_wrap(cf_record_t *rec, cf_runner_t *out);

/* "results_dir/results.db" into buf (0), -1 when it does not fit. */
int cf_record_default_path(const char *results_dir, char *buf, size_t n);

#endif
