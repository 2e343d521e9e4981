/* SPDX-License-Identifier: MIT */
/* cf_scanjob.c: the scan job on the rig and the fit of its journal
 * (cf_scanjob.h). */
#include "cf_scanjob.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_fitsrc.h"
#include "cf_log.h"
#include "cf_scanfast.h"
#include "cf_store_file.h"
#include "rig_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void progress(const cf_job_ctl_t *c, int pct)
{
    if (c && c->progress)
        c->progress(c->ctx, pct);
}

/* The stop request as it came (scan.h: a negative value is its reason). */
static int stop(const cf_job_ctl_t *c)
{
    return c && c->should_stop ? c->should_stop(c->ctx) : 0;
}

int cf_scanjob_plan(const cf_scanjob_opts_t *o, scan_plan_t *pl)
{
    return scan_plan_init(pl, fmin(o->x0, o->x1), fmax(o->x0, o->x1), fmin(o->y0, o->y1),
                          fmax(o->y0, o->y1), o->step, o->step);
}

typedef struct sj_ctx {
    const cf_scanjob_opts_t *o;
    const cf_job_ctl_t *ctl;
    int last;
} sj_ctx_t;

/* A point into the live fit (o->fit), after it is journalled: the fit's
 * nf_err_t ends the scan (where SCAN_AT_CALLER), its message logged. */
static int live_add(const sj_ctx_t *c, const double xyz[3])
{
    char msg[256];
    int rc = cf_fitjob_add(c->o->fit, xyz, msg, sizeof msg);
    if (rc)
        cf_log(CF_LOG_ERROR, "scan: the live fit: %s", msg);
    return rc;
}

static int on_point(void *ctx, const jnl_rec_t *r)
{
    return live_add(ctx, r->xyz);
}

static double clk_now(void *ctx)
{
    (void)ctx;
    return cli_now();
}

static int clk_stop(void *ctx)
{
    return stop(((const sj_ctx_t *)ctx)->ctl);
}

static const rig_clock_ops_t sj_clock = {RIG_OPS_VERSION, clk_now, clk_stop};

static void on_progress(void *ctx, long done, long planned, uint64_t acked)
{
    sj_ctx_t *c = ctx;
    (void)acked;
    int pct = c->o->pct0 + (int)((double)(c->o->pct1 - c->o->pct0) * (double)done /
                                 (double)(planned > 0 ? planned : 1));
    if (pct != c->last) {
        c->last = pct;
        progress(c->ctl, pct);
    }
}

/* The fast methods (cf_scanfast.h): rows instead of grid points for
 * progress and the stop check; each point into the live fit (o->fit). */
static int fast_point(void *ctx, const double xyz[3])
{
    return live_add(ctx, xyz);
}

static int fast_stop(void *ctx)
{
    return stop(((const sj_ctx_t *)ctx)->ctl);
}

static void fast_progress(void *ctx, long rows_done, long rows, long points)
{
    (void)points;
    on_progress(ctx, rows_done, rows, 0);
}

/* The fast methods (cf_scanfast.h), on the fly or the profiler: the
 * result in the stop-and-go terms. fail_index is the failing row's first
 * grid point in the method's own scan order: on the fly, rows of nx points
 * along x; the profiler, profile by profile, each ny (Width) points along
 * y (its plan: profiles along x, cf_scanjob_run), so profile r's first
 * point is r * ny (the journal's order too), not scan_plan_point's. */
