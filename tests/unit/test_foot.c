/* SPDX-License-Identifier: MIT */
/* test_foot.c: the true foot (issue 14): projection onto a thin, strongly
 * twisted strip and onto a plate folded back over itself near an edge, 10^4
 * random points within 3 mm of each, against an independent brute force
 * (a dense parameter grid, every local minimum of it near the best refined
 * by a shrinking pattern search). Every foot's distance must equal the
 * brute-force minimum, and no point may get a boundary foot where an
 * interior foot is nearer. */

#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_quad.h"
#include "nf_refine.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include "ref_job.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define TOL 1e-9
#define NPTS 10000
#define REACH 3.0 /* mm: how far points lie from the surface */

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist3(const double *a, const double *b)
{
    const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot3(d, d));
}

/* Clamped uniform knots of degree p for n + 1 control points on [0, 1]. */
static void uniform_knots(double *K, int n, int p)
{
    for (int i = 0; i <= n + p + 1; i++) {
        const int k = i - p;
        K[i] = k <= 0 ? 0.0 : (i > n ? 1.0 : (double)k / (n - p + 1));
    }
}

/* Greville abscissa of control point i (knot average). */
static double greville(const double *K, int i, int p)
{
    double g = 0.0;
    for (int k = 1; k <= p; k++)
        g += K[i + k];
    return g / p;
}

static double *surf_new(nf_surf_t *s, int nu, int nv)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, 3, 3), sizeof(double));
    assert_non_null(mem);
    nf_surf_wire(s, 3, 3, nu, nv, mem);
    uniform_knots(s->U, nu - 1, 3);
    uniform_knots(s->V, nv - 1, 3);
    s->w = NULL;
    return mem;
}

/* A strip 100 x 5 mm, its cross-section turned by 90 degrees from one end
 * to the other (a helicoid's piece): P = (x, w cos t, w sin t). */
static double *make_twisted(nf_surf_t *s)
{
    const int nu = 12, nv = 4;
    double *mem = surf_new(s, nu, nv);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double a = greville(s->U, i, 3), b = greville(s->V, j, 3);
            const double t = 0.5 * 3.14159265358979323846 * a, w = 5.0 * (b - 0.5);
            double *P = s->cp + 3 * (i + j * nu);
            P[0] = 100.0 * a;
            P[1] = w * cos(t);
            P[2] = w * sin(t);
        }
    return mem;
}

/* A plate 60 x 26 mm whose edge v = 1 is folded back over it (a hem): the
 * cross-section runs along y, turns up and round at y ~ 27 and returns
 * 4 mm above the plate to end at y = 16. */
static double *make_folded(nf_surf_t *s)
{
    static const double yz[][2] = {{0, 0},  {8, 0},  {16, 0}, {22, 0},  {27, 0},
                                   {29, 2}, {27, 4}, {22, 4}, {16, 4.2}};
    const int nu = 6, nv = (int)(sizeof yz / sizeof yz[0]);
    double *mem = surf_new(s, nu, nv);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double a = greville(s->U, i, 3);
            double *P = s->cp + 3 * (i + j * nu);
            P[0] = 60.0 * a;
            P[1] = yz[j][0] + 0.5 * sin(3.0 * a); /* not quite a cylinder */
            P[2] = yz[j][1];
        }
    return mem;
}

/* ---- brute force, independent of nf_project ---- */

/* Samples per side of a block: each block keeps a bounding sphere of its
 * samples, so that a block provably too far is skipped unread (the search
 * stays exhaustive: a skipped block holds no sample within the band). */
#define BLK 8

typedef struct brute {
    const nf_surf_t *s;
    int nu, nv;
    double *P;
    double h;   /* longest chord between neighbouring samples */
    int bu, bv; /* blocks */
    double *bc; /* per block: centre x y z and radius */
} brute_t;

