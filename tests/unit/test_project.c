/* SPDX-License-Identifier: MIT */
/* test_project.c: point projection (nf_project, nf_seed_*) against results
 * known by construction (S + h n, points on the surface, an exactly linear
 * plane) and against brute-force dense sampling with local refinement, in
 * the interior, beyond the boundary and at degenerate points. */

#include "cf_test.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define TOL 1e-9

/* Seed grid as cellfit sizes it (nf_seed_size, at most 256^2 samples). */
static double *seed_grid(const nf_surf_t *s, nf_seed_t *g)
{
    int nsu, nsv;
    nf_seed_size(s, 65536L, &nsu, &nsv);
    double *pts = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(nsu, nsv));
    assert_non_null(pts);
    nf_seed_init_uv(g, s, nsu, nsv, pts);
    return pts;
}

/* As cellfit projects: nf_project_seeded (the seed grid's best starts). */
static void project(const nf_surf_t *s, const nf_seed_t *g, const double Q[3], nf_proj_t *pr)
{
    assert_ptr_equal(g->s, s);
    int rc = nf_project_seeded(g, Q, TOL, pr);
    if (rc != NF_OK)
        fail_msg("nf_project_seeded %d for Q = (%.17g, %.17g, %.17g)", rc, Q[0], Q[1], Q[2]);
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot3(d, d));
}

/* Point, unit normal Su x Sv / |.| and tangents at (u, v). */
static void frame(const nf_surf_t *s, double u, double v, double S[3], double n[3], double Su[3],
                  double Sv[3])
{
    double d[27];
    nf_surf_derivs(s, u, v, 1, d);
    for (int c = 0; c < 3; c++) {
        S[c] = d[c];
        Sv[c] = d[3 + c];
        Su[c] = d[9 + c];
    }
    n[0] = Su[1] * Sv[2] - Su[2] * Sv[1];
    n[1] = Su[2] * Sv[0] - Su[0] * Sv[2];
    n[2] = Su[0] * Sv[1] - Su[1] * Sv[0];
    double l = sqrt(dot3(n, n));
    for (int c = 0; c < 3; c++)
        n[c] /= l;
}

/* Smallest radius of curvature over a 81 x 81 parameter grid (principal
 * curvatures from the fundamental forms). */
static double min_radius(const nf_surf_t *s)
{
    double u0, u1, v0, v1, kmax = 0.0;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (int j = 0; j <= 80; j++)
        for (int i = 0; i <= 80; i++) {
            double d[27], u = u0 + (u1 - u0) * i / 80.0, v = v0 + (v1 - v0) * j / 80.0;
            nf_surf_derivs(s, u, v, 2, d);
            const double *Su = d + 9, *Sv = d + 3, *Suu = d + 18, *Suv = d + 12, *Svv = d + 6;
            double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                           Su[0] * Sv[1] - Su[1] * Sv[0]};
            double l = sqrt(dot3(n, n));
            double E = dot3(Su, Su), F = dot3(Su, Sv), G = dot3(Sv, Sv);
            double L = dot3(Suu, n) / l, M = dot3(Suv, n) / l, N = dot3(Svv, n) / l;
            double det = E * G - F * F;
            double K = (L * N - M * M) / det, H = (E * N - 2 * F * M + G * L) / (2 * det);
            double k = fabs(H) + sqrt(fmax(H * H - K, 0.0));
            kmax = fmax(kmax, k);
        }
    return 1.0 / kmax;
}

/* A parameter inside a random knot span, 10%..90% of the way across it (away
 * from knot lines, where degree-1 surfaces crease). */
static double in_span(const double *K, int n, int p)
{
    int l;
    do
        l = p + (int)ref_rand(0, n - p + 1);
    while (!(K[l] < K[l + 1]));
    return K[l] + (K[l + 1] - K[l]) * ref_rand(0.1, 0.9);
}

/* The thin surface: each column of control points pulled towards its first
 * point by 1e-3, so that the v direction is 1000 times shorter and curvier.
 * The weights are made constant along v (the column's first): weights that
 * vary along v would slide the point along u as v changes, and the surface
 * would be nearly a curve (Su parallel to Sv), not a thin one. */
static void make_thin(nf_surf_t *s)
{
    for (int j = 1; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            double *P = s->cp + 3 * (i + (long)j * s->nu), *P0 = s->cp + 3 * i;
            for (int c = 0; c < 3; c++)
                P[c] = P0[c] + 1e-3 * (P[c] - P0[c]);
            if (s->w)
                s->w[i + (long)j * s->nu] = s->w[i];
        }
}

typedef struct stats {
    double du, dv, dh;
    int iters;
} stats_t;

/* (a) Q = S(u*, v*) + h n(u*, v*), |h| < 0.1 min radius: the projection
 * returns (u*, v*) and dist = h. */
