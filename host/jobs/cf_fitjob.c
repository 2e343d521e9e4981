/* SPDX-License-Identifier: MIT */
/* cf_fitjob.c: the one fit job (cf_fitjob.h): passes over a point source
 * into the stripes (Eq. 7), reprojection, robust reweighting, the check of
 * each round and the tolerance loop of Section 2.2; the best round kept. */
#include "cf_fitjob.h"
#include "cf_bigmem.h"
#include "cf_cli.h"
#include "cf_edges.h"
#include "cf_err.h"
#include "cf_fitpass.h"
#include "cf_holdout.h"
#include "cf_pair.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "cf_surfrow.h"
#include "nf_err.h"
#include "nf_fold.h"
#include "nf_footprint.h"
#include "nf_knots.h"
#include "nf_knotsel.h"
#include "nf_loopctl.h"
#include "nf_project.h"
#include "nf_prune.h"
#include "nf_refine.h"
#include "nf_robust.h"
#include "rig_err.h"
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Points read (and projected) at a time: a batch is the fitter's binning
 * window for random order (up to N points, nf_fit_add_rows). Fixed, and
 * touched whole when allocated, so that memory never follows the points.
 * 5 doubles a point fill one 2 MiB huge page (cf_bigmem) and no more. */
#define BATCH 52400
#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain */
#define FOOT 3        /* doubles per kept foot: u v d (|distance|, negative: on a bound) */
#define SEEDS 8       /* seed samples per knot span and direction (cf_seedgrid) */

struct cf_fitjob {
    cf_fitjob_opts_t o;
    nf_surf_t base; /* the nominal, refined to the net asked */
    long need;      /* fitter bytes of the current round's net */
    void *mem;      /* the fitter's arena */
    double *buf, *rows;
    long *src; /* per kept row, its index in the batch (for messages) */
    long cap;  /* rows buf holds */
    long rcap; /* rows rows and src hold: cap when projecting or weighting, else 1 (issue 20) */
    int two;   /* the round's fit passes may read in halves: a second accumulator in mem */
    /* The round's fit passes of projected points add each batch in two
     * halves, the second into the shard: on the second core, or after the
     * first on one (cf_accum: the same sums, so the same fit either way). */
    int shard;
    int used2; /* some pass read in halves */
    /* The first pass when points arrive live (cf_fitjob_add). */
    int live;
    struct pass *lp;
    /* The live points held (issue 19): x y z, at most CF_FITJOB_HOLD_ROWS;
     * the passes after the scan read them, not the journal. hold_over: more
     * came, the hold is gone and the source serves. */
    double *hold;
    long nhold, hcap;
    int hold_over;
    long nlive; /* live points added */
    /* The feet of the last check pass (FOOT per point in source order, at
     * most CF_FITJOB_HOLD_ROWS; NaN u: search again): the next round's fit
     * pass projects onto that fit refined by Boehm insertion, the same
     * surface, so each foot is its foot there (Newton from it ends where
     * it starts: test_foot's refined_part). Before round 0's check: round
     * 0's feet on the surface it projected onto. nfeet 0: none. */
    double *feet;
    long nfeet, fcap;
    /* 1: the last fit checked has one layer: its search's quadrilaterals
     * served (no quadrilateral faced away from their plane's normal), or
     * it was proven a height field (nf_fold_free): the check pass may take
     * Newton from the last feet. Over a fold the surface's change between
     * fits can swap which layer is nearer: every valley within reach of
     * Newton's foot is tried too (START_FOLD). feet_base: the feet are
     * round 0's, on the base, which its fit may have moved far: its check
     * asks the fit first (the proof, else its grid). */
    int flat;
    int feet_base;
};

