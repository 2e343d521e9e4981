/* SPDX-License-Identifier: MIT */
/* test_robust.c: robust reweighting that does no harm (issue 14), at the
 * nf_fit level against dense solves of Eq. 7 (ref_dense.c): on Gaussian
 * noise without outliers every weight stays 1 and the robust fit is the
 * plain least-squares one; on a clean part whose residuals are the fit's
 * own approximation error the floor keeps every point (without it a large
 * share is flagged); with 1 % gross outliers the robust fit is the dense
 * solve on the clean subset. */
#include "cf_test.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_robust.h"
#include "nf_solve.h"
#include "ref_dense.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ITERS 3 /* robust passes, as cellfit fit --robust */

/* Standard normal deviate (Box-Muller on ref_rand). */
static double gauss(void)
{
    const double a = 1.0 - ref_rand(0.0, 1.0), b = ref_rand(0.0, 1.0);
    return sqrt(-2.0 * log(a)) * cos(2.0 * 3.14159265358979323846 * b);
}

/* A copy of s (own storage) with its control points moved by up to d: the
 * nominal P0 the fit starts from. */
static double *nominal_of(const nf_surf_t *s, nf_surf_t *b, double d)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(s->nu, s->nv, s->p, s->q), sizeof(double));
    assert_non_null(mem);
    nf_surf_wire(b, s->p, s->q, s->nu, s->nv, mem);
    memcpy(b->U, s->U, sizeof(double) * (size_t)(s->nu + s->p + 1));
    memcpy(b->V, s->V, sizeof(double) * (size_t)(s->nv + s->q + 1));
    for (long k = 0; k < 3L * s->nu * s->nv; k++)
        b->cp[k] = s->cp[k] + ref_rand(-d, d);
    b->w = NULL;
    return mem;
}

/* nf_fit of the rows with weights w (NULL: all 1; weight 0: left out),
 * into P (3N). */
static void fit(const nf_surf_t *base, const double *pts, long M, const double *w, double *P)
{
    const nf_solver_t sv = NF_SOLVER_CHOL;
    const long need = nf_fit_bytes(base->nu, base->nv, base->p, base->q, sv);
    void *mem = malloc((size_t)need);
    assert_non_null(mem);
    nf_arena_t ar;
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_params_t prm = {NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, sv};
    nf_fit_t f;
    assert_int_equal(nf_fit_init(&f, base, &prm, &ar), NF_OK);
    for (long k = 0; k < M; k++) {
        const double *q = pts + 5 * k;
        const double wk = w ? w[k] : 1.0;
        if (wk > 0.0)
            assert_int_equal(nf_fit_add(&f, q[0], q[1], q + 2, wk), NF_OK);
    }
    assert_int_equal(nf_fit_finish(&f), NF_OK);
    nf_solve_opts_t o = {1e-14, 200000, 1};
    nf_solve_stats_t st;
    assert_int_equal(nf_fit_solve(&f, sv, &o, &st), NF_OK);
    memcpy(P, f.P, sizeof(double) * 3 * (size_t)f.n);
    free(mem);
}

/* The dense Eq. 7 solve of the rows (ref_eq7, Gaussian elimination). */
static void dense(const nf_surf_t *base, const double *pts, long M, double *P)
{
    double *A, *b;
    ref_eq7(base, pts, M, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, &A, &b);
    assert_int_equal(ref_solve(A, b, (long)base->nu * base->nv, P), 0);
    free(A);
    free(b);
}

/* |Q - S(u, v)| of row q to the surface base with control points P. */
static double resid(const nf_surf_t *base, const double *P, const double *q)
{
    nf_surf_t s = *base;
    s.cp = (double *)P;
    double S[3];
    nf_surf_eval(&s, q[0], q[1], S);
    return sqrt((q[2] - S[0]) * (q[2] - S[0]) + (q[3] - S[1]) * (q[3] - S[1]) +
                (q[4] - S[2]) * (q[4] - S[2]));
}

/* Largest distance between the surfaces with nets P1, P2 over a 51 x 51
 * parameter grid. */