static void offsets_on(const nf_surf_t *s, int npts, stats_t *st)
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    const double hmax = fmin(0.1 * min_radius(s), 2.0);
    nf_seed_t g;
    double *pts = seed_grid(s, &g);
    for (int t = 0; t < npts; t++) {
        double us = in_span(s->U, s->nu - 1, s->p), vs = in_span(s->V, s->nv - 1, s->q);
        double S[3], n[3], Su[3], Sv[3], Q[3], h = ref_rand(-hmax, hmax);
        frame(s, us, vs, S, n, Su, Sv);
        for (int c = 0; c < 3; c++)
            Q[c] = S[c] + h * n[c];
        nf_proj_t pr;
        project(s, &g, Q, &pr);
        if (!(fabs(pr.u - us) <= TOL * (u1 - u0) && fabs(pr.v - vs) <= TOL * (v1 - v0)))
            print_message("(u*, v*) = (%.17g, %.17g), h %.17g: got (%.17g, %.17g), dist %.17g\n",
                          us, vs, h, pr.u, pr.v, pr.dist);
        assert_near(pr.u, us, TOL * (u1 - u0));
        assert_near(pr.v, vs, TOL * (v1 - v0));
        assert_near(pr.dist, h, TOL);
        assert_int_equal(pr.clamped, 0);
        st->du = fmax(st->du, fabs(pr.u - us) / (u1 - u0));
        st->dv = fmax(st->dv, fabs(pr.v - vs) / (v1 - v0));
        st->dh = fmax(st->dh, fabs(pr.dist - h));
        st->iters = pr.iters > st->iters ? pr.iters : st->iters;
    }
    free(pts);
}

static void test_normal_offsets(void **state)
{
    (void)state;
    stats_t st = {0, 0, 0, 0};
    nf_surf_t s;
    ref_seed(1001);
    /* The curved rational bicubic, and the same made thin. */
    ref_surf_random(&s, 3, 3, 7, 6, -1.0, 2.0, 0.5, 4.0, 0.5, 2.0);
    offsets_on(&s, 300, &st);
    make_thin(&s);
    offsets_on(&s, 300, &st);
    ref_surf_free(&s);
    /* Degrees 1..5, equal and mixed, rational and polynomial. */
    for (int d = 1; d <= 5; d++)
        for (int mixed = 0; mixed <= 1; mixed++) {
            int q = mixed ? 1 + (d + 1) % 5 : d;
            ref_surf_random(&s, d, q, d + 4, q + 3, 10.0, 10.5, -3.0, 3.0, 0.5, 2.0);
            if (mixed)
                s.w = NULL;
            offsets_on(&s, 150, &st);
            ref_surf_free(&s);
        }
    print_message("normal offsets: max |du| %.3g, |dv| %.3g (of the domain), |dist - h| %.3g, "
                  "max iterations %d\n",
                  st.du, st.dv, st.dh, st.iters);
}

/* Brute force over a dense sample grid of the surface, nu x nv samples
 * (BN x BN, or long and narrow for the thin surface: a square grid would
 * put its samples a width apart along it). */
typedef struct brute {
    const nf_surf_t *s;
    double *P;
    int nu, nv;
    double u0, u1, v0, v1;
} brute_t;

#define BN 401

static void brute_init_n(brute_t *b, const nf_surf_t *s, int nu, int nv)
{
    b->s = s;
    b->nu = nu;
    b->nv = nv;
    nf_surf_domain(s, &b->u0, &b->u1, &b->v0, &b->v1);
    b->P = malloc(sizeof(double) * 3 * (size_t)nu * (size_t)nv);
    assert_non_null(b->P);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++)
            nf_surf_eval(s, b->u0 + (b->u1 - b->u0) * i / (nu - 1),
                         b->v0 + (b->v1 - b->v0) * j / (nv - 1), b->P + 3 * (i + (long)j * nu));
}

static void brute_init(brute_t *b, const nf_surf_t *s)
{
    brute_init_n(b, s, BN, BN);
}

/* Zoom from one start: 40 rounds of an 11 x 11 search in a window of 1.5
 * sample spacings that shrinks by 0.4 each round. */
static double zoom(const brute_t *b, const double Q[3], double *u, double *v)
{
    double best = INFINITY, hu = 1.5 * (b->u1 - b->u0) / (b->nu - 1),
           hv = 1.5 * (b->v1 - b->v0) / (b->nv - 1);
    for (int round = 0; round < 40; round++) {
        double cu = *u, cv = *v;
        for (int j = -5; j <= 5; j++)
            for (int i = -5; i <= 5; i++) {
                double tu = fmin(fmax(cu + hu * i / 5.0, b->u0), b->u1);
                double tv = fmin(fmax(cv + hv * j / 5.0, b->v0), b->v1), P[3];
                nf_surf_eval(b->s, tu, tv, P);
                double d = dist3(P, Q);
                if (d < best) {
                    best = d;
                    *u = tu;
                    *v = tv;
                }
            }
        hu *= 0.4;
        hv *= 0.4;
    }
    return best;
}

/* The grid's 8 nearest samples, each zoomed (the nearest sample alone can
 * sit in the wrong valley). */
