/* cmd_fit.c: `cellfit fit`: fit the control net of a base surface's space
 * to points (Eq. 7), streaming the point file once into the stripes per
 * pass and once more for the residual summary; with --tol, the loop of
 * Section 2.2 (fit, reparameterise, insert knots until the tolerance
 * holds), with --robust, iteratively reweighted passes against outliers.
 * Memory is the job's byte formula plus buffers of the net's size (seed
 * grid, span counts, copies of the surface), whatever the number of points. */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_loop.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "cmd.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_knots.h"
#include "nf_project.h"
#include "nf_robust.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

/* Points read (and projected) at a time: a batch is the fitter's binning
 * window for random order (up to N points, nf_fit_add_rows). Fixed, and
 * touched whole when allocated, so that memory never follows the points. */
#define BATCH 65536
#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain */

/* Start points for projection: surface samples (8 per knot span and
 * direction) binned in a cell grid; host memory O(net), never O(points). */
typedef cf_seedgrid_t projector_t;

static int projector_init(projector_t *pj, const nf_surf_t *s)
{
    return cf_seedgrid_init(pj, s, 8);
}

/* What projection saw in a pass (Piegl & Tiller's parameterisation step):
 * feet clamped to the domain boundary, and points farther than the limit
 * from the surface (measured off the part, or the wrong base), which are
 * flagged and, with --drop-far, left out of the fit. */
typedef struct proj_count {
    double far;   /* limit, mm */
    int drop_far; /* 1: far points are not fitted */
    long clamped, nfar, dropped;
    long *src; /* per kept row, its index in the batch (for messages) */
} proj_count_t;

/* rows of x y z in, rows of u v x y z out (distance in *dist if asked);
 * returns the rows written: all n, less the far ones when pc drops them. */
static long project_rows(projector_t *pj, const double *xyz, long n, double *uvxyz, double *dist,
                         proj_count_t *pc)
{
    long m = 0;
    for (long k = 0; k < n; k++) {
        const double *Q = xyz + 3 * k;
        nf_proj_t pr;
        cf_seedgrid_project(pj, Q, PROJ_TOL, &pr); /* best point kept on ENOCONV */
        if (pc) {
            pc->clamped += pr.clamped != 0;
            if (fabs(pr.dist) > pc->far) {
                pc->nfar++;
                if (pc->drop_far) {
                    pc->dropped++;
                    continue;
                }
            }
            pc->src[m] = k;
        }
        double *r = uvxyz + 5 * m;
        if (dist)
            dist[m] = pr.dist;
        m++;
        r[0] = pr.u;
        r[1] = pr.v;
        r[2] = Q[0];
        r[3] = Q[1];
        r[4] = Q[2];
    }
    return m;
}

#define MAX_ROUNDS 64

typedef struct fit_opts {
    const char *base, *points, *out;
    int uv, json;
    long entity, reparam;
    double alpha, beta, tol;
    long max_iter;
    nf_solver_t solver;
    double dtol, within; /* --tol (mm, 0: no loop) and --within (percent) */
    double far;          /* --far: distance limit of projected points, mm (0: 5 % of the part) */
    int drop_far;        /* --drop-far */
    long max_cp, max_rounds;
    cf_refine_t refine;
    int robust;
    long robust_iters;
} fit_opts_t;