static double surf_gap(const nf_surf_t *base, const double *P1, const double *P2)
{
    nf_surf_t a = *base, b = *base;
    a.cp = (double *)P1;
    b.cp = (double *)P2;
    double u0, u1, v0, v1, g = 0.0;
    nf_surf_domain(base, &u0, &u1, &v0, &v1);
    for (int j = 0; j <= 50; j++)
        for (int i = 0; i <= 50; i++) {
            double A[3], B[3];
            const double u = u0 + (u1 - u0) * i / 50.0, v = v0 + (v1 - v0) * j / 50.0;
            nf_surf_eval(&a, u, v, A);
            nf_surf_eval(&b, u, v, B);
            g = fmax(g, sqrt((A[0] - B[0]) * (A[0] - B[0]) + (A[1] - B[1]) * (A[1] - B[1]) +
                             (A[2] - B[2]) * (A[2] - B[2])));
        }
    return g;
}

/* The fit job's robust passes (host/cmd_fit.c): a plain fit, then ITERS
 * times the histogram of residuals to the last fit, the scale with the
 * floor, and a refit with the weights. *last: the last pass's counts. */
static void robust_fit(const nf_surf_t *base, const double *pts, long M, double floor, double *P,
                       nf_robust_t *last)
{
    double *w = malloc(sizeof(double) * (size_t)M);
    assert_non_null(w);
    fit(base, pts, M, NULL, P);
    for (int it = 0; it < ITERS; it++) {
        nf_rhist_t h;
        nf_rhist_init(&h);
        for (long k = 0; k < M; k++)
            nf_rhist_add(&h, resid(base, P, pts + 5 * k));
        assert_int_equal(nf_robust_init(last, &h, floor), NF_OK);
        for (long k = 0; k < M; k++)
            w[k] = nf_robust_weight(last, resid(base, P, pts + 5 * k));
        fit(base, pts, M, w, P);
    }
    free(w);
}

static double max_diff(const double *a, const double *b, long n, double *scale)
{
    double m = 0.0, s = 0.0;
    for (long i = 0; i < n; i++) {
        m = fmax(m, fabs(a[i] - b[i]));
        s = fmax(s, fabs(b[i]));
    }
    *scale = s;
    return m;
}

/* A smooth bicubic part on [0, 1]^2 with uniform knots: control points at
 * 10 mm spacing, heights a gentle wave, plus (bump > 0) a narrow bump of
 * that height at the centre. Own storage, returned for free(). */
static double *smooth_part(nf_surf_t *s, int nu, int nv, double bump)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, 3, 3), sizeof(double));
    assert_non_null(mem);
    nf_surf_wire(s, 3, 3, nu, nv, mem);
    for (int i = 0; i < nu + 4; i++)
        s->U[i] = i < 4 ? 0.0 : (i >= nu ? 1.0 : (double)(i - 3) / (nu - 3));
    for (int j = 0; j < nv + 4; j++)
        s->V[j] = j < 4 ? 0.0 : (j >= nv ? 1.0 : (double)(j - 3) / (nv - 3));
    s->w = NULL;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double x = 60.0 * i / (nu - 1), y = 60.0 * j / (nv - 1);
            const double r2 = (x - 30.0) * (x - 30.0) + (y - 30.0) * (y - 30.0);
            double *c = s->cp + 3 * (i + (long)j * nu);
            c[0] = x;
            c[1] = y;
            c[2] = 3.0 * sin(0.05 * x) * cos(0.04 * y) + bump * exp(-r2 / 20.0);
        }
    return mem;
}

/* M points at random parameters on t, Gaussian noise sigma per coordinate. */
static double *sample(const nf_surf_t *t, long M, double sigma)
{
    double *pts = malloc(sizeof(double) * 5 * (size_t)M);
    assert_non_null(pts);
    for (long k = 0; k < M; k++) {
        double *q = pts + 5 * k;
        q[0] = ref_rand(0.0, 1.0);
        q[1] = ref_rand(0.0, 1.0);
        nf_surf_eval(t, q[0], q[1], q + 2);
        for (int c = 0; c < 3; c++)
            q[2 + c] += sigma * gauss();
    }
    return pts;
}

/* Gaussian noise, no outliers: no weight below 1 in any pass, and the
 * robust fit is the plain dense solve (to the solver's precision). */