static int run_fast(const cf_scanjob_opts_t *o, const scan_job_t *job, jnl_t *j, sj_ctx_t *sc,
                    scan_result_t *res, char *msg, size_t ml)
{
    const int prof = o->method == CF_SCAN_PROFILER;
    cf_scanfast_cb_t cb = {o->fit ? fast_point : NULL, fast_progress, fast_stop, sc};
    cf_scanfast_res_t fr;
    int rc = prof ? cf_scanfast_profiler(o->gev_uri, o->gev_geom, 0, 0, j, &cb, &fr, msg, ml)
                  : cf_scanfast_otf(o->rig, &job->plan, &job->kin,
                                    o->period_us > 0 ? o->period_us : 50, j, &cb, &fr, msg, ml);
    if (o->fast_out)
        *o->fast_out = fr;
    if (o->t_last_row && fr.t_last_row > 0)
        *o->t_last_row = fr.t_last_row;
    res->points = fr.points;
    res->flagged = fr.flagged;
    res->done = fr.points + fr.flagged;
    res->fail_index = fr.fail_row >= 0 ? fr.fail_row * (prof ? job->plan.ny : job->plan.nx) : -1;
    res->code = rc;
    res->where = fr.where;
    const int lvl = rc ? CF_LOG_WARN : CF_LOG_INFO;
    const double pps = fr.seconds > 0 ? (double)fr.points / fr.seconds : 0;
    if (prof)
        cf_log(lvl,
               "scan by the profiler: %ld profiles, %ld points, %.0f points/s; lost: %ld profiles "
               "(%ld frames), %ld bad frames, %ld dropouts",
               fr.rows_done, fr.points, pps, fr.profiles_lost, fr.frames_lost, fr.frames_bad,
               fr.dropouts);
    else
        cf_log(lvl,
               "scan on the fly: %ld rows, %ld points, %.0f points/s; lost: %ld readings, %ld "
               "triggers, %ld on both sides (%ld dropped by the probe), %ld overrun, %ld rows cut; "
               "%ld events after the rows' ends dropped",
               fr.rows_done, fr.points, pps, fr.lost_readings, fr.lost_triggers, fr.both_lost,
               fr.dropped_by_probe, fr.overrun, fr.rows_cut, fr.past_end);
    return rc;
}

int cf_scanjob_run(const cf_scanjob_opts_t *o, const cf_job_ctl_t *ctl, scan_result_t *res,
                   char *msg, size_t ml)
{
    memset(res, 0, sizeof *res);
    res->fail_index = -1;
    scan_job_t job;
    memset(&job, 0, sizeof job);
    int prof = o->method == CF_SCAN_PROFILER;
    if (prof && (!o->gev_uri || !o->gev_geom))
        return cf_fail(msg, ml, RIG_EARG, "scan_method profiler: no profiler (gev: URI, geometry)");
    if (prof) /* the profiler's plan: profiles along x, points along y (as cmd_scan.c) */
        job.plan = (scan_plan_t){o->gev_geom->x0, o->gev_geom->y0,       o->gev_geom->dx,
                                 o->gev_geom->dy, o->gev_geom->profiles, o->gev_geom->width};
    else if (cf_scanjob_plan(o, &job.plan))
        return cf_fail(msg, ml, RIG_EARG, "scan region (%g, %g)-(%g, %g) step %g: no plan", o->x0,
                       o->y0, o->x1, o->y1, o->step);
    job.stage = o->stage;
    job.probe = o->probe;
    job.kin.z0 = o->z0;
    memcpy(job.kin.cal, o->cal, sizeof o->cal);
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    if (o->nominal && cf_fitsrc_nominal_id(o->nominal, &h.nominal_hash, h.nominal_name))
        return cf_fail(msg, ml, RIG_EIO, "%s: cannot read the nominal", o->nominal);
    cf_store_file_t f;
    rig_store_t st;
    int rc = cf_store_file_open(&f, o->journal, CF_STORE_CREATE, &st, msg, ml);
    if (rc)
        return rc;
    if (o->method != CF_SCAN_STOP)
        (void)cf_store_file_buffer(&f, 65536); /* one sync a row: records gathered (cmd_scan.c) */
    h.sync_every = JNL_SYNC_EVERY_DEFAULT;
    h.job_id = (uint64_t)o->job_id;
    h.t_start = cli_now();
    h.utc_start = cli_utc_now(); /* the cell controller has a wall clock: records date */
    scan_header(&job, &h);
    if (o->method == CF_SCAN_OTF)
        cf_scanfast_header(&job.kin, scan_plan_count(&job.plan), &h);
    else if (prof)
        cf_scanfast_header(&(scan_kin_t){o->gev_geom->z0, {0, 0, 0}}, scan_plan_count(&job.plan),
                           &h);
    jnl_t j;
    if ((rc = jnl_create(&j, st, &h)) != RIG_OK) {
        rc = cf_fail(msg, ml, rc, "%s: %s (%s)", o->journal, rig_strerror(rc), f.err);
        cf_store_file_close(&f);
        unlink(o->journal);
        return rc;
    }
    if (o->part_id && *o->part_id && (rc = jnl_meta(&j, JNL_META_PART_ID, o->part_id, h.t_start))) {
        jnl_end(&j, rc, cli_now());
        cf_store_file_close(&f);
        return cf_fail(msg, ml, rc, "%s: the part ID: %s", o->journal, rig_strerror(rc));
    }
    sj_ctx_t sc = {o, ctl, -1};
    job.clock = (rig_clock_t){&sj_clock, &sc};
    job.cb = (scan_cb_t){o->fit ? on_point : NULL, on_progress, &sc};
    if (o->t_last_row)
        *o->t_last_row = 0;
    progress(ctl, o->pct0);
    if (o->method == CF_SCAN_OTF || prof)
        rc = run_fast(o, &job, &j, &sc, res, msg, ml);
    else {
        rc = scan_run(&job, &j, res);
        if (o->t_last_row)
            *o->t_last_row = cli_now(); /* the last grid point's reading is the last row's end */
    }
    if (rc)
        cf_fail(msg, ml, rc, "%s: job ended at grid point %ld: %s (%llu records acknowledged)",
                o->journal, res->fail_index, rig_strerror(rc), (unsigned long long)jnl_acked(&j));
    cf_store_file_close(&f);
    return rc;
}