static void brute_init(brute_t *b, const nf_surf_t *s, int nu, int nv)
{
    b->s = s;
    b->nu = nu;
    b->nv = nv;
    b->P = malloc(sizeof(double) * 3 * (size_t)nu * (size_t)nv);
    assert_non_null(b->P);
    b->h = 0.0;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double *P = b->P + 3 * (i + (long)j * nu);
            nf_surf_eval(s, (double)i / (nu - 1), (double)j / (nv - 1), P);
            if (i > 0)
                b->h = fmax(b->h, dist3(P, P - 3));
            if (j > 0)
                b->h = fmax(b->h, dist3(P, P - 3 * nu));
        }
    b->bu = (nu + BLK - 1) / BLK;
    b->bv = (nv + BLK - 1) / BLK;
    b->bc = malloc(sizeof(double) * 4 * (size_t)b->bu * (size_t)b->bv);
    assert_non_null(b->bc);
    for (int bj = 0; bj < b->bv; bj++)
        for (int bi = 0; bi < b->bu; bi++) {
            double *c = b->bc + 4 * (bi + (long)bj * b->bu);
            const int ci = bi * BLK + BLK / 2 < nu ? bi * BLK + BLK / 2 : nu - 1;
            const int cj = bj * BLK + BLK / 2 < nv ? bj * BLK + BLK / 2 : nv - 1;
            for (int k = 0; k < 3; k++)
                c[k] = b->P[3 * (ci + (long)cj * nu) + k];
            c[3] = 0.0;
            for (int j = bj * BLK; j < bj * BLK + BLK && j < nv; j++)
                for (int i = bi * BLK; i < bi * BLK + BLK && i < nu; i++)
                    c[3] = fmax(c[3], dist3(c, b->P + 3 * (i + (long)j * nu)));
        }
}

/* Pattern search from (u, v): a 5 x 5 pattern over a window of 2 sample
 * spacings, recentred on its best and halved, until the window is far
 * below rounding of the parameters. */
static double zoom(const brute_t *b, const double Q[3], double *u, double *v)
{
    double P[3];
    nf_surf_eval(b->s, *u, *v, P);
    double best = dist3(P, Q), hu = 2.0 / (b->nu - 1), hv = 2.0 / (b->nv - 1);
    for (int round = 0; round < 52; round++) {
        const double cu = *u, cv = *v;
        for (int j = -2; j <= 2; j++)
            for (int i = -2; i <= 2; i++) {
                const double tu = fmin(fmax(cu + hu * i / 2.0, 0.0), 1.0);
                const double tv = fmin(fmax(cv + hv * j / 2.0, 0.0), 1.0);
                nf_surf_eval(b->s, tu, tv, P);
                const double d = dist3(P, Q);
                if (d < best) {
                    best = d;
                    *u = tu;
                    *v = tv;
                }
            }
        hu *= 0.5;
        hv *= 0.5;
    }
    return best;
}

/* The nearest point: every grid sample that is a local minimum of the
 * distance over its 8 neighbours and within 2 h of the nearest sample (a
 * valley holding the true minimum has a sample that near) is refined; the
 * best refined distance, its parameters, and the best refined distance of
 * an interior foot (parameters off the bounds) in *dint. */
static double brute(const brute_t *b, const double Q[3], double *ub, double *vb, double *dint)
{
    /* The nearest sample: an upper bound from the blocks' spheres first,
     * then every sample of every block that can hold a nearer one. */
    const long nb = (long)b->bu * b->bv;
    double up = INFINITY;
    for (long k = 0; k < nb; k++)
        up = fmin(up, dist3(b->bc + 4 * k, Q) + b->bc[4 * k + 3]);
    double dmin2 = INFINITY;
    for (long k = 0; k < nb; k++) {
        if (dist3(b->bc + 4 * k, Q) - b->bc[4 * k + 3] > up)
            continue;
        const int bi = (int)(k % b->bu), bj = (int)(k / b->bu);
        for (int j = bj * BLK; j < bj * BLK + BLK && j < b->nv; j++)
            for (int i = bi * BLK; i < bi * BLK + BLK && i < b->nu; i++) {
                const double *P = b->P + 3 * (i + (long)j * b->nu);
                const double dx = P[0] - Q[0], dy = P[1] - Q[1], dz = P[2] - Q[2];
                const double d2 = dx * dx + dy * dy + dz * dz;
                dmin2 = d2 < dmin2 ? d2 : dmin2;
            }
    }
    const double dmin = sqrt(dmin2), reach = dmin + 2.0 * b->h, band = reach * reach;
    double best = INFINITY;
    *dint = INFINITY;
    for (long k = 0; k < nb; k++) {
        if (dist3(b->bc + 4 * k, Q) - b->bc[4 * k + 3] > reach)
            continue;
        const int bi = (int)(k % b->bu), bj = (int)(k / b->bu);
        for (int j = bj * BLK; j < bj * BLK + BLK && j < b->nv; j++)
            for (int i = bi * BLK; i < bi * BLK + BLK && i < b->nu; i++) {
                const double *P = b->P + 3 * (i + (long)j * b->nu);
                const double dx = P[0] - Q[0], dy = P[1] - Q[1], dz = P[2] - Q[2];
                if (!(dx * dx + dy * dy + dz * dz <= band))
                    continue;
                const double d = sqrt(dx * dx + dy * dy + dz * dz);
                int lmin = 1;
                for (int dj = -1; dj <= 1 && lmin; dj++)
                    for (int di = -1; di <= 1; di++) {
                        const int ii = i + di, jj = j + dj;
                        if ((di || dj) && ii >= 0 && ii < b->nu && jj >= 0 && jj < b->nv &&
                            dist3(b->P + 3 * (ii + (long)jj * b->nu), Q) < d) {
                            lmin = 0;
                            break;
                        }
                    }
                if (!lmin)
                    continue;
                double u = (double)i / (b->nu - 1), v = (double)j / (b->nv - 1);
                const double dr = zoom(b, Q, &u, &v);
                if (u > 0.0 && u < 1.0 && v > 0.0 && v < 1.0)
                    *dint = fmin(*dint, dr);
                if (dr < best) {
                    best = dr;
                    *ub = u;
                    *vb = v;
                }
            }
    }
    return best;
}