static int parse(int argc, char **argv, fit_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->tol = 1e-12;
    o->max_iter = 20000;
    o->solver = NF_SOLVER_AUTO;
    o->within = 100.0;
    o->max_cp = NF_MAX_CP;
    o->max_rounds = 12;
    o->refine = CF_REFINE_RESIDUAL;
    o->robust_iters = 3;
    int loop_opt = 0;
    for (int i = 1; i < argc;) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int takes = 1;
        if (!strcmp(a, "--uv"))
            o->uv = 1, takes = 0;
        else if (!strcmp(a, "--json"))
            o->json = 1, takes = 0;
        else if (!strcmp(a, "--robust"))
            o->robust = 1, takes = 0;
        else if (!strcmp(a, "--drop-far"))
            o->drop_far = 1, takes = 0;
        else if (!v)
            return cli_error("fit", CLI_USAGE, "option %s needs a value", a);
        else if (!strcmp(a, "--base"))
            o->base = v;
        else if (!strcmp(a, "--points"))
            o->points = v;
        else if (!strcmp(a, "--out"))
            o->out = v;
        else if (!strcmp(a, "--alpha")) {
            if (cli_double(v, &o->alpha) || o->alpha < 0)
                return cli_error("fit", CLI_USAGE, "--alpha '%s': need a number >= 0", v);
        } else if (!strcmp(a, "--beta")) {
            if (cli_double(v, &o->beta) || o->beta < 0)
                return cli_error("fit", CLI_USAGE, "--beta '%s': need a number >= 0", v);
        } else if (!strcmp(a, "--solve-tol")) {
            if (cli_double(v, &o->tol) || !(o->tol > 0) || o->tol >= 1)
                return cli_error("fit", CLI_USAGE, "--solve-tol '%s': need 0 < tol < 1", v);
        } else if (!strcmp(a, "--max-iter")) {
            if (cli_int(v, 1, 100000000, &o->max_iter))
                return cli_error("fit", CLI_USAGE, "--max-iter '%s': need 1..1e8", v);
        } else if (!strcmp(a, "--reparam")) {
            if (cli_int(v, 0, 100, &o->reparam))
                return cli_error("fit", CLI_USAGE, "--reparam '%s': need 0..100", v);
        } else if (!strcmp(a, "--tol")) {
            if (cli_double(v, &o->dtol) || !(o->dtol > 0))
                return cli_error("fit", CLI_USAGE, "--tol '%s': need a distance > 0 (mm)", v);
        } else if (!strcmp(a, "--far")) {
            if (cli_double(v, &o->far) || !(o->far > 0))
                return cli_error("fit", CLI_USAGE, "--far '%s': need a distance > 0 (mm)", v);
        } else if (!strcmp(a, "--within")) {
            if (cli_double(v, &o->within) || !(o->within > 0) || o->within > 100)
                return cli_error("fit", CLI_USAGE, "--within '%s': need a percentage in (0, 100]",
                                 v);
            loop_opt = 1;
        } else if (!strcmp(a, "--max-cp")) {
            if (cli_int(v, 4, NF_MAX_CP, &o->max_cp))
                return cli_error("fit", CLI_USAGE, "--max-cp '%s': need 4..%ld (board %s)", v,
                                 (long)NF_MAX_CP, BOARD_NAME);
            loop_opt = 1;
        } else if (!strcmp(a, "--max-rounds")) {
            if (cli_int(v, 1, MAX_ROUNDS, &o->max_rounds))
                return cli_error("fit", CLI_USAGE, "--max-rounds '%s': need 1..%d", v, MAX_ROUNDS);
            loop_opt = 1;
        } else if (!strcmp(a, "--refine")) {
            if (!strcmp(v, "uniform"))
                o->refine = CF_REFINE_UNIFORM;
            else if (!strcmp(v, "residual"))
                o->refine = CF_REFINE_RESIDUAL;
            else
                return cli_error("fit", CLI_USAGE, "--refine '%s': uniform or residual", v);
            loop_opt = 1;
        } else if (!strcmp(a, "--robust-iters")) {
            if (cli_int(v, 1, 100, &o->robust_iters))
                return cli_error("fit", CLI_USAGE, "--robust-iters '%s': need 1..100", v);
            o->robust = 1;
        } else if (!strcmp(a, "--entity")) {
            if (cli_int(v, 1, 9999999, &o->entity))
                return cli_error("fit", CLI_USAGE, "--entity '%s': need a DE number", v);
        } else if (!strcmp(a, "--solver")) {
            if (cli_solver(v, &o->solver))
                return cli_error("fit", CLI_USAGE, "--solver '%s': auto, gs, chol or pcg", v);
        } else
            return cli_error("fit", CLI_USAGE, "unknown option '%s'", a);
        i += 1 + takes;
    }
    if (!o->base || !o->points || !o->out)
        return cli_error("fit", CLI_USAGE, "need --base BASE.igs --points FILE --out OUT.igs");
    if (o->uv && (o->far > 0 || o->drop_far))
        return cli_error("fit", CLI_USAGE,
                         "--far and --drop-far apply to projected points: "
                         "not with --uv");
    if (o->uv && o->reparam)
        return cli_error("fit", CLI_USAGE, "--reparam projects x y z points: not with --uv");
    if (loop_opt && !(o->dtol > 0))
        return cli_error("fit", CLI_USAGE,
                         "--within, --max-cp, --max-rounds and --refine need --tol T");
    return CLI_OK;
}

