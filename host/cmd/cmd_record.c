/* SPDX-License-Identifier: MIT */
/* cmd_record.c: a shell job's row in the results database (cmd_record.h). */
#define _DEFAULT_SOURCE /* gethostname, realpath beside C11 */
#include "cmd_record.h"
#include "cf_cli.h"
#include <string.h>

int cmd_record_table(cf_opt_t *t, cmd_record_t *r)
{
    memset(r, 0, sizeof *r);
    t[0] = (cf_opt_t){.name = "record",
                      .kind = CF_OPT_FLAG,
                      .dst = &r->on,
                      .help = "record the job in the cell's results database (as serve does; "
                              "cellfit results shows it)"};
    t[1] = (cf_opt_t){.name = "db",
                      .kind = CF_OPT_STR,
                      .dst = &r->db,
                      .arg = "PATH",
                      .help = "--record into this database, or a results folder's results.db "
                              "(implies --record)",
                      .def = "results/results.db"};
    return CMD_RECORD_N;
}

#if CF_NO_PLANT
int cmd_record(const char *cmd, const cmd_record_t *r, const cmd_record_job_t *j)
{
    (void)j;
    if (!r->on && !r->db)
        return CLI_OK;
    return cli_error(cmd, CLI_FAIL,
                     "--record: this cellfit is built without SQLite (libsqlite3-dev): the "
                     "job is not recorded");
}
#else
#include "cf_record.h"
#include "cf_resdb.h"
#include "cf_sha256.h"
#include "cf_uuid.h"
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

/* A file written by the job: its absolute path and its checksum. */
static int file_row(const char *path, char *pbuf, size_t pn, char sum[65])
{
    char abs[PATH_MAX];
    if (!path)
        return 0;
    if (!realpath(path, abs) || strlen(abs) >= pn || cf_sha256_file(abs, sum))
        return -1;
    memcpy(pbuf, abs, strlen(abs) + 1);
    return 0;
}

/* The fit job's status as the PLC's FIT_STATUS register says it (serve's
 * rows: plc_fsm.h's PLC_FIT_*). */
static long fit_status(cf_fitjob_status_t s)
{
    switch (s) {
    case CF_FITJOB_MET: return PLC_FIT_MET;
    case CF_FITJOB_NOT_MET_DATA_LIMIT: return PLC_FIT_NOT_MET_DATA;
    case CF_FITJOB_NOT_MET_MAX_CP: return PLC_FIT_NOT_MET_MAX_CP;
    case CF_FITJOB_NOT_MET_NO_PROGRESS: return PLC_FIT_NOT_MET_NO_PROGRESS;
    default: return PLC_FIT_NONE;
    }
}

static void fill_fit(cf_resdb_job_t *row, const cf_fitjob_result_t *f, const cf_fitjob_opts_t *o)
{
    double tol = o ? (o->stats_tol > 0 ? o->stats_tol : o->tol) : 0;
    row->has_fit = 1;
    row->fit_status = fit_status(f->status);
    row->rms = f->rms;
    if (f->stats) { /* signed deviations, when the job kept them */
        row->max_dev = f->stats->max;
        row->min_dev = f->stats->min;
    } else
        row->max_dev = row->min_dev = NAN; /* stored as NULL */
    row->within_pct = tol > 0 ? f->within_pct : NAN;
    row->verdict = tol > 0 ? (f->max_abs <= tol ? 1 : 2) : 0; /* 0: NULL */
    row->points = f->points;
    row->control_points = (long)f->surf.nu * f->surf.nv;
}

int cmd_record_db_path(const char *db, char *buf, size_t n)
{
    const char *p = db ? db : "results/results.db";
    struct stat sb;
    if (!stat(p, &sb) && S_ISDIR(sb.st_mode))
        return cf_record_default_path(p, buf, n);
    return snprintf(buf, n, "%s", p) >= (int)n ? -1 : 0;
}

int cmd_record(const char *cmd, const cmd_record_t *r, const cmd_record_job_t *j)
{
    if (!r->on && !r->db)
        return CLI_OK;
    char path[4096], msg[512];
    if (cmd_record_db_path(r->db, path, sizeof path))
        return cli_error(cmd, CLI_FAIL, "--db %s: path too long; the job is not recorded", r->db);
    /* An existing file must be ours: cf_resdb_open would migrate anything. */
    struct stat sb;
    int ce = stat(path, &sb) ? CF_RESDB_OK : cf_resdb_check(path, msg, sizeof msg);
    if (ce == CF_RESDB_ENOLIB) /* msg names the package to install */
        return cli_error(cmd, CLI_FAIL, "--record: %s; the job is not recorded", msg);
    if (ce)
        return cli_error(cmd, CLI_FAIL,
                         "--record: %s; the job is not recorded (--db: a results database, "
                         "a folder for its results.db, or a new file)",
                         msg);
    cf_resdb_job_t *row = calloc(1, sizeof *row);
    if (!row)
        return cli_error(cmd, CLI_FAIL, "--record: out of memory; the job is not recorded");
    int ec = CLI_OK;
    if (cf_uuid_new(row->job_uuid)) {
        ec = cli_error(cmd, CLI_FAIL,
                       "--record: no UUID (the kernel's random source); the job "
                       "is not recorded");
        goto out;
    }
    cf_resdb_now_iso(row->ended_at);
    cli_iso8601(cli_utc_now() - (cli_now() - j->t0), row->started_at, sizeof row->started_at);
    if (gethostname(row->cell_id, sizeof row->cell_id - 1) || !row->cell_id[0])
        snprintf(row->cell_id, sizeof row->cell_id, "cell");
    snprintf(row->command, sizeof row->command, "%s", j->command);
    snprintf(row->state, sizeof row->state, "%s", j->code ? "error" : "done");
    row->error_code = j->code < 0 ? -(long)j->code : j->code;
    if (j->fit && !j->code)
        fill_fit(row, j->fit, j->fo);
    const char *bad = NULL;
    if (file_row(j->surface, row->surface_path, sizeof row->surface_path, row->surface_sha256))
        bad = j->surface;
    else if (file_row(j->report, row->report_path, sizeof row->report_path, row->report_sha256))
        bad = j->report;
    else if (file_row(j->journal, row->journal_path, sizeof row->journal_path, row->journal_sha256))
        bad = j->journal;
    if (bad) {
        ec = cli_error(cmd, CLI_FAIL,
                       "--record: %s: cannot read it back for its checksum; the "
                       "job is not recorded",
                       bad);
        goto out;
    }
    cf_resdb_t *db;
    if (cf_resdb_open(path, &db, msg, sizeof msg)) {
        ec = cli_error(cmd, CLI_FAIL, "--record: %s; the job is not recorded", msg);
        goto out;
    }
    int e = cf_resdb_record(db, row, 0, 0); /* no outbox: nothing to forward */
    cf_resdb_close(db);
    if (e)
        ec = cli_error(cmd, CLI_FAIL, "--record: %s: %s; the job is not recorded", path,
                       cf_resdb_strerror(e));
    else
        fprintf(stderr, "%s: recorded job %s in %s\n", cmd, row->job_uuid, path);
out:
    free(row);
    return ec;
}
#endif
