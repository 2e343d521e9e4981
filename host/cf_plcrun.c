/* cf_plcrun.c: the job runner of `cellfit serve` on files (cf_plcrun.h):
 * PLC parameters to cf_job options, cf_job's outcome to PLC codes. */
#include "cf_plcrun.h"
#include "cf_err.h"
#include "cf_log.h"
#include "nf_err.h"
#include "rig_err.h"
#include <stdio.h>
#include <string.h>
#include <time.h>

static void fit_opts(const cf_plcrun_t *rr, const plc_params_t *p, cf_job_fit_opts_t *o)
{
    o->nominal = rr->nominal;
    o->points = rr->points;
    o->alpha = p->alpha;
    o->beta = p->beta;
    o->tol = p->tol;
    o->net_u = p->net_u;
    o->net_v = p->net_v;
}

/* Parameter checks before a command is accepted (1xx, nothing started).
 * A nominal that cannot be read is left to the job (301), so the PLC sees
 * a job error with the file named in the log. */
static int run_check(void *ctx, int cmd, const plc_params_t *p)
{
    cf_plcrun_t *rr = ctx;
    char msg[512];
    if ((cmd == PLC_C_SCAN || cmd == PLC_C_SCAN_FIT) && !(p->x0 != p->x1 && p->y0 != p->y1))
        return PLC_E_BAD_PARAM; /* an empty scan region */
    switch (cmd) {
    case PLC_C_FIT:
    case PLC_C_SCAN_FIT: {
        if (!rr->nominal || !rr->points)
            return PLC_E_NO_JOB_FILES;
        cf_job_fit_opts_t o;
        fit_opts(rr, p, &o);
        int rc = cf_job_check(&o, msg, sizeof msg);
        if (rc == CF_EARG || rc == NF_EBUDGET) {
            cf_log(CF_LOG_WARN, "fit refused: %s", msg);
            return rc == CF_EARG ? PLC_E_BAD_PARAM : PLC_E_TOO_BIG;
        }
        return 0;
    }
    case PLC_C_EXPORT:
        if (p->folder >= PLC_MAX_FOLDERS || !rr->results_dir[p->folder]) {
            cf_log(CF_LOG_WARN, "export refused: results folder %u not configured", p->folder);
            return PLC_E_BAD_PARAM;
        }
        return 0;
    default: return 0;
    }
}

/* RIG WIRING (issue 4): home the stage (rig_stage_ops.home) and scan the
 * region into the journal (firmware/scan.h) once hal/ and the scan job are
 * merged; cmd_serve then builds the stage and probe from --stage/--probe and
 * sets cf_runner_t.rig. Until then no runner has a rig: the state machine
 * refuses these commands with 106 before they get here. */
static int run_home(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    (void)ctx, (void)p, (void)ctl;
    return PLC_E_NO_RIG;
}

static int run_scan(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    (void)ctx, (void)p, (void)ctl;
    return PLC_E_NO_RIG;
}

static int run_fit(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl, plc_results_t *res)
{
    cf_plcrun_t *rr = ctx;
    char msg[512];
    cf_job_fit_opts_t o;
    fit_opts(rr, p, &o);
    if (rr->have_last) {
        cf_job_result_free(&rr->last);
        rr->have_last = 0;
    }
    int rc = cf_job_check(&o, msg, sizeof msg);
    if (rc) {
        cf_log(CF_LOG_ERROR, "fit: %s", msg);
        return rc == NF_EBUDGET ? PLC_E_TOO_BIG : PLC_E_NOMINAL;
    }
    rc = cf_job_fit(&o, ctl, &rr->last, msg, sizeof msg);
    if (rc == RIG_EABORTED)
        return CF_PLC_ABORTED;
    if (rc) {
        cf_log(CF_LOG_ERROR, "fit: %s", msg);
        switch (rc) {
        case CF_EEMPTY: return PLC_E_NO_POINTS;
        case CF_ENOMEM: return PLC_E_MEMORY;
        case CF_EIO:
        case CF_EPARSE:
        case CF_EUNSUPPORTED: return PLC_E_POINTS;
        default: return rc == NF_EDOMAIN || rc == NF_ENONFINITE ? PLC_E_POINTS : PLC_E_FIT;
        }
    }
    rr->have_last = 1;
    rr->last_part = p->part;
    const cf_stats_t *st = rr->last.st;
    res->rms = (float)cf_stats_rms(st);
    res->max = (float)st->max;
    res->min = (float)st->min;
    res->within_pct = (float)cf_stats_within_pct(st);
    res->verdict = st->max_abs <= st->tol ? PLC_VERDICT_PASS : PLC_VERDICT_FAIL;
    res->points = (uint32_t)rr->last.points;
    res->control_points = (uint32_t)((long)rr->last.fitted.nu * rr->last.fitted.nv);
    res->duration_ms = (uint32_t)(rr->last.seconds * 1000.0 + 0.5);
    return 0;
}

static int run_export(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_plcrun_t *rr = ctx;
    char name[64], msg[512];
    if (!rr->have_last)
        return PLC_E_INTERNAL; /* the state machine holds results: we must too */
    if (ctl && ctl->progress)
        ctl->progress(ctl->ctx, 0);
    long long utc = (long long)time(NULL);
    cf_job_folder_name(rr->last_part, utc, name, sizeof name);
    snprintf(rr->last_export, sizeof rr->last_export, "%s/%s", rr->results_dir[p->folder], name);
    cf_job_meta_t meta = {rr->last_part, p->program, p->seq, rr->nominal,
                          rr->points,    BOARD_NAME, utc};
    if (cf_job_export(&rr->last, &meta, rr->last_export, msg, sizeof msg)) {
        cf_log(CF_LOG_ERROR, "export: %s", msg);
        return PLC_E_EXPORT;
    }
    cf_log(CF_LOG_INFO, "export: wrote %s/fitted.igs and report.json", rr->last_export);
    return 0;
}

/* RIG WIRING: rig_stage_ops.stop once a stage exists; the fit and export
 * stop on the server's flag between batches. */
static void run_abort(void *ctx)
{
    (void)ctx;
}

void cf_plcrun_init(cf_plcrun_t *rr, cf_runner_t *out)
{
    memset(out, 0, sizeof *out);
    out->check = run_check;
    out->home = run_home;
    out->scan = run_scan;
    out->fit = run_fit;
    out->export_result = run_export;
    out->abort = run_abort;
    out->ctx = rr;
    out->rig = 0;
}

void cf_plcrun_free(cf_plcrun_t *rr)
{
    if (rr->have_last)
        cf_job_result_free(&rr->last);
    rr->have_last = 0;
}