/* ---- the projections under test ---- */

/* Random points within REACH of s: a surface point plus a vector uniform in
 * the ball of radius REACH. */
static void random_point(const nf_surf_t *s, double Q[3])
{
    double S[3], e[3];
    nf_surf_eval(s, ref_rand(0.0, 1.0), ref_rand(0.0, 1.0), S);
    do
        for (int c = 0; c < 3; c++)
            e[c] = ref_rand(-1.0, 1.0);
    while (dot3(e, e) > 1.0);
    for (int c = 0; c < 3; c++)
        Q[c] = S[c] + REACH * e[c];
}

/* The projections cellfit uses: nf_project_seeded over the seed grid
 * nf_seed_size sizes; nf_quad_project (where the surface does not fold over
 * in the maximum-area plane); and cf_seedgrid_project itself, what the fit,
 * report, project and the library call: the quadrilaterals, or over a fold
 * its square grid's cells (8 samples per span of the longer direction,
 * 16..1024). It used to take only the nearest sample and nf_project from
 * it: 16 of the folded part's 10^4 feet in the wrong valley, up to 5.8 %
 * too far; now it takes every valley's start within the band. */
enum { BY_SEEDED, BY_QUAD, BY_GRID, BY_GRID_FEW, N_BY };
static const char *by_name[N_BY] = {"nf_project_seeded", "nf_quad_project", "cf_seedgrid_project",
                                    "cf_seedgrid_project (few points: the paper's blanket)"};

typedef struct tally {
    long wrong;        /* distance not the brute-force minimum */
    long edge_wrong;   /* of them: a boundary foot where an interior one is nearer */
    long clamped;      /* boundary feet */
    double worst;      /* largest (ours - brute) / max(1, brute) */
    double worst_edge; /* largest (ours - interior) of edge_wrong */
} tally_t;

static void check(const char *part, int by, const nf_proj_t *pr, const double Q[3], double db,
                  double dint, tally_t *t)
{
    const double ours = fabs(pr->dist), scale = fmax(1.0, db);
    assert_near(ours, dist3(pr->foot, Q), 1e-12 * scale);
    t->clamped += pr->clamped != 0;
    /* Never nearer than brute force beyond its own rounding: that would
     * make brute force, not the projection, the thing under test. */
    if (ours < db - 1e-9 * scale)
        fail_msg("%s: brute force %.17g missed the foot %.17g of %s at (%.17g, %.17g)", part, db,
                 ours, by_name[by], pr->u, pr->v);
    const double ex = (ours - db) / scale;
    t->worst = fmax(t->worst, ex);
    if (ex > TOL) {
        t->wrong++;
        if (pr->clamped && dint < ours - TOL * scale) {
            t->edge_wrong++;
            t->worst_edge = fmax(t->worst_edge, ours - dint);
        }
        if (t->wrong <= 3)
            print_message("%s, %s: Q (%.6f, %.6f, %.6f) foot (%.9f, %.9f)%s at %.9f, brute "
                          "force %.9f\n",
                          part, by_name[by], Q[0], Q[1], Q[2], pr->u, pr->v,
                          pr->clamped ? " clamped" : "", ours, db);
    }
}

