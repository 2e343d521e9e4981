/* SPDX-License-Identifier: MIT */
/* test_surfrow.c: cf_surfrow (rows of one v) against closed forms and
 * against nf_surf_eval (the plain per-point Eq. 1), in raster and random
 * order, on uniform and uneven knots, degrees 3 x 3 and 2 x 3, rational
 * surfaces (which it hands to nf_surf_eval), and the domain's edges. */
#include "cf_err.h"
#include "cf_surf.h"
#include "cf_surfrow.h"
#include "cf_test.h"
#include "nf_surf.h"
#include <stdlib.h>
#include <string.h>

static unsigned long long rng = 88172645463325252ULL;

static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* Clamped knots on [0, 1]; uneven: interior knots jittered. */
static void knots(double *K, int n, int p, int uneven)
{
    for (int i = 0; i <= p; i++) {
        K[i] = 0.0;
        K[n + i] = 1.0;
    }
    for (int i = p + 1; i < n; i++) {
        double t = (double)(i - p) / (n - p);
        K[i] = uneven ? t + 0.3 * (urand() - 0.5) / (n - p) : t;
    }
}

/* Greville abscissa of control point i: (K[i+1] + ... + K[i+p]) / p. */
static double greville(const double *K, int i, int p)
{
    double g = 0.0;
    for (int j = 1; j <= p; j++)
        g += K[i + j];
    return g / p;
}

static void make(nf_surf_t *s, int p, int q, int nu, int nv, int uneven, int linear)
{
    assert_int_equal(cf_surf_alloc(s, p, q, nu, nv), 0);
    knots(s->U, nu, p, uneven);
    knots(s->V, nv, q, uneven);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double *P = s->cp + 3 * (i + (long)j * nu);
            double a = greville(s->U, i, p), b = greville(s->V, j, q);
            P[0] = linear ? a : 100 * a;
            P[1] = linear ? b : 50 * b;
            P[2] = linear ? a + 2 * b : 10 * (urand() - 0.5);
        }
}

/* Raster (rows of one v, some points repeated) then random order. */
static void points(double *uv, long n, int raster)
{
    long side = (long)sqrt((double)n);
    for (long k = 0; k < n; k++) {
        if (raster) {
            uv[2 * k] = (double)(k % side) / (side - 1);
            uv[2 * k + 1] = (double)(k / side) / (side - 1);
        } else {
            uv[2 * k] = urand();
            uv[2 * k + 1] = urand();
        }
    }
    uv[0] = -0.25; /* clamped to the domain, like nf_surf_eval */
    uv[2 * n - 1] = 1.5;
}

/* Linear precision: P_ij = (xi_i, eta_j, xi_i + 2 eta_j) gives S(u, v) =
 * (u, v, u + 2 v) exactly, on any knots (closed form). */
static void test_linear_precision(void **state)
{
    (void)state;
    for (int uneven = 0; uneven <= 1; uneven++)
        for (int raster = 0; raster <= 1; raster++) {
            nf_surf_t s;
            make(&s, 3, 3, 23, 17, uneven, 1);
            cf_surfrow_t e;
            assert_int_equal(cf_surfrow_init(&e, &s), CF_OK);
            enum { M = 40000 };
            static double uv[2 * M];
            points(uv, M, raster);
            for (long k = 0; k < M; k++) {
                double P[3], u = fmin(fmax(uv[2 * k], 0), 1), v = fmin(fmax(uv[2 * k + 1], 0), 1);
                cf_surfrow_eval(&e, uv[2 * k], uv[2 * k + 1], P);
                assert_near(P[0], u, 1e-14);
                assert_near(P[1], v, 1e-14);
                assert_near(P[2], u + 2 * v, 4e-14);
            }
            cf_surfrow_free(&e);
            cf_surf_free(&s);
        }
}

/* Any net: the same point as nf_surf_eval to rounding. */
static void check_vs_eval(int p, int q, int nu, int nv, int uneven, int rational)
{
    nf_surf_t s;
    make(&s, p, q, nu, nv, uneven, 0);
    if (rational)
        for (long i = 0; i < (long)nu * nv; i++)
            s.w[i] = 0.5 + urand();
    nf_surf_t *use = &s;
    double *w = s.w;
    if (!rational && (nu & 1))
        s.w = NULL; /* polynomial; even nu: weights all 1 (as IGES gives), polynomial too */
    cf_surfrow_t e;
    assert_int_equal(cf_surfrow_init(&e, use), CF_OK);
    enum { M = 60000 };
    static double uv[2 * M];
    for (int raster = 0; raster <= 1; raster++) {
        points(uv, M, raster);
        for (long k = 0; k < M; k++) {
            double P[3], Q[3];
            cf_surfrow_eval(&e, uv[2 * k], uv[2 * k + 1], P);
            nf_surf_eval(use, uv[2 * k], uv[2 * k + 1], Q);
            for (int c = 0; c < 3; c++)
                if (rational)
                    assert_memory_equal(&P[c], &Q[c], sizeof(double));
                else
                    assert_near(P[c], Q[c], 1e-12);
        }
    }
    cf_surfrow_free(&e);
    s.w = w;
    cf_surf_free(&s);
}

