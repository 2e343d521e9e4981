/* cf_fitjob.c: the one fit job (cf_fitjob.h): passes over a point source
 * into the stripes (Eq. 7), reprojection, robust reweighting, the check of
 * each round and the tolerance loop of Section 2.2; the best round kept. */
#include "cf_fitjob.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_knots.h"
#include "nf_project.h"
#include "nf_refine.h"
#include "nf_robust.h"
#include "rig_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Points read (and projected) at a time: a batch is the fitter's binning
 * window for random order (up to N points, nf_fit_add_rows). Fixed, and
 * touched whole when allocated, so that memory never follows the points. */
#define BATCH 65536
#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain */
#define SEEDS 8       /* seed samples per knot span and direction (cf_seedgrid) */

struct cf_fitjob {
    cf_fitjob_opts_t o;
    nf_surf_t base; /* the nominal, refined to the net asked */
    long need;      /* fitter bytes of the current round's net */
    void *mem;      /* the fitter's arena */
    double *buf, *rows;
    long *src; /* per kept row, its index in the batch (for messages) */
    long cap;  /* rows the three buffers hold */
    /* The first pass when points arrive live (cf_fitjob_add). */
    int live;
    struct pass *lp;
};

void cf_fitjob_defaults(cf_fitjob_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->solver = NF_SOLVER_AUTO;
    o->solve_tol = 1e-12;
    o->max_iter = 20000;
    o->within = 100.0;
    o->max_cp = NF_MAX_CP;
    o->max_rounds = 12;
    o->refine = CF_REFINE_RESIDUAL;
    o->robust_iters = 3;
}

const char *cf_fitjob_status_name(cf_fitjob_status_t s)
{
    switch (s) {
    case CF_FITJOB_PLAIN: return "plain";
    case CF_FITJOB_MET: return "met";
    case CF_FITJOB_NOT_MET_DATA_LIMIT: return "not_met_data_limit";
    case CF_FITJOB_NOT_MET_MAX_CP: return "not_met_max_cp";
    case CF_FITJOB_NOT_MET_NO_PROGRESS: return "not_met_no_progress";
    }
    return "unknown";
}

int cf_fitjob_input_error(int rc)
{
    switch (rc) {
    case NF_EBUDGET:
    case NF_EDEGREE:
    case NF_EKNOTS:
    case NF_EWEIGHT:
    case NF_EDOMAIN:
    case NF_ENONFINITE:
    case NF_ENODATA:
    case NF_ESINGULAR:
    case NF_ESIZE:
    case CF_EIO:
    case CF_EPARSE:
    case CF_ENOTFOUND:
    case CF_EUNSUPPORTED:
    case CF_EARG:
    case CF_EEMPTY:
    case RIG_ECORRUPT: return 1;
    default: return 0;
    }
}