static void run_part(const char *part, const nf_surf_t *s, int bnu, int bnv,
                     unsigned long long seed)
{
    assert_int_equal(nf_surf_check(s), NF_OK);
    brute_t b;
    brute_init(&b, s, bnu, bnv);
    /* The seed grid as cellfit sizes it. */
    int nsu, nsv;
    nf_seed_size(s, 65536L, &nsu, &nsv);
    double *spts = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(nsu, nsv));
    assert_non_null(spts);
    nf_seed_t g;
    nf_seed_init_uv(&g, s, nsu, nsv, spts);
    cf_seedgrid_t sg, sgf;
    assert_int_equal(cf_seedgrid_init(&sg, s, 8), CF_OK);
    assert_int_equal(cf_seedgrid_init_n(&sgf, s, 8, NPTS), CF_OK);
    assert_int_equal(sgf.use_quad, sg.use_quad);
    assert_true(!sg.use_quad || sgf.quad.tol > sg.quad.tol); /* the coarser blanket */
    print_message("%s: cf_seedgrid by %s\n", part,
                  sg.use_quad ? "quadrilaterals" : "its 3-D cell grid (the surface folds)");
    /* The quadrilaterals, as cellfit's fit uses them where the surface does
     * not fold over in the maximum-area plane. */
    const long maxq = 65536L;
    const size_t qb = NF_QUAD_BYTES(maxq, s->nu, s->nv);
    void *qmem = malloc(qb);
    assert_non_null(qmem);
    nf_quad_t quad;
    const nf_quad_params_t prm = {NF_QUAD_SEED_TOL, 1e9, 0};
    const int have_quad = nf_quad_init(&quad, s, &prm, maxq, qmem, qb) == NF_OK && !quad.folded;
    tally_t t[N_BY] = {{0}};
    long interior_best = 0;
    ref_seed(seed);
    for (int k = 0; k < NPTS; k++) {
        double Q[3], ub = 0, vb = 0, dint;
        random_point(s, Q);
        const double db = brute(&b, Q, &ub, &vb, &dint);
        interior_best += dint <= db;
        nf_proj_t pr;
        assert_int_equal(nf_project_seeded(&g, Q, TOL, &pr), NF_OK);
        check(part, BY_SEEDED, &pr, Q, db, dint, &t[BY_SEEDED]);
        if (have_quad) {
            int rc = nf_quad_project(&quad, Q, TOL, &pr);
            assert_true(rc == NF_OK);
            check(part, BY_QUAD, &pr, Q, db, dint, &t[BY_QUAD]);
        }
        assert_int_equal(cf_seedgrid_project(&sg, Q, TOL, &pr), NF_OK);
        check(part, BY_GRID, &pr, Q, db, dint, &t[BY_GRID]);
        assert_int_equal(cf_seedgrid_project(&sgf, Q, TOL, &pr), NF_OK);
        check(part, BY_GRID_FEW, &pr, Q, db, dint, &t[BY_GRID_FEW]);
    }
    long wrong = 0;
    for (int by = 0; by < N_BY; by++) {
        if (by == BY_QUAD && !have_quad)
            continue;
        print_message("%s (%ld points, %ld with an interior foot), %s: %ld feet not the nearest "
                      "(%ld a boundary foot with an interior one nearer, by up to %.3g mm), "
                      "%ld on the boundary, worst excess %.3g (relative)\n",
                      part, (long)NPTS, interior_best, by_name[by], t[by].wrong, t[by].edge_wrong,
                      t[by].worst_edge, t[by].clamped, t[by].worst);
        wrong += t[by].wrong;
    }
    free(qmem);
    cf_seedgrid_free(&sg);
    cf_seedgrid_free(&sgf);
    free(spts);
    free(b.bc);
    free(b.P);
    assert_int_equal(wrong, 0);
}

static void test_twisted_strip(void **state)
{
    (void)state;
    nf_surf_t s;
    double *mem = make_twisted(&s);
    run_part("twisted strip", &s, 1001, 51, 1401);
    free(mem);
}

static void test_folded_edge(void **state)
{
    (void)state;
    nf_surf_t s;
    double *mem = make_folded(&s);
    run_part("folded edge", &s, 401, 301, 1402);
    free(mem);
}

/* A point under the hem's free edge (v = 1, at y = 16, z = 4.2), nearer
 * the plate below it: Newton started on the hem near its edge walks to the
 * edge and would hold there (a boundary foot 2.66 mm away where the plate
 * is 2 mm away: what nf_project returned before issue 14, for all 40
 * starts); the projection must give the plate's foot, as brute force. */