static void test_clean_noise_keeps_weight_one(void **state)
{
    (void)state;
    ref_seed(1411);
    nf_surf_t t, base;
    double *tm = smooth_part(&t, 7, 7, 0.0);
    double *bm = nominal_of(&t, &base, 0.5);
    const long M = 6000, n = 3L * base.nu * base.nv;
    const double sigma = 0.01;
    double *pts = sample(&t, M, sigma);
    double *P = malloc(sizeof(double) * (size_t)n), *X = malloc(sizeof(double) * (size_t)n);
    for (int withfloor = 0; withfloor < 2; withfloor++) {
        nf_robust_t rb;
        robust_fit(&base, pts, M, withfloor ? sigma : 0.0, P, &rb);
        dense(&base, pts, M, X);
        double sc, d = max_diff(P, X, n, &sc);
        print_message("gaussian noise %.3g, floor %.3g: scale %.4g (MAD sigma %.4g), %lld partial, "
                      "%lld flagged of %lld; robust - dense plain %.3g (net scale %.3g)\n",
                      sigma, rb.floor, rb.scale, rb.sigma, rb.partial, rb.flagged, rb.n, d, sc);
        assert_int_equal(rb.n, M);
        assert_int_equal(rb.partial, 0);
        assert_int_equal(rb.flagged, 0);
        assert_int_equal(nf_robust_warn(&rb), 0);
        assert_true(d <= 1e-9 * sc);
    }
    free(P);
    free(X);
    free(pts);
    free(bm);
    free(tm);
}

/* A clean part the net cannot represent exactly: the residuals are the
 * fit's approximation error, and the MAD scale is that error, not noise.
 * Without a floor the points of a bump the net cannot follow are flagged
 * and the fit moves away from the plain one (the harm of issue 14); with a
 * floor of a quarter of the tolerance (T = twice the plain fit's largest
 * residual) nothing is flagged and the robust fit stays within T / 10 of
 * the plain dense solve. */
static void test_floor_on_clean_part(void **state)
{
    (void)state;
    ref_seed(1412);
    nf_surf_t t, base;
    double *tm = smooth_part(&t, 31, 31, 0.5);    /* the part: a fine net with a bump */
    double *bm = smooth_part(&base, 10, 10, 0.0); /* the fit's space: no room for it */
    const long M = 5000, n = 3L * 100;
    double *pts = sample(&t, M, 0.0);
    double *P = malloc(sizeof(double) * (size_t)n), *X = malloc(sizeof(double) * (size_t)n);
    dense(&base, pts, M, X);
    double mx = 0.0;
    for (long k = 0; k < M; k++)
        mx = fmax(mx, resid(&base, X, pts + 5 * k));
    const double T = 2.0 * mx;
    nf_robust_t rb;
    robust_fit(&base, pts, M, 0.0, P, &rb);
    const double share0 = nf_robust_share(&rb), gap0 = surf_gap(&base, P, X);
    print_message("clean part: plain max residual %.4g mm; no floor: MAD sigma %.4g, %.1f %% "
                  "flagged, robust fit %.4g mm from the plain one\n",
                  mx, rb.sigma, 100.0 * share0, gap0);
    /* Without the floor: points of the bump flagged, the fit moved (the
     * harm of issue 14); the floor below is what removes it. */
    assert_true(rb.flagged > 0 && gap0 > 0.1 * 2.0 * mx);
    robust_fit(&base, pts, M, 0.25 * T, P, &rb);
    const double gap = surf_gap(&base, P, X);
    print_message("clean part, floor %.4g (T/4): %lld partial, %lld flagged, robust fit %.4g mm "
                  "from the plain one (T = %.4g)\n",
                  rb.floor, rb.partial, rb.flagged, gap, T);
    assert_int_equal(rb.flagged, 0);
    assert_int_equal(nf_robust_warn(&rb), 0);
    assert_true(gap <= 0.1 * T);
    free(P);
    free(X);
    free(pts);
    free(bm);
    free(tm);
}

/* 1 % gross outliers (1..5 mm along z, either sign) on Gaussian noise: the
 * last pass flags exactly the outliers, and the robust fit is the dense
 * solve on the clean subset; the plain fit is far from it. */