/* Diagonal of the bounding box of s's control points (the part's size). */
static double net_diagonal(const nf_surf_t *s)
{
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (long k = 0; k < (long)s->nu * s->nv; k++)
        for (int c = 0; c < 3; c++) {
            double x = s->cp[3 * k + c];
            lo[c] = x < lo[c] ? x : lo[c];
            hi[c] = x > hi[c] ? x : hi[c];
        }
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* Refine s (heap) in one direction to n control points: the knots of
 * nf_refine_widest inserted by Boehm (the same surface, so P0 keeps its
 * meaning in Eq. 7). */
static int refine_dir(nf_surf_t *s, int n, int in_v)
{
    int have = in_v ? s->nv : s->nu, r = n - have;
    if (r <= 0)
        return 0;
    double *X = malloc(sizeof(double) * (size_t)r);
    nf_surf_t out;
    if (!X || cf_surf_alloc(&out, s->p, s->q, in_v ? s->nu : n, in_v ? n : s->nv)) {
        free(X);
        return CF_ENOMEM;
    }
    int rc = nf_refine_widest(in_v ? s->V : s->U, have, in_v ? s->q : s->p, r, X);
    if (!rc)
        rc = in_v ? nf_refine_v(s, X, r, &out) : nf_refine_u(s, X, r, &out);
    free(X);
    if (rc) {
        cf_surf_free(&out);
        return rc;
    }
    cf_surf_free(s);
    *s = out;
    return 0;
}

int cf_fitjob_open(cf_fitjob_t **jp, const nf_surf_t *nominal, const cf_fitjob_opts_t *o, char *msg,
                   size_t ml)
{
    *jp = NULL;
    if ((o->loop || o->stats) && !(o->tol > 0))
        return cf_fail(msg, ml, CF_EARG, "a tolerance loop or statistics need a tolerance > 0");
    int nu = o->net_u > 0 ? o->net_u : nominal->nu, nv = o->net_v > 0 ? o->net_v : nominal->nv;
    if (nu < nominal->nu || nv < nominal->nv)
        return cf_fail(msg, ml, CF_EARG, "net %d x %d is smaller than the nominal's %d x %d", nu,
                       nv, nominal->nu, nominal->nv);
    long need = nf_fit_bytes(nu, nv, nominal->p, nominal->q, o->solver);
    if ((double)nu * nv > (double)NF_MAX_CP || need < 0 || need > NF_ARENA_BYTES) {
        nf_solver_t used = o->solver == NF_SOLVER_AUTO
                               ? nf_solver_pick(nu, nv, nominal->p, nominal->q)
                               : o->solver;
        return cf_fail(msg, ml, NF_EBUDGET,
                       "a %d x %d net of degree %d x %d with solver %s needs %ld bytes; board %s "
                       "allows %ld: job refused",
                       nu, nv, nominal->p, nominal->q, nf_solver_name(used), need, BOARD_NAME,
                       (long)NF_ARENA_BYTES);
    }
    if (o->loop && (long)nu * nv > o->max_cp)
        return cf_fail(msg, ml, CF_EARG, "the base net has %ld control points, --max-cp %ld",
                       (long)nu * nv, o->max_cp);
    cf_fitjob_t *j = calloc(1, sizeof *j);
    if (!j)
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    j->o = *o;
    if (!(j->o.far > 0)) /* default: 5 % of the diagonal of the base's control net */
        j->o.far = 0.05 * net_diagonal(nominal);
    j->need = need;
    int rc = CF_ENOMEM;
    if (cf_surf_copy(&j->base, nominal) || (rc = refine_dir(&j->base, nu, 0)) ||
        (rc = refine_dir(&j->base, nv, 1))) {
        cf_fitjob_close(j);
        return cf_fail(msg, ml, rc, "refining the nominal to %d x %d: %s", nu, nv, cf_strerror(rc));
    }
    *jp = j;
    return 0;
}

const nf_surf_t *cf_fitjob_base(const cf_fitjob_t *j)
{
    return &j->base;
}

long cf_fitjob_bytes(const cf_fitjob_t *j)
{
    return j->need;
}

/* Every page of p written: malloc followed by a zeroing memset may become
 * calloc, whose fresh pages stay untouched until the points reach them. */
static void touch(void *p, size_t n)
{
    volatile unsigned char *c = p;
    for (size_t i = 0; i < n; i += 4096)
        c[i] = 0;
}

/* Batch buffers for n rows (at most BATCH), touched whole when allocated so
 * that memory never follows the points: a journal of a few hundred points
 * (the cell's scans) needs no 5 MB of them, a file of unknown length gets
 * BATCH. */
static int buffers(cf_fitjob_t *j, long n)
{
    n = n < 1 ? BATCH : n > BATCH ? BATCH : n;
    if (j->cap >= n)
        return 0;
    free(j->buf), free(j->rows), free(j->src);
    j->buf = malloc(sizeof(double) * 5 * (size_t)n);
    j->rows = malloc(sizeof(double) * 5 * (size_t)n);
    j->src = malloc(sizeof(long) * (size_t)n);
    j->cap = j->buf && j->rows && j->src ? n : 0;
    if (!j->cap)
        return CF_ENOMEM;
    touch(j->buf, sizeof(double) * 5 * (size_t)n); /* resident now, whatever the points */
    touch(j->rows, sizeof(double) * 5 * (size_t)n);
    touch(j->src, sizeof(long) * (size_t)n);
    return 0;
}

/* Robust reweighting of a pass: Tukey weights of the residuals to the
 * previous fit prev, cut off at c = NF_TUKEY_C sigma (sigma from the MAD). */
typedef struct weigh {
    double c;
    const nf_surf_t *prev;
} weigh_t;

/* One pass: a fresh fitter on cur's space (P0 = cur's net), parameters
 * given or by projection onto proj. */
typedef struct pass {
    nf_arena_t ar;
    nf_fit_t f;
    cf_seedgrid_t pj;
    const nf_surf_t *cur, *proj;
    const weigh_t *wt;
    long points, rejected, clamped, nfar, dropped;
    double ss0, mx0; /* |distance| to proj of the points projected */
    nf_solve_stats_t st;
    double t0, t_acc, t_solve;
} pass_t;

/* Distance of row q (u v x y z) to s at its parameters. */
static double dist_at(const nf_surf_t *s, const double *q)
{
    double P[3];
    nf_surf_eval(s, q[0], q[1], P);
    return sqrt((q[2] - P[0]) * (q[2] - P[0]) + (q[3] - P[1]) * (q[3] - P[1]) +
                (q[4] - P[2]) * (q[4] - P[2]));
}

/* Eq. 7's refusals in words: the control point left free, the bytes. */
static int fit_error(int rc, const nf_fit_t *f, const nf_surf_t *s, const char *name, char *msg,
                     size_t ml)
{
    long b = f->bad_index;
    int i = b >= 0 ? (int)(b % s->nu) : -1, k = b >= 0 ? (int)(b / s->nu) : -1;
    switch (rc) {
    case NF_ENODATA:
        return cf_fail(msg, ml, rc,
                       "%s: control point (%d, %d) has no data under it and alpha = beta = 0: "
                       "the points do not determine the surface (measure there, or give --beta)",
                       name, i, k);
    case NF_ESINGULAR:
        return cf_fail(msg, ml, rc,
                       "%s: the points do not determine the surface: control point (%d, %d) is "
                       "left free (numerically rank-deficient normal equations; give "
                       "--alpha/--beta > 0 or more data there)",
                       name, i, k);
    case NF_ENOCONV:
        return cf_fail(msg, ml, rc, "%s; try --solver chol or more --max-iter", nf_strerror(rc));
    case NF_EBUDGET:
        return cf_fail(msg, ml, rc,
                       "job needs %ld bytes, board %s allows %ld: %s (use fewer control "
                       "points or another solver)",
                       f->need_bytes, BOARD_NAME, (long)NF_ARENA_BYTES, nf_strerror(rc));
    default: return cf_fail(msg, ml, rc, "%s: %s", name, nf_strerror(rc));
    }
}

static int pass_begin(cf_fitjob_t *j, pass_t *ps, const nf_surf_t *cur, const nf_surf_t *proj,
                      const weigh_t *wt, const char *name, char *msg, size_t ml)
{
    memset(ps, 0, sizeof *ps);
    ps->cur = cur;
    ps->proj = proj;
    ps->wt = wt;
    ps->t0 = cli_now();
    nf_arena_init(&ps->ar, j->mem, (size_t)j->need);
    nf_fit_params_t prm = {j->o.alpha, j->o.beta, j->o.solver};
    int rc = nf_fit_init(&ps->f, cur, &prm, &ps->ar);
    if (rc)
        return fit_error(rc, &ps->f, cur, name, msg, ml);
    if (proj && cf_seedgrid_init(&ps->pj, proj, SEEDS))
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    return 0;
}

/* n rows (x y z, or u v x y z without proj) into the fit: projected (far
 * points counted, dropped with drop_far), weighted (robust), added. On an
 * error *bad is the batch index of the row that failed. */
static int pass_rows(cf_fitjob_t *j, pass_t *ps, const double *in, long n, long *bad)
{
    const double *uv = in;
    long m = n;
    if (ps->proj) {
        m = 0;
        for (long k = 0; k < n; k++) {
            const double *Q = in + 3 * k;
            nf_proj_t pr;
            cf_seedgrid_project(&ps->pj, Q, PROJ_TOL, &pr); /* best point kept on ENOCONV */
            double d = fabs(pr.dist);
            ps->clamped += pr.clamped != 0;
            ps->ss0 += d * d;
            ps->mx0 = d > ps->mx0 ? d : ps->mx0;
            if (d > j->o.far) {
                ps->nfar++;
                if (j->o.drop_far) {
                    ps->dropped++;
                    continue;
                }
            }
            j->src[m] = k;
            double *r = j->rows + 5 * m++;
            r[0] = pr.u, r[1] = pr.v, r[2] = Q[0], r[3] = Q[1], r[4] = Q[2];
        }
        uv = j->rows;
    }
    int rc = 0;
    long b = -1;
    if (!ps->wt)
        rc = nf_fit_add_rows(&ps->f, uv, m, &b);
    else
        for (long k = 0; k < m && !rc; k++) {
            const double *q = uv + 5 * k;
            double w = nf_tukey(dist_at(ps->wt->prev, q), ps->wt->c);
            if (w > 0)
                rc = nf_fit_add(&ps->f, q[0], q[1], q + 2, w);
            else
                ps->rejected++;
            b = k;
        }
    if (rc)
        *bad = ps->proj && b >= 0 ? j->src[b] : b;
    ps->points += n;
    return rc;
}

static int pass_solve(cf_fitjob_t *j, pass_t *ps, nf_surf_t *out, const char *name, char *msg,
                      size_t ml)
{
    double t1 = cli_now();
    int rc = nf_fit_finish(&ps->f);
    nf_solve_opts_t so = {j->o.solve_tol, (int)j->o.max_iter, 1};
    if (!rc)
        rc = nf_fit_solve(&ps->f, j->o.solver, &so, &ps->st);
    if (rc)
        return fit_error(rc, &ps->f, ps->cur, name, msg, ml);
    memcpy(out->cp, ps->f.P, sizeof(double) * (size_t)(3 * ps->f.n));
    ps->t_acc = t1 - ps->t0;
    ps->t_solve = cli_now() - t1;
    return 0;
}

static void pass_free(pass_t *ps)
{
    cf_seedgrid_free(&ps->pj);
}

int cf_fitjob_add(cf_fitjob_t *j, const double xyz[3], char *msg, size_t ml)
{
    int rc;
    if (!j->live) {
        if (!j->lp)
            j->lp = calloc(1, sizeof *j->lp);
        if (!j->mem)
            j->mem = malloc((size_t)j->need);
        if (!j->lp || !j->mem || buffers(j, 1))
            return cf_fail(msg, ml, CF_ENOMEM, "cannot allocate %ld bytes", j->need);
        if ((rc = pass_begin(j, j->lp, &j->base, &j->base, NULL, "live points", msg, ml)))
            return rc;
        j->live = 1;
    }
    long bad;
    rc = pass_rows(j, j->lp, xyz, 1, &bad);
    return rc ? cf_fail(msg, ml, rc, "%s", nf_strerror(rc)) : 0;
}

/* A run: the source, the control, the progress span of the pass going. */
typedef struct run {
    cf_fitjob_t *j;
    const cf_fitsrc_t *src;
    const cf_job_ctl_t *ctl;
    int pct0, pct1;
    double plo, phi; /* the pass's share of the job, 0..1 */
    long total;      /* points per pass (-1: not known yet) */
    char *msg;
    size_t ml;
} run_t;

static void progress(const run_t *r, long done)
{
    if (!r->ctl || !r->ctl->progress)
        return;
    double f = r->total > 0 ? (double)done / (double)r->total : 0.0;
    f = f > 1 ? 1 : f;
    double x = r->plo + (r->phi - r->plo) * f;
    r->ctl->progress(r->ctl->ctx, r->pct0 + (int)((double)(r->pct1 - r->pct0) * x));
}

static int stopped(const run_t *r)
{
    return r->ctl && r->ctl->should_stop && r->ctl->should_stop(r->ctl->ctx);
}

static int rewind_src(const run_t *r)
{
    return r->src->rewind(r->src->ctx, r->msg, r->ml);
}

/* One fit pass from the source into out (cur's shape). */
static int fit_pass(run_t *r, const nf_surf_t *cur, const nf_surf_t *proj, const weigh_t *wt,
                    nf_surf_t *out, pass_t *ps)
{
    cf_fitjob_t *j = r->j;
    const cf_fitsrc_t *s = r->src;
    int rc = pass_begin(j, ps, cur, s->cols == 5 ? NULL : proj, wt, s->name, r->msg, r->ml);
    if (!rc)
        rc = rewind_src(r);
    long got;
    while (!rc && (got = s->read(s->ctx, j->buf, j->cap, r->msg, r->ml)) != 0) {
        if (got < 0) {
            rc = (int)got;
            break;
        }
        if (stopped(r)) {
            rc = RIG_EABORTED;
            break;
        }
        long before = ps->points, bad = 0;
        rc = pass_rows(j, ps, j->buf, got, &bad);
        if (rc) {
            char at[4200];
            s->where(s->ctx, before + bad, at, sizeof at);
            if (rc == NF_EDOMAIN && !ps->proj) {
                const double *q = j->buf + 5 * bad;
                double u0, u1, v0, v1;
                nf_surf_domain(cur, &u0, &u1, &v0, &v1);
                cf_fail(r->msg, r->ml, rc,
                        "%s: parameters (%.17g, %.17g) outside the knot domain "
                        "[%.17g, %.17g] x [%.17g, %.17g] of the base",
                        at, q[0], q[1], u0, u1, v0, v1);
            } else
                cf_fail(r->msg, r->ml, rc, "%s: %s", at, nf_strerror(rc));
            break;
        }
        progress(r, ps->points);
    }
    if (!rc && r->total < 0)
        r->total = ps->points;
    if (!rc && ps->points == 0)
        rc = cf_fail(r->msg, r->ml, CF_EEMPTY, "%s: no points", s->name);
    if (!rc && ps->dropped == ps->points)
        rc = cf_fail(r->msg, r->ml, CF_EEMPTY,
                     "%s: all %ld points are farther than %g mm from the base (--far): wrong "
                     "base?",
                     s->name, ps->points, j->o.far);
    if (!rc)
        rc = pass_solve(j, ps, out, s->name, r->msg, r->ml);
    pass_free(ps);
    return rc;
}

typedef struct resid {
    double ss, mx;
    long n, within;  /* points, and those with |d| <= tol */
    long outliers;   /* points with |d| >= the robust cut-off (not counted in spans) */
    nf_rhist_t hist; /* |d| for the robust scale */
} resid_t;

/* A pass over the points against the fit s: |Q - S(u, v)| at the given
 * parameters, else the normal distance to s (projection). Sums for the
 * summary, the count within tol (if > 0), the |d| histogram, (if sr) the
 * excess per knot span of the points out of tolerance (those beyond cut
 * > 0, the points a robust fit rejects, go to their cells only), and (if
 * st) the signed normal deviations. */
static int measure(run_t *r, const nf_surf_t *s, nf_spanres_t *sr, double cut, resid_t *out,
                   cf_stats_t *st)
{
    cf_fitjob_t *j = r->j;
    const cf_fitsrc_t *src = r->src;
    double tol = j->o.tol;
    memset(out, 0, sizeof *out);
    nf_rhist_init(&out->hist);
    cf_seedgrid_t pj;
    memset(&pj, 0, sizeof pj);
    int uv = src->cols == 5;
    if ((!uv || st) && cf_seedgrid_init(&pj, s, SEEDS))
        return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
    int rc = rewind_src(r);
    long got = 0;
    while (!rc && (got = src->read(src->ctx, j->buf, j->cap, r->msg, r->ml)) > 0) {
        if (stopped(r)) {
            rc = RIG_EABORTED;
            break;
        }
        for (long k = 0; k < got; k++) {
            const double *Q = j->buf + (long)src->cols * k + (src->cols - 3);
            double *q = j->rows, sd = 0.0;
            if (uv)
                memcpy(q, j->buf + 5 * k, sizeof(double) * 5);
            if (!uv || st) {
                nf_proj_t pr;
                cf_seedgrid_project(&pj, Q, PROJ_TOL, &pr); /* best point kept on ENOCONV */
                sd = pr.dist;
                if (!uv)
                    q[0] = pr.u, q[1] = pr.v, q[2] = Q[0], q[3] = Q[1], q[4] = Q[2];
            }
            double d = dist_at(s, q);
            out->ss += d * d;
            out->mx = d > out->mx ? d : out->mx;
            out->n++;
            out->within += tol > 0 && d <= tol;
            nf_rhist_add(&out->hist, d);
            if (cut > 0 && d >= cut) {
                out->outliers++;
                if (sr)
                    nf_spanres_add_rejected(sr, q[0], q[1], d);
            } else if (sr)
                nf_spanres_add(sr, q[0], q[1], d);
            if (st)
                cf_stats_add(st, sd);
        }
        progress(r, out->n);
    }
    if (got < 0)
        rc = (int)got;
    cf_seedgrid_free(&pj);
    return rc;
}

static int replace_copy(nf_surf_t *dst, const nf_surf_t *src)
{
    cf_surf_free(dst);
    return cf_surf_copy(dst, src);
}

/* Share of the job of round k: everything without the loop, else halves. */
static void round_span(const cf_fitjob_opts_t *o, int k, double *lo, double *hi)
{
    *lo = o->loop ? 1.0 - ldexp(1.0, -k) : 0.0;
    *hi = o->loop ? 1.0 - ldexp(1.0, -k - 1) : 1.0;
}

static void set_pass(run_t *r, double lo, double hi, int i, int n)
{
    r->plo = lo + (hi - lo) * i / n;
    r->phi = lo + (hi - lo) * (i + 1) / n;
}

static char *warning(cf_fitjob_result_t *res)
{
    return res->nwarn < CF_FITJOB_MAX_WARN ? res->warn[res->nwarn++] : NULL;
}

/* The surfaces of a run. */
typedef struct surfs {
    nf_surf_t cur, fit, prev, nxt;
    cf_stats_t *st; /* the round's deviations (swapped with the best's) */
    double *srmem;
} surfs_t;

static void surfs_free(surfs_t *s)
{
    cf_surf_free(&s->cur);
    cf_surf_free(&s->fit);
    cf_surf_free(&s->prev);
    cf_surf_free(&s->nxt);
    free(s->st);
    free(s->srmem);
}

/* Round k on S->cur: the fit passes (the first from the live points when
 * there are), the robust passes, and the check. */
static int one_round(run_t *r, int k, surfs_t *S, resid_t *res, pass_t *po, double *c,
                     long *rejected, nf_spanres_t **srp, nf_spanres_t *sr, cf_fitjob_result_t *out)
{
    cf_fitjob_t *j = r->j;
    const cf_fitjob_opts_t *o = &j->o;
    int uv = r->src->cols == 5, rc;
    double lo, hi;
    round_span(o, k, &lo, &hi);
    int npass = (int)(o->reparam + 1 + (o->robust ? 2 * o->robust_iters : 0) + 1), ip = 0;
    /* Round k fits in the space of cur with P0 = cur's net: the base
     * first, then the previous fit refined (Section 2.2). */
    j->need = nf_fit_bytes(S->cur.nu, S->cur.nv, S->cur.p, S->cur.q, o->solver);
    if (!(k == 0 && j->live)) {
        free(j->mem);
        j->mem = malloc((size_t)j->need);
    }
    if (!j->mem || replace_copy(&S->fit, &S->cur) || replace_copy(&S->prev, &S->cur))
        return cf_fail(r->msg, r->ml, CF_ENOMEM, "cannot allocate %ld bytes", j->need);
    /* Pass 0 takes parameters from the source or from projection onto cur;
     * each reparam pass projects onto the previous fit and refits in the
     * same space with the same nominal P0. */
    for (long pass = 0; pass <= o->reparam; pass++) {
        set_pass(r, lo, hi, ip++, npass);
        if (k == 0 && pass == 0 && j->live) {
            rc = pass_solve(j, j->lp, &S->fit, "live points", r->msg, r->ml);
            pass_free(j->lp);
            *po = *j->lp; /* its counts and timings */
            if (!rc && po->points == 0)
                rc = cf_fail(r->msg, r->ml, CF_EEMPTY, "no measured points to fit");
            if (!rc && r->total < 0)
                r->total = po->points;
        } else
            rc = fit_pass(r, &S->cur, uv ? NULL : &S->prev, NULL, &S->fit, po);
        if (rc)
            return rc;
        if (k == 0 && pass == 0) {
            out->points = po->points;
            out->clamped = po->clamped;
            out->far = po->nfar;
            out->dropped = po->dropped;
            out->nominal_rms = po->points ? sqrt(po->ss0 / (double)po->points) : 0.0;
            out->nominal_max = po->mx0;
        }
        out->t_acc += po->t_acc;
        out->t_solve += po->t_solve;
        memcpy(S->prev.cp, S->fit.cp, sizeof(double) * 3 * (size_t)S->cur.nu * (size_t)S->cur.nv);
    }
    /* Robust passes: the MAD of the residuals to the last fit sets the
     * scale, Tukey weights of those residuals the next fit. */
    *c = 0.0;
    *rejected = 0;
    for (long it = 0; o->robust && it < o->robust_iters; it++) {
        set_pass(r, lo, hi, ip++, npass);
        if ((rc = measure(r, &S->prev, NULL, 0.0, res, NULL)))
            return rc;
        *c = NF_TUKEY_C * nf_rhist_sigma(&res->hist);
        if (!(*c > 0))
            break; /* the fit is exact: nothing to reweight */
        weigh_t wt = {*c, &S->prev};
        set_pass(r, lo, hi, ip++, npass);
        if ((rc = fit_pass(r, &S->cur, uv ? NULL : &S->prev, &wt, &S->fit, po)))
            return rc;
        *rejected = po->rejected;
        out->t_acc += po->t_acc;
        out->t_solve += po->t_solve;
        memcpy(S->prev.cp, S->fit.cp, sizeof(double) * 3 * (size_t)S->cur.nu * (size_t)S->cur.nv);
    }
    /* The check: distances of all points to this fit, and where they are
     * out of tolerance (per knot span). */
    free(S->srmem);
    S->srmem = NULL;
    *srp = NULL;
    if (o->loop && o->refine == CF_REFINE_RESIDUAL) {
        S->srmem = malloc(sizeof(double) *
                          (size_t)NF_SPANRES_DOUBLES(S->fit.nu, S->fit.nv, S->fit.p, S->fit.q));
        if (!S->srmem)
            return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
        nf_spanres_init(sr, &S->fit, o->tol, S->srmem);
        *srp = sr;
    }
    if (S->st && (rc = cf_stats_init(S->st, o->stats_tol > 0 ? o->stats_tol : o->tol)))
        return cf_fail(r->msg, r->ml, rc, "statistics: %s", cf_strerror(rc));
    set_pass(r, lo, hi, npass - 1, npass);
    if ((rc = measure(r, &S->fit, *srp, *c, res, S->st)))
        return rc;
    if (*srp)
        nf_spanres_fold(*srp); /* rejected misfit in one place: a feature */
    return 0;
}

int cf_fitjob_run(cf_fitjob_t *j, const cf_fitsrc_t *src, const cf_job_ctl_t *ctl, int pct0,
                  int pct1, cf_fitjob_result_t *out, char *msg, size_t ml)
{
    const cf_fitjob_opts_t *o = &j->o;
    double t0 = cli_now();
    memset(out, 0, sizeof *out);
    run_t r = {j, src, ctl, pct0, pct1, 0.0, 1.0, src->total, msg, ml};
    surfs_t S;
    memset(&S, 0, sizeof S);
    cf_stats_t *best_st = NULL;
    if (o->stats && (!(S.st = malloc(sizeof *S.st)) || !(best_st = malloc(sizeof *best_st)))) {
        free(S.st);
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    }
    int rc = 0;
    if (buffers(j, src->total) || cf_surf_copy(&S.cur, &j->base)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        goto fail;
    }
    if (r.ctl && r.ctl->progress)
        r.ctl->progress(r.ctl->ctx, pct0);
    out->far_limit = o->far;
    double best_within = -1.0, best_rms = 0.0;
    for (int k = 0;; k++) {
        double tr = cli_now(), c = 0.0;
        resid_t res;
        pass_t po;
        long rejected = 0;
        nf_spanres_t sr, *srp = NULL;
        if ((rc = one_round(&r, k, &S, &res, &po, &c, &rejected, &srp, &sr, out)))
            goto fail;
        cf_round_t *rd = &out->rounds[out->nrounds++];
        rd->nu = S.fit.nu;
        rd->nv = S.fit.nv;
        rd->within_pct = 100.0 * (double)res.within / (double)res.n;
        rd->rms = sqrt(res.ss / (double)res.n);
        rd->mx = res.mx;
        rd->sigma = c / NF_TUKEY_C;
        rd->rejected = rejected;
        rd->seconds = cli_now() - tr;
        /* Keep the best fit: most points within tolerance, then lowest rms. */
        if (rd->within_pct > best_within || (rd->within_pct == best_within && rd->rms < best_rms)) {
            if (replace_copy(&out->surf, &S.fit)) {
                rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
                goto fail;
            }
            best_within = rd->within_pct;
            best_rms = rd->rms;
            out->within_pct = rd->within_pct;
            out->rms = rd->rms;
            out->max_abs = rd->mx;
            out->sigma = rd->sigma;
            out->outliers = rd->rejected;
            out->solve = po.st;
            out->bytes = j->need;
            if (S.st) {
                cf_stats_t *t = best_st;
                best_st = S.st;
                S.st = t;
            }
        }
        if (!o->loop) {
            out->status = CF_FITJOB_PLAIN;
            break;
        }
        if ((double)res.within >= o->within / 100.0 * (double)res.n) {
            out->status = CF_FITJOB_MET;
            break;
        }
        if (k + 1 >= o->max_rounds || k + 1 >= CF_FITJOB_MAX_ROUNDS) {
            out->status = CF_FITJOB_NOT_MET_NO_PROGRESS;
            snprintf(out->why, sizeof out->why, "after %ld rounds (--max-rounds)", o->max_rounds);
            break;
        }
        int stop = 0;
        rc = cf_loop_next(&S.fit, srp, o->refine, o->max_cp, o->solver, &S.nxt, &stop, out->why,
                          sizeof out->why);
        if (rc) {
            cf_fail(msg, ml, rc, "%s", out->why);
            goto fail;
        }
        if (stop) {
            out->status =
                stop == CF_LOOP_STOP_DATA ? CF_FITJOB_NOT_MET_DATA_LIMIT : CF_FITJOB_NOT_MET_MAX_CP;
            break;
        }
        cf_surf_free(&S.cur);
        S.cur = S.nxt;
        memset(&S.nxt, 0, sizeof S.nxt);
    }
    char *w;
    if (out->far > 0 && (w = warning(out)))
        snprintf(w, sizeof out->warn[0], "%ld points farther than %g mm from the base, %s",
                 out->far, o->far, o->drop_far ? "left out" : "fitted");
    if (out->clamped > 0 && (w = warning(out)))
        snprintf(w, sizeof out->warn[0], "%ld feet clamped to the domain boundary", out->clamped);
    out->stats = best_st;
    best_st = NULL;
    out->seconds = cli_now() - t0;
    if (r.ctl && r.ctl->progress)
        r.ctl->progress(r.ctl->ctx, pct1);
    surfs_free(&S);
    return 0;
fail:
    surfs_free(&S);
    free(best_st);
    cf_fitjob_result_free(out);
    return rc;
}

void cf_fitjob_close(cf_fitjob_t *j)
{
    if (!j)
        return;
    if (j->lp)
        pass_free(j->lp);
    free(j->lp);
    free(j->mem);
    free(j->buf);
    free(j->rows);
    free(j->src);
    cf_surf_free(&j->base);
    free(j);
}

void cf_fitjob_result_free(cf_fitjob_result_t *r)
{
    cf_surf_free(&r->surf);
    free(r->stats);
    memset(r, 0, sizeof *r);
}
