/* cf_plcrun.c: the job runner of `cellfit serve` (cf_plcrun.h): PLC
 * parameters to cf_job / cf_scanjob options, their outcome to PLC codes. */
#include "cf_plcrun.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_log.h"
#include "cf_scanjob.h"
#include "nf_err.h"
#include "rig_err.h"
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static void fit_opts(const cf_plcrun_t *rr, const plc_params_t *p, cf_job_fit_opts_t *o)
{
    o->nominal = rr->nominal;
    o->points = rr->points;
    o->fit = rr->fit; /* the configured loop, robust passes, reprojection */
    o->fit.alpha = p->alpha;
    o->fit.beta = p->beta;
    o->fit.tol = p->tol;
    o->fit.net_u = p->net_u;
    o->fit.net_v = p->net_v;
}

static const char *journal_dir(const cf_plcrun_t *rr, const plc_params_t *p)
{
    if (rr->journal_dir)
        return rr->journal_dir;
    return p->folder < PLC_MAX_FOLDERS ? rr->results_dir[p->folder] : NULL;
}

static void scan_opts(const cf_plcrun_t *rr, const plc_params_t *p, cf_scanjob_opts_t *o)
{
    memset(o, 0, sizeof *o);
    if (rr->rig) {
        o->stage = rr->rig->stage;
        o->probe = rr->rig->probe;
    }
    o->x0 = p->x0, o->y0 = p->y0, o->x1 = p->x1, o->y1 = p->y1, o->step = p->step;
    o->z0 = rr->z0;
    memcpy(o->cal, rr->cal, sizeof o->cal);
    o->nominal = rr->nominal;
    o->job_id = (unsigned long long)time(NULL) * 65536ull + p->seq;
    o->pct0 = 0;
    o->pct1 = p->cmd == PLC_C_SCAN_FIT ? 70 : 100;
    /* issue 19: the scan method (config scan_method) */
    o->method = rr->scan_method;
    o->rig = rr->rig;
    o->period_us = rr->scan_period_us;
}

/* The scan's checks before it is accepted: a plan inside the stage's soft
 * limits (read at start-up: no I/O here), a folder for the journal. */
static int check_scan(const cf_plcrun_t *rr, const plc_params_t *p)
{
    cf_scanjob_opts_t o;
    scan_plan_t pl;
    scan_opts(rr, p, &o);
    if (cf_scanjob_plan(&o, &pl)) {
        cf_log(CF_LOG_WARN, "scan refused: region (%g, %g)-(%g, %g) with step %g has no plan",
               p->x0, p->y0, p->x1, p->y1, p->step);
        return PLC_E_BAD_PARAM;
    }
    const hal_stage_t *st = &rr->rig->st;
    double x1 = pl.x0 + (double)(pl.nx - 1) * pl.dx, y1 = pl.y0 + (double)(pl.ny - 1) * pl.dy;
    if (rr->rig->stage.ops &&
        (pl.x0 < st->lo[0] || x1 > st->hi[0] || pl.y0 < st->lo[1] || y1 > st->hi[1])) {
        cf_log(CF_LOG_WARN,
               "scan refused: region (%g, %g)-(%g, %g) outside the stage's limits "
               "[%g, %g] x [%g, %g]",
               pl.x0, pl.y0, x1, y1, st->lo[0], st->hi[0], st->lo[1], st->hi[1]);
        return PLC_E_BAD_PARAM;
    }
    if (!journal_dir(rr, p)) {
        cf_log(CF_LOG_WARN, "scan refused: no journal folder (journal_dir, or results_dir.%u)",
               p->folder);
        return PLC_E_BAD_PARAM;
    }
    return 0;
}

