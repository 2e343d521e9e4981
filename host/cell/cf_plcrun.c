/* SPDX-License-Identifier: MIT */
/* cf_plcrun.c: the job runner of `cellfit serve` (cf_plcrun.h): PLC
 * parameters to cf_job / cf_scanjob options, their outcome to PLC codes. */
#include "cf_plcrun.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_log.h"
#include "cf_scanfast.h"
#include "cf_scanjob.h"
#include "jnl.h"
#include "nf_err.h"
#include "rig_err.h"
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

/* The nominal RECIPE chooses: 0 `nominal`, N `nominal.N`; NULL: none. */
static const char *job_nominal(const cf_plcrun_t *rr, const plc_params_t *p)
{
    if (p->recipe == 0)
        return rr->nominal;
    return p->recipe < CF_PLCRUN_RECIPES ? rr->recipe[p->recipe] : NULL;
}

/* The PLC's fit settings (map version 2) over the configured rest (solver,
 * rounds, robust passes): FIT_TOL > 0 runs the loop to it, while the
 * statistics and the verdict stay at TOLERANCE. */
static void fit_opts(const cf_plcrun_t *rr, const plc_params_t *p, cf_job_fit_opts_t *o)
{
    o->nominal = job_nominal(rr, p);
    o->points = rr->points;
    o->fit = rr->fit;
    o->fit.alpha = p->alpha;
    o->fit.beta = p->beta;
    o->fit.tol = p->tol;
    o->fit.stats_tol = 0;
    o->fit.net_u = p->net_u;
    o->fit.net_v = p->net_v;
    o->fit.loop = p->fit_tol > 0;
    if (o->fit.loop) {
        o->fit.tol = p->fit_tol;
        o->fit.stats_tol = p->tol;
        o->fit.within = p->fit_within;
        o->fit.max_cp = p->fit_max_cp ? (long)p->fit_max_cp : NF_MAX_CP;
        o->fit.refine = p->fit_refine == PLC_REFINE_UNIFORM    ? CF_REFINE_UNIFORM
                        : p->fit_refine == PLC_REFINE_RESIDUAL ? CF_REFINE_RESIDUAL
                                                               : CF_REFINE_AUTO;
    }
    o->fit.robust = p->fit_robust != 0;
    o->fit.reparam = p->fit_reparam;
}

static double min_free(const cf_plcrun_t *rr)
{
    return rr->min_free > 0 ? rr->min_free : CF_PLCRUN_MIN_FREE;
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
    o->nominal = job_nominal(rr, p);
    o->job_id = (unsigned long long)time(NULL) * 65536ull + p->seq;
    o->pct0 = 0;
    o->pct1 = p->cmd == PLC_C_SCAN_FIT ? 70 : 100;
    /* issue 19: the scan method (config scan_method) */
    o->method = rr->scan_method;
    o->rig = rr->rig;
    o->period_us = rr->scan_period_us;
    o->gev_uri = rr->gev_uri;
    o->gev_geom = &rr->gev_geom;
}

/* A folder a job will write into: there, writable, and with min_bytes
 * free (a full disk found before any motion, not at the journal's end). */
static int check_folder(const char *what, const char *dir, double min_bytes)
{
    struct statvfs vs;
    if (access(dir, W_OK | X_OK)) {
        cf_log(CF_LOG_WARN, "%s refused: folder %s: %s", what, dir, strerror(errno));
        return PLC_E_BAD_PARAM;
    }
    if (!statvfs(dir, &vs) && (double)vs.f_bavail * (double)vs.f_frsize < min_bytes) {
        cf_log(CF_LOG_WARN, "%s refused: folder %s: %.0f bytes free, the job needs %.0f", what, dir,
               (double)vs.f_bavail * (double)vs.f_frsize, min_bytes);
        return PLC_E_BAD_PARAM;
    }
    return 0;
}

/* The scan's checks before it is accepted: a plan inside the stage's soft
 * limits (read at start-up: no I/O here), a folder for the journal that
 * takes its records. */
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
    /* One record a grid point, the header, and a margin for the rest. */
    double need = (double)JNL_HDR_BYTES + (double)pl.nx * pl.ny * JNL_REC_BYTES + min_free(rr);
    return check_folder("scan", journal_dir(rr, p), need);
}

/* The fit's checks: the recipe's nominal configured (114), the files
 * (111), the net and fit settings against the nominal and the board (108,
 * 110). A nominal that cannot be read is left to the job, which ends at
 * once in 301 before any motion (run_scan checks it first), so the PLC
 * sees the documented code with the file named in the log. */
