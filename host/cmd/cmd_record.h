/* SPDX-License-Identifier: MIT */
/* cmd_record.h: `--record` and `--db` of `cellfit fit` and `cellfit scan`:
 * a job run at the shell recorded in the cell's results database
 * (cf_resdb.h) as serve records a PLC's: a UUID, start and end (UTC ISO
 * 8601), state, the fit's figures, the output files' paths (absolute) and
 * SHA-256, in one synced transaction. No outbox entry: a later serve does
 * not forward these rows (`cellfit results export` takes them to the
 * plant). A shell job has no PLC: part number, program and sequence are 0,
 * the cell is the host name. The fit job computes no signed deviations
 * here, so max_dev and min_dev are NULL; within_pct and verdict (max |d|
 * <= tol, serve's rule) need --tol, else NULL. */
#ifndef CMD_RECORD_H
#define CMD_RECORD_H

#include "cf_fitjob.h"
#include "cf_opt.h"

#define CMD_RECORD_N 2 /* rows cmd_record_table writes */

typedef struct cmd_record {
    int on;         /* --record */
    const char *db; /* --db: a file, or a results folder (its results.db) */
} cmd_record_t;

/* The rows --record and --db into t (r zeroed first). Returns CMD_RECORD_N. */
int cmd_record_table(cf_opt_t *t, cmd_record_t *r);

/* The database --db names (NULL: the default results/results.db): a
 * folder stands for its results.db. 0, or -1 when it does not fit in n. */
int cmd_record_db_path(const char *db, char *buf, size_t n);

/* What the job wrote and how it ended, for its row. */
typedef struct cmd_record_job {
    const char *command;                    /* "fit", "scan", "scan_fit" */
    double t0;                              /* cli_now() when the job started */
    int code;                               /* 0 done; else the job's (negative) error code */
    const cf_fitjob_result_t *fit;          /* NULL: no fit */
    const cf_fitjob_opts_t *fo;             /* its options (tol) */
    const char *surface, *report, *journal; /* files written, NULL: none */
} cmd_record_job_t;

/* With --record (or --db): the row into the database. CLI_OK (also when
 * not asked), or CLI_FAIL after one line on stderr naming the database;
 * on success one line on stderr gives the job's UUID. */
int cmd_record(const char *cmd, const cmd_record_t *r, const cmd_record_job_t *j);

#endif