/* The job's run over the journal's points (fj's first pass is live when
 * points were added to it, cf_fitjob.h). */
static int fit_journal(cf_fitjob_t *fj, const char *journal, const cf_job_ctl_t *ctl, int pct0,
                       int pct1, cf_job_result_t *out, char *msg, size_t ml)
{
    int rc;
    cf_store_file_t fl;
    rig_store_t st;
    fl.fd = -1;
    jnl_reader_t rd;
    jnl_header_t h;
    jnl_info_t in;
    if ((rc = cf_store_file_open(&fl, journal, CF_STORE_READ, &st, msg, ml)))
        goto out;
    if ((rc = jnl_reader_open(&rd, st, &h, &in)) != 0) {
        rc = cf_fail(msg, ml, rc, "%s: %s", journal, rig_strerror(rc));
        goto out;
    }
    if (in.points == 0) {
        rc = cf_fail(msg, ml, CF_EEMPTY, "%s: no measured point", journal);
        goto out;
    }
    cf_fitsrc_t src;
    cf_fitsrc_jnl_t jc;
    cf_fitsrc_journal(&src, &jc, &rd, journal, (long)in.points);
    rc = cf_fitjob_run(fj, &src, ctl, pct0, pct1, out, msg, ml);
out:
    cf_store_file_close(&fl);
    return rc;
}

int cf_scanjob_fit(const char *journal, const cf_job_fit_opts_t *fo, const cf_job_ctl_t *ctl,
                   int pct0, int pct1, cf_job_result_t *out, char *msg, size_t ml)
{
    memset(out, 0, sizeof *out);
    cf_fitjob_t *fj = NULL;
    int rc = cf_job_open(fo, &fj, msg, ml);
    if (rc)
        return rc;
    rc = fit_journal(fj, journal, ctl, pct0, pct1, out, msg, ml);
    cf_fitjob_close(fj);
    return rc;
}

int cf_scanjob_fit_live(cf_fitjob_t *fj, const char *journal, const cf_job_ctl_t *ctl, int pct0,
                        int pct1, cf_job_result_t *out, const char **from, char *msg, size_t ml)
{
    memset(out, 0, sizeof *out);
    int held = cf_fitjob_held(fj);
    if (from)
        *from = held ? "memory" : "journal";
    /* Held: the points of the first pass in the order they came, which is
     * the journal's (the same fit, no pass over the file). */
    if (held)
        return cf_fitjob_run(fj, NULL, ctl, pct0, pct1, out, msg, ml);
    return fit_journal(fj, journal, ctl, pct0, pct1, out, msg, ml);
}