static int check_fit(const cf_plcrun_t *rr, const plc_params_t *p, int need_points)
{
    char msg[512];
    if (p->fit_max_cp > (uint32_t)NF_MAX_CP) {
        cf_log(CF_LOG_WARN, "fit refused: FIT_MAX_CP %lu beyond the board's %ld",
               (unsigned long)p->fit_max_cp, (long)NF_MAX_CP);
        return PLC_E_TOO_BIG;
    }
    if (p->recipe && !job_nominal(rr, p)) {
        cf_log(CF_LOG_WARN, "fit refused: RECIPE %u: no nominal.%u configured", p->recipe,
               p->recipe);
        return PLC_E_NO_RECIPE;
    }
    if (!job_nominal(rr, p) || (need_points && !rr->points))
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

/* Parameter checks before a command is accepted (1xx, nothing started). */
static int run_check(void *ctx, int cmd, const plc_params_t *p)
{
    cf_plcrun_t *rr = ctx;
    int rc;
    if ((cmd == PLC_C_SCAN || cmd == PLC_C_SCAN_FIT) && !(p->x0 != p->x1 && p->y0 != p->y1))
        return PLC_E_BAD_PARAM; /* an empty scan region */
    switch (cmd) {
    case PLC_C_SCAN: return check_scan(rr, p);
    case PLC_C_SCAN_FIT: return (rc = check_fit(rr, p, 0)) ? rc : check_scan(rr, p);
    case PLC_C_FIT: return check_fit(rr, p, 1);
    case PLC_C_EXPORT:
        if (p->folder >= PLC_MAX_FOLDERS || !rr->results_dir[p->folder]) {
            cf_log(CF_LOG_WARN, "export refused: results folder %u not configured", p->folder);
            return PLC_E_BAD_PARAM;
        }
        return check_folder("export", rr->results_dir[p->folder], min_free(rr));
    default: return 0;
    }
}

int cf_plcrun_rig_code(int rc, int where)
{
    switch (rc) {
    case RIG_OK: return 0;
    case RIG_EABORTED: return CF_PLC_ABORTED;
    case RIG_ELOST: return PLC_E_RIG_GONE;
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

/* The stop check of the stage driver (while it waits for a move or
 * homing) and of the transports (hal_set_stop: retries, late replies and
 * reconnects give up at once): the running phase's stop, or an ABORT's STOP
 * sent with no job running (one attempt, not the retries). */
static int rig_should_stop(void *ctx)
{
    const cf_plcrun_t *rr = ctx;
    const cf_job_ctl_t *c = rr->ctl;
    return rr->idle_stop || (c && c->should_stop && c->should_stop(c->ctx) != 0);
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

/* The live fit job of a SCAN_FIT that will not be run (an earlier job's
 * left by an abort between the phases, or this scan's failure). */
static void live_close(cf_plcrun_t *rr)
{
    cf_fitjob_close(rr->live);
    rr->live = NULL;
}

static int run_scan(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_plcrun_t *rr = ctx;
    char msg[512];
    live_close(rr);
    if (!rr->rig || !rr->rig->stage.ops || !rr->rig->probe.ops)
        return PLC_E_NO_RIG;
    rr->job_t0 = cli_now();
    rr->t_last_row = 0;
    if (p->cmd == PLC_C_SCAN_FIT) {
        /* The nominal read and the fit job opened before any motion: a bad
         * nominal is 301 now, not after the whole scan; the points go into
         * the job as they arrive (as the shell's `scan --fit`), so the
         * first pass is done with the last row. */
        cf_job_fit_opts_t fo;
        fit_opts(rr, p, &fo);
        int rc = cf_job_open(&fo, &rr->live, msg, sizeof msg);
        if (rc) {
            rr->live = NULL;
            cf_log(CF_LOG_ERROR, "scan: %s", msg);
            return rc == NF_EBUDGET  ? PLC_E_TOO_BIG
                   : rc == CF_ENOMEM ? PLC_E_MEMORY
                                     : PLC_E_NOMINAL;
        }
    }
    const char *dir = journal_dir(rr, p);
    if (!dir || journal_name(dir, p->part, rr->journal, sizeof rr->journal)) {
        cf_log(CF_LOG_ERROR, "scan: no journal name free in %s", dir ? dir : "(none)");
        live_close(rr);
        return PLC_E_RIG;
    }
    cf_scanjob_opts_t o;
    scan_opts(rr, p, &o);
    o.journal = rr->journal;
    cf_scanfast_res_t fr;
    memset(&fr, 0, sizeof fr);
    o.fast_out = &fr;
    o.part_id = p->part_id;
    o.fit = rr->live;
    o.t_last_row = &rr->t_last_row;
    scan_result_t res;
    rig_take(rr, ctl);
    int rc = cf_scanjob_run(&o, ctl, &res, msg, sizeof msg);
    if (rc)
        live_close(rr);
    /* SCAN_TRIGGERS .. SCAN_OVERRUNS: this scan's (0 when stop-and-go). */
    const long counts[CF_PLC_SCAN_COUNTS] = {
        fr.triggers, fr.dropped_by_probe, fr.lost_readings, fr.lost_triggers, fr.both_lost,
        fr.dup,      fr.overrun};
    for (int i = 0; i < CF_PLC_SCAN_COUNTS; i++)
        atomic_store(&rr->scan_counts[i], counts[i] > 0 ? (unsigned)counts[i] : 0u);
    const char *det = res.where == SCAN_AT_STAGE   ? hal_stage_error(o.stage.ctx)
                      : res.where == SCAN_AT_PROBE ? hal_probe_error(o.probe.ctx)
                                                   : "";
    rig_give(rr);
    if (rc == RIG_EOPEN || (rc && res.done == 0 && res.where == SCAN_AT_NONE)) {
        cf_log(CF_LOG_ERROR, "scan: %s", msg);
        return PLC_E_RIG;
    }
    if (rc == RIG_EABORTED || rc == RIG_ELOST) {
        cf_log(CF_LOG_WARN, "scan: stopped at grid point %ld%s; journal %s consistent",
               res.fail_index, rc == RIG_ELOST ? " (the rig was lost)" : "", rr->journal);
        return CF_PLC_ABORTED;
    }
    if (rc && res.where == SCAN_AT_CALLER) {
        /* The live fit refused a point (its message logged) */
        cf_log(CF_LOG_ERROR, "scan: %s", msg);
        return rc == NF_EDOMAIN || rc == NF_ENONFINITE ? PLC_E_POINTS : PLC_E_FIT;
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
    switch (rr->last.status) {
    case CF_FITJOB_MET: res->fit_status = PLC_FIT_MET; break;
    case CF_FITJOB_NOT_MET_DATA_LIMIT: res->fit_status = PLC_FIT_NOT_MET_DATA; break;
    case CF_FITJOB_NOT_MET_MAX_CP: res->fit_status = PLC_FIT_NOT_MET_MAX_CP; break;
    case CF_FITJOB_NOT_MET_NO_PROGRESS: res->fit_status = PLC_FIT_NOT_MET_NO_PROGRESS; break;
    default: res->fit_status = PLC_FIT_NONE; break;
    }
    /* What the export records of the job (RESULT_SEQ, JOB_TIME, PART_ID). */
    rr->last_seq = p->seq;
    rr->last_program = p->program;
    rr->last_utc = (long long)p->utc;
    snprintf(rr->last_part_id, sizeof rr->last_part_id, "%s", p->part_id);
    rr->last_nominal = job_nominal(rr, p);
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
    /* A live job was opened on these settings before the scan: no second
     * read of the nominal after the last row. */
    int rc = scan && rr->live ? 0 : cf_job_check(&o, msg, sizeof msg);
    if (rc) {
        cf_log(CF_LOG_ERROR, "fit: %s", msg);
        return rc == NF_EBUDGET ? PLC_E_TOO_BIG : PLC_E_NOMINAL;
    }
    const char *from = "journal";
    if (scan && rr->live) {
        rc = cf_scanjob_fit_live(rr->live, rr->journal, ctl, 70, 100, &rr->last, &from, msg,
                                 sizeof msg);
        live_close(rr);
    } else
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
    if (scan && rr->t_last_row > 0)
        cf_log(CF_LOG_INFO, "fit: points from %s, ready %.3f s after the last row (%.3f s solving)",
               from, cli_now() - rr->t_last_row, rr->last.t_solve);
    rr->last_scan = scan;
    snprintf(rr->last_journal, sizeof rr->last_journal, "%s", scan ? rr->journal : "");
    fill_results(rr, p, scan ? cli_now() - rr->job_t0 : rr->last.seconds, res);
    return 0;
}

static int run_export(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_plcrun_t *rr = ctx;
    char name[128], msg[512];
    if (!rr->have_last)
        return PLC_E_INTERNAL; /* the state machine holds results: we must too */
    if (ctl && ctl->progress)
        ctl->progress(ctl->ctx, 0);
    /* A folder of its own per export: the job's time and sequence name
     * it, a UUID keeps two exports of one part in one second apart. */
    long long utc = rr->last_utc ? rr->last_utc : (long long)time(NULL);
    if (cf_job_unique_name(rr->last_part, utc, rr->last_seq, name, sizeof name)) {
        cf_log(CF_LOG_ERROR, "export: no random UUID for the folder name");
        return PLC_E_EXPORT;
    }
    snprintf(rr->last_export, sizeof rr->last_export, "%s/%s", rr->results_dir[p->folder], name);
    cf_job_meta_t meta = {rr->last_part,
                          rr->last_program,
                          rr->last_seq,
                          rr->last_nominal ? rr->last_nominal : rr->nominal,
                          rr->last_scan ? NULL : rr->points,
                          BOARD_NAME,
                          utc,
                          rr->last_scan ? rr->last_journal : NULL,
                          rr->last_part_id,
                          p->seq,
                          (long long)time(NULL),
                          rr->checks};
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
        rr->idle_stop = 1; /* a hung stage holds the server thread one timeout, not the retries */
        int rc = s->ops->stop(s->ctx);
        rr->idle_stop = 0;
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
        hal_set_stop(rr->rig->st.h, rig_should_stop, rr);
        hal_set_stop(rr->rig->pr.h, rig_should_stop, rr);
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
    live_close(rr);
    if (rr->have_last)
        cf_job_result_free(&rr->last);
    rr->have_last = 0;
    pthread_mutex_destroy(&rr->rig_mu);
}