static void test_edge_restart(void **state)
{
    (void)state;
    nf_surf_t s;
    double *mem = make_folded(&s);
    brute_t b;
    brute_init(&b, &s, 401, 301);
    double worst = 0.0, edge_gap = INFINITY;
    for (int k = 0; k < 40; k++) {
        const double u = 0.1 + 0.02 * k;
        double E[3];
        nf_surf_eval(&s, u, 1.0, E);
        /* 1.5 mm beyond the edge, 2.2 below it. */
        const double Q[3] = {E[0], E[1] - 1.5, E[2] - 2.2};
        double ub, vb, dint;
        const double db = brute(&b, Q, &ub, &vb, &dint);
        /* The case: the foot is on the plate (interior), and the edge curve's
         * nearest point (sampled finely) is well beyond it. */
        double de = INFINITY;
        for (int i = 0; i <= 6000; i++) {
            double P[3];
            nf_surf_eval(&s, i / 6000.0, 1.0, P);
            de = fmin(de, dist3(P, Q));
        }
        assert_true(vb > 0.0 && vb < 0.5 && dint == db);
        edge_gap = fmin(edge_gap, de - db);
        nf_proj_t pr;
        assert_int_equal(nf_project(&s, Q, u, 0.97, TOL, &pr), NF_OK);
        assert_int_equal(pr.clamped, 0);
        assert_near(fabs(pr.dist), db, TOL * fmax(1.0, db));
        worst = fmax(worst, fabs(pr.dist) - db);
    }
    print_message("hem edge: 40 starts on the hem beside its free edge, the edge at least %.3g mm "
                  "further than the plate's foot: every foot on the plate (|dist| - brute force "
                  "<= %.3g)\n",
                  edge_gap, worst);
    assert_true(edge_gap > 0.1);
    free(b.bc);
    free(b.P);
    free(mem);
}

/* The tolerance loop's check pass (cf_fitjob's measure): the foot on the
 * refined net starts Newton on the next fit (here r moved by up to 0.05 mm
 * per coordinate); nf_quad_newton's foot, where it converges, must be the
 * next fit's true foot (brute force; over a fold after
 * cf_seedgrid_nearer), and it must give up on every foot that brute force
 * puts on the boundary (unless nearer found it); there nf_project from the
 * same start (its true-foot check at the bound) must find brute force's
 * foot.
 * The warm start assumes the fit moves less than the valleys are apart:
 * moves of 0.5 mm pass here, random moves of 2 mm on the wavy field (4 mm
 * waves) put a few feet in other valleys. Returns how many nf_quad_newton
 * carried. */
static long next_fit(const char *part, const nf_surf_t *r, int bnu, int bnv, const double *feet,
                     const double (*pts)[3], int n)
{
    nf_surf_t r2;
    assert_int_equal(cf_surf_alloc(&r2, r->p, r->q, r->nu, r->nv), CF_OK);
    memcpy(r2.U, r->U, sizeof(double) * (size_t)(r->nu + r->p + 1));
    memcpy(r2.V, r->V, sizeof(double) * (size_t)(r->nv + r->q + 1));
    for (long k = 0; k < 3L * r->nu * r->nv; k++)
        r2.cp[k] = r->cp[k] + 0.05 * ref_rand(-1.0, 1.0);
    r2.w = NULL;
    assert_int_equal(nf_surf_check(&r2), NF_OK);
    const size_t nb = NF_QUAD_NEWTON_BYTES(r2.nu, r2.nv);
    void *nm = malloc(nb);
    assert_non_null(nm);
    nf_quad_t nq;
    assert_int_equal(nf_quad_newton_init(&nq, &r2, nm, nb), NF_OK);
    brute_t b;
    brute_init(&b, &r2, bnu, bnv);
    cf_seedgrid_t sg;
    assert_int_equal(cf_seedgrid_init(&sg, &r2, 8), CF_OK);
    long fast = 0, edge = 0, nback = 0, layer = 0;
    double worst = 0.0;
    for (int k = 0; k < n; k++) {
        double ub = 0, vb = 0, dint, u = feet[2 * k], v = feet[2 * k + 1];
        nf_proj_t f;
        /* as the fit job's check pass */
        const int ok = nf_quad_newton(&nq, pts[k], CF_FITJOB_WARM_TOL, &u, &v, &f);
        /* over a fold the job then tries the other layers' valleys
         * (START_FOLD): the nearer foot */
        if (ok && !sg.use_quad) {
            const double d0 = fabs(f.dist);
            assert_int_equal(cf_seedgrid_nearer(&sg, &nq, pts[k], TOL, &f), NF_OK);
            layer += fabs(f.dist) < d0 - 1e-9 * fmax(1.0, d0);
        }
        const double db = brute(&b, pts[k], &ub, &vb, &dint), scale = fmax(1.0, db);
        /* brute force's foot on the boundary: nearer than any interior one */
        const int on_edge = dint > db + 1e-9 * scale;
        edge += on_edge;
        if (ok && on_edge && !f.clamped)
            fail_msg("%s next fit: point %d converged inside (%.17g) where brute force's foot is "
                     "on the boundary (%.17g)",
                     part, k, fabs(f.dist), db);
        if (!ok) {
            /* cf_fitjob keeps nf_project's foot from the warm start when
             * it is on a bound (over a fold: then the nearer one), else
             * searches */
            nf_proj_t g;
            assert_int_equal(nf_project(&r2, pts[k], feet[2 * k], feet[2 * k + 1], TOL, &g), NF_OK);
            if (!g.clamped)
                assert_int_equal(cf_seedgrid_project(&sg, pts[k], TOL, &g), NF_OK);
            else if (!sg.use_quad)
                assert_int_equal(cf_seedgrid_nearer(&sg, &nq, pts[k], TOL, &g), NF_OK);
            nback += !g.clamped;
            if (fabs(fabs(g.dist) - db) > 1e-9 * scale)
                fail_msg("%s next fit: point %d nf_project from the warm start %.17g (clamped %d), "
                         "brute force %.17g",
                         part, k, fabs(g.dist), g.clamped, db);
            worst = fmax(worst, fabs(fabs(g.dist) - db) / scale);
            continue;
        }
        fast++;
        if (fabs(fabs(f.dist) - db) > 1e-9 * scale)
            fail_msg("%s next fit: point %d warm foot %.17g, brute force %.17g", part, k,
                     fabs(f.dist), db);
        worst = fmax(worst, fabs(fabs(f.dist) - db) / scale);
    }
    print_message("%s next fit: %ld of %d feet by nf_quad_newton from the last fit's foot (%ld "
                  "of them then on a nearer layer, cf_seedgrid_nearer), %ld by nf_project from "
                  "it (on a bound), %ld by the search (%ld on the boundary by brute force), worst "
                  "difference from brute force %.3g (relative)\n",
                  part, fast, n, layer, n - fast - nback, nback, edge, worst);
    cf_seedgrid_free(&sg);
    free(b.bc);
    free(b.P);
    free(nm);
    cf_surf_free(&r2);
    return fast;
}