static void test_same_as_nf_surf_eval(void **state)
{
    (void)state;
    check_vs_eval(3, 3, 10, 10, 0, 0);
    check_vs_eval(3, 3, 11, 10, 0, 0);
    check_vs_eval(3, 3, 41, 29, 1, 0);
    check_vs_eval(2, 3, 12, 31, 1, 0);
    check_vs_eval(3, 2, 4, 5, 0, 0); /* one span per direction */
    check_vs_eval(3, 3, 15, 12, 1, 1);
}

/* Along one row: the inline case (same row, same u span) must not take a
 * u past the domain's end unclamped, nor one on the span's far knot; a
 * row's first point (no row set-up) and the ones after agree with
 * nf_surf_eval, on uniform and uneven knots. */
static void test_row_walk_edges(void **state)
{
    (void)state;
    for (int uneven = 0; uneven <= 1; uneven++) {
        nf_surf_t s;
        make(&s, 3, 3, 11, 9, uneven, 0);
        double *w = s.w;
        s.w = NULL; /* polynomial */
        cf_surfrow_t e;
        assert_int_equal(cf_surfrow_init(&e, &s), CF_OK);
        const double k1 = s.U[s.nu - 1]; /* the last span's start */
        const double u[] = {0.97,  0.99, 1.0,    nextafter(1.0, 2.0),   1.25,
                            0.999, 1.5,  k1,     nextafter(k1, 0.0),    0.5 * (k1 + 1.0),
                            -0.5,  0.0,  s.U[4], nextafter(s.U[4], 0.0)};
        for (int row = 0; row < 3; row++) {
            const double v = row == 0 ? 0.5 : row == 1 ? 1.0 : -3.0;
            for (size_t k = 0; k < sizeof u / sizeof u[0]; k++) {
                double P[3], Q[3];
                cf_surfrow_eval(&e, u[k], v, P);
                nf_surf_eval(&s, u[k], v, Q);
                for (int c = 0; c < 3; c++)
                    assert_near(P[c], Q[c], 1e-12);
            }
        }
        cf_surfrow_free(&e);
        s.w = w;
        cf_surf_free(&s);
    }
}

/* Knots far from 0 in v (1e18 + 256 j: V[q] - 1 is V[q] there): the first
 * row, at the domain's start, is computed, not taken for a row already
 * seen (it was, and read columns never computed: garbage, valgrind's
 * uninitialised values). */
static void test_far_knots(void **state)
{
    (void)state;
    nf_surf_t s;
    make(&s, 3, 3, 7, 6, 0, 0);
    double *w = s.w;
    s.w = NULL; /* polynomial */
    for (int i = 0; i < s.nv + s.q + 1; i++) {
        const int j = i < s.q ? 0 : i > s.nv ? s.nv - s.q : i - s.q;
        s.V[i] = 1e18 + 256.0 * j;
    }
    assert_true(s.V[s.q] - 1.0 == s.V[s.q]);
    cf_surfrow_t e;
    assert_int_equal(cf_surfrow_init(&e, &s), CF_OK);
    const double v[] = {s.V[s.q], s.V[s.q], s.V[s.q + 1], s.V[s.nv]};
    for (size_t r = 0; r < sizeof v / sizeof v[0]; r++)
        for (int k = 0; k <= 8; k++) {
            double P[3], Q[3];
            cf_surfrow_eval(&e, k / 8.0, v[r], P);
            nf_surf_eval(&s, k / 8.0, v[r], Q);
            for (int c = 0; c < 3; c++)
                assert_near(P[c], Q[c], 1e-9);
        }
    cf_surfrow_free(&e);
    s.w = w;
    cf_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_knots),
        cmocka_unit_test(test_linear_precision),
        cmocka_unit_test(test_same_as_nf_surf_eval),
        cmocka_unit_test(test_row_walk_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
