/* cf_scanjob.c: the scan job on the rig and the fit of its journal
 * (cf_scanjob.h). */
#include "cf_scanjob.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_seedgrid.h"
#include "cf_sfit.h"
#include "cf_store_file.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_project.h"
#include "rig_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define SJ_PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain (as cf_job) */

static void progress(const cf_job_ctl_t *c, int pct)
{
    if (c && c->progress)
        c->progress(c->ctx, pct);
}

static int stop(const cf_job_ctl_t *c)
{
    return c && c->should_stop && c->should_stop(c->ctx);
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

int cf_scanjob_run(const cf_scanjob_opts_t *o, const cf_job_ctl_t *ctl, scan_result_t *res,
                   char *msg, size_t ml)
{
    memset(res, 0, sizeof *res);
    res->fail_index = -1;
    scan_job_t job;
    memset(&job, 0, sizeof job);
    if (cf_scanjob_plan(o, &job.plan))
        return cf_fail(msg, ml, RIG_EARG, "scan region (%g, %g)-(%g, %g) step %g: no plan", o->x0,
                       o->y0, o->x1, o->y1, o->step);
    job.stage = o->stage;
    job.probe = o->probe;
    job.kin.z0 = o->z0;
    memcpy(job.kin.cal, o->cal, sizeof o->cal);
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    if (o->nominal && cf_sfit_nominal_id(o->nominal, &h.nominal_hash, h.nominal_name))
        return cf_fail(msg, ml, RIG_EIO, "%s: cannot read the nominal", o->nominal);
    cf_store_file_t f;
    rig_store_t st;
    int rc = cf_store_file_open(&f, o->journal, CF_STORE_CREATE, &st, msg, ml);
    if (rc)
        return rc;
    h.sync_every = JNL_SYNC_EVERY_DEFAULT;
    h.job_id = (uint64_t)o->job_id;
    h.t_start = cli_now();
    scan_header(&job, &h);
    jnl_t j;
    if ((rc = jnl_create(&j, st, &h)) != RIG_OK) {
        rc = cf_fail(msg, ml, rc, "%s: %s (%s)", o->journal, rig_strerror(rc), f.err);
        cf_store_file_close(&f);
        unlink(o->journal);
        return rc;
    }
    sj_ctx_t sc = {o, ctl, -1};
    job.clock = (rig_clock_t){&sj_clock, &sc};
    job.cb = (scan_cb_t){NULL, on_progress, &sc};
    progress(ctl, o->pct0);
    rc = scan_run(&job, &j, res);
    if (rc)
        cf_fail(msg, ml, rc, "%s: job ended at grid point %ld: %s (%llu records acknowledged)",
                o->journal, res->fail_index, rig_strerror(rc), (unsigned long long)jnl_acked(&j));
    cf_store_file_close(&f);
    return rc;
}

/* Every valid point of the journal, projected onto pj's surface: into the
 * fit (f) or the statistics (st). */
static int pass(jnl_reader_t *rd, const cf_seedgrid_t *pj, nf_fit_t *f, cf_stats_t *st,
                const cf_job_ctl_t *ctl, long total, int pct0, int pct1, long *count)
{
    jnl_rec_t r;
    int rc;
    long n = 0;
    jnl_reader_rewind(rd);
    while ((rc = jnl_reader_next(rd, &r)) == 1) {
        if (r.type != JNL_T_POINT || (r.flags & JNL_F_NOSURF))
            continue;
        if (n % 256 == 0) {
            if (stop(ctl))
                return RIG_EABORTED;
            if (total > 0)
                progress(ctl, pct0 + (int)((double)(pct1 - pct0) * (double)n / (double)total));
        }
        double u0, v0;
        nf_proj_t pr;
        cf_seedgrid_start(pj, r.xyz, &u0, &v0);
        int e = nf_project(pj->seed.s, r.xyz, u0, v0, SJ_PROJ_TOL, &pr);
        if (e && e != NF_ENOCONV) /* the best point is kept on ENOCONV */
            return e;
        if (f && (e = nf_fit_add(f, pr.u, pr.v, r.xyz, 1.0)) != 0)
            return e;
        if (st && (e = cf_stats_add(st, pr.dist)) != 0)
            return e;
        n++;
    }
    *count = n;
    return rc < 0 ? rc : 0;
}

int cf_scanjob_fit(const char *journal, const cf_job_fit_opts_t *fo, const cf_job_ctl_t *ctl,
                   int pct0, int pct1, cf_job_result_t *out, char *msg, size_t ml)
{
    double t0 = cli_now();
    memset(out, 0, sizeof *out);
    nf_surf_t base;
    long need = 0, n = 0;
    int rc = cf_job_load_base(fo, &base, &need, msg, ml);
    if (rc)
        return rc;
    cf_store_file_t fl;
    rig_store_t st;
    fl.fd = -1;
    void *arena = NULL;
    cf_seedgrid_t sg;
    memset(&sg, 0, sizeof sg);
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
    out->bytes = need;
    out->st = malloc(sizeof *out->st);
    arena = malloc((size_t)need);
    if (!out->st || !arena || cf_surf_copy(&out->fitted, &base) ||
        cf_seedgrid_init(&sg, &base, 8)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "cannot allocate %ld bytes", need);
        goto out;
    }
    if ((rc = cf_stats_init(out->st, fo->tol)))
        goto out;
    nf_arena_t ar;
    nf_fit_t f;
    nf_arena_init(&ar, arena, (size_t)need);
    nf_fit_params_t prm = {fo->alpha, fo->beta, NF_SOLVER_AUTO};
    if ((rc = nf_fit_init(&f, &base, &prm, &ar))) {
        rc = cf_fail(msg, ml, rc, "%s: %s", journal, nf_strerror(rc));
        goto out;
    }
    int mid = pct0 + (pct1 - pct0) / 2;
    if ((rc = pass(&rd, &sg, &f, NULL, ctl, (long)in.points, pct0, mid, &n)))
        goto fail_msg;
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    rc = nf_fit_finish(&f);
    if (!rc)
        rc = nf_fit_solve(&f, NF_SOLVER_AUTO, &so, &out->solve);
    if (rc)
        goto fail_msg;
    memcpy(out->fitted.cp, f.P, sizeof(double) * (size_t)(3 * f.n));
    /* The deviations: the points read back from the journal, projected
     * onto the fitted surface. */
    cf_seedgrid_free(&sg);
    if (cf_seedgrid_init(&sg, &out->fitted, 8)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        goto out;
    }
    if ((rc = pass(&rd, &sg, NULL, out->st, ctl, (long)in.points, mid, pct1, &n)))
        goto fail_msg;
    out->points = n;
    out->seconds = cli_now() - t0;
    progress(ctl, pct1);
    goto out;
fail_msg:
    if (rc != RIG_EABORTED)
        cf_fail(msg, ml, rc, "%s: %s", journal,
                rc <= RIG_EARG && rc >= RIG_ESTATE ? rig_strerror(rc) : nf_strerror(rc));
out:
    cf_seedgrid_free(&sg);
    free(arena);
    cf_store_file_close(&fl);
    cf_surf_free(&base);
    if (rc)
        cf_job_result_free(out);
    return rc;
}