/* Line number of point index k (0-based) of a rewindable file, for messages. */
static long line_of_point(cf_points_t *r, long k)
{
    double row[5];
    char msg[16];
    if (cf_points_rewind(r))
        return -1;
    for (long i = 0; i <= k; i++)
        if (cf_points_read(r, row, 1, msg, sizeof msg) != 1)
            return -1;
    return cf_points_line(r);
}

/* points: the file the data came from, named by the refusals it causes. */
static int fit_error(int rc, const nf_fit_t *f, const nf_surf_t *s, const char *points)
{
    long b = f->bad_index;
    int i = b >= 0 ? (int)(b % s->nu) : -1, j = b >= 0 ? (int)(b / s->nu) : -1;
    switch (rc) {
    case NF_ENODATA:
        return cli_error("fit", CLI_USAGE,
                         "%s: control point (%d, %d) has no data under it and alpha = beta = 0: "
                         "the points do not determine the surface (measure there, or give --beta)",
                         points, i, j);
    case NF_ESINGULAR:
        return cli_error("fit", CLI_USAGE,
                         "%s: the points do not determine the surface: control point (%d, %d) is "
                         "left free (numerically rank-deficient normal equations; give "
                         "--alpha/--beta > 0 or more data there)",
                         points, i, j);
    case NF_ENOCONV:
        return cli_error("fit", CLI_FAIL, "%s; try --solver chol or more --max-iter",
                         nf_strerror(rc));
    case NF_EBUDGET:
        return cli_error("fit", CLI_USAGE,
                         "job needs %ld bytes, board %s allows %ld: %s (use fewer control "
                         "points or another solver)",
                         f->need_bytes, BOARD_NAME, (long)NF_ARENA_BYTES, nf_strerror(rc));
    default: return cli_error("fit", CLI_FAIL, "%s", nf_strerror(rc));
    }
}

typedef struct resid {
    double ss, mx;
    long n, within;  /* points, and those with |d| <= --tol */
    long outliers;   /* points with |d| >= the robust cut-off (not counted in spans) */
    nf_rhist_t hist; /* |d| for the robust scale */
} resid_t;

/* Distance of row q (u v x y z) to s at its parameters. */
static double dist_at(const nf_surf_t *s, const double *q)
{
    double P[3];
    nf_surf_eval(s, q[0], q[1], P);
    return sqrt((q[2] - P[0]) * (q[2] - P[0]) + (q[3] - P[1]) * (q[3] - P[1]) +
                (q[4] - P[2]) * (q[4] - P[2]));
}

/* A pass over the points against the fit s: |Q - S(u, v)| at the given
 * parameters with --uv, else the normal distance to s (projection). Sums
 * for the summary, the count within tol (if > 0), the |d| histogram, and
 * (if sr) the excess per knot span of the points out of tolerance; those
 * beyond cut (> 0: points a robust fit rejects) go to their cells only. */