/* The tolerance loop's next round (cf_fitjob): Boehm insertion keeps the
 * surface, so the foot found on it is the foot on the refined net: Newton
 * from there must end on the refined surface's true foot (brute force on
 * the refined surface) at the same parameters and distance, without a
 * search (so the fit pass reuses it as it is). nf_quad_newton likewise
 * must converge on every interior foot and give up on every boundary one;
 * the feet then start the check pass's Newton on the next fit (next_fit). */
static void refined_part(const char *part, const nf_surf_t *s, int bnu, int bnv,
                         unsigned long long seed)
{
    int nu, nv;
    assert_int_equal(nf_refine_uniform_size(s, &nu, &nv), NF_OK);
    nf_surf_t r;
    assert_int_equal(cf_surf_alloc(&r, s->p, s->q, nu, nv), CF_OK);
    assert_int_equal(nf_refine_uniform(s, &r), NF_OK);
    assert_int_equal(nf_surf_check(&r), NF_OK);
    brute_t b;
    brute_init(&b, &r, bnu, bnv);
    cf_seedgrid_t sg;
    assert_int_equal(cf_seedgrid_init(&sg, s, 8), CF_OK);
    const size_t nb = NF_QUAD_NEWTON_BYTES(r.nu, r.nv);
    void *nm = malloc(nb);
    assert_non_null(nm);
    nf_quad_t nq;
    assert_int_equal(nf_quad_newton_init(&nq, &r, nm, nb), NF_OK);
    ref_seed(seed);
    double worst = 0.0, moved = 0.0;
    long clamped = 0;
    const int n = NPTS / 5;
    double(*pts)[3] = malloc(sizeof *pts * (size_t)n), *feet = malloc(sizeof(double) * 2 * n);
    assert_non_null(pts);
    assert_non_null(feet);
    for (int k = 0; k < n; k++) {
        double Q[3], ub = 0, vb = 0, dint;
        random_point(s, Q);
        nf_proj_t f0, f1, f2;
        assert_int_equal(cf_seedgrid_project(&sg, Q, TOL, &f0), NF_OK);
        assert_int_equal(nf_project(&r, Q, f0.u, f0.v, TOL, &f1), NF_OK);
        double u2 = f0.u, v2 = f0.v;
        const int fast = nf_quad_newton(&nq, Q, TOL, &u2, &v2, &f2);
        if (fast != !f1.clamped)
            fail_msg("%s: point %d: nf_quad_newton %s on a foot %s the boundary", part, k,
                     fast ? "converged" : "gave up", f1.clamped ? "on" : "off");
        if (fast && (fabs(f2.u - f1.u) > 1e-7 || fabs(f2.v - f1.v) > 1e-7 ||
                     fabs(fabs(f2.dist) - fabs(f1.dist)) > TOL * fmax(1.0, fabs(f1.dist))))
            fail_msg("%s: point %d: nf_quad_newton (%.17g, %.17g) %.17g, nf_project (%.17g, "
                     "%.17g) %.17g",
                     part, k, f2.u, f2.v, f2.dist, f1.u, f1.v, f1.dist);
        /* The fit job's warm Newton stops at CF_FITJOB_WARM_TOL and takes
         * the step: the same foot to 1e-9 of the domain. */
        double u3 = f0.u, v3 = f0.v;
        nf_proj_t f3;
        if (fast && (!nf_quad_newton(&nq, Q, CF_FITJOB_WARM_TOL, &u3, &v3, &f3) ||
                     fabs(f3.u - f2.u) > TOL || fabs(f3.v - f2.v) > TOL ||
                     fabs(fabs(f3.dist) - fabs(f2.dist)) > TOL * fmax(1.0, fabs(f2.dist))))
            fail_msg("%s: point %d: the warm Newton (%.17g, %.17g) %.17g, to 1e-9 (%.17g, "
                     "%.17g) %.17g",
                     part, k, f3.u, f3.v, f3.dist, f2.u, f2.v, f2.dist);
        for (int c = 0; c < 3; c++)
            pts[k][c] = Q[c];
        feet[2 * k] = f1.u;
        feet[2 * k + 1] = f1.v;
        const double db = brute(&b, Q, &ub, &vb, &dint), scale = fmax(1.0, db);
        if (fabs(f1.dist) < db - 1e-9 * scale)
            fail_msg("%s: brute force %.17g missed the foot %.17g", part, db, fabs(f1.dist));
        worst = fmax(worst, (fabs(f1.dist) - db) / scale);
        moved = fmax(moved, fmax(fabs(f1.u - f0.u), fabs(f1.v - f0.v)));
        /* cf_fitjob's fit pass takes the old foot as it is: same distance,
         * same bound */
        if (fabs(fabs(f1.dist) - fabs(f0.dist)) > 1e-9 * scale || f1.clamped != f0.clamped)
            fail_msg("%s: point %d: foot before insertion %.17g (clamped %d), after %.17g (%d)",
                     part, k, f0.dist, f0.clamped, f1.dist, f1.clamped);
        clamped += f1.clamped != 0;
    }
    print_message("%s refined %d x %d -> %d x %d: %d feet by Newton from the foot before "
                  "insertion, %ld on the boundary, worst excess over brute force %.3g "
                  "(relative), parameters moved by at most %.3g\n",
                  part, s->nu, s->nv, nu, nv, n, clamped, worst, moved);
    assert_true(worst <= TOL);
    assert_true(moved <= 1e-7);
    /* Most feet are interior and stay so: the warm path must carry them.
     * Over a fold (no quadrilaterals) a moved layer can become the nearer
     * one (this folded edge: 1.409 mm from Newton's foot, 1.384 mm on the
     * other layer): cf_seedgrid_nearer after Newton. */
    assert_true(next_fit(part, &r, bnu, bnv, feet, (const double(*)[3])pts, n) >=
                (n - clamped) / 2);
    free(pts);
    free(feet);
    free(nm);
    cf_seedgrid_free(&sg);
    free(b.bc);
    free(b.P);
    cf_surf_free(&r);
}