static int check_fit(const cf_plcrun_t *rr, const plc_params_t *p, int need_points)
{
    char msg[512];
    if (!rr->nominal || (need_points && !rr->points))
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

/* Parameter checks before a command is accepted (1xx, nothing started).
 * A nominal that cannot be read is left to the job (301), so the PLC sees
 * a job error with the file named in the log. */
static int run_check(void *ctx, int cmd, const plc_params_t *p)
{
    cf_plcrun_t *rr = ctx;
    int rc;
    if ((cmd == PLC_C_SCAN || cmd == PLC_C_SCAN_FIT) && !(p->x0 != p->x1 && p->y0 != p->y1))
        return PLC_E_BAD_PARAM; /* an empty scan region */
    switch (cmd) {
    case PLC_C_SCAN: return check_scan(rr, p);
    case PLC_C_SCAN_FIT: return (rc = check_scan(rr, p)) ? rc : check_fit(rr, p, 0);
    case PLC_C_FIT: return check_fit(rr, p, 1);
    case PLC_C_EXPORT:
        if (p->folder >= PLC_MAX_FOLDERS || !rr->results_dir[p->folder]) {
            cf_log(CF_LOG_WARN, "export refused: results folder %u not configured", p->folder);
            return PLC_E_BAD_PARAM;
        }
        return 0;
    default: return 0;
    }
}

int cf_plcrun_rig_code(int rc, int where)
{
    switch (rc) {
    case RIG_OK: return 0;
    case RIG_EABORTED: return CF_PLC_ABORTED;
    case RIG_ETIMEOUT:
    case RIG_EDISCONNECT:
    case RIG_ECRC:
    case RIG_EOPEN: return PLC_E_RIG_LINK;
    case RIG_EESTOP: return PLC_E_ESTOP;
    default: break;
    }
    switch (where) {
    case SCAN_AT_PROBE: return PLC_E_PROBE;
    case SCAN_AT_JOURNAL: return PLC_E_RIG;
    case SCAN_AT_STAGE: return PLC_E_STAGE;
    default: return rc == RIG_EIO || rc == RIG_EFULL ? PLC_E_RIG : PLC_E_STAGE;
    }
}

/* The stage driver's stop check while it waits for a move or homing. */
static int rig_should_stop(void *ctx)
{
    const cf_job_ctl_t *c = ((cf_plcrun_t *)ctx)->ctl;
    return c && c->should_stop && c->should_stop(c->ctx);
}

static void rig_take(cf_plcrun_t *rr, const cf_job_ctl_t *ctl)
{
    pthread_mutex_lock(&rr->rig_mu);
    rr->ctl = ctl;
}

static void rig_give(cf_plcrun_t *rr)
{
    rr->ctl = NULL;
    pthread_mutex_unlock(&rr->rig_mu);
}

static int run_home(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_plcrun_t *rr = ctx;
    (void)p;
    if (!rr->rig || !rr->rig->stage.ops)
        return PLC_E_NO_RIG;
    const rig_stage_t *s = &rr->rig->stage;
    rig_take(rr, ctl);
    if (ctl && ctl->progress)
        ctl->progress(ctl->ctx, 0);
    uint32_t bits = 0;
    int rc = s->ops->status(s->ctx, &bits);
    if (!rc && (bits & RIG_ST_FAULT) && !(bits & RIG_ST_ESTOP)) {
        /* "clear the stage, RESET, HOME": the reference run clears a
         * latched drive fault first. */
        cf_log(CF_LOG_WARN, "home: drive fault latched: resetting it");
        rc = s->ops->reset_fault(s->ctx);
    }
    if (!rc)
        rc = s->ops->home(s->ctx);
    if (rc && rc != RIG_EABORTED)
        cf_log(CF_LOG_ERROR, "home: %s: %s", rig_strerror(rc), hal_stage_error(s->ctx));
    rig_give(rr);
    return cf_plcrun_rig_code(rc, SCAN_AT_STAGE);
}

/* A journal name not yet taken: <dir>/<part>_<UTC>[-N].jnl. */
static int journal_name(const char *dir, unsigned long part, char *buf, size_t n)
{
    char base[64];
    cf_job_folder_name(part, (long long)time(NULL), base, sizeof base);
    for (int k = 1; k < 100; k++) {
        if (k == 1)
            snprintf(buf, n, "%s/%s.jnl", dir, base);
        else
            snprintf(buf, n, "%s/%s-%d.jnl", dir, base, k);
        if (access(buf, F_OK))
            return 0;
    }
    return -1;
}

static int run_scan(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_plcrun_t *rr = ctx;
    char msg[512];
    if (!rr->rig || !rr->rig->stage.ops || !rr->rig->probe.ops)
        return PLC_E_NO_RIG;
    rr->job_t0 = cli_now();
    const char *dir = journal_dir(rr, p);
    if (!dir || journal_name(dir, p->part, rr->journal, sizeof rr->journal)) {
        cf_log(CF_LOG_ERROR, "scan: no journal name free in %s", dir ? dir : "(none)");
        return PLC_E_RIG;
    }
    cf_scanjob_opts_t o;
    scan_opts(rr, p, &o);
    o.journal = rr->journal;
    scan_result_t res;
    rig_take(rr, ctl);
    int rc = cf_scanjob_run(&o, ctl, &res, msg, sizeof msg);
    const char *det = res.where == SCAN_AT_STAGE   ? hal_stage_error(o.stage.ctx)
                      : res.where == SCAN_AT_PROBE ? hal_probe_error(o.probe.ctx)
                                                   : "";
    rig_give(rr);
    if (rc == RIG_EOPEN || (rc && res.done == 0 && res.where == SCAN_AT_NONE)) {
        cf_log(CF_LOG_ERROR, "scan: %s", msg);
        return PLC_E_RIG;
    }
    if (rc == RIG_EABORTED) {
        cf_log(CF_LOG_WARN, "scan: stopped at grid point %ld; journal %s consistent",
               res.fail_index, rr->journal);
        return CF_PLC_ABORTED;
    }
    if (rc) {
        cf_log(CF_LOG_ERROR, "scan: %s%s%s", msg, *det ? ": " : "", det);
        return cf_plcrun_rig_code(rc, res.where);
    }
    cf_log(CF_LOG_INFO, "scan: %ld points (%ld without a surface) into %s", res.points, res.flagged,
           rr->journal);
    return 0;
}

static void fill_results(cf_plcrun_t *rr, const plc_params_t *p, double secs, plc_results_t *res)
{
    rr->have_last = 1;
    rr->last_part = p->part;
    const cf_stats_t *st = rr->last.stats;
    res->rms = (float)cf_stats_rms(st);
    res->max = (float)st->max;
    res->min = (float)st->min;
    res->within_pct = (float)cf_stats_within_pct(st);
    res->verdict = st->max_abs <= st->tol ? PLC_VERDICT_PASS : PLC_VERDICT_FAIL;
    res->points = (uint32_t)rr->last.points;
    res->control_points = (uint32_t)((long)rr->last.surf.nu * rr->last.surf.nv);
    res->duration_ms = (uint32_t)(secs * 1000.0 + 0.5);
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
    int scan = p->cmd == PLC_C_SCAN_FIT;
    int rc = cf_job_check(&o, msg, sizeof msg);
    if (rc) {
        cf_log(CF_LOG_ERROR, "fit: %s", msg);
        return rc == NF_EBUDGET ? PLC_E_TOO_BIG : PLC_E_NOMINAL;
    }
    rc = scan ? cf_scanjob_fit(rr->journal, &o, ctl, 70, 100, &rr->last, msg, sizeof msg)
              : cf_job_fit(&o, ctl, &rr->last, msg, sizeof msg);
    if (rc == RIG_EABORTED)
        return CF_PLC_ABORTED;
    if (rc) {
        cf_log(CF_LOG_ERROR, "fit: %s", msg);
        switch (rc) {
        case CF_EEMPTY: return PLC_E_NO_POINTS;
        case CF_ENOMEM: return PLC_E_MEMORY;
        case CF_EIO:
        case CF_EPARSE:
        case CF_EUNSUPPORTED: return scan ? PLC_E_RIG : PLC_E_POINTS;
        default:
            if (rc <= RIG_EARG && rc >= RIG_ESTATE)
                return PLC_E_RIG; /* the journal could not be read back */
            return rc == NF_EDOMAIN || rc == NF_ENONFINITE ? PLC_E_POINTS : PLC_E_FIT;
        }
    }
    cf_log(CF_LOG_INFO, "fit: %ld points, %d x %d net, %d round%s, fit_status %s%s%s",
           rr->last.points, rr->last.surf.nu, rr->last.surf.nv, rr->last.nrounds,
           rr->last.nrounds > 1 ? "s" : "", cf_fitjob_status_name(rr->last.status),
           rr->last.why[0] ? ": " : "", rr->last.why);
    for (int i = 0; i < rr->last.nwarn; i++)
        cf_log(CF_LOG_WARN, "fit: %s", rr->last.warn[i]);
    rr->last_scan = scan;
    snprintf(rr->last_journal, sizeof rr->last_journal, "%s", scan ? rr->journal : "");
    fill_results(rr, p, scan ? cli_now() - rr->job_t0 : rr->last.seconds, res);
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
    cf_job_meta_t meta = {rr->last_part,
                          p->program,
                          p->seq,
                          rr->nominal,
                          rr->last_scan ? NULL : rr->points,
                          BOARD_NAME,
                          utc,
                          rr->last_scan ? rr->last_journal : NULL};
    if (cf_job_export(&rr->last, &meta, rr->last_export, msg, sizeof msg)) {
        cf_log(CF_LOG_ERROR, "export: %s", msg);
        return PLC_E_EXPORT;
    }
    cf_log(CF_LOG_INFO, "export: wrote %s/fitted.igs and report.json", rr->last_export);
    return 0;
}

/* From the server thread. A phase holding the rig stops the stage itself
 * within one poll (the stop flag is already set); otherwise stop it now. */
static void run_abort(void *ctx)
{
    cf_plcrun_t *rr = ctx;
    if (!rr->rig || !rr->rig->stage.ops || rr->sim_lost)
        return;
    if (pthread_mutex_trylock(&rr->rig_mu) == 0) {
        const rig_stage_t *s = &rr->rig->stage;
        int rc = s->ops->stop(s->ctx);
        pthread_mutex_unlock(&rr->rig_mu);
        if (rc)
            cf_log(CF_LOG_WARN, "abort: stage stop: %s", hal_stage_error(s->ctx));
        else
            cf_log(CF_LOG_INFO, "abort: stage stopped");
    }
}

/* The simulator's process, watched from the server thread. */
static int run_health(void *ctx)
{
    cf_plcrun_t *rr = ctx;
    char msg[128];
    if (!rr->sim || rr->sim_lost || !cf_simchild_ended(rr->sim, msg, sizeof msg))
        return 0;
    rr->sim_lost = 1;
    cf_log(CF_LOG_ERROR, "rig: cellsim (pid %ld) %s: error %d", (long)rr->sim->pid, msg,
           PLC_E_RIG_GONE);
    return PLC_E_RIG_GONE;
}

void cf_plcrun_init(cf_plcrun_t *rr, cf_runner_t *out)
{
    memset(out, 0, sizeof *out);
    pthread_mutex_init(&rr->rig_mu, NULL);
    if (rr->rig) {
        rr->rig->st.should_stop = rig_should_stop;
        rr->rig->st.stop_ctx = rr;
    }
    out->check = run_check;
    out->home = run_home;
    out->scan = run_scan;
    out->fit = run_fit;
    out->export_result = run_export;
    out->abort = run_abort;
    out->health = run_health;
    out->ctx = rr;
    out->rig = rr->rig && rr->rig->stage.ops && rr->rig->probe.ops;
}

void cf_plcrun_free(cf_plcrun_t *rr)
{
    if (rr->have_last)
        cf_job_result_free(&rr->last);
    rr->have_last = 0;
    pthread_mutex_destroy(&rr->rig_mu);
}