static int measure(cf_points_t *r, const nf_surf_t *s, projector_t *pj, double tol,
                   nf_spanres_t *sr, double cut, double *buf, double *rows, resid_t *out, char *msg,
                   size_t ml)
{
    memset(out, 0, sizeof *out);
    nf_rhist_init(&out->hist);
    if (cf_points_rewind(r))
        return cli_error("fit", CLI_FAIL, "cannot re-read the points for the summary");
    long got;
    while ((got = cf_points_read(r, buf, BATCH, msg, ml)) > 0) {
        const double *uv = buf;
        if (pj) {
            project_rows(pj, buf, got, rows, NULL, NULL);
            uv = rows;
        }
        for (long k = 0; k < got; k++) {
            const double *q = uv + 5 * k;
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
        }
    }
    if (got < 0)
        return cli_error("fit", CLI_USAGE, "%s", msg);
    return CLI_OK;
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

/* Peak resident set of this process (getrusage reports KiB on Linux). */
static long peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru))
        return -1;
    return ru.ru_maxrss * 1024L;
}

typedef struct pass_out {
    long points;
    long rejected;              /* robust passes: points given weight 0 */
    long clamped, far, dropped; /* projection: feet on the boundary, points beyond --far */
    nf_solve_stats_t st;
    double t_acc, t_solve;
} pass_out_t;

/* Robust reweighting of a pass: Tukey weights of the residuals to the
 * previous fit prev, cut off at c = NF_TUKEY_C sigma (sigma from the MAD). */
typedef struct weigh {
    double c;
    const nf_surf_t *prev;
} weigh_t;

/* One fit: stream the points (parameters given, or by projection onto
 * proj_onto) into a fresh job on base's space, solve, leave P in out->cp.
 * With wt, each point's weight is nf_tukey of its distance to wt->prev
 * (proj_onto when projecting); points of weight 0 are left out. */
static int fit_pass(const fit_opts_t *o, const nf_surf_t *base, const nf_surf_t *proj_onto,
                    const weigh_t *wt, cf_points_t *pr, void *mem, long need, double *buf,
                    double *rows, long *src, nf_surf_t *out, pass_out_t *po)
{
    char msg[512];
    nf_arena_t ar;
    nf_fit_t f;
    projector_t pj;
    memset(&pj, 0, sizeof pj);
    int ec = CLI_OK;
    double t0 = cli_now();
    memset(po, 0, sizeof *po);
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_params_t prm = {o->alpha, o->beta, o->solver};
    int rc = nf_fit_init(&f, base, &prm, &ar);
    if (rc)
        return fit_error(rc, &f, base, o->points);
    if (proj_onto && projector_init(&pj, proj_onto))
        return cli_error("fit", CLI_FAIL, "out of memory");
    if (cf_points_rewind(pr)) {
        cf_seedgrid_free(&pj);
        return cli_error("fit", CLI_USAGE, "%s: cannot read the points again", o->points);
    }
    long got;
    proj_count_t pc = {o->far, o->drop_far, 0, 0, 0, src};
    while ((got = cf_points_read(pr, buf, BATCH, msg, sizeof msg)) > 0) {
        long bad = -1, n = got;
        const double *uv = buf;
        if (proj_onto) {
            n = project_rows(&pj, buf, got, rows, NULL, &pc);
            uv = rows;
        }
        if (!wt)
            rc = nf_fit_add_rows(&f, uv, n, &bad);
        else
            for (long k = 0; k < n && !rc; k++) {
                const double *q = uv + 5 * k;
                double w = nf_tukey(dist_at(wt->prev, q), wt->c);
                if (w > 0)
                    rc = nf_fit_add(&f, q[0], q[1], q + 2, w);
                else
                    po->rejected++;
                bad = k;
            }
        if (rc) {
            const double *q = uv + 5 * bad;
            long line = line_of_point(pr, po->points + (proj_onto ? src[bad] : bad));
            double u0, u1, v0, v1;
            nf_surf_domain(base, &u0, &u1, &v0, &v1);
            if (rc == NF_EDOMAIN)
                ec = cli_error("fit", CLI_USAGE,
                               "%s:%ld: parameters (%.17g, %.17g) outside the knot domain "
                               "[%.17g, %.17g] x [%.17g, %.17g] of %s",
                               o->points, line, q[0], q[1], u0, u1, v0, v1, o->base);
            else
                ec = cli_error("fit", CLI_USAGE, "%s:%ld: %s", o->points, line, nf_strerror(rc));
            cf_seedgrid_free(&pj);
            return ec;
        }
        po->points += got;
    }
    cf_seedgrid_free(&pj);
    po->clamped = pc.clamped;
    po->far = pc.nfar;
    po->dropped = pc.dropped;
    if (got < 0)
        return cli_error("fit", CLI_USAGE, "%s", msg);
    if (po->points == 0)
        return cli_error("fit", CLI_USAGE, "%s: no points", o->points);
    if (po->dropped == po->points)
        return cli_error("fit", CLI_USAGE,
                         "%s: all %ld points are farther than %g mm from %s (--far): wrong base?",
                         o->points, po->points, o->far, o->base);
    double t1 = cli_now();
    rc = nf_fit_finish(&f);
    nf_solve_opts_t so = {o->tol, (int)o->max_iter, 1};
    if (!rc)
        rc = nf_fit_solve(&f, o->solver, &so, &po->st);
    if (rc)
        return fit_error(rc, &f, base, o->points);
    memcpy(out->cp, f.P, sizeof(double) * (size_t)(3 * f.n));
    po->t_acc = t1 - t0;
    po->t_solve = cli_now() - t1;
    return CLI_OK;
}