/* A height field of waves 4 mm high, 9 mm apart: over a trough or a crest
 * the distance has several valleys (points reach 3 mm from it). */
static double *make_wavy(nf_surf_t *s)
{
    const int nu = 12, nv = 12;
    double *mem = surf_new(s, nu, nv);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double a = greville(s->U, i, 3), b = greville(s->V, j, 3);
            double *P = s->cp + 3 * (i + j * nu);
            P[0] = 40.0 * a;
            P[1] = 40.0 * b;
            P[2] = 4.0 * sin(9.0 * a) * cos(7.0 * b);
        }
    return mem;
}

static void test_refined_start(void **state)
{
    (void)state;
    nf_surf_t s;
    double *wm = make_wavy(&s);
    refined_part("wavy height field", &s, 801, 801, 1405);
    free(wm);
    double *mem = make_twisted(&s);
    refined_part("twisted strip", &s, 1001, 51, 1403);
    free(mem);
    mem = make_folded(&s);
    refined_part("folded edge", &s, 401, 301, 1404);
    free(mem);
}

/* The fit job's first check (cf_fitjob.c, round 0): Newton from each
 * point's foot on the base, kept by the fit pass, then over a fold the
 * other valleys within reach (START_FOLD), instead of a search. Points of
 * truth sampled 60 x 60 and moved up to 0.5 mm in z, one round of the
 * loop from base: the check's rms, largest distance and share within tol
 * must be brute force's distances to that round's fit, on one core and on
 * two. Returns how far (mm along the fit) the furthest start, the foot on
 * base, lay from brute force's foot. */