static double brute(const brute_t *b, const double Q[3], double *ub, double *vb)
{
    double bd[8];
    long bk[8];
    for (int t = 0; t < 8; t++) {
        bd[t] = INFINITY;
        bk[t] = 0;
    }
    for (long k = 0; k < (long)b->nu * b->nv; k++) {
        double d = dist3(b->P + 3 * k, Q);
        if (d < bd[7]) {
            int t = 7;
            for (; t > 0 && bd[t - 1] > d; t--) {
                bd[t] = bd[t - 1];
                bk[t] = bk[t - 1];
            }
            bd[t] = d;
            bk[t] = k;
        }
    }
    double best = INFINITY;
    for (int t = 0; t < 8; t++) {
        double u = b->u0 + (b->u1 - b->u0) * (double)(bk[t] % b->nu) / (b->nu - 1);
        double v = b->v0 + (b->v1 - b->v0) * (double)(bk[t] / b->nu) / (b->nv - 1);
        double d = zoom(b, Q, &u, &v);
        if (d < best) {
            best = d;
            *ub = u;
            *vb = v;
        }
    }
    return best;
}

/* (b) Random points at moderate offsets: never worse than brute force. */
static void test_against_brute_force(void **state)
{
    (void)state;
    ref_seed(2002);
    double worst = -INFINITY, better = 0.0;
    const int shapes[][3] = {{3, 3, 0}, {2, 4, 0}, {5, 5, 0}, {1, 2, 0}, {3, 3, 1}};
    for (size_t c = 0; c < sizeof shapes / sizeof shapes[0]; c++) {
        nf_surf_t s;
        int p = shapes[c][0], q = shapes[c][1];
        ref_surf_random(&s, p, q, p + 4, q + 4, -1.0, 1.0, 3.0, 7.0, 0.5, 2.0);
        if (shapes[c][2])
            make_thin(&s);
        /* Offsets moderate for the shape: up to 2 along the normal and 0.5
         * across (1/500 of that on the thin surface, 1000 times narrower). */
        double scale = shapes[c][2] ? 0.002 : 1.0;
        brute_t b;
        if (shapes[c][2])
            brute_init_n(&b, &s, 16001, 11);
        else
            brute_init(&b, &s);
        nf_seed_t g;
        double *pts = seed_grid(&s, &g);
        for (int t = 0; t < 60; t++) {
            double u = ref_rand(b.u0, b.u1), v = ref_rand(b.v0, b.v1);
            double S[3], n[3], Su[3], Sv[3], Q[3];
            frame(&s, u, v, S, n, Su, Sv);
            double h = ref_rand(-2, 2);
            for (int k = 0; k < 3; k++)
                Q[k] = S[k] + scale * (h * n[k] + ref_rand(-0.5, 0.5));
            nf_proj_t pr;
            project(&s, &g, Q, &pr);
            double ub, vb, db = brute(&b, Q, &ub, &vb);
            assert_near(fabs(pr.dist), dist3(pr.foot, Q), 1e-12 * (1 + fabs(pr.dist)));
            if (!(fabs(pr.dist) <= db + TOL))
                fail_msg("shape %zu point %d: dist %.17g, brute force %.17g at (%.17g, %.17g), "
                         "ours at (%.17g, %.17g)",
                         c, t, fabs(pr.dist), db, ub, vb, pr.u, pr.v);
            worst = fmax(worst, fabs(pr.dist) - db);
            better = fmax(better, db - fabs(pr.dist));
        }
        free(pts);
        free(b.P);
        ref_surf_free(&s);
    }
    print_message("brute force: ours - brute at most %.3g (ours better by up to %.3g)\n", worst,
                  better);
}

/* Closest point of the boundary curve C(t) = S(edge, t) (dir 0: u fixed at
 * e) to Q: 20001 samples, then golden-section search around the best. */
static double edge_brute(const nf_surf_t *s, int dir, double e, const double Q[3], double *tb)
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    double a = dir == 0 ? v0 : u0, b = dir == 0 ? v1 : u1, best = INFINITY, t = a;
    for (int i = 0; i <= 20000; i++) {
        double x = a + (b - a) * i / 20000.0, P[3];
        nf_surf_eval(s, dir == 0 ? e : x, dir == 0 ? x : e, P);
        double d = dist3(P, Q);
        if (d < best) {
            best = d;
            t = x;
        }
    }
    double lo = fmax(a, t - (b - a) / 20000.0), hi = fmin(b, t + (b - a) / 20000.0);
    const double gr = 0.5 * (sqrt(5.0) - 1.0);
    for (int it = 0; it < 100; it++) {
        double x1 = hi - gr * (hi - lo), x2 = lo + gr * (hi - lo), P1[3], P2[3];
        nf_surf_eval(s, dir == 0 ? e : x1, dir == 0 ? x1 : e, P1);
        nf_surf_eval(s, dir == 0 ? e : x2, dir == 0 ? x2 : e, P2);
        if (dist3(P1, Q) < dist3(P2, Q))
            hi = x2;
        else
            lo = x1;
    }
    double x = 0.5 * (lo + hi), P[3];
    nf_surf_eval(s, dir == 0 ? e : x, dir == 0 ? x : e, P);
    if (dist3(P, Q) < best) {
        best = dist3(P, Q);
        t = x;
    }
    *tb = t;
    return best;
}