void cf_fitjob_defaults(cf_fitjob_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->solver = NF_SOLVER_AUTO;
    o->solve_tol = 1e-12;
    o->max_iter = 20000;
    o->probe = 1;
    o->threads = 1;
    o->cores = 1;
    o->within = 100.0;
    o->max_cp = NF_MAX_CP;
    o->max_rounds = 12;
    o->refine = CF_REFINE_AUTO;
    o->robust_iters = 3;
    o->min_gain = NF_LOOPCTL_MIN_GAIN;
    o->prune = CF_FITJOB_PRUNE_TRIALS;
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
    if (o->holdout == 1 || o->holdout < 0 || !(o->noise >= 0) || !(o->min_gain >= 0))
        return cf_fail(msg, ml, CF_EARG, "holdout %ld (0 or >= 2), noise %g, min gain %g (>= 0)",
                       o->holdout, o->noise, o->min_gain);
    int nu = o->net_u > 0 ? o->net_u : nominal->nu, nv = o->net_v > 0 ? o->net_v : nominal->nv;
    if (nu < nominal->nu || nv < nominal->nv)
        return cf_fail(msg, ml, CF_EARG, "net %d x %d is smaller than the nominal's %d x %d", nu,
                       nv, nominal->nu, nominal->nv);
    nf_surf_t net = {.p = nominal->p, .q = nominal->q, .nu = nu, .nv = nv};
    long need = cf_fitpass_bytes(&net, o->solver, o->threads);
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

int cf_fitjob_held(const cf_fitjob_t *j)
{
    return j->live && !j->hold_over && j->nhold > 0 && j->nhold == j->nlive;
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
 * (the cell's scans) needs no 5 MB of them, nor a small file (its lines,
 * the source's bound), and a file of unknown length gets BATCH. rows and
 * src serve projection (proj: the fit pass's rows, the check pass's feet);
 * given parameters without statistics need one row of rows and no src:
 * 3 MB less. */
static int buffers(cf_fitjob_t *j, long n, int proj)
{
    n = n < 1 ? BATCH : n > BATCH ? BATCH : n;
    long rn = proj || j->o.robust ? n : 1; /* rows built per point: projected or weighted */
    if (j->cap >= n && j->rcap >= rn)
        return 0;
    n = n > j->cap ? n : j->cap;
    rn = proj || j->o.robust ? n : rn > j->rcap ? rn : j->rcap;
    cf_bigmem_free(j->buf), cf_bigmem_free(j->rows), free(j->src);
    j->buf = cf_bigmem_alloc(sizeof(double) * 5 * (size_t)n);
    size_t cols = j->o.robust ? 6 : 5; /* u v x y z, and w for robust passes */
    j->rows = cf_bigmem_alloc(sizeof(double) * cols * (size_t)rn);
    j->src = malloc(sizeof(long) * (size_t)rn);
    j->cap = j->buf && j->rows && j->src ? n : 0;
    j->rcap = j->cap ? rn : 0;
    if (!j->cap)
        return CF_ENOMEM;
    touch(j->buf, sizeof(double) * 5 * (size_t)n); /* resident now, whatever the points */
    touch(j->rows, sizeof(double) * cols * (size_t)rn);
    touch(j->src, sizeof(long) * (size_t)rn);
    return 0;
}

/* Robust reweighting of a pass: Tukey weights of the residuals to the
 * previous fit prev, cut off at c = NF_TUKEY_C sigma (sigma from the MAD). */
typedef struct weigh {
    double c;
    const nf_surf_t *prev;
} weigh_t;

/* Feet on a surface by the seed grid's search, the grid set up at its
 * first use (a pass that projects nothing never builds it); and Newton
 * alone from a start of the caller's (nf_quad_newton), set up likewise. */
typedef struct proj {
    const nf_surf_t *s;
    cf_seedgrid_t g;
    int ready;
    int borrowed; /* g is another proj_t's (read only but for its counters): not freed */
    long points;  /* projections the pass makes at most (-1: not known), for g's blanket */
    int rc;       /* the last projection's code */
    nf_quad_t nq;
    void *nqmem;
    int nready; /* 1: nq set up; -1: no memory for it */
} proj_t;

/* Newton on p->s from (u, v): the inline one to an interior foot, else
 * nf_project from (u, v) when it ends on a bound (there nf_project_edge
 * compared the foot with the edge's other minima and the valleys beside
 * it: the true foot, issue 14). 0 otherwise: the caller then searches (an
 * interior foot Newton could not reach directly may lie in another valley). */
static int proj_newton(proj_t *p, const double Q[3], double u, double v, nf_proj_t *out)
{
    if (!p->nready) {
        /* Newton's set-up, then the power form of the spans (its
         * derivatives; without it the basis path, the same feet). */
        const size_t b = NF_QUAD_NEWTON_BYTES(p->s->nu, p->s->nv),
                     pb = NF_QUAD_POWER_BYTES(p->s->nu, p->s->nv);
        p->nqmem = malloc(b + pb);
        p->nready = p->nqmem && nf_quad_newton_init(&p->nq, p->s, p->nqmem, b) == NF_OK ? 1 : -1;
        if (p->nready > 0 && pb)
            (void)nf_quad_power(&p->nq, (double *)(void *)((char *)p->nqmem + b), pb);
    }
    double un = u, vn = v;
    if ((p->nready < 0 || !nf_quad_newton(&p->nq, Q, CF_FITJOB_WARM_TOL, &un, &vn, out)) &&
        (nf_project(p->s, Q, u, v, PROJ_TOL, out) != NF_OK || !out->clamped))
        return 0;
    p->rc = NF_OK;
    return 1;
}

static int proj_foot(proj_t *p, const double Q[3], nf_proj_t *out)
{
    if (!p->ready) {
        if (cf_seedgrid_init_n(&p->g, p->s, SEEDS, p->points))
            return CF_ENOMEM;
        p->ready = 1;
    }
    if (!Q)
        return 0;                                         /* the grid only */
    p->rc = cf_seedgrid_project(&p->g, Q, PROJ_TOL, out); /* best point kept on ENOCONV */
    return 0;
}

/* Room for n feet (doubling up to CF_FITJOB_HOLD_ROWS): 0 when there is
 * none, the feet then let go (the next round searches every foot). */
static int feet_room(cf_fitjob_t *j, long n)
{
    if (n <= j->fcap)
        return 1;
    long cap = j->fcap ? 2 * j->fcap : 4096;
    while (cap < n && cap <= CF_FITJOB_HOLD_ROWS)
        cap *= 2;
    double *f =
        cap <= CF_FITJOB_HOLD_ROWS ? realloc(j->feet, sizeof(double) * FOOT * (size_t)cap) : NULL;
    if (!f) {
        free(j->feet);
        j->feet = NULL;
        j->fcap = j->nfeet = 0;
        return 0;
    }
    j->feet = f;
    j->fcap = cap;
    return 1;
}

static void proj_free(proj_t *p)
{
    if (p->ready && !p->borrowed)
        cf_seedgrid_free(&p->g);
    p->ready = p->borrowed = 0;
    free(p->nqmem);
    p->nqmem = NULL;
    p->nready = 0;
}

/* One pass: a fresh fitter on cur's space (P0 = cur's net, cf_fitpass in
 * the job's arena), parameters given or by projection onto proj. */
typedef struct pass {
    cf_fitpass_t fp;
    proj_t pj, pj2; /* pj2: the second core's searches (feet_batch) */
    const nf_surf_t *proj;
    const weigh_t *wt;
    long nin;       /* the first nin of the job's feet are on proj (Boehm): Newton from them */
    int keep;       /* each foot into the job's feet (round 0: the check's starts) */
    cf_edges_t ed;  /* the rows' footprint, the pins (issue 14; mem NULL: free edges) */
    cf_edges_t ed2; /* with the shard: its half's footprint (edges_hook), merged into ed */
    long points, clamped, nfar, dropped;
    double ss0, mx0; /* |distance| to proj of the points projected */
} pass_t;

/* The foot of point i on the surface before Boehm insertion, which is its
 * foot after it (the same surface: Newton, nf_project's boundary check
 * included, would end where it starts); 0 (search) when there is none.
 * The pass reads u, v, |dist| and clamped only: foot[] is not set. */
static int foot_from(const cf_fitjob_t *j, const pass_t *ps, long i, nf_proj_t *out)
{
    if (i >= ps->nin || !(j->feet[FOOT * i] == j->feet[FOOT * i]))
        return 0;
    const double *f = j->feet + FOOT * i;
    out->u = f[0];
    out->v = f[1];
    out->dist = fabs(f[2]);
    out->clamped = signbit(f[2]) != 0;
    out->foot[0] = out->foot[1] = out->foot[2] = NAN;
    out->iters = 0;
    return 1;
}

/* Foot i (NaN u: none) into room the job's feet have. */
static void foot_set(cf_fitjob_t *j, long i, const nf_proj_t *pr, int ok)
{
    double *f = j->feet + FOOT * i;
    f[0] = ok ? pr->u : NAN;
    f[1] = pr->v;
    f[2] = pr->clamped ? -fabs(pr->dist) : fabs(pr->dist);
}

/* Foot i (NaN u: none) into the job's feet, in order. */
static void foot_keep(cf_fitjob_t *j, long i, const nf_proj_t *pr, int ok)
{
    if (i > j->nfeet || (i == j->nfeet && !feet_room(j, i + 1)))
        return;
    foot_set(j, i, pr, ok);
    j->nfeet += i == j->nfeet;
}

/* Distance of row q (u v x y z) to s at its parameters. */
static double dist_at(const nf_surf_t *s, const double *q)
{
    double P[3];
    nf_surf_eval(s, q[0], q[1], P);
    return sqrt((q[2] - P[0]) * (q[2] - P[0]) + (q[3] - P[1]) * (q[3] - P[1]) +
                (q[4] - P[2]) * (q[4] - P[2]));
}

/* What a kept foot starts: Newton to the foot on the surface projected
 * onto; the foot itself (a fit pass's, foot_from's: the same surface);
 * Newton, then over a fold the other layers' valleys that may hold a
 * nearer foot (cf_seedgrid_nearer: a change of the fit can swap which
 * layer is nearer). */
enum { START_NEWTON, START_AS_IS, START_FOLD };

/* The feet of a batch's points k0 .. k1 - 1 (point n0 + k of the pass),
 * on either thread: from the last check's foot where there is one (how:
 * START_*), else the search; per point u, v, the signed distance,
 * clamped, and 1 when converged, into res (5 doubles a point). Each
 * thread its own proj_t (the search's grid built where it is first
 * needed). */
typedef struct feet_part {
    proj_t *pj;
    const double *buf, *feet;
    int cols;
    long k0, k1, n0, nin;
    double *res;
    int rc;
    int how;
} feet_part_t;

static void *feet_part(void *arg)
{
    feet_part_t *fp = arg;
    for (long k = fp->k0; k < fp->k1; k++) {
        const double *Q = fp->buf + (long)fp->cols * k + (fp->cols - 3);
        const long n = fp->n0 + k;
        const double *f = n < fp->nin && fp->feet ? fp->feet + FOOT * n : NULL;
        nf_proj_t pr;
        double *o = fp->res + 5 * k;
        if (fp->how == START_AS_IS && f && f[0] == f[0]) {
            o[0] = f[0], o[1] = f[1], o[2] = fabs(f[2]), o[3] = signbit(f[2]) != 0, o[4] = 1.0;
            continue;
        }
        const int warm =
            f && f[0] == f[0] && fp->how != START_AS_IS && proj_newton(fp->pj, Q, f[0], f[1], &pr);
        if ((!warm || fp->how == START_FOLD) && proj_foot(fp->pj, warm ? NULL : Q, &pr)) {
            fp->rc = CF_ENOMEM;
            return NULL;
        }
        if (warm && fp->how == START_FOLD)
            fp->pj->rc = cf_seedgrid_nearer(&fp->pj->g, fp->pj->nready > 0 ? &fp->pj->nq : NULL, Q,
                                            PROJ_TOL, &pr);
        o[0] = pr.u, o[1] = pr.v, o[2] = pr.dist, o[3] = pr.clamped, o[4] = fp->pj->rc == NF_OK;
    }
    return NULL;
}

/* Below this many points a batch's feet stay on one thread. */
#define FEET_SPLIT 512

/* One search grid for both halves of a batch of got points (the first is
 * point n0; the first nin have starts): built in pj when some point of the
 * batch has no start or every start needs it (how: START_FOLD), then lent
 * to pj2 (the grid's counters are each thread's). 0 or CF_ENOMEM. */
static int grid_share(proj_t *pj, proj_t *pj2, long got, long n0, long nin, int how)
{
    int rc;
    if (!pj->ready && (nin < n0 + got || how == START_FOLD) && (rc = proj_foot(pj, NULL, NULL)))
        return rc;
    if (pj->ready && !pj2->ready) {
        pj2->g = pj->g;
        pj2->ready = pj2->borrowed = 1;
    }
    return 0;
}

/* The feet of a batch of got points (the first is point n0 of the pass)
 * into res: on two threads when the job has two cores (opts.cores), the
 * second half with pj2; the same feet either way. how: what a kept foot
 * starts (START_*). */
static int feet_batch(const cf_fitjob_t *j, proj_t *pj, proj_t *pj2, const double *buf, int cols,
                      long got, long n0, long nin, int how, double *res)
{
    feet_part_t fp[2] = {{pj, buf, j->feet, cols, 0, got, n0, nin, res, 0, how},
                         {pj2, buf, j->feet, cols, got, got, n0, nin, res, 0, how}};
    cf_pair_t th;
    int on = 0;
    if (j->o.cores > 1 && got >= FEET_SPLIT) {
        int rc = grid_share(pj, pj2, got, n0, nin, how);
        if (rc)
            return rc;
        fp[0].k1 = fp[1].k0 = got / 2;
        on = !cf_pair_start(&th, feet_part, &fp[1]);
    }
    feet_part(&fp[0]);
    if (on)
        cf_pair_join(&th);
    else
        feet_part(&fp[1]);
    return fp[0].rc ? fp[0].rc : fp[1].rc;
}

static int pass_begin(cf_fitjob_t *j, pass_t *ps, const nf_surf_t *cur, const nf_surf_t *proj,
                      const weigh_t *wt, int threads, const char *name, char *msg, size_t ml)
{
    memset(ps, 0, sizeof *ps);
    ps->proj = proj;
    ps->wt = wt;
    int rc = cf_fitpass_begin(&ps->fp, j->mem, (size_t)j->need, cur, j->o.alpha, j->o.beta,
                              j->o.solver, threads, name, msg, ml);
    if (rc)
        return rc;
    ps->pj.s = ps->pj2.s = proj;
    ps->pj.points = ps->pj2.points = -1;
    if (!j->o.free_edges && (rc = cf_edges_begin(&ps->ed, cur)))
        return cf_fail(msg, ml, rc, "data footprint: %s", cf_strerror(rc));
    return 0;
}

/* n rows (x y z, or u v x y z without proj) into the fit: projected (far
 * points counted, dropped with drop_far), weighted (robust: a sixth
 * column), added. On an error *bad is the batch index of the row that
 * failed. */
static int pass_rows(cf_fitjob_t *j, pass_t *ps, const double *in, long n, long *bad)
{
    const double *uv = in;
    long m = n;
    int cols = ps->wt ? 6 : 5;
    /* Searches (a point without a kept foot) on two cores: the batch's
     * feet into rows first, 5 doubles at each point's index, read before
     * its row is written (m <= k); the same feet as one thread's. */
    const int pre = ps->proj && !ps->wt && j->o.cores > 1 && n >= FEET_SPLIT &&
                    ps->nin < ps->points + n && j->rcap >= n;
    if (pre &&
        feet_batch(j, &ps->pj, &ps->pj2, in, 3, n, ps->points, ps->nin, START_AS_IS, j->rows)) {
        *bad = 0;
        return CF_ENOMEM;
    }
    if (ps->proj || ps->wt) {
        m = 0;
        for (long k = 0; k < n; k++) {
            double *r = j->rows + cols * m;
            if (ps->proj) {
                const double *Q = in + 3 * k;
                nf_proj_t pr;
                int ok = 1;
                if (pre) {
                    const double *f = j->rows + 5 * k;
                    pr.u = f[0], pr.v = f[1], pr.dist = f[2], pr.clamped = (int)f[3];
                    ok = f[4] != 0.0;
                } else if (!foot_from(j, ps, ps->points + k, &pr)) {
                    if (proj_foot(&ps->pj, Q, &pr)) {
                        *bad = k;
                        return CF_ENOMEM;
                    }
                    ok = ps->pj.rc == NF_OK;
                }
                if (ps->keep)
                    foot_keep(j, ps->points + k, &pr, ok);
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
                r[0] = pr.u, r[1] = pr.v, r[2] = Q[0], r[3] = Q[1], r[4] = Q[2];
            } else
                memcpy(r, in + 5 * k, sizeof(double) * 5);
            if (ps->wt)
                r[5] = nf_tukey(dist_at(ps->wt->prev, r), ps->wt->c);
            j->src[m++] = k;
        }
        uv = j->rows;
    }
    long b = -1;
    int rc = cf_fitpass_rows(&ps->fp, uv, m, cols, &b);
    if (rc)
        *bad = uv != in && b >= 0 ? j->src[b] : b;
    /* The footprint of the rows in the fit (weight > 0): where data are. */
    if (!rc && cols == 5 && !ps->fp.hook) /* with the hook: on the halves' threads */
        cf_edges_add_rows(&ps->ed, uv, m, 5);
    for (long k = 0; !rc && cols == 6 && ps->ed.mem && k < m; k++)
        if (uv[6 * k + 5] > 0)
            cf_edges_add(&ps->ed, uv[6 * k], uv[6 * k + 1]);
    ps->points += n;
    return rc;
}

/* Footprint counts of the second half into the first's (cf_edges_add of
 * every row: the same counts as one thread's, saturating alike). */
static void edges_merge(cf_edges_t *a, const cf_edges_t *b)
{
    if (a->mem && b->mem)
        (void)nf_footprint_merge(&a->fp, &b->fp); /* the same net: cannot fail */
}

/* A fit pass's rows with the shard: each half's footprint on its thread
 * (cf_fitpass's hook), the second's merged before the pins. */
static void edges_hook(void *ctx, int half, const double *rows, long n)
{
    struct pass *ps = ctx;
    cf_edges_add_rows(half ? &ps->ed2 : &ps->ed, rows, n, 5);
}

static int pass_solve(cf_fitjob_t *j, pass_t *ps, nf_surf_t *out, const char *name, char *msg,
                      size_t ml)
{
    nf_solve_opts_t so = {j->o.solve_tol, (int)j->o.max_iter, j->o.probe};
    edges_merge(&ps->ed, &ps->ed2);
    cf_edges_free(&ps->ed2);
    /* Outside the footprint the nominal, not an extrapolation (issue 14). */
    long np = cf_edges_pin(&ps->ed, &j->base, &ps->fp);
    if (np < 0)
        return cf_fail(msg, ml, (int)np, "%s: pinning the control points without data: %s", name,
                       cf_strerror((int)np));
    return cf_fitpass_solve(&ps->fp, &so, out, name, msg, ml);
}

static void pass_free(pass_t *ps)
{
    proj_free(&ps->pj);
    proj_free(&ps->pj2);
    cf_edges_free(&ps->ed);
    cf_edges_free(&ps->ed2);
}

/* The live point xyz into the hold (doubling up to
 * CF_FITJOB_HOLD_ROWS; past it, or without memory, the hold is let go and
 * the later passes read the source). */
static void hold_add(cf_fitjob_t *j, const double xyz[3])
{
    if (j->hold_over)
        return;
    if (j->nhold == j->hcap) {
        long cap = j->hcap ? 2 * j->hcap : 4096;
        double *h =
            cap <= CF_FITJOB_HOLD_ROWS ? realloc(j->hold, sizeof(double) * 3 * (size_t)cap) : NULL;
        if (!h) {
            free(j->hold);
            j->hold = NULL;
            j->nhold = j->hcap = 0;
            j->hold_over = 1;
            return;
        }
        j->hold = h;
        j->hcap = cap;
    }
    memcpy(j->hold + 3 * j->nhold++, xyz, sizeof(double) * 3);
}

/* The hold as a source: rows x y z, as the journal's. */
typedef struct held {
    const cf_fitjob_t *j;
    long next;
} held_t;

static int held_rewind(void *ctx, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    ((held_t *)ctx)->next = 0;
    return 0;
}

static long held_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    held_t *h = ctx;
    (void)msg, (void)ml;
    long n = h->j->nhold - h->next < max ? h->j->nhold - h->next : max;
    memcpy(rows, h->j->hold + 3 * h->next, sizeof(double) * 3 * (size_t)n);
    h->next += n;
    return n;
}

static void held_where(void *ctx, long k, char *buf, size_t n)
{
    (void)ctx;
    snprintf(buf, n, "live point %ld", k);
}

int cf_fitjob_add(cf_fitjob_t *j, const double xyz[3], char *msg, size_t ml)
{
    int rc;
    if (!j->live) {
        if (!j->lp) { /* the fitter's 32-byte-aligned members: calloc gives 16 */
            size_t al = _Alignof(struct pass), sz = (sizeof *j->lp + al - 1) / al * al;
            if ((j->lp = aligned_alloc(al, sz)))
                memset(j->lp, 0, sz);
        }
        if (!j->mem)
            j->mem = cf_bigmem_alloc((size_t)j->need);
        if (!j->lp || !j->mem || buffers(j, 1, 1))
            return cf_fail(msg, ml, CF_ENOMEM, "cannot allocate %ld bytes", j->need);
        if ((rc = pass_begin(j, j->lp, &j->base, &j->base, NULL, j->o.threads, "live points", msg,
                             ml)))
            return rc;
        j->live = 1;
    }
    long bad;
    rc = pass_rows(j, j->lp, xyz, 1, &bad);
    j->nlive++;
    if (!rc)
        hold_add(j, xyz);
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

/* A second accumulator for cur's net is small (CF_FITJOB_SHARD_MAX) and
 * the pass with it within the board's bytes. */
static int shard_fits(const cf_fitjob_t *j, const nf_surf_t *cur)
{
    long sh = nf_fit_shard_bytes(cur->nu, cur->nv, cur->p, cur->q),
         need = cf_fitpass_bytes(cur, j->o.solver, 2);
    return sh >= 0 && sh <= CF_FITJOB_SHARD_MAX && need > 0 && need <= NF_ARENA_BYTES;
}

/* Room for a pass in halves on cur's net (opts.cores): a second
 * accumulator of at most CF_FITJOB_SHARD_MAX bytes within the board's
 * arena, for a source that may split (given parameters). */
static int halves_room(const cf_fitjob_t *j, const run_t *r, const nf_surf_t *cur)
{
    if (j->o.cores < 2 || j->o.threads > 1 || !r->src->split || r->src->cols != 5)
        return 0;
    return shard_fits(j, cur);
}

/* Projected points (x y z) accumulate with the shard whatever the cores
 * (j->shard), so that one core's fit is two cores' bit for bit; once the
 * count is known (after round 0, or from the start for a file read whole
 * at open: its bound), and only where the points outweigh the shard:
 * zeroing and merging it costs about its stripe width a control point, a
 * point about 16 of its products a core (the narrow ridge's 3,420 control
 * points at 15,933 points ran 7 % slower with it). */
static int shard_room(const cf_fitjob_t *j, const run_t *r, const nf_surf_t *cur)
{
    const double width = (double)cur->q * cur->nu + cur->p + 1;
    const long n = r->total > 0 ? r->total : cf_fitsrc_most(r->src);
    return j->o.threads == 1 && r->src->cols == 3 && n > 0 &&
           16.0 * (double)n >= (double)cur->nu * cur->nv * width && shard_fits(j, cur);
}

/* The source in two halves for two threads (opts.cores): 1 and half[],
 * else 0 (one reader; nothing changed but the position, every pass
 * rewinds). */
static int halves(const run_t *r, cf_fitsrc_t half[2])
{
    char m[256];
    return r->j->o.cores > 1 && r->src->split && r->src->cols == 5 && r->j->cap >= 2 &&
           !r->src->split(r->src->ctx, half, m, sizeof m);
}

/* One half of a pass on its thread (the first on the caller's: progress
 * and the stop request there). The first half's error wins (file order):
 * it halts the second. */
typedef struct half {
    const run_t *r; /* the first half only */
    const cf_fitsrc_t *src;
    double *buf;
    long cap;
    atomic_int *halt;
    int rc, rd; /* the error; rd 1: from reading (its message in msg) */
    long n;     /* points done */
    char msg[1024];
    /* fit */
    nf_fit_t *f;
    cf_edges_t *ed;
    long bad; /* the half's index of the row the fitter refused */
    double row[5];
    /* measure */
    const nf_surf_t *s;
    double tol, cut;
    int want_hist;
    struct resid *res;
} half_t;

/* The next rows of a half: the count, 0 at its end or on a halt. */
static long half_read(half_t *h)
{
    if (atomic_load(h->halt))
        return 0;
    long got = h->src->read(h->src->ctx, h->buf, h->cap, h->msg, sizeof h->msg);
    if (got < 0) {
        h->rc = (int)got;
        h->rd = 1;
        return 0;
    }
    if (h->r && got && stopped(h->r)) {
        h->rc = RIG_EABORTED;
        return 0;
    }
    return got;
}

static void half_end(half_t *h)
{
    if (h->r && h->rc)
        atomic_store(h->halt, 1);
}

static void *fit_half(void *arg)
{
    half_t *h = arg;
    long got;
    while ((got = half_read(h)) > 0) {
        long b = -1;
        int rc = nf_fit_add_rows(h->f, h->buf, got, &b);
        if (rc) {
            h->rc = rc;
            h->bad = h->n + (b >= 0 ? b : 0);
            memcpy(h->row, h->buf + 5 * (b >= 0 ? b : 0), sizeof h->row);
            break;
        }
        cf_edges_add_rows(h->ed, h->buf, got, 5);
        h->n += got;
        if (h->r)
            progress(h->r, 2 * h->n);
    }
    half_end(h);
    return NULL;
}

/* Run fn on two halves, the second on a new thread (without one, after
 * the first on this). Then, when the first read to its end, the second's
 * lines count from the file's start (join). */
static void two_halves(const run_t *r, const cf_fitsrc_t half[2], half_t h[2], void *(*fn)(void *))
{
    /* What every pass's halves share: the readers, the job's batch buffer
     * in two, the halt flag. */
    atomic_int halt;
    atomic_init(&halt, 0);
    const long c = r->j->cap / 2;
    for (int k = 0; k < 2; k++) {
        h[k].src = &half[k];
        h[k].buf = r->j->buf + 5 * c * k;
        h[k].cap = c;
        h[k].halt = &halt;
    }
    h[0].r = r;
    cf_pair_t th;
    int on = !cf_pair_start(&th, fn, &h[1]); /* signals stay the caller's */
    fn(&h[0]);
    if (on)
        cf_pair_join(&th);
    else
        fn(&h[1]);
    if (!h[0].rc && r->src->join)
        r->src->join(r->src->ctx);
}

/* The error of two halves as one reader would give it: the first's, else
 * the second's with its true line (join done). 0 when neither failed. */
static int halves_error(const run_t *r, const cf_fitsrc_t half[2], half_t h[2])
{
    half_t *e = h[0].rc ? &h[0] : h[1].rc ? &h[1] : NULL;
    if (!e)
        return 0;
    const cf_fitsrc_t *hs = &half[e - h];
    if (e->rd) { /* the reader repeats its error, now with the file's line */
        double row[5];
        return (int)hs->read(hs->ctx, row, 0, r->msg, r->ml);
    }
    return e->rc;
}

/* A pass of given parameters read in halves: the first into the job's
 * fitter and footprint, the second into the shard and a footprint of its
 * own, merged (the solve merges the shard). */
static int fit_halves(run_t *r, const nf_surf_t *cur, const cf_fitsrc_t half[2], pass_t *ps)
{
    cf_edges_t ed1;
    memset(&ed1, 0, sizeof ed1);
    int rc;
    if (ps->ed.mem && (rc = cf_edges_begin(&ed1, cur)))
        return cf_fail(r->msg, r->ml, rc, "data footprint: %s", cf_strerror(rc));
    half_t h[2] = {{.f = &ps->fp.f, .ed = &ps->ed}, {.f = ps->fp.sh, .ed = &ed1}};
    double t = cli_now();
    two_halves(r, half, h, fit_half);
    ps->fp.t_rows += cli_now() - t;
    ps->points = h[0].n + h[1].n;
    edges_merge(&ps->ed, &ed1);
    cf_edges_free(&ed1);
    rc = halves_error(r, half, h);
    const half_t *e = &h[h[0].rc ? 0 : 1];
    if (rc && rc != RIG_EABORTED && !e->rd) { /* the fitter's refusal */
        char at[4200];
        half[e - h].where(half[e - h].ctx, e->bad, at, sizeof at);
        cf_fitpass_row_error(&ps->fp, rc, e->row, at, r->msg, r->ml);
    }
    return rc;
}

/* A fit pass's feet (projecting onto proj): none kept, the job's feet
 * taken as they are (proj is the surface they were found on, refined), or
 * each point's foot kept for the check's Newton (round 0). */
enum { FEET_NONE, FEET_USE, FEET_KEEP };

/* One fit pass from the source into out (cur's shape). */
static int fit_pass(run_t *r, const nf_surf_t *cur, const nf_surf_t *proj, const weigh_t *wt,
                    int feet, nf_surf_t *out, pass_t *ps)
{
    cf_fitjob_t *j = r->j;
    const cf_fitsrc_t *s = r->src;
    cf_fitsrc_t half[2];
    /* Given parameters, unweighted, the second accumulator in the arena:
     * each half read and accumulated on its own core (issue 20). */
    const int two = j->two && !wt && halves(r, half);
    const int shard = !two && !wt && j->shard;
    int rc = pass_begin(j, ps, cur, s->cols == 5 ? NULL : proj, wt, two || shard ? 2 : j->o.threads,
                        s->name, r->msg, r->ml);
    if (!rc && shard) {
        ps->fp.serial = j->o.cores < 2;
        j->used2 |= !ps->fp.serial;
        if (ps->ed.mem && !cf_edges_begin(&ps->ed2, cur)) { /* else one footprint, in pass_rows */
            ps->fp.hook = edges_hook;
            ps->fp.hook_ctx = ps;
        }
    }
    if (feet == FEET_USE && ps->proj)
        ps->nin = j->nfeet;
    ps->keep = feet == FEET_KEEP && ps->proj && !rc;
    if (ps->keep)
        j->nfeet = 0;
    if (two && !rc) {
        j->used2 = 1;
        rc = fit_halves(r, cur, half, ps);
    } else if (!rc)
        rc = rewind_src(r);
    long got;
    while (!two && !rc && (got = s->read(s->ctx, j->buf, j->cap, r->msg, r->ml)) != 0) {
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
            if (!ps->proj)
                cf_fitpass_row_error(&ps->fp, rc, j->buf + 5 * bad, at, r->msg, r->ml);
            else
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
    if (ps->keep && (rc || j->nfeet != ps->points))
        j->nfeet = 0; /* not every point's: no starts */
    if (ps->keep)     /* the check then sees its fit's grid (START_FOLD) */
        j->feet_base = j->nfeet > 0;
    pass_free(ps);
    return rc;
}

typedef struct resid {
    double ss, mx;
    long n, within;  /* points, and those with |d| <= tol */
    long outliers;   /* points with |d| >= the robust cut-off (not counted in spans) */
    nf_rhist_t hist; /* |d| for the robust scale */
} resid_t;

/* The check pass's per-span counts: residual (sr) or auto (ks, with the
 * data footprint fp); NULL members are not filled. */
typedef struct check {
    nf_spanres_t *sr;
    nf_knotsel_t *ks;
    nf_knotsel_t *kr; /* auto + robust: the rejected points' misfit (cf_loop_fold_auto) */
    nf_footprint_t *fp;
} check_t;

/* A pass over the points against the fit s: |Q - S(u, v)| at the given
 * parameters, else the normal distance to s (projection). Sums for the
 * summary, the count within tol (if > 0), the |d| histogram, (if ck) the
 * excess per knot span of the points out of tolerance (those beyond cut
 * > 0, the points a robust fit rejects, go to their cells only, and to the
 * knot chooser as data without misfit), the footprint of the feet not
 * clamped to the boundary, and (if st) the signed normal deviations. The
 * |d| histogram (a log10 per point) only if want_hist: only the robust
 * scale reads it (issue 20). */
/* A distance d (its square d2 as computed) into measure's sums. */
static inline double resid_dist(resid_t *out, double d, double d2, double tol, double cut,
                                int want_hist)
{
    out->ss += d2;
    out->mx = d > out->mx ? d : out->mx;
    out->n++;
    out->within += tol > 0 && d <= tol;
    if (want_hist)
        nf_rhist_add(&out->hist, d);
    out->outliers += cut > 0 && d >= cut;
    return d;
}

/* |Q - S(u, v)|^2 of one row (u v x y z) at its parameters. */
static inline double resid_d2(cf_surfrow_t *ev, const double *q)
{
    double P[3];
    cf_surfrow_eval(ev, q[0], q[1], P);
    return (q[2] - P[0]) * (q[2] - P[0]) + (q[3] - P[1]) * (q[3] - P[1]) +
           (q[4] - P[2]) * (q[4] - P[2]);
}

/* The distance of one row (u v x y z) to s at its parameters into the
 * sums: measure's, on either thread. */
static inline double resid_add(resid_t *out, cf_surfrow_t *ev, const double *q, double tol,
                               double cut, int want_hist)
{
    const double d2 = resid_d2(ev, q);
    return resid_dist(out, sqrt(d2), d2, tol, cut, want_hist);
}

/* resid_add's sums where nothing needs d itself (no tolerance, no cut, no
 * histogram: a plain fit's rms and max): no square root per point. The
 * root of the largest d^2 is the largest d (sqrt is monotonic and
 * correctly rounded); the caller takes it once. */
static inline void resid_add2(resid_t *out, double *mx2, cf_surfrow_t *ev, const double *q)
{
    const double d2 = resid_d2(ev, q);
    out->ss += d2;
    *mx2 = d2 > *mx2 ? d2 : *mx2;
}

static void *measure_half(void *arg)
{
    half_t *h = arg;
    cf_surfrow_t ev;
    if (cf_surfrow_init(&ev, h->s)) {
        h->rc = CF_ENOMEM;
        snprintf(h->msg, sizeof h->msg, "out of memory");
        half_end(h);
        return NULL;
    }
    const int sums = !(h->tol > 0) && !(h->cut > 0) && !h->want_hist;
    double mx2 = 0.0;
    long got;
    while ((got = half_read(h)) > 0) {
        for (long k = 0; sums && k < got; k++)
            resid_add2(h->res, &mx2, &ev, h->buf + 5 * k);
        for (long k = 0; !sums && k < got; k++)
            resid_add(h->res, &ev, h->buf + 5 * k, h->tol, h->cut, h->want_hist);
        h->res->n += sums ? got : 0;
        h->n += got;
        if (h->r)
            progress(h->r, 2 * h->n);
    }
    const double mx = sqrt(mx2);
    h->res->mx = mx > h->res->mx ? mx : h->res->mx;
    cf_surfrow_free(&ev);
    half_end(h);
    return NULL;
}

/* b's sums into out's (a pass measured in parts; the histogram by its
 * bins). */
static void resid_merge(resid_t *out, const resid_t *b)
{
    out->ss += b->ss;
    out->mx = b->mx > out->mx ? b->mx : out->mx;
    out->n += b->n;
    out->within += b->within;
    out->outliers += b->outliers;
    out->hist.n += b->hist.n;
    out->hist.zero += b->hist.zero;
    out->hist.over += b->hist.over;
    out->hist.max = b->hist.max > out->hist.max ? b->hist.max : out->hist.max;
    for (int i = 0; i < NF_RHIST_BINS; i++)
        out->hist.bin[i] += b->hist.bin[i];
}

/* The loop's check pass in two parts (auto refinement, neither robust
 * nor with statistics): each batch of FEET_SPLIT points or more in
 * halves, each half's feet and then its sums (distances, the knot
 * chooser's spans unless a pruning trial's, the footprint) into its own
 * part, the second part merged into the first after the pass. On two
 * cores the halves run at once, on one in turn: the sums are grouped
 * alike, so the fit is the same. feet: the half's feet are kept
 * (Newton's starts next round). */
typedef struct check_part {
    feet_part_t fp;
    cf_fitjob_t *j;
    int feet;
    double tol;
    resid_t *res;
    nf_knotsel_t *ks;
    nf_footprint_t *foot;
} check_part_t;

static void *check_half(void *arg)
{
    check_part_t *c = arg;
    feet_part(&c->fp);
    if (c->fp.rc)
        return NULL;
    for (long k = c->fp.k0; k < c->fp.k1; k++) {
        const double *f = c->fp.res + 5 * k;
        nf_proj_t pr;
        pr.u = f[0], pr.v = f[1], pr.dist = f[2], pr.clamped = (int)f[3];
        if (c->feet)
            foot_set(c->j, c->fp.n0 + k, &pr, f[4] != 0.0);
        const double d = resid_dist(c->res, fabs(f[2]), f[2] * f[2], c->tol, 0.0, 0);
        if (c->ks)
            nf_knotsel_add(c->ks, f[0], f[1], d);
        if (!pr.clamped)
            nf_footprint_add(c->foot, f[0], f[1]); /* outside the domain: not counted */
    }
    return NULL;
}

/* The second part's counts (check_half); ksmem NULL: no chooser's. */
typedef struct check_two {
    resid_t res;
    nf_knotsel_t ks;
    nf_footprint_t foot;
    double *ksmem;
    void *fmem;
} check_two_t;

static int check_two_init(check_two_t *t, const nf_surf_t *s, double tol, int chooser)
{
    memset(t, 0, sizeof *t);
    nf_rhist_init(&t->res.hist);
    const long fb = nf_footprint_bytes(s->nu, s->nv, s->p, s->q);
    t->ksmem = chooser
                   ? malloc(sizeof(double) * (size_t)NF_KNOTSEL_DOUBLES(s->nu, s->nv, s->p, s->q))
                   : NULL;
    t->fmem = fb > 0 ? malloc((size_t)fb) : NULL;
    if ((chooser && (!t->ksmem || nf_knotsel_init(&t->ks, s, tol, t->ksmem))) || !t->fmem ||
        nf_footprint_init(&t->foot, s, t->fmem, (size_t)fb)) {
        free(t->ksmem);
        free(t->fmem);
        t->ksmem = NULL;
        t->fmem = NULL;
        return 0;
    }
    return 1;
}

static void check_two_free(check_two_t *t)
{
    free(t->ksmem);
    free(t->fmem);
}

/* One batch of got points (the first is point n0 of the pass) in two
 * parts: a into out, ck's chooser (if any) and footprint; b into t. */
static int check_batch(cf_fitjob_t *j, proj_t *pj, proj_t *pj2, const check_t *ck, check_two_t *t,
                       resid_t *out, int cols, long got, long n0, long nin, int how, int keep)
{
    if (grid_share(pj, pj2, got, n0, nin, how))
        return CF_ENOMEM;
    /* Kept feet in place when they follow on: room for the batch first. */
    const int feet = keep && j->nfeet == n0 && feet_room(j, n0 + got);
    const long h = got / 2;
    check_part_t c[2] = {{{pj, j->buf, j->feet, cols, 0, h, n0, nin, j->rows, 0, how},
                          j,
                          feet,
                          j->o.tol,
                          out,
                          ck->ks,
                          ck->fp},
                         {{pj2, j->buf, j->feet, cols, h, got, n0, nin, j->rows, 0, how},
                          j,
                          feet,
                          j->o.tol,
                          &t->res,
                          ck->ks ? &t->ks : NULL,
                          &t->foot}};
    cf_pair_t th;
    const int on = j->o.cores > 1 && !cf_pair_start(&th, check_half, &c[1]);
    check_half(&c[0]);
    if (on)
        cf_pair_join(&th);
    else
        check_half(&c[1]);
    if (feet && !c[0].fp.rc && !c[1].fp.rc)
        j->nfeet = n0 + got;
    return c[0].fp.rc ? c[0].fp.rc : c[1].fp.rc;
}

/* measure of given parameters with nothing per span, in halves: the sums
 * of each merged. */
static int measure_halves(run_t *r, const nf_surf_t *s, const cf_fitsrc_t half[2], double cut,
                          resid_t *out, int want_hist)
{
    cf_fitjob_t *j = r->j;
    resid_t b;
    memset(&b, 0, sizeof b);
    nf_rhist_init(&b.hist);
    half_t h[2] = {{.s = s, .tol = j->o.tol, .cut = cut, .want_hist = want_hist, .res = out},
                   {.s = s, .tol = j->o.tol, .cut = cut, .want_hist = want_hist, .res = &b}};
    two_halves(r, half, h, measure_half);
    resid_merge(out, &b);
    int rc = halves_error(r, half, h);
    if (rc == CF_ENOMEM)
        return cf_fail(r->msg, r->ml, rc, "out of memory");
    return rc;
}

static int measure(run_t *r, const nf_surf_t *s, const check_t *ck, double cut, resid_t *out,
                   cf_stats_t *st, int want_hist)
{
    nf_spanres_t *sr = ck ? ck->sr : NULL;
    cf_fitjob_t *j = r->j;
    const cf_fitsrc_t *src = r->src;
    double tol = j->o.tol;
    memset(out, 0, sizeof *out);
    nf_rhist_init(&out->hist);
    proj_t pj, pj2;
    memset(&pj, 0, sizeof pj);
    memset(&pj2, 0, sizeof pj2);
    pj.s = pj2.s = s;
    /* Known from the first pass for any source (a fit pass projects with -1:
     * a journal, whose count is known before, fits as its points file). */
    pj.points = pj2.points = r->total;
    int uv = src->cols == 5;
    /* The check's feet: the next round's fit pass starts from them. The
     * feet before (the last check's, on the previous fit) start this
     * pass's Newton; where it fails, the search. (A start from the last
     * foot trusts the fit to move less than the distance's valleys are
     * apart: test_foot's next_fit; on the loop data sets every warm foot
     * was the search's.) Over a fold the other layers' valleys within
     * reach of Newton's foot are tried too (START_FOLD). */
    const int keep = ck && !uv && j->o.loop;
    const long nin = uv ? 0 : j->nfeet;
    /* A fit proven a height field (nf_fold_free: every line along one
     * direction meets it once, so it has no second layer; hodograph
     * bounds, O(N)) needs no grid to say so: the blanket on round 0's fit
     * cost about a tenth of the loop on holes at 3,833 points. The proof
     * and the blanket's test are different sufficient signs (the blanket
     * judges its quadrilaterals against its maximum-area plane); either
     * one lets the check start from the kept feet. */
    const int unfolded = nin > 0 && !(j->flat && !j->feet_base) && nf_fold_free(s);
    const int how = (j->flat && !j->feet_base) || unfolded ? START_NEWTON : START_FOLD;
    if (unfolded)
        j->flat = 1;
    if (keep)
        j->nfeet = j->feet_base = 0;
    /* Given parameters and only the sums: each half on its own core. */
    cf_fitsrc_t half[2];
    if (uv && !st && !(ck && (ck->sr || ck->ks || ck->kr || ck->fp)) && halves(r, half)) {
        j->used2 = 1;
        return measure_halves(r, s, half, cut, out, want_hist);
    }
    cf_surfrow_t ev; /* S(u, v) a row of one v at a time (issue 20) */
    if (cf_surfrow_init(&ev, s))
        return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
    /* The loop's plain check in two parts (check_batch); without the
     * second part's memory, one. */
    check_two_t two;
    const int parts = !uv && !st && ck && ck->fp && !ck->sr && !ck->kr && !(cut > 0) &&
                      !want_hist && check_two_init(&two, s, tol, ck->ks != NULL);
    int rc = rewind_src(r);
    long got = 0, seen = 0;
    while (!rc && (got = src->read(src->ctx, j->buf, j->cap, r->msg, r->ml)) > 0) {
        if (stopped(r)) {
            rc = RIG_EABORTED;
            break;
        }
        if (parts && got >= FEET_SPLIT) {
            if (check_batch(j, &pj, &pj2, ck, &two, out, src->cols, got, seen, nin, how, keep)) {
                rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
                break;
            }
            seen += got;
            progress(r, seen);
            continue;
        }
        /* The batch's feet first (j->rows: 5 doubles a point), then the
         * sums in the points' order. */
        const int proj = !uv || st;
        if (proj && feet_batch(j, &pj, &pj2, j->buf, src->cols, got, seen, nin, how, j->rows)) {
            rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
            break;
        }
        for (long k = 0; k < got; k++) {
            const double *Q = j->buf + (long)src->cols * k + (src->cols - 3);
            double q[5], sd = 0.0;
            int clamped = 0;
            if (uv)
                memcpy(q, j->buf + 5 * k, sizeof(double) * 5);
            if (proj) {
                const double *f = j->rows + 5 * k;
                nf_proj_t pr;
                pr.u = f[0], pr.v = f[1], pr.dist = f[2], pr.clamped = (int)f[3];
                if (keep)
                    foot_keep(j, seen + k, &pr, f[4] != 0.0);
                sd = pr.dist;
                clamped = !uv && pr.clamped;
                if (!uv)
                    q[0] = pr.u, q[1] = pr.v, q[2] = Q[0], q[3] = Q[1], q[4] = Q[2];
            }
            /* projected: the foot's distance, S at the foot already known */
            double d = uv ? resid_add(out, &ev, q, tol, cut, want_hist)
                          : resid_dist(out, fabs(sd), sd * sd, tol, cut, want_hist);
            if (sr && cut > 0 && d >= cut)
                nf_spanres_add_rejected(sr, q[0], q[1], d);
            else if (sr)
                nf_spanres_add(sr, q[0], q[1], d);
            /* A point the robust pass rejected is data, not misfit (NaN):
             * a spike is not a shape. (nf_spanres_fold's rescue of a
             * rejected cluster, a feature, has no auto counterpart yet.) */
            if (ck && ck->ks)
                nf_knotsel_add(ck->ks, q[0], q[1], cut > 0 && d >= cut ? NAN : d);
            if (ck && ck->kr && cut > 0 && d >= cut)
                nf_knotsel_add(ck->kr, q[0], q[1], d);
            if (ck && ck->fp && !clamped)
                nf_footprint_add(ck->fp, q[0], q[1]); /* outside the domain: not counted */
            if (st)
                cf_stats_add(st, sd);
        }
        seen += got;
        progress(r, seen);
    }
    if (!rc && got < 0)
        rc = (int)got;
    if (parts) { /* the second part after the first: the same sums on one core or two */
        resid_merge(out, &two.res);
        if (!rc && ((ck->ks && nf_knotsel_merge(ck->ks, &two.ks)) ||
                    nf_footprint_merge(ck->fp, &two.foot)))
            rc = cf_fail(r->msg, r->ml, CF_EARG, "check pass: parts of other surfaces");
        check_two_free(&two);
    }
    if (keep && (rc || out->n != j->nfeet))
        j->nfeet = 0; /* not every point's: no starts */
    cf_surfrow_free(&ev);
    if (pj.ready || pj2.ready)
        j->flat = pj.ready ? pj.g.use_quad : pj2.g.use_quad;
    proj_free(&pj);
    proj_free(&pj2);
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
    int cur_is_base; /* round 0 fits in the job's base itself: no copy of it */
    cf_stats_t *st;  /* the round's deviations (swapped with the best's) */
    double *srmem;
    void *fpmem;       /* auto: the footprint's cells */
    double *krmem;     /* auto + robust: kr's spans */
    double *crmem;     /* auto + robust: the cells of the rejected points (sr) */
    nf_knotsel_t kr;   /* auto + robust: the rejected points' misfit */
    nf_knotsel_t ks;   /* auto: the check pass's spans (in srmem) */
    nf_footprint_t fp; /* auto: where the points are */
    nf_robust_t rb;    /* the last robust pass's scale */
    /* A pruning trial: pass 0 projects onto this fit (the check's feet are
     * on it) instead of cur, the knot-removed start; NULL: cur. src0: pass
     * 0 reads these rows instead (u v x y z: the feet themselves, which
     * Newton on proj0 would return; NULL: the job's source). */
    const nf_surf_t *proj0;
    const cf_fitsrc_t *src0;
} surfs_t;

static void surfs_free(surfs_t *s)
{
    if (!s->cur_is_base)
        cf_surf_free(&s->cur);
    cf_surf_free(&s->fit);
    cf_surf_free(&s->prev);
    cf_surf_free(&s->nxt);
    free(s->st);
    free(s->srmem);
    free(s->fpmem);
    free(s->krmem);
    free(s->crmem);
}

/* Round k on S->cur: the fit passes (the first from the live points when
 * there are), the robust passes, and the check. */
static int one_round(run_t *r, int k, surfs_t *S, resid_t *res, pass_t *po, double *c,
                     long *rejected, check_t *ck, nf_spanres_t *sr, cf_fitjob_result_t *out)
{
    cf_fitjob_t *j = r->j;
    const cf_fitjob_opts_t *o = &j->o;
    int uv = r->src->cols == 5, rc;
    double lo, hi;
    round_span(o, k, &lo, &hi);
    int npass = (int)(o->reparam + 1 + (o->robust ? 2 * o->robust_iters : 0) + 1), ip = 0;
    /* Round k fits in the space of cur with P0 = cur's net: the base
     * first, then the previous fit refined (Section 2.2). */
    j->two = !(k == 0 && j->live) && halves_room(j, r, &S->cur);
    j->shard = !(k == 0 && j->live) && !j->two && shard_room(j, r, &S->cur);
    j->need = cf_fitpass_bytes(&S->cur, o->solver, j->two || j->shard ? 2 : o->threads);
    if (!(k == 0 && j->live)) {
        cf_bigmem_free(j->mem);
        j->mem = cf_bigmem_alloc((size_t)j->need);
    }
    /* prev: the surface projected onto and the robust weights' fit; a plain
     * fit at given parameters needs neither (issue 20: one net less). */
    const int want_prev = !uv || o->robust;
    if (!want_prev)
        cf_surf_free(&S->prev);
    if (!j->mem || replace_copy(&S->fit, &S->cur) || (want_prev && replace_copy(&S->prev, &S->cur)))
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
        } else {
            const nf_surf_t *pj = pass == 0 && S->proj0 ? S->proj0 : &S->prev;
            const cf_fitsrc_t *own = r->src;
            if (pass == 0 && S->src0)
                r->src = S->src0;
            /* Round 0's last pass keeps the feet: its check starts from
             * them (test_foot's first_check). */
            const int feet = pass == 0 && k > 0                        ? FEET_USE
                             : k == 0 && pass == o->reparam && o->loop ? FEET_KEEP
                                                                       : FEET_NONE;
            rc = fit_pass(r, &S->cur, r->src->cols == 5 ? NULL : pj, NULL, feet, &S->fit, po);
            r->src = own;
        }
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
        out->t_acc += po->fp.t_acc;
        out->t_solve += po->fp.t_solve;
        out->t_rows += po->fp.t_rows;
        out->t_merge += po->fp.t_merge;
        if (want_prev)
            memcpy(S->prev.cp, S->fit.cp,
                   sizeof(double) * 3 * (size_t)S->cur.nu * (size_t)S->cur.nv);
    }
    /* Robust passes: the MAD of the residuals to the last fit sets the
     * scale, floored by the probe's noise or a share of tol (nf_robust:
     * clean data keep their weight), Tukey weights of those residuals the
     * next fit, zero from NF_ROBUST_CUT scales on. */
    *c = 0.0;
    *rejected = 0;
    memset(&S->rb, 0, sizeof S->rb);
    for (long it = 0; o->robust && it < o->robust_iters; it++) {
        set_pass(r, lo, hi, ip++, npass);
        if ((rc = measure(r, &S->prev, NULL, 0.0, res, NULL, 1)))
            return rc;
        if ((rc = nf_robust_init(&S->rb, &res->hist, out->robust_floor)))
            return cf_fail(r->msg, r->ml, rc, "robust scale: %s", nf_strerror(rc));
        *c = NF_ROBUST_CUT * S->rb.scale;
        if (!(*c > 0))
            break; /* the fit is exact: nothing to reweight */
        weigh_t wt = {*c, &S->prev};
        set_pass(r, lo, hi, ip++, npass);
        if ((rc = fit_pass(r, &S->cur, uv ? NULL : &S->prev, &wt, FEET_NONE, &S->fit, po)))
            return rc;
        *rejected = po->fp.rejected;
        out->t_acc += po->fp.t_acc;
        out->t_solve += po->fp.t_solve;
        out->t_rows += po->fp.t_rows;
        out->t_merge += po->fp.t_merge;
        memcpy(S->prev.cp, S->fit.cp, sizeof(double) * 3 * (size_t)S->cur.nu * (size_t)S->cur.nv);
    }
    /* The check: distances of all points to this fit, and where they are
     * out of tolerance (per knot span). */
    free(S->srmem);
    free(S->fpmem);
    free(S->krmem);
    free(S->crmem);
    S->srmem = NULL;
    S->fpmem = NULL;
    S->krmem = NULL;
    S->crmem = NULL;
    memset(ck, 0, sizeof *ck);
    if (o->loop && o->refine == CF_REFINE_RESIDUAL) {
        S->srmem = malloc(sizeof(double) *
                          (size_t)NF_SPANRES_DOUBLES(S->fit.nu, S->fit.nv, S->fit.p, S->fit.q));
        if (!S->srmem)
            return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
        nf_spanres_init(sr, &S->fit, o->tol, S->srmem);
        ck->sr = sr;
    } else if (o->loop && o->refine == CF_REFINE_AUTO) {
        /* A pruning trial (proj0) inserts no knots: no chooser, nor
         * (robust) its rejected clusters; the footprint is the result's. */
        const int chooser = !S->proj0;
        long fb = nf_footprint_bytes(S->fit.nu, S->fit.nv, S->fit.p, S->fit.q);
        S->srmem = chooser ? malloc(sizeof(double) * (size_t)NF_KNOTSEL_DOUBLES(
                                                         S->fit.nu, S->fit.nv, S->fit.p, S->fit.q))
                           : NULL;
        S->fpmem = fb > 0 ? malloc((size_t)fb) : NULL;
        if ((chooser && !S->srmem) || !S->fpmem)
            return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
        if ((chooser && (rc = nf_knotsel_init(&S->ks, &S->fit, o->tol, S->srmem))) ||
            (rc = nf_footprint_init(&S->fp, &S->fit, S->fpmem, (size_t)fb)))
            return cf_fail(r->msg, r->ml, rc, "check pass: %s", nf_strerror(rc));
        ck->ks = chooser ? &S->ks : NULL;
        ck->fp = &S->fp;
        if (o->robust && chooser) { /* rejected clusters: a feature still draws knots */
            S->krmem = malloc(sizeof(double) *
                              (size_t)NF_KNOTSEL_DOUBLES(S->fit.nu, S->fit.nv, S->fit.p, S->fit.q));
            S->crmem = malloc(sizeof(double) *
                              (size_t)NF_SPANRES_DOUBLES(S->fit.nu, S->fit.nv, S->fit.p, S->fit.q));
            if (!S->krmem || !S->crmem)
                return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
            if ((rc = nf_knotsel_init(&S->kr, &S->fit, o->tol, S->krmem)))
                return cf_fail(r->msg, r->ml, rc, "check pass: %s", nf_strerror(rc));
            nf_spanres_init(sr, &S->fit, o->tol, S->crmem);
            ck->kr = &S->kr;
            ck->sr = sr;
        }
    }
    if (S->st && (rc = cf_stats_init(S->st, o->stats_tol > 0 ? o->stats_tol : o->tol)))
        return cf_fail(r->msg, r->ml, rc, "statistics: %s", cf_strerror(rc));
    set_pass(r, lo, hi, npass - 1, npass);
    if ((rc = measure(r, &S->fit, ck, *c, res, S->st, 0)))
        return rc;
    if (ck->kr && cf_loop_fold_auto(ck->ks, ck->kr, ck->sr) < 0)
        return cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
    else if (!ck->kr && ck->sr)
        nf_spanres_fold(ck->sr); /* rejected misfit in one place: a feature */
    return 0;
}

/* The verdict of the knot chooser's loop after round k (auto): the knots
 * of the next round into cand (*n), the job's status and why into out; 0
 * to go on. */
static int auto_verdict(const cf_fitjob_opts_t *o, nf_loopctl_t *lc, const nf_knotsel_t *ks,
                        const nf_surf_t *fit, int k, double pct, nf_knotsel_cand_t *cand, int *n,
                        cf_fitjob_result_t *out)
{
    int kst = NF_KNOTSEL_NONE_OUT,
        mr = (int)(o->max_rounds < CF_FITJOB_MAX_ROUNDS ? o->max_rounds : CF_FITJOB_MAX_ROUNDS);
    nf_knotsel_opts_t ko;
    memset(&ko, 0, sizeof ko);
    ko.max_cp = o->max_cp;
    nf_loopctl_record(lc, pct, (long)fit->nu * fit->nv);
    ko.max_add = nf_loopctl_budget(lc, o->within, fit->nu < fit->nv ? fit->nu : fit->nv);
    ko.per_span = nf_loopctl_per_span(pct, o->within);
    *n = 0;
    nf_knotsel_choose(ks, &ko, cand, NF_KNOTSEL_CANDS(fit->nu, fit->nv, fit->p, fit->q), n, &kst);
    /* min_gain 0 means no gain is asked: the least the rules take. Near
     * the target a round cannot gain more than what is missing: the least
     * gain is at most a quarter of the gap to the best share so far. */
    double gap = o->within - (lc->best > 0 ? lc->best : 0.0);
    double mg = o->min_gain < 0.25 * gap ? o->min_gain : 0.25 * gap;
    mg = mg > 1e-12 ? mg : 1e-12;
    int v = nf_loopctl_verdict(lc, pct, o->within, mg, k, mr, kst);
    const char *rule = nf_loopctl_str(v);
    switch (v) {
    case NF_LOOPCTL_CONTINUE: return 0;
    case NF_LOOPCTL_MET:
        out->status = CF_FITJOB_MET;
        snprintf(out->why, sizeof out->why, "%s: %.3f %% within (need %g %%)", rule, pct,
                 o->within);
        return 1;
    case NF_LOOPCTL_DATA_LIMIT:
        out->status = CF_FITJOB_NOT_MET_DATA_LIMIT;
        snprintf(out->why, sizeof out->why, "%s: %s (%ld points, %d x %d net)", rule,
                 kst == NF_KNOTSEL_HALF_PTS ? "the next split would pass half the points"
                                            : "no span out of tolerance holds data to split",
                 ks->n, fit->nu, fit->nv);
        return 1;
    case NF_LOOPCTL_MAX_CP:
        out->status = CF_FITJOB_NOT_MET_MAX_CP;
        snprintf(out->why, sizeof out->why,
                 "%s: the next split would pass --max-cp %ld or the "
                 "board's %ld control points",
                 rule, o->max_cp, (long)NF_MAX_CP);
        return 1;
    case NF_LOOPCTL_NO_PROGRESS:
        out->status = CF_FITJOB_NOT_MET_NO_PROGRESS;
        snprintf(out->why, sizeof out->why,
                 "%s: %d rounds in a row gained less than %g points of share (best %.3f %%)", rule,
                 NF_LOOPCTL_PATIENCE, o->min_gain, lc->best);
        return 1;
    default: /* the round limit: the job's status has no fifth value */
        out->status = CF_FITJOB_NOT_MET_NO_PROGRESS;
        snprintf(out->why, sizeof out->why, "%s: after %d rounds (--max-rounds)", rule, k + 1);
        return 1;
    }
}

/* The job's source with each point's kept foot in front (u v x y z): a
 * pruning trial's first fit pass at the feet the last check found on the
 * fit it projects onto, without projecting again (Newton would end at
 * once where it starts). */
typedef struct feet_src {
    const cf_fitjob_t *j;
    const cf_fitsrc_t *in;
    long next;
} feet_src_t;

static int feet_rewind(void *ctx, char *msg, size_t ml)
{
    feet_src_t *f = ctx;
    f->next = 0;
    return f->in->rewind(f->in->ctx, msg, ml);
}

static long feet_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    feet_src_t *f = ctx;
    long got = f->in->read(f->in->ctx, rows, max, msg, ml);
    if (got <= 0)
        return got;
    if (f->next + got > f->j->nfeet)
        return cf_fail(msg, ml, CF_EARG, "%s: more points than feet kept", f->in->name);
    /* x y z rows widened in place from the last: row k's 5 doubles start
     * at or after row k's 3 for k >= 1, and row 0's are copied first. */
    for (long k = got - 1; k >= 0; k--) {
        const double x = rows[3 * k], y = rows[3 * k + 1], z = rows[3 * k + 2];
        const double *ft = f->j->feet + FOOT * (f->next + k);
        rows[5 * k] = ft[0], rows[5 * k + 1] = ft[1];
        rows[5 * k + 2] = x, rows[5 * k + 3] = y, rows[5 * k + 4] = z;
    }
    f->next += got;
    return got;
}

static void feet_where(void *ctx, long k, char *buf, size_t n)
{
    const feet_src_t *f = ctx;
    f->in->where(f->in->ctx, k, buf, n);
}

/* 1 when every point has a finite kept foot (the feet source serves). */
static int feet_all(const cf_fitjob_t *j, long points)
{
    if (j->nfeet != points || points <= 0)
        return 0;
    for (long i = 0; i < FOOT * j->nfeet; i++)
        if (!isfinite(j->feet[i]))
            return 0;
    return 1;
}

/* The round just measured (rd, its passes po and check ck) as the job's
 * result: its fit (moved when there is no loop), figures, footprint and
 * deviations (swapped into *best_st). */
static int keep_round(cf_fitjob_t *j, surfs_t *S, const cf_round_t *rd, const pass_t *po,
                      const check_t *ck, cf_stats_t **best_st, cf_fitjob_result_t *out)
{
    if (!j->o.loop) { /* the only round: its fit is the result, moved */
        cf_surf_free(&out->surf);
        out->surf = S->fit;
        memset(&S->fit, 0, sizeof S->fit);
    } else if (replace_copy(&out->surf, &S->fit))
        return CF_ENOMEM;
    out->within_pct = rd->within_pct;
    out->rms = rd->rms;
    out->max_abs = rd->mx;
    out->sigma = rd->sigma;
    out->outliers = rd->rejected;
    out->solve = po->fp.st;
    out->store_bytes = cf_fitpass_store_bytes(&po->fp);
    out->bytes = j->need;
    out->threads = j->used2 ? 2 : 1;
    out->pinned = po->ed.pinned;
    if (ck->fp) {
        nf_footprint_stats_t fs;
        nf_footprint_stats(ck->fp, &fs);
        out->fp_cells = fs.cells;
        out->fp_filled = fs.filled;
        out->fp_empty = fs.empty;
        out->fp_outline = fs.outline;
    }
    if (S->st) {
        cf_stats_t *t = *best_st;
        *best_st = S->st;
        S->st = t;
    }
    return 0;
}

/* The figures of the round just measured into rd. */
static void round_record(cf_round_t *rd, const surfs_t *S, const resid_t *res, double c,
                         long rejected, double t0)
{
    memset(rd, 0, sizeof *rd);
    rd->nu = S->fit.nu;
    rd->nv = S->fit.nv;
    rd->within_pct = 100.0 * (double)res->within / (double)res->n;
    rd->rms = sqrt(res->ss / (double)res->n);
    rd->mx = res->mx;
    rd->sigma = c > 0 ? S->rb.scale : 0.0;
    rd->rejected = rejected;
    rd->seconds = cli_now() - t0;
}

/* The pruning stage (auto, once met; issue 14): the loop's knot choice
 * overshoots by whole lines, so up to o->prune trials each take one knot
 * line the loop inserted out of the best fit (nf_prune_rank: the least
 * removal error per control point saved first) and fit the data afresh
 * at those knots, from the knot-removed surface (the space and P0; pass 0
 * at the best fit's feet, which the last check kept: feet_src, else by
 * projection onto the best fit). A trial
 * that still meets `within` becomes the best fit, else it is undone (the
 * feet of the best fit put back) and its knot not tried again. Only lines
 * of at least 1 / CF_FITJOB_PRUNE_MIN_LINE of the net are tried; after
 * CF_FITJOB_PRUNE_MISSES undone in a row the rest rank worse still and the
 * stage ends. Rounds k0, k0 + 1, ... */
static int prune(run_t *r, surfs_t *S, int k0, double alpha0, cf_stats_t **best_st,
                 cf_fitjob_result_t *out)
{
    cf_fitjob_t *j = r->j;
    const long trials = j->o.prune;
    nf_prune_cand_t *cand = NULL;
    double undone[2 * CF_FITJOB_MAX_ROUNDS]; /* dir, knot of the trials undone */
    int nundone = 0, misses = 0, rc = 0;
    double *feet = NULL; /* the best fit's feet while a trial overwrites them */
    for (long t = 0;
         t < trials && misses < CF_FITJOB_PRUNE_MISSES && out->nrounds < CF_FITJOB_MAX_ROUNDS;
         t++) {
        const nf_surf_t *b = &out->surf;
        int n = 0, cap = NF_PRUNE_CANDS(b->nu, b->nv, b->p, b->q);
        nf_prune_cand_t *cc = realloc(cand, sizeof *cand * (size_t)(cap > 0 ? cap : 1));
        if (!cc) {
            rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
            break;
        }
        cand = cc;
        if ((rc = nf_prune_rank(b, &j->base, cand, cap, &n))) {
            rc = cf_fail(r->msg, r->ml, rc, "pruning: %s", nf_strerror(rc));
            break;
        }
        int pick = -1;
        const long ncp = (long)b->nu * b->nv;
        for (int i = 0; i < n && pick < 0; i++) {
            if (CF_FITJOB_PRUNE_MIN_LINE * (cand[i].dir ? b->nu : b->nv) < ncp)
                continue; /* a trial costs about a round: not for a line this small */
            pick = i;
            for (int u = 0; u < nundone; u++)
                if (undone[2 * u] == cand[i].dir && undone[2 * u + 1] == cand[i].x)
                    pick = -1;
        }
        if (pick < 0)
            break; /* every line the loop inserted is needed or too small */
        const nf_prune_cand_t c = cand[pick];
        nf_surf_t cut;
        double err;
        if (cf_surf_alloc(&cut, b->p, b->q, b->nu - (c.dir == 0), b->nv - (c.dir == 1))) {
            rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
            break;
        }
        if ((rc = nf_prune_remove(b, c.dir, c.index, &cut, &err))) {
            cf_surf_free(&cut);
            rc = cf_fail(r->msg, r->ml, rc, "pruning: %s", nf_strerror(rc));
            break;
        }
        if (!S->cur_is_base)
            cf_surf_free(&S->cur);
        S->cur = cut;
        S->cur_is_base = 0;
        /* The best fit's feet, put back when the trial is undone. */
        const long nf = j->nfeet;
        if (nf > 0) {
            double *f = realloc(feet, sizeof(double) * FOOT * (size_t)nf);
            if (!f) {
                rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
                break;
            }
            feet = f;
            memcpy(feet, j->feet, sizeof(double) * FOOT * (size_t)nf);
        }
        double tr = cli_now(), cut_c = 0.0;
        resid_t res;
        pass_t po;
        long rejected = 0;
        nf_spanres_t sr;
        check_t ck;
        j->o.alpha = nf_loopctl_alpha(alpha0, &j->base, &S->cur, NF_LOOPCTL_ALPHA_K);
        S->proj0 = b;
        /* The feet as given parameters, unless far points are dropped (a
         * projection decides that). */
        feet_src_t fs = {j, r->src, 0};
        cf_fitsrc_t fsrc = {5,          r->src->total, r->src->name, feet_rewind, feet_read,
                            feet_where, &fs,           NULL,         NULL,        r->src->bound};
        S->src0 = r->src->cols == 3 && !j->o.drop_far && feet_all(j, out->points) ? &fsrc : NULL;
        rc = one_round(r, k0 + (int)t, S, &res, &po, &cut_c, &rejected, &ck, &sr, out);
        S->proj0 = NULL;
        S->src0 = NULL;
        if (rc)
            break;
        cf_round_t *rd = &out->rounds[out->nrounds++];
        round_record(rd, S, &res, cut_c, rejected, tr);
        rd->prune_dir = c.dir;
        rd->prune_knot = c.x;
        rd->prune_err = err;
        if (rd->within_pct >= j->o.within) {
            rd->prune = 1;
            out->pruned++;
            misses = 0;
            if (keep_round(j, S, rd, &po, &ck, best_st, out)) {
                rc = cf_fail(r->msg, r->ml, CF_ENOMEM, "out of memory");
                break;
            }
        } else {
            rd->prune = -1;
            misses++;
            undone[2 * nundone] = c.dir;
            undone[2 * nundone + 1] = c.x;
            nundone++;
            if (nf > 0 && j->fcap >= nf) {
                memcpy(j->feet, feet, sizeof(double) * FOOT * (size_t)nf);
                j->nfeet = nf;
            } else
                j->nfeet = 0; /* the next trial searches every foot */
        }
    }
    free(cand);
    free(feet);
    j->o.alpha = alpha0;
    if (!rc && out->pruned > 0)
        snprintf(out->why, sizeof out->why,
                 "met: %.3f %% within (need %g %%), %d knot line%s pruned", out->within_pct,
                 j->o.within, out->pruned, out->pruned > 1 ? "s" : "");
    return rc;
}

/* The held-out rows measured against the best fit (opts.holdout). */
static int holdout_check(run_t *r, const cf_fitsrc_t *in, cf_fitjob_result_t *out)
{
    cf_holdout_t hc;
    cf_fitsrc_t hs;
    cf_holdout_src(&hs, &hc, in, r->j->o.holdout, 1);
    r->src = &hs;
    r->j->nfeet = 0; /* the kept feet are the fitted rows': no starts for these */
    resid_t res;
    int rc = measure(r, &out->surf, NULL, 0.0, &res, NULL, 1); /* p99 from the histogram */
    r->src = in;
    if (rc)
        return rc;
    out->ho_points = res.n;
    out->ho_rms = res.n ? sqrt(res.ss / (double)res.n) : 0.0;
    out->ho_p99 = nf_rhist_quantile(&res.hist, 0.99);
    out->ho_max = res.mx;
    return 0;
}

int cf_fitjob_run(cf_fitjob_t *j, const cf_fitsrc_t *src, const cf_job_ctl_t *ctl, int pct0,
                  int pct1, cf_fitjob_result_t *out, char *msg, size_t ml)
{
    const cf_fitjob_opts_t *o = &j->o;
    double t0 = cli_now(), alpha0 = o->alpha;
    memset(out, 0, sizeof *out);
    if (o->holdout >= 2 && j->live)
        return cf_fail(msg, ml, CF_EARG, "--holdout needs a points source, not live points");
    if (!src && !cf_fitjob_held(j))
        return cf_fail(msg, ml, CF_EARG, "no point source, and the live points are not all held");
    /* With a holdout the rounds read only the rows kept for the fit. */
    const cf_fitsrc_t *all = src;
    cf_holdout_t hk;
    cf_fitsrc_t ks_src;
    if (o->holdout >= 2) {
        cf_holdout_src(&ks_src, &hk, src, o->holdout, 0);
        src = &ks_src;
    }
    /* A live job whose points are all held reads them, not the source:
     * no journal verified and read back (issue 19), the same points in the
     * same order, so the same fit as the journal's replay. */
    held_t hc = {j, 0};
    cf_fitsrc_t hs = {3,
                      j->nhold,
                      src ? src->name : "live points",
                      held_rewind,
                      held_read,
                      held_where,
                      &hc,
                      NULL,
                      NULL,
                      0};
    if (cf_fitjob_held(j))
        src = &hs;
    run_t r = {j, src, ctl, pct0, pct1, 0.0, 1.0, src->total, msg, ml};
    surfs_t S;
    memset(&S, 0, sizeof S);
    cf_stats_t *best_st = NULL;
    nf_knotsel_cand_t *cand = NULL;
    nf_loopctl_t lc;
    nf_loopctl_init(&lc);
    out->robust_floor =
        o->noise > CF_FITJOB_FLOOR_TOL * o->tol ? o->noise : CF_FITJOB_FLOOR_TOL * o->tol;
    if (o->stats && (!(S.st = malloc(sizeof *S.st)) || !(best_st = malloc(sizeof *best_st)))) {
        free(S.st);
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    }
    int rc = 0;
    /* Round 0 fits in the base's space from its net, which no round
     * changes: it is read in place, not copied (issue 20). No feet from
     * an earlier run of the job start its Newton. */
    j->nfeet = j->feet_base = 0;
    S.cur = j->base;
    S.cur_is_base = 1;
    /* rows: also the feet of a check pass's batch, with stats too */
    if (buffers(j, cf_fitsrc_most(src), src->cols != 5 || o->stats)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        goto fail;
    }
    if (r.ctl && r.ctl->progress)
        r.ctl->progress(r.ctl->ctx, pct0);
    out->far_limit = o->far;
    double best_within = -1.0, best_rms = 0.0, best_share = 0.0;
    double prev_ss = -1.0; /* the last round's sum of squared distances and net */
    long prev_cp = 0;
    for (int k = 0;; k++) {
        double tr = cli_now(), c = 0.0;
        resid_t res;
        pass_t po;
        long rejected = 0;
        nf_spanres_t sr;
        check_t ck;
        /* auto: alpha follows the knot spacing of each level (nf_loopctl). */
        if (o->loop && o->refine == CF_REFINE_AUTO)
            j->o.alpha = nf_loopctl_alpha(alpha0, &j->base, &S.cur, NF_LOOPCTL_ALPHA_K);
        if ((rc = one_round(&r, k, &S, &res, &po, &c, &rejected, &ck, &sr, out)))
            goto fail;
        cf_round_t *rd = &out->rounds[out->nrounds++];
        round_record(rd, &S, &res, c, rejected, tr);
        /* auto, short of the target: a round whose added control points
         * took less from the distances than noise would (nf_loopctl_supported)
         * fitted noise; it is not kept, and the loop stops (issue 14: never
         * more control points than the data support). Robust fits weigh
         * their sums otherwise: not for them. */
        const long ncp = (long)S.fit.nu * S.fit.nv;
        if (o->loop && o->refine == CF_REFINE_AUTO && !o->robust && prev_ss >= 0.0 &&
            rd->within_pct < o->within &&
            !nf_loopctl_supported(prev_ss, prev_cp, res.ss, ncp, res.n)) {
            out->status = CF_FITJOB_NOT_MET_DATA_LIMIT;
            snprintf(out->why, sizeof out->why,
                     "not_met_data_limit: round %d's %ld more control points fit noise (squared "
                     "distances %.4g -> %.4g mm^2, under %g variances of %.3g each; best %.3f %%)",
                     k, ncp - prev_cp, prev_ss, res.ss, NF_LOOPCTL_NOISE_K,
                     res.ss / (double)(res.n - ncp), best_within);
            break;
        }
        prev_ss = res.ss;
        prev_cp = ncp;
        /* Keep the best fit: most points within tolerance, then lowest rms. */
        if (rd->within_pct > best_within || (rd->within_pct == best_within && rd->rms < best_rms)) {
            if (keep_round(j, &S, rd, &po, &ck, &best_st, out)) {
                rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
                goto fail;
            }
            best_within = rd->within_pct;
            best_rms = rd->rms;
            best_share = po.points > 0 ? (double)rejected / (double)po.points : 0.0;
        }
        if (!o->loop) {
            out->status = CF_FITJOB_PLAIN;
            break;
        }
        int stop = 0, n = 0;
        if (o->refine == CF_REFINE_AUTO) {
            free(cand);
            cand = malloc(sizeof *cand *
                          (size_t)NF_KNOTSEL_CANDS(S.fit.nu, S.fit.nv, S.fit.p, S.fit.q));
            if (!cand) {
                rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
                goto fail;
            }
            if (auto_verdict(o, &lc, &S.ks, &S.fit, k, rd->within_pct, cand, &n, out))
                break;
            rc = cf_loop_insert(&S.fit, cand, n, o->max_cp, o->solver, &S.nxt, &stop, out->why,
                                sizeof out->why);
        } else {
            if ((double)res.within >= o->within / 100.0 * (double)res.n) {
                out->status = CF_FITJOB_MET;
                snprintf(out->why, sizeof out->why, "met: %.3f %% within (need %g %%)",
                         rd->within_pct, o->within);
                break;
            }
            if (k + 1 >= o->max_rounds || k + 1 >= CF_FITJOB_MAX_ROUNDS) {
                out->status = CF_FITJOB_NOT_MET_NO_PROGRESS;
                snprintf(out->why, sizeof out->why,
                         "not_met_max_rounds: after %ld rounds (--max-rounds)", o->max_rounds);
                break;
            }
            rc = cf_loop_next(&S.fit, ck.sr, o->refine, o->max_cp, o->solver, &S.nxt, &stop,
                              out->why, sizeof out->why);
            /* Never more control points than half the points. */
            if (!rc && !stop && 2 * (long)S.nxt.nu * S.nxt.nv > res.n) {
                stop = CF_LOOP_STOP_DATA;
                snprintf(out->why, sizeof out->why,
                         "the next net (%d x %d) would pass half the %ld points", S.nxt.nu,
                         S.nxt.nv, res.n);
                cf_surf_free(&S.nxt);
            }
        }
        if (rc) {
            cf_fail(msg, ml, rc, "%s", out->why);
            goto fail;
        }
        if (stop) {
            out->status =
                stop == CF_LOOP_STOP_DATA ? CF_FITJOB_NOT_MET_DATA_LIMIT : CF_FITJOB_NOT_MET_MAX_CP;
            /* The rule's name first, as auto says it ("not_met_...: why"). */
            const char *name = cf_fitjob_status_name(out->status);
            size_t nl = strlen(name) + 2, wl = strlen(out->why);
            if (wl + nl >= sizeof out->why)
                wl = sizeof out->why - nl - 1;
            memmove(out->why + nl, out->why, wl);
            out->why[nl + wl] = '\0';
            memcpy(out->why, name, nl - 2);
            out->why[nl - 2] = ':';
            out->why[nl - 1] = ' ';
            break;
        }
        if (!S.cur_is_base)
            cf_surf_free(&S.cur);
        S.cur_is_base = 0;
        S.cur = S.nxt;
        memset(&S.nxt, 0, sizeof S.nxt);
    }
    j->o.alpha = alpha0;
    /* Met with auto: knot lines the loop need not have inserted go again. */
    if (o->loop && o->refine == CF_REFINE_AUTO && out->status == CF_FITJOB_MET && o->prune > 0 &&
        (rc = prune(&r, &S, out->nrounds, alpha0, &best_st, out)))
        goto fail;
    if (out->pruned > 0) /* the result is a pruning trial's fit now */
        best_share = out->points > 0 ? (double)out->outliers / (double)out->points : 0.0;
    if (o->holdout >= 2 && (rc = holdout_check(&r, all, out)))
        goto fail;
    char *w;
    if (o->robust && best_share > NF_ROBUST_WARN_SHARE && (w = warning(out)))
        snprintf(w, sizeof out->warn[0],
                 "robust: %.1f %% of the points flagged as outliers (scale %.3g mm, floor %.3g "
                 "mm): the scale or the part may be wrong",
                 100.0 * best_share, out->sigma, out->robust_floor);
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
    free(cand);
    return 0;
fail:
    j->o.alpha = alpha0;
    surfs_free(&S);
    free(best_st);
    free(cand);
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
    cf_bigmem_free(j->mem);
    cf_bigmem_free(j->buf);
    cf_bigmem_free(j->rows);
    free(j->src);
    free(j->hold);
    free(j->feet);
    cf_surf_free(&j->base);
    free(j);
}

void cf_fitjob_result_free(cf_fitjob_result_t *r)
{
    cf_surf_free(&r->surf);
    free(r->stats);
    memset(r, 0, sizeof *r);
}