static double first_check(const char *part, const nf_surf_t *base, const nf_surf_t *truth,
                          double tol)
{
    const char *d = getenv("CF_TEST_TMP");
    char path[600];
    snprintf(path, sizeof path, "%s/cf_foot_%ld_first.xyz", d && *d ? d : "/tmp", (long)getpid());
    enum { N = 60 };
    static double pts[N * N][3];
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    srand(1406);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            double *Q = pts[i + N * j];
            nf_surf_eval(truth, (i + 0.5) / N, (j + 0.5) / N, Q);
            Q[2] += ref_rand(-0.5, 0.5);
            fprintf(f, "%.17g %.17g %.17g\n", Q[0], Q[1], Q[2]);
        }
    assert_int_equal(fclose(f), 0);
    cf_seedgrid_t sg; /* the starts: the base's feet */
    assert_int_equal(cf_seedgrid_init(&sg, base, 8), CF_OK);
    double far = 0.0;
    for (int cores = 1; cores <= 2; cores++) {
        cf_fitjob_opts_t o;
        cf_fitjob_defaults(&o);
        o.tol = tol;
        o.within = 99.0;
        o.loop = 1;
        o.refine = CF_REFINE_AUTO;
        o.max_rounds = 1;
        o.cores = o.threads = cores;
        cf_fitjob_t *j = NULL;
        char m[1024];
        assert_int_equal(cf_fitjob_open(&j, base, &o, m, sizeof m), CF_OK);
        cf_fitjob_result_t r;
        if (ref_job_file(j, path, 3, &r, m, sizeof m))
            fail_msg("%s", m);
        cf_fitjob_close(j);
        assert_int_equal(r.nrounds, 1);
        assert_int_equal(r.points, N * N);
        brute_t b;
        brute_init(&b, &r.surf, 401, 401);
        double mx = 0.0, ss = 0.0;
        long within = 0, near_tol = 0;
        for (int k = 0; k < N * N; k++) {
            double ub, vb, dint, P[3], B[3];
            const double db = brute(&b, pts[k], &ub, &vb, &dint);
            mx = fmax(mx, db);
            ss += db * db;
            within += db <= o.tol;
            near_tol += fabs(db - o.tol) < 1e-9;
            nf_proj_t g;
            assert_int_equal(cf_seedgrid_project(&sg, pts[k], TOL, &g), NF_OK);
            nf_surf_eval(&r.surf, ub, vb, P);
            nf_surf_eval(&r.surf, g.u, g.v, B);
            far = fmax(far, dist3(P, B));
        }
        print_message("%s, first check on %d core%s: %d points, rms %.6f (brute force %.6f), max "
                      "%.6f (%.6f), within %.3f %% (%.3f %%), starts up to %.3f mm from the "
                      "feet\n",
                      part, cores, cores > 1 ? "s" : "", N * N, r.rms, sqrt(ss / (N * N)),
                      r.max_abs, mx, r.within_pct, 100.0 * (double)within / (N * N), far);
        assert_near(r.max_abs, mx, 1e-9 * fmax(1.0, mx));
        assert_near(r.rms, sqrt(ss / (N * N)), 1e-9);
        assert_near(r.within_pct, 100.0 * (double)within / (N * N),
                    100.0 * (double)near_tol / (N * N) + 1e-9);
        free(b.bc);
        free(b.P);
        cf_fitjob_result_free(&r);
    }
    cf_seedgrid_free(&sg);
    remove(path);
    return far;
}

/* A plane base under the wavy field (8 mm from crest to trough): the fit
 * moves far from the base, so the starts are far from the feet; and the
 * hem as its own base (two layers 4 mm apart: START_FOLD's valleys). */
static void test_first_check(void **state)
{
    (void)state;
    nf_surf_t w, plane;
    double *wm = make_wavy(&w), *bm = surf_new(&plane, 4, 4);
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *P = plane.cp + 3 * (i + 4 * j);
            P[0] = 40.0 * i / 3.0, P[1] = 40.0 * j / 3.0, P[2] = 0.0;
        }
    assert_true(first_check("wavy field, plane base", &plane, &w, 0.8) > 1.0);
    free(bm);
    free(wm);
    nf_surf_t hem;
    double *hm = make_folded(&hem);
    cf_seedgrid_t sg;
    assert_int_equal(cf_seedgrid_init(&sg, &hem, 8), CF_OK);
    assert_false(sg.use_quad); /* folded: the check's START_FOLD */
    cf_seedgrid_free(&sg);
    first_check("hem", &hem, &hem, 0.2);
    free(hm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_twisted_strip), cmocka_unit_test(test_folded_edge),
        cmocka_unit_test(test_edge_restart),  cmocka_unit_test(test_refined_start),
        cmocka_unit_test(test_first_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