static void test_outliers_one_percent(void **state)
{
    (void)state;
    ref_seed(1413);
    nf_surf_t t, base;
    double *tm = smooth_part(&t, 7, 7, 0.0);
    double *bm = nominal_of(&t, &base, 0.5);
    const long M = 6000, n = 3L * base.nu * base.nv;
    const double sigma = 0.01;
    double *pts = sample(&t, M, sigma);
    double *clean = malloc(sizeof(double) * 5 * (size_t)M);
    long nc = 0, nout = 0;
    for (long k = 0; k < M; k++) {
        double *q = pts + 5 * k;
        if (k % 100 == 37) { /* 1 % */
            q[4] += (ref_rand(0, 1) < 0.5 ? -1.0 : 1.0) * ref_rand(1.0, 5.0);
            nout++;
        } else
            memcpy(clean + 5 * nc++, q, sizeof(double) * 5);
    }
    double *P = malloc(sizeof(double) * (size_t)n), *X = malloc(sizeof(double) * (size_t)n);
    double *Y = malloc(sizeof(double) * (size_t)n);
    nf_robust_t rb;
    robust_fit(&base, pts, M, sigma, P, &rb);
    dense(&base, clean, nc, X);
    fit(&base, pts, M, NULL, Y);
    double sc, d = max_diff(P, X, n, &sc);
    const double gap = surf_gap(&base, P, X), gap_plain = surf_gap(&base, Y, X);
    print_message("1 %% outliers (%ld of %ld): scale %.4g, %lld flagged (share %.4f), %lld "
                  "partial; robust - dense clean %.3g (net), %.3g mm (surface); plain fit %.3g "
                  "mm from it (noise %.3g)\n",
                  nout, M, rb.scale, rb.flagged, nf_robust_share(&rb), rb.partial, d, gap,
                  gap_plain, sigma);
    assert_int_equal(rb.flagged, nout);
    assert_int_equal(rb.partial, 0);
    assert_int_equal(nf_robust_warn(&rb), 0);
    assert_true(d <= 1e-9 * sc);
    assert_true(gap_plain > sigma); /* the outliers matter: the check can fail */
    free(P);
    free(X);
    free(Y);
    free(clean);
    free(pts);
    free(bm);
    free(tm);
}

static void test_arguments(void **state)
{
    (void)state;
    nf_rhist_t h;
    nf_rhist_init(&h);
    nf_robust_t rb;
    assert_int_equal(nf_robust_init(NULL, &h, 0.0), NF_EARG);
    assert_int_equal(nf_robust_init(&rb, NULL, 0.0), NF_EARG);
    assert_int_equal(nf_robust_init(&rb, &h, -1.0), NF_EARG);
    assert_int_equal(nf_robust_init(&rb, &h, NAN), NF_EARG);
    assert_int_equal(nf_robust_init(&rb, &h, INFINITY), NF_EARG);
    /* Empty histogram, no floor: an exact fit, every weight 1. */
    assert_int_equal(nf_robust_init(&rb, &h, 0.0), NF_OK);
    assert_true(nf_robust_weight(&rb, 1e3) == 1.0);
    assert_true(nf_robust_share(&rb) == 0.0);
    /* Floor 0.1: weight 1 to 0.3, 0 from 0.6, the biweight between. */
    assert_int_equal(nf_robust_init(&rb, &h, 0.1), NF_OK);
    assert_true(nf_robust_weight(&rb, -0.3) == 1.0);
    assert_near(nf_robust_weight(&rb, 0.45), 0.5625, 1e-12); /* t = 1/2: (3/4)^2 */
    assert_true(nf_robust_weight(&rb, 0.61) == 0.0);
    assert_true(nf_robust_weight(&rb, NAN) == 0.0);
    assert_int_equal(rb.n, 4);
    assert_int_equal(rb.flagged, 2);
    assert_int_equal(rb.partial, 1);
    assert_near(nf_robust_share(&rb), 0.5, 0.0);
    assert_int_equal(nf_robust_warn(&rb), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_clean_noise_keeps_weight_one),
        cmocka_unit_test(test_floor_on_clean_part),
        cmocka_unit_test(test_outliers_one_percent),
        cmocka_unit_test(test_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