/* (c) Points beyond an edge project onto it (clamped, parameter exactly on
 * the bound) at the boundary curve's closest point; beyond a corner, onto
 * the corner. */
static void test_boundary(void **state)
{
    (void)state;
    ref_seed(3003);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 7, 7, 2.0, 5.0, -1.0, 1.0, 0.5, 2.0);
    double u0, u1, v0, v1, worst_d = 0.0, worst_t = 0.0;
    nf_surf_domain(&s, &u0, &u1, &v0, &v1);
    nf_seed_t g;
    double *pts = seed_grid(&s, &g);
    brute_t b;
    brute_init(&b, &s);
    for (int edge = 0; edge < 4; edge++) {
        const int dir = edge / 2; /* 0: u fixed at u0 / u1; 1: v fixed */
        const double e = dir == 0 ? (edge & 1 ? u1 : u0) : (edge & 1 ? v1 : v0);
        const double sgn = edge & 1 ? 1.0 : -1.0;
        for (int t = 0; t < 25; t++) {
            double x = dir == 0 ? ref_rand(v0 + 0.1 * (v1 - v0), v1 - 0.1 * (v1 - v0))
                                : ref_rand(u0 + 0.1 * (u1 - u0), u1 - 0.1 * (u1 - u0));
            double S[3], n[3], Su[3], Sv[3], Q[3], o[3];
            frame(&s, dir == 0 ? e : x, dir == 0 ? x : e, S, n, Su, Sv);
            /* Outward: the cross-boundary derivative, less its part along
             * the boundary, signed out of the domain. */
            const double *X = dir == 0 ? Su : Sv, *T = dir == 0 ? Sv : Su;
            double f = dot3(X, T) / dot3(T, T);
            for (int c = 0; c < 3; c++)
                o[c] = sgn * (X[c] - f * T[c]);
            double lo = sqrt(dot3(o, o)), a = ref_rand(0.5, 3.0), h = ref_rand(-1.0, 1.0);
            for (int c = 0; c < 3; c++)
                Q[c] = S[c] + a * o[c] / lo + h * n[c];
            nf_proj_t pr;
            project(&s, &g, Q, &pr);
            assert_int_equal(pr.clamped, 1);
            assert_true((dir == 0 ? pr.u : pr.v) == e);
            double tb, db = edge_brute(&s, dir, e, Q, &tb);
            double range = dir == 0 ? v1 - v0 : u1 - u0;
            assert_near(fabs(pr.dist), db, TOL);
            assert_near(dir == 0 ? pr.v : pr.u, tb, 1e-6 * range);
            double P[3], ub, vb;
            nf_surf_eval(&s, dir == 0 ? e : tb, dir == 0 ? tb : e, P);
            for (int c = 0; c < 3; c++)
                assert_near(pr.foot[c], P[c], 1e-6);
            assert_true(fabs(pr.dist) <= brute(&b, Q, &ub, &vb) + TOL);
            worst_d = fmax(worst_d, fabs(fabs(pr.dist) - db));
            worst_t = fmax(worst_t, fabs((dir == 0 ? pr.v : pr.u) - tb) / range);
        }
    }
    /* Corners. */
    for (int corner = 0; corner < 4; corner++) {
        double uc = corner & 1 ? u1 : u0, vc = corner & 2 ? v1 : v0;
        double su = corner & 1 ? 1.0 : -1.0, sv = corner & 2 ? 1.0 : -1.0;
        for (int t = 0; t < 5; t++) {
            double S[3], n[3], Su[3], Sv[3], Q[3];
            frame(&s, uc, vc, S, n, Su, Sv);
            double a = ref_rand(0.5, 2.0) / sqrt(dot3(Su, Su)),
                   c2 = ref_rand(0.5, 2.0) / sqrt(dot3(Sv, Sv)), h = ref_rand(-0.5, 0.5);
            for (int c = 0; c < 3; c++)
                Q[c] = S[c] + su * a * Su[c] + sv * c2 * Sv[c] + h * n[c];
            nf_proj_t pr;
            project(&s, &g, Q, &pr);
            double ub, vb, db = brute(&b, Q, &ub, &vb);
            assert_true(fabs(pr.dist) <= db + TOL);
            if (ub == uc && vb == vc) { /* the corner is the closest point */
                assert_int_equal(pr.clamped, 1);
                assert_true(pr.u == uc && pr.v == vc);
                assert_near(fabs(pr.dist), dist3(S, Q), 1e-12 * dist3(S, Q));
            }
        }
    }
    print_message("boundary: | |dist| - edge brute force | <= %.3g, parameter %.3g of the range\n",
                  worst_d, worst_t);
    free(pts);
    free(b.P);
    ref_surf_free(&s);
}

/* (d) Points on the surface, interior, on edges and at corners: distance
 * zero to rounding, parameters back to rounding, not clamped. */