static int replace_copy(nf_surf_t *dst, const nf_surf_t *src)
{
    cf_surf_free(dst);
    return cf_surf_copy(dst, src);
}

int cmd_fit(int argc, char **argv)
{
    fit_opts_t o;
    int rc = parse(argc, argv, &o);
    if (rc)
        return rc;
    char msg[512], why[256] = "";
    double t0 = cli_now();
    nf_surf_t base, cur, fit, prev, best, nxt;
    memset(&cur, 0, sizeof cur);
    memset(&fit, 0, sizeof fit);
    memset(&prev, 0, sizeof prev);
    memset(&best, 0, sizeof best);
    memset(&nxt, 0, sizeof nxt);
    rc = cf_iges_read(o.base, (int)o.entity, &base, msg, sizeof msg);
    if (rc)
        return cli_error("fit", CLI_USAGE, "%s", msg);
    if (!(o.far > 0)) /* default: 5 % of the diagonal of the base's control net */
        o.far = 0.05 * net_diagonal(&base);

    long need = nf_fit_bytes(base.nu, base.nv, base.p, base.q, o.solver);
    nf_solver_t used =
        o.solver == NF_SOLVER_AUTO ? nf_solver_pick(base.nu, base.nv, base.p, base.q) : o.solver;
    if (need < 0 || need > NF_ARENA_BYTES) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE,
                         "%s: a %d x %d net of degree %d x %d with solver %s needs %ld bytes; "
                         "board %s allows %ld: job refused",
                         o.base, base.nu, base.nv, base.p, base.q, nf_solver_name(used), need,
                         BOARD_NAME, (long)NF_ARENA_BYTES);
    }
    if (o.dtol > 0 && (long)base.nu * base.nv > o.max_cp) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE, "%s: the base net has %ld control points, --max-cp %ld",
                         o.base, (long)base.nu * base.nv, o.max_cp);
    }
    cf_points_t *pr = NULL;
    rc = cf_points_open(&pr, o.points, o.uv ? 5 : 3, msg, sizeof msg);
    if (rc) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE, "%s", msg);
    }
    void *mem = NULL;
    double *buf = malloc(sizeof(double) * 5 * BATCH), *rows = malloc(sizeof(double) * 5 * BATCH);
    long *src = malloc(sizeof(long) * BATCH); /* projected rows' input index */
    double *srmem = NULL;
    int ec = CLI_OK, met = 0, nr = 0;
    cf_round_t rounds[MAX_ROUNDS];
    pass_out_t po = {0, 0, 0, 0, 0, {NF_SOLVER_AUTO, 0, 0.0}, 0.0, 0.0};
    double t_acc = 0.0, t_solve = 0.0, best_within = -1.0, best_rms = 0.0, c = 0.0;
    resid_t res, best_res;
    nf_solve_stats_t best_st = po.st;
    long rejected = 0, best_need = need;
    if (!buf || !rows || !src || cf_surf_copy(&cur, &base)) {
        ec = cli_error("fit", CLI_FAIL, "out of memory");
        goto done;
    }
    memset(buf, 0, sizeof(double) * 5 * BATCH); /* resident now, whatever the points */
    memset(rows, 0, sizeof(double) * 5 * BATCH);
    memset(src, 0, sizeof(long) * BATCH);
    /* Round r fits in the space of cur with P0 = cur's net: the base first,
     * then the previous fit refined (Section 2.2). */
    for (int round = 0;; round++) {
        double tr = cli_now();
        need = nf_fit_bytes(cur.nu, cur.nv, cur.p, cur.q, o.solver);
        free(mem);
        mem = malloc((size_t)need);
        if (!mem || replace_copy(&fit, &cur) || replace_copy(&prev, &cur)) {
            ec = cli_error("fit", CLI_FAIL, "cannot allocate %ld bytes", need);
            goto done;
        }
        /* Pass 0 takes parameters from the file or from projection onto
         * cur; each --reparam pass projects onto the previous fit and
         * refits in the same space with the same nominal P0. */
        for (long pass = 0; pass <= o.reparam; pass++) {
            ec = fit_pass(&o, &cur, o.uv ? NULL : &prev, NULL, pr, mem, need, buf, rows, src, &fit,
                          &po);
            if (ec)
                goto done;
            t_acc += po.t_acc;
            t_solve += po.t_solve;
            memcpy(prev.cp, fit.cp, sizeof(double) * 3 * (size_t)cur.nu * (size_t)cur.nv);
        }
        /* Robust passes: the MAD of the residuals to the last fit sets the
         * scale, Tukey weights of those residuals the next fit. */
        c = 0.0;
        rejected = 0;
        for (long it = 0; o.robust && it < o.robust_iters; it++) {
            projector_t pj;
            memset(&pj, 0, sizeof pj);
            if (!o.uv && projector_init(&pj, &prev)) {
                ec = cli_error("fit", CLI_FAIL, "out of memory");
                goto done;
            }
            ec = measure(pr, &prev, o.uv ? NULL : &pj, 0.0, NULL, 0.0, buf, rows, &res, msg,
                         sizeof msg);
            cf_seedgrid_free(&pj);
            if (ec)
                goto done;
            c = NF_TUKEY_C * nf_rhist_sigma(&res.hist);
            if (!(c > 0))
                break; /* the fit is exact: nothing to reweight */
            weigh_t wt = {c, &prev};
            ec = fit_pass(&o, &cur, o.uv ? NULL : &prev, &wt, pr, mem, need, buf, rows, src, &fit,
                          &po);
            if (ec)
                goto done;
            rejected = po.rejected;
            t_acc += po.t_acc;
            t_solve += po.t_solve;
            memcpy(prev.cp, fit.cp, sizeof(double) * 3 * (size_t)cur.nu * (size_t)cur.nv);
        }
        /* The check: distances of all points to this fit, and where they
         * are out of tolerance (per knot span). */
        nf_spanres_t sr, *srp = NULL;
        free(srmem);
        srmem = NULL;
        if (o.dtol > 0 && o.refine == CF_REFINE_RESIDUAL) {
            srmem =
                malloc(sizeof(double) * (size_t)NF_SPANRES_DOUBLES(fit.nu, fit.nv, fit.p, fit.q));
            if (!srmem) {
                ec = cli_error("fit", CLI_FAIL, "out of memory");
                goto done;
            }
            nf_spanres_init(&sr, &fit, o.dtol, srmem);
            srp = &sr;
        }
        projector_t pj;
        memset(&pj, 0, sizeof pj);
        if (!o.uv && projector_init(&pj, &fit)) {
            ec = cli_error("fit", CLI_FAIL, "out of memory");
            goto done;
        }
        ec = measure(pr, &fit, o.uv ? NULL : &pj, o.dtol, srp, c, buf, rows, &res, msg, sizeof msg);
        cf_seedgrid_free(&pj);
        if (ec)
            goto done;
        if (srp)
            nf_spanres_fold(srp); /* rejected misfit in one place: a feature */
        cf_round_t *rd = &rounds[nr++];
        rd->nu = fit.nu;
        rd->nv = fit.nv;
        rd->within_pct = 100.0 * (double)res.within / (double)res.n;
        rd->rms = sqrt(res.ss / (double)res.n);
        rd->mx = res.mx;
        rd->sigma = c / NF_TUKEY_C;
        rd->rejected = rejected;
        rd->seconds = cli_now() - tr;
        if (o.dtol > 0 && !o.json)
            cf_round_print(stdout, round, rd, o.dtol, o.robust);
        /* Keep the best fit: most points within tolerance, then lowest rms. */
        if (rd->within_pct > best_within || (rd->within_pct == best_within && rd->rms < best_rms)) {
            if (replace_copy(&best, &fit)) {
                ec = cli_error("fit", CLI_FAIL, "out of memory");
                goto done;
            }
            best_within = rd->within_pct;
            best_rms = rd->rms;
            best_res = res;
            best_st = po.st;
            best_need = need;
        }
        if (!(o.dtol > 0))
            break;
        if ((double)res.within >= o.within / 100.0 * (double)res.n) {
            met = 1;
            break;
        }
        if (round + 1 >= o.max_rounds) {
            snprintf(why, sizeof why, "after %ld rounds (--max-rounds)", o.max_rounds);
            break;
        }
        int stop = 0;
        rc = cf_loop_next(&fit, srp, o.refine, o.max_cp, o.solver, &nxt, &stop, why, sizeof why);
        if (rc) {
            ec = cli_error("fit", CLI_FAIL, "%s", why);
            goto done;
        }
        if (stop)
            break;
        cf_surf_free(&cur);
        cur = nxt;
        memset(&nxt, 0, sizeof nxt);
    }
    double t2 = cli_now();
    rc = cf_iges_write(o.out, &best, "cellfit fit", msg, sizeof msg);
    if (rc) {
        ec = cli_error("fit", CLI_FAIL, "%s", msg);
        goto done;
    }
    double t3 = cli_now();
    res = best_res;
    double rms = sqrt(res.ss / (double)res.n);
    long ncp = (long)best.nu * best.nv;
    if (o.json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_int(&j, "points", po.points);
        cf_json_int(&j, "control_points", ncp);
        cf_json_int(&j, "nu", best.nu);
        cf_json_int(&j, "nv", best.nv);
        cf_json_int(&j, "p", best.p);
        cf_json_int(&j, "q", best.q);
        cf_json_num(&j, "alpha", o.alpha);
        cf_json_num(&j, "beta", o.beta);
        cf_json_str(&j, "parameters", o.uv ? "given" : "projected");
        cf_json_int(&j, "reparam", o.reparam);
        if (!o.uv) {
            cf_json_int(&j, "clamped", po.clamped);
            cf_json_num(&j, "far_limit", o.far);
            cf_json_int(&j, "far", po.far);
            cf_json_int(&j, "dropped", po.dropped);
        }
        cf_json_str(&j, "solver", nf_solver_name(best_st.solver));
        cf_json_int(&j, "iterations", best_st.iterations);
        cf_json_num(&j, "rel_residual", best_st.rel_residual);
        cf_json_num(&j, "rms", rms);
        cf_json_num(&j, "max_abs", res.mx);
        if (o.dtol > 0) {
            cf_json_num(&j, "tol", o.dtol);
            cf_json_num(&j, "within", o.within);
            cf_json_num(&j, "within_tol_pct", best_within);
            cf_json_bool(&j, "tol_met", met);
            cf_json_str(&j, "refine", o.refine == CF_REFINE_UNIFORM ? "uniform" : "residual");
            if (!met)
                cf_json_str(&j, "stopped", why);
            cf_rounds_json(&j, rounds, nr, o.robust);
        }
        if (o.robust) {
            cf_json_int(&j, "robust_iters", o.robust_iters);
            cf_json_num(&j, "robust_sigma", rounds[nr - 1].sigma);
            cf_json_int(&j, "outliers", rounds[nr - 1].rejected);
        }
        cf_json_num(&j, "seconds", t3 - t0);
        cf_json_num(&j, "accumulate_seconds", t_acc);
        cf_json_num(&j, "solve_seconds", t_solve);
        cf_json_int(&j, "bytes", best_need);
        cf_json_int(&j, "peak_rss_bytes", peak_rss());
        cf_json_str(&j, "board", BOARD_NAME);
        cf_json_str(&j, "out", o.out);
        cf_json_end(&j);
    } else {
        printf("cellfit fit: %ld points, %ld control points (%d x %d, degree %d x %d)\n", po.points,
               ncp, best.nu, best.nv, best.p, best.q);
        printf("  parameters %s", o.uv ? "given (--uv)" : "by projection onto the base");
        if (o.reparam)
            printf(", then %ld reparameterisation pass%s", o.reparam, o.reparam > 1 ? "es" : "");
        if (!o.uv)
            printf("\n  projection: %ld feet clamped to the boundary, %ld points farther than "
                   "%g mm (%s)",
                   po.clamped, po.far, o.far,
                   o.drop_far ? "dropped" : "kept; --drop-far drops them");
        printf("\n  alpha %g  beta %g  solver %s  iterations %d  relative residual %.2e\n", o.alpha,
               o.beta, nf_solver_name(best_st.solver), best_st.iterations, best_st.rel_residual);
        if (o.robust)
            printf("  robust: %ld Tukey passes, sigma %.3g mm, %ld points rejected as outliers\n",
                   o.robust_iters, rounds[nr - 1].sigma, rounds[nr - 1].rejected);
        printf("  rms %.6g  max %.6g  (%s)\n", rms, res.mx,
               o.uv ? "|Q - S(u,v)| at the given parameters" : "normal distance to the fit");
        if (o.dtol > 0)
            printf("  tolerance %g mm: %.3f %% of the points within (need %g %%): %s\n", o.dtol,
                   best_within, o.within, met ? "met" : "NOT met");
        printf("  %.3f s (read + accumulate %.3f, solve %.3f, summary + write %.3f)\n", t3 - t0,
               t_acc, t_solve, t3 - t2);
        printf("  %ld bytes of fitter memory (board %s allows %ld)\n", best_need, BOARD_NAME,
               (long)NF_ARENA_BYTES);
        printf("  wrote %s\n", o.out);
    }
    /* The best surface is written either way; a tolerance not met is a
     * failure of the work (exit 1), said in one line. */
    if (o.dtol > 0 && !met)
        ec = cli_error("fit", CLI_FAIL,
                       "tolerance %g mm not met: %.3f %% of the points within, need %g %%; "
                       "stopped: %s; wrote the best fit (%d x %d) to %s",
                       o.dtol, best_within, o.within, why, best.nu, best.nv, o.out);
done:
    cf_points_close(pr);
    free(buf);
    free(rows);
    free(src);
    free(mem);
    free(srmem);
    cf_surf_free(&prev);
    cf_surf_free(&fit);
    cf_surf_free(&cur);
    cf_surf_free(&best);
    cf_surf_free(&nxt);
    cf_surf_free(&base);
    return ec;
}