static void test_on_surface(void **state)
{
    (void)state;
    ref_seed(4004);
    double worst_p = 0.0, worst_d = 0.0;
    for (int d = 1; d <= 5; d++)
        for (int thin = 0; thin <= 1; thin++) {
            nf_surf_t s;
            ref_surf_random(&s, d, 4 - d % 4, d + 3, 7, -5.0, -2.0, 0.0, 0.001, 0.5, 2.0);
            if (thin)
                make_thin(&s);
            double u0, u1, v0, v1;
            nf_surf_domain(&s, &u0, &u1, &v0, &v1);
            nf_seed_t g;
            double *pts = seed_grid(&s, &g);
            for (int t = 0; t < 200; t++) {
                double u = ref_rand(u0, u1), v = ref_rand(v0, v1), Q[3];
                if (t % 10 == 0) /* on an edge */
                    u = t % 20 ? u0 : u1;
                if (t % 25 == 0) /* at a corner */
                    v = t % 50 ? v0 : v1;
                nf_surf_eval(&s, u, v, Q);
                nf_proj_t pr;
                project(&s, &g, Q, &pr);
                double du = fabs(pr.u - u) / (u1 - u0), dv = fabs(pr.v - v) / (v1 - v0);
                assert_true(du <= 1e-10 && dv <= 1e-10);
                assert_true(fabs(pr.dist) <= 1e-12 * (1.0 + fabs(Q[0]) + fabs(Q[1]) + fabs(Q[2])));
                assert_int_equal(pr.clamped, 0);
                worst_p = fmax(worst_p, fmax(du, dv));
                worst_d = fmax(worst_d, fabs(pr.dist));
            }
            free(pts);
            ref_surf_free(&s);
        }
    print_message("on the surface: parameters within %.3g of the domain, |dist| <= %.3g\n", worst_p,
                  worst_d);
}

/* A plane with linear parametrization (control points at the Greville
 * abscissae: x = 10 u, y = 5 v whatever the degree): the projection is
 * known in closed form, inside and beyond the domain. */
static void test_plane_exact(void **state)
{
    (void)state;
    ref_seed(5005);
    for (int p = 1; p <= 5; p++) {
        nf_surf_t s;
        ref_surf_random(&s, p, 6 - p, p + 3, 9 - p, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
        for (int j = 0; j < s.nv; j++)
            for (int i = 0; i < s.nu; i++) {
                double *P = s.cp + 3 * (i + (long)j * s.nu), gu = 0, gv = 0;
                for (int k = 1; k <= p; k++)
                    gu += s.U[i + k] / p;
                for (int k = 1; k <= 6 - p; k++)
                    gv += s.V[j + k] / (6 - p);
                P[0] = 10.0 * gu;
                P[1] = 5.0 * gv;
                P[2] = 0.0;
                s.w[i + (long)j * s.nu] = 2.0; /* equal weights: still the plane */
            }
        nf_seed_t g;
        double *pts = seed_grid(&s, &g);
        for (int t = 0; t < 100; t++) {
            double Q[3] = {ref_rand(-3, 13), ref_rand(-2, 7), ref_rand(-4, 4)};
            nf_proj_t pr;
            project(&s, &g, Q, &pr);
            double ue = fmin(fmax(Q[0] / 10.0, 0.0), 1.0), ve = fmin(fmax(Q[1] / 5.0, 0.0), 1.0);
            double foot[3] = {10.0 * ue, 5.0 * ve, 0.0};
            int outside = Q[0] < 0 || Q[0] > 10 || Q[1] < 0 || Q[1] > 5;
            assert_near(pr.u, ue, 1e-12);
            assert_near(pr.v, ve, 1e-12);
            assert_int_equal(pr.clamped, outside);
            /* n = Su x Sv = +z: the sign is z's, the size the distance. */
            assert_near(pr.dist, copysign(dist3(foot, Q), Q[2]), 1e-12);
        }
        free(pts);
        ref_surf_free(&s);
    }
}

/* D = |S(u, v) - Q|^2 with the parameters clamped to the domain. */
static double dsq(const nf_surf_t *s, double u, double v, const double Q[3])
{
    double u0, u1, v0, v1, P[3];
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    nf_surf_eval(s, fmin(fmax(u, u0), u1), fmin(fmax(v, v0), v1), P);
    double d = dist3(P, Q);
    return d * d;
}

/* (u, v) is a local minimum of the distance in the domain: no neighbour at
 * 1e-6 of the domain (8 directions) is closer. Unlike a gradient test this
 * holds on the creases of C0 surfaces too, where the minimum is a kink. */
static void assert_local_min(const nf_surf_t *s, const nf_proj_t *pr, const double Q[3])
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    const double D = dsq(s, pr->u, pr->v, Q), eu = 1e-6 * (u1 - u0), ev = 1e-6 * (v1 - v0);
    for (int k = 0; k < 8; k++) {
        static const int dir[8][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                      {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
        double Dn = dsq(s, pr->u + dir[k][0] * eu, pr->v + dir[k][1] * ev, Q);
        if (!(Dn >= D - 1e-10 * (1.0 + D)))
            fail_msg("(%.17g, %.17g) is no local minimum: D %.17g, at +(%d, %d) %.17g", pr->u,
                     pr->v, D, dir[k][0], dir[k][1], Dn);
    }
}

/* Arbitrary starts (anywhere, also outside the domain) and points anywhere
 * around the net: NF_OK, a local minimum of the distance, never further
 * than the start. */
static void test_any_start(void **state)
{
    (void)state;
    ref_seed(6006);
    int maxit = 0;
    for (int d = 1; d <= 5; d++) {
        nf_surf_t s;
        ref_surf_random(&s, d, d, d + 5, d + 4, 0.0, 3.0, 1.0, 2.0, 0.5, 2.0);
        double u0, u1, v0, v1;
        nf_surf_domain(&s, &u0, &u1, &v0, &v1);
        for (int t = 0; t < 300; t++) {
            double Q[3] = {ref_rand(-10, 10.0 * s.nu + 10), ref_rand(-10, 10.0 * s.nv + 10),
                           ref_rand(-20, 20)};
            double us = ref_rand(u0 - 1.0, u1 + 1.0), vs = ref_rand(v0 - 0.5, v1 + 0.5);
            nf_proj_t pr;
            int rc = nf_project(&s, Q, us, vs, TOL, &pr);
            assert_int_equal(rc, NF_OK);
            maxit = pr.iters > maxit ? pr.iters : maxit;
            assert_true(pr.dist * pr.dist <= dsq(&s, us, vs, Q) + 1e-12);
            assert_near(fabs(pr.dist), dist3(pr.foot, Q), 1e-12 * (1 + fabs(pr.dist)));
            assert_local_min(&s, &pr, Q);
        }
        ref_surf_free(&s);
    }
    print_message("arbitrary starts: at most %d iterations\n", maxit);
}

/* A collapsed edge (every control point of row v = v0 the same: Su = 0
 * there, no normal). Points near the surface around the pole, started from
 * the seed and from the pole with every u: the foot by construction, never
 * worse than brute force; the pole itself: distance 0, unsigned. */
static void test_degenerate_pole(void **state)
{
    (void)state;
    ref_seed(7007);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 7, 7, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    for (int i = 1; i < s.nu; i++)
        for (int c = 0; c < 3; c++)
            s.cp[3 * i + c] = s.cp[c];
    assert_int_equal(nf_surf_check(&s), NF_OK);
    nf_seed_t g;
    double *pts = seed_grid(&s, &g);
    brute_t b;
    brute_init(&b, &s);
    double worst = 0.0;
    int climbs = 0;
    for (int t = 0; t < 60; t++) {
        double us = ref_rand(0.05, 0.95), vs = ref_rand(0.02, 0.2), S[3], n[3], Su[3], Sv[3], Q[3],
               h = ref_rand(-0.05, 0.05);
        frame(&s, us, vs, S, n, Su, Sv);
        for (int c = 0; c < 3; c++)
            Q[c] = S[c] + h * n[c];
        nf_proj_t pr, pp;
        project(&s, &g, Q, &pr);
        double ub, vb, db = brute(&b, Q, &ub, &vb);
        assert_true(isfinite(pr.dist) && isfinite(pr.u) && isfinite(pr.v));
        if (!(fabs(pr.dist) <= db + TOL))
            print_message(
                "pole t %d: dist %.17g at (%.17g, %.17g), brute %.17g at (%.17g, %.17g)\n", t,
                pr.dist, pr.u, pr.v, db, ub, vb);
        assert_true(fabs(pr.dist) <= db + TOL);
        assert_near(pr.dist, h, TOL);
        /* From the pole, with the worst u on purpose (the one whose way out
         * of the pole climbs most): a local minimum, and if on the pole,
         * one that no way out of it improves (the 8-neighbour test sees
         * only the ways near the foot's u). */
        double uw = 0.0, gw = -INFINITY;
        for (int k = 0; k <= 64; k++) {
            double P[3], nn[3], Pu[3], Pv[3];
            frame(&s, k / 64.0, 0.0, P, nn, Pu, Pv);
            double r[3] = {P[0] - Q[0], P[1] - Q[1], P[2] - Q[2]};
            if (dot3(r, Pv) / sqrt(dot3(Pv, Pv)) > gw) {
                gw = dot3(r, Pv) / sqrt(dot3(Pv, Pv));
                uw = k / 64.0;
            }
        }
        climbs += gw > 0.0;
        assert_int_equal(nf_project(&s, Q, uw, 0.0, TOL, &pp), NF_OK);
        assert_local_min(&s, &pp, Q);
        if (pp.v == 0.0)
            for (int k = 0; k <= 64; k++)
                assert_true(dsq(&s, k / 64.0, 1e-6, Q) >= pp.dist * pp.dist - 1e-12);
        worst = fmax(worst, fabs(pp.dist) - fabs(pr.dist));
    }
    double pole[3] = {s.cp[0], s.cp[1], s.cp[2]};
    for (int t = 0; t < 5; t++) {
        nf_proj_t pr;
        assert_int_equal(nf_project(&s, pole, ref_rand(0, 1), ref_rand(0, 1), TOL, &pr), NF_OK);
        assert_true(fabs(pr.dist) <= 1e-12 && pr.dist >= 0.0);
        assert_near(pr.v, 0.0, 1e-9);
    }
    /* Points all around the pole (also behind the fan of ways out), from
     * the worst u: where that way climbs, stopping on the pole would be
     * wrong unless no way out descends. */
    for (int t = 0; t < 40; t++) {
        const double Q[3] = {s.cp[0] + ref_rand(-3, 3), s.cp[1] + ref_rand(-3, 3),
                             s.cp[2] + ref_rand(-3, 3)};
        double uw = 0.0, gw = -INFINITY;
        for (int k = 0; k <= 64; k++) {
            double P[3], nn[3], Pu[3], Pv[3];
            frame(&s, k / 64.0, 0.0, P, nn, Pu, Pv);
            double r[3] = {P[0] - Q[0], P[1] - Q[1], P[2] - Q[2]};
            if (dot3(r, Pv) / sqrt(dot3(Pv, Pv)) > gw) {
                gw = dot3(r, Pv) / sqrt(dot3(Pv, Pv));
                uw = k / 64.0;
            }
        }
        climbs += gw > 0.0;
        nf_proj_t pp;
        assert_int_equal(nf_project(&s, Q, uw, 0.0, TOL, &pp), NF_OK);
        assert_local_min(&s, &pp, Q);
        if (pp.v == 0.0)
            for (int k = 0; k <= 64; k++)
                assert_true(dsq(&s, k / 64.0, 1e-6, Q) >= pp.dist * pp.dist - 1e-12);
    }
    assert_true(climbs > 10); /* the escape was needed */
    print_message("pole: started on the pole (%d of 100 on a climbing way out), at most %.3g "
                  "further than from the seed\n",
                  climbs, worst);
    free(pts);
    free(b.P);
    ref_surf_free(&s);
}

/* A V-shaped valley of degree 1 (x = 10 u, crease at u = 1/2: z = 5 - x
 * left of it, x - 5 right): a point above it, right of the crease, has a
 * local minimum of the distance on each face, known in closed form. Newton
 * from the left face stops at the left one; the seeded projection (starts
 * on both sides of a crease near the foot) must return the nearer, right
 * one. */
static void test_crease_valley(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_surf_random(&s, 1, 1, 3, 2, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    const double U[] = {0, 0, 0.5, 1, 1}, V[] = {0, 0, 1, 1};
    for (int i = 0; i < 5; i++)
        s.U[i] = U[i];
    for (int j = 0; j < 4; j++)
        s.V[j] = V[j];
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            double *P = s.cp + 3 * (i + 3 * j);
            P[0] = 5.0 * i;
            P[1] = 10.0 * j;
            P[2] = i == 1 ? 0.0 : 5.0;
        }
    assert_int_equal(nf_surf_check(&s), NF_OK);
    const double Q[3] = {5.3, 5.0, 2.0};
    nf_proj_t left, best;
    assert_int_equal(nf_project(&s, Q, 0.3, 0.5, TOL, &left), NF_OK);
    assert_near(left.u, 0.415, 1e-12); /* foot (4.15, 5, 0.85) */
    assert_near(fabs(left.dist), 2.3 / sqrt(2.0), 1e-12);
    nf_seed_t g;
    double pts[NF_SEED_DOUBLES(2, 2)];
    nf_seed_init(&g, &s, 2, pts); /* corners only: no sample near either foot */
    assert_int_equal(nf_project_seeded(&g, Q, TOL, &best), NF_OK);
    assert_near(best.u, 0.615, 1e-12); /* foot (6.15, 5, 1.15) */
    assert_near(best.v, 0.5, 1e-12);
    assert_near(fabs(best.dist), 1.7 / sqrt(2.0), 1e-12);
    double *big = seed_grid(&s, &g);
    assert_int_equal(nf_project_seeded(&g, Q, TOL, &best), NF_OK);
    assert_near(best.u, 0.615, 1e-12);
    free(big);
    /* Both feet within a sample spacing of the crease, the nearer one on the
     * left: Q = (4.95, 5, 0.3) has its feet at u = 0.4825 (distance
     * 0.25/sqrt 2) and u = 0.5125 (0.35/sqrt 2). The single sample lies on
     * the crease, and Newton from there goes right; the restart across the
     * crease finds the left one. */
    const double Q2[3] = {4.95, 5.0, 0.3};
    double one[NF_SEED_DOUBLES(1, 1)];
    nf_seed_init(&g, &s, 1, one);
    assert_int_equal(nf_project(&s, Q2, 0.5, 0.5, TOL, &left), NF_OK);
    assert_near(left.u, 0.5125, 1e-12);
    assert_near(left.dist, 0.35 / sqrt(2.0), 1e-12);
    assert_int_equal(nf_project_seeded(&g, Q2, TOL, &best), NF_OK);
    assert_near(best.u, 0.4825, 1e-12);
    assert_near(best.v, 0.5, 1e-12);
    assert_near(best.dist, 0.25 / sqrt(2.0), 1e-12); /* n = (1, 0, 1)/sqrt 2 there */
    ref_surf_free(&s);
}

/* nf_seed_starts: the first start is nf_seed_start's, the others nearer
 * last, each a local minimum of the sample distance over the grid. */
static void test_seed_starts(void **state)
{
    (void)state;
    ref_seed(8118);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 8, 8, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    nf_seed_t g;
    double *pts = seed_grid(&s, &g);
    for (int t = 0; t < 100; t++) {
        double Q[3] = {ref_rand(-10, 80), ref_rand(-10, 80), ref_rand(-30, 30)}, u0, v0;
        double us[NF_SEED_MAX_STARTS], vs[NF_SEED_MAX_STARTS];
        int n = nf_seed_starts(&g, Q, NF_SEED_MAX_STARTS, us, vs);
        nf_seed_start(&g, Q, &u0, &v0);
        assert_true(n >= 1 && n <= NF_SEED_MAX_STARTS);
        assert_true(us[0] == u0 && vs[0] == v0);
        double prev = 0.0;
        for (int k = 0; k < n; k++) {
            double P[3];
            nf_surf_eval(&s, us[k], vs[k], P);
            assert_true(dist3(P, Q) >= prev - 1e-12);
            prev = dist3(P, Q);
        }
    }
    free(pts);
    ref_surf_free(&s);
}

/* The seed is the nearest of the samples, evaluated here independently. */
static void test_seed(void **state)
{
    (void)state;
    ref_seed(8008);
    nf_surf_t s;
    ref_surf_random(&s, 2, 3, 6, 7, -1.0, 1.0, 4.0, 8.0, 0.5, 2.0);
    for (int ns = 1; ns <= 17; ns += 4) {
        double *pts = malloc(sizeof(double) * 3 * (size_t)(ns * ns));
        nf_seed_t g;
        nf_seed_init(&g, &s, ns, pts);
        assert_int_equal(g.ns, ns);
        for (int t = 0; t < 50; t++) {
            double Q[3] = {ref_rand(-10, 60), ref_rand(-10, 70), ref_rand(-10, 10)}, u, v, P[3];
            nf_seed_start(&g, Q, &u, &v);
            nf_surf_eval(&s, u, v, P);
            double best = dist3(P, Q);
            for (int j = 0; j < ns; j++)
                for (int i = 0; i < ns; i++) {
                    double su = ns == 1 ? 0.0 : -1.0 + 2.0 * i / (ns - 1);
                    double sv = ns == 1 ? 6.0 : 4.0 + 4.0 * j / (ns - 1);
                    nf_surf_eval(&s, su, sv, P);
                    assert_true(best <= dist3(P, Q) + 1e-12);
                }
            assert_true(u >= -1.0 && u <= 1.0 && v >= 4.0 && v <= 8.0);
        }
        free(pts);
    }
    /* ns = 2: exactly the corners. */
    double pts[12], Q[3], u, v;
    nf_seed_t g;
    nf_seed_init(&g, &s, 2, pts);
    nf_surf_eval(&s, 1.0, 8.0, Q);
    nf_seed_start(&g, Q, &u, &v);
    assert_true(u == 1.0 && v == 8.0);
    ref_surf_free(&s);
}

static void test_arguments(void **state)
{
    (void)state;
    ref_seed(9009);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 5, 5, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    double Q[3] = {20.0, 20.0, 1.0};
    nf_proj_t pr;
    assert_int_equal(nf_project(NULL, Q, 0.5, 0.5, TOL, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, NULL, 0.5, 0.5, TOL, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, 0.5, TOL, NULL), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, 0.5, 0.0, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, 0.5, -1e-9, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, 0.5, NAN, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, 0.5, 1.0, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, NAN, 0.5, TOL, &pr), NF_EARG);
    assert_int_equal(nf_project(&s, Q, 0.5, INFINITY, TOL, &pr), NF_EARG);
    double Qn[3] = {1.0, NAN, 0.0}, Qi[3] = {1.0, 0.0, -INFINITY};
    assert_int_equal(nf_project(&s, Qn, 0.5, 0.5, TOL, &pr), NF_ENONFINITE);
    assert_int_equal(nf_project(&s, Qi, 0.5, 0.5, TOL, &pr), NF_ENONFINITE);
    /* A start outside the domain is clamped, not refused. */
    assert_int_equal(nf_project(&s, Q, -5.0, 7.0, TOL, &pr), NF_OK);
    assert_true(pr.u >= 0.0 && pr.u <= 1.0 && pr.v >= 0.0 && pr.v <= 1.0);
    ref_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normal_offsets),  cmocka_unit_test(test_against_brute_force),
        cmocka_unit_test(test_boundary),        cmocka_unit_test(test_on_surface),
        cmocka_unit_test(test_plane_exact),     cmocka_unit_test(test_any_start),
        cmocka_unit_test(test_degenerate_pole), cmocka_unit_test(test_crease_valley),
        cmocka_unit_test(test_seed_starts),     cmocka_unit_test(test_seed),
        cmocka_unit_test(test_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
