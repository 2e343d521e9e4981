/* SPDX-License-Identifier: MIT */
/* test_coons.c: boundary curves, Coons base surfaces and the plane base
 * (Piegl & Tiller 2001, Section 2; nf_curve, nf_coons, nf_base), and IGES
 * entity 126. References are independent: the Cox-de Boor recursion for
 * curves, the true surface the curves and points come from, closed forms
 * (bilinear patch of four lines, eigenvectors of a rotated diagonal). */
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_base.h"
#include "nf_basis.h"
#include "nf_coons.h"
#include "nf_curve.h"
#include "nf_err.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------ helpers */

static void curve_alloc(nf_curve_t *c, int p, int n)
{
    nf_curve_wire(c, p, n, calloc((size_t)NF_CURVE_DOUBLES(n, p), sizeof(double)));
}

static void curve_free(nf_curve_t *c)
{
    free(c->U);
    memset(c, 0, sizeof *c);
}

/* C(u) by the recursive definition (ref_bspline), rational. */
static void ref_curve(const nf_curve_t *c, double u, double out[3])
{
    double W = 0.0, h[3] = {0, 0, 0};
    for (int i = 0; i < c->n; i++) {
        double b = ref_bspline(i, c->p, c->U, c->n + c->p + 1, u) * (c->w ? c->w[i] : 1.0);
        W += b;
        for (int k = 0; k < 3; k++)
            h[k] += b * c->cp[3 * i + k];
    }
    for (int k = 0; k < 3; k++)
        out[k] = h[k] / W;
}

/* A random clamped curve on [a, b]: interior knots random (one doubled
 * when there is room), points a wiggly line, weights in [wlo, whi]. */
static void random_curve(nf_curve_t *c, int p, int n, double a, double b, double wlo, double whi)
{
    curve_alloc(c, p, n);
    for (int i = 0; i <= p; i++) {
        c->U[i] = a;
        c->U[n + i] = b;
    }
    for (int i = p + 1; i < n; i++)
        c->U[i] = a + (b - a) * ref_rand(0.05, 0.95);
    for (int i = p + 2; i < n; i++) /* insertion sort */
        for (int j = i; j > p + 1 && c->U[j] < c->U[j - 1]; j--) {
            double t = c->U[j];
            c->U[j] = c->U[j - 1];
            c->U[j - 1] = t;
        }
    if (n - p >= 3 && p >= 2)
        c->U[p + 2] = c->U[p + 1];
    for (int i = 0; i < n; i++) {
        c->cp[3 * i] = 10.0 * i + ref_rand(-2, 2);
        c->cp[3 * i + 1] = ref_rand(-3, 3);
        c->cp[3 * i + 2] = ref_rand(-3, 3);
        c->w[i] = ref_rand(wlo, whi);
    }
}

static double d3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* Row j (which = 0) or column i (which = 1) of a surface's net as a curve. */
static void iso_curve(const nf_surf_t *s, int which, int idx, nf_curve_t *c)
{
    int p = which ? s->q : s->p, n = which ? s->nv : s->nu;
    curve_alloc(c, p, n);
    memcpy(c->U, which ? s->V : s->U, sizeof(double) * (size_t)(n + p + 1));
    for (int k = 0; k < n; k++) {
        long at = which ? idx + (long)k * s->nu : k + (long)idx * s->nu;
        memcpy(c->cp + 3 * k, s->cp + 3 * at, 3 * sizeof(double));
        c->w[k] = s->w ? s->w[at] : 1.0;
    }
}

/* The four boundary curves of s: C0 (v = v0), C1 (v = v1), D0 (u = u0), D1. */
static void boundary(const nf_surf_t *s, nf_curve_t c[4])
{
    iso_curve(s, 0, 0, &c[0]);
    iso_curve(s, 0, s->nv - 1, &c[1]);
    iso_curve(s, 1, 0, &c[2]);
    iso_curve(s, 1, s->nu - 1, &c[3]);
}

static double *prep(nf_coons_t *cs, const nf_curve_t c[4], int pmin, double tol, int *rc)
{
    long need = nf_coons_doubles(c, pmin);
    assert_true(need > 0);
    double *mem = malloc(sizeof(double) * (size_t)need);
    *rc = nf_coons_prepare(cs, c, pmin, tol, mem, need);
    return mem;
}

static void surf_for(const nf_coons_t *cs, nf_surf_t *s)
{
    int p, q, nu, nv;
    nf_coons_size(cs, &p, &q, &nu, &nv);
    nf_surf_wire(s, p, q, nu, nv, malloc(sizeof(double) * (size_t)NF_SURF_DOUBLES(nu, nv, p, q)));
}

/* ------------------------------------------------------------- curves */

static void test_curve_eval_and_derivs(void **state)
{
    (void)state;
    ref_seed(11);
    nf_curve_t c;
    random_curve(&c, 3, 9, -1.0, 2.0, 0.5, 2.0);
    assert_int_equal(nf_curve_check(&c), NF_OK);
    for (int k = 0; k <= 100; k++) {
        double u = -1.0 + 3.0 * k / 100, P[3], R[3], ck[9], cp[9], cm[9];
        nf_curve_eval(&c, u, P);
        ref_curve(&c, u, R);
        assert_true(d3(P, R) <= 1e-12 * 30);
        /* Derivatives against central differences (away from knots the
         * curve is smooth; h small against the spans). */
        double h = 1e-5;
        if (u - 2 * h < -1.0 || u + 2 * h > 2.0)
            continue;
        int near_knot = 0;
        for (int i = 0; i < c.n + c.p + 1; i++)
            near_knot |= fabs(c.U[i] - u) < 3 * h;
        if (near_knot)
            continue;
        nf_curve_derivs(&c, u, 2, ck);
        nf_curve_derivs(&c, u + h, 1, cp);
        nf_curve_derivs(&c, u - h, 1, cm);
        for (int m = 0; m < 3; m++) {
            double fd1 = (cp[m] - cm[m]) / (2 * h), fd2 = (cp[3 + m] - cm[3 + m]) / (2 * h);
            assert_near(ck[3 + m], fd1, 1e-5 * (1 + fabs(fd1)));
            assert_near(ck[6 + m], fd2, 1e-4 * (1 + fabs(fd2)));
        }
    }
    curve_free(&c);
}

static void test_curve_elevate_refine_reverse(void **state)
{
    (void)state;
    ref_seed(12);
    for (int p = 1; p <= 3; p++)
        for (int t = 0; t + p <= NF_MAX_DEGREE; t++) {
            nf_curve_t c, e, r;
            random_curve(&c, p, p + 5, 0.5, 3.0, 0.4, 2.5);
            int ne = nf_curve_elevate_size(&c, t);
            curve_alloc(&e, p + t, ne);
            assert_int_equal(nf_curve_elevate(&c, t, &e), NF_OK);
            assert_int_equal(nf_curve_check(&e), NF_OK);
            double X[4] = {0.7, 1.3, 2.1, 2.9};
            curve_alloc(&r, p + t, ne + 4);
            assert_int_equal(nf_curve_refine(&e, X, 4, &r), NF_OK);
            for (int k = 0; k <= 200; k++) {
                double u = 0.5 + 2.5 * k / 200, A[3], B[3], C[3];
                ref_curve(&c, u, A);
                ref_curve(&e, u, B);
                ref_curve(&r, u, C);
                if (d3(A, B) > 1e-12 * 60 || d3(A, C) > 1e-12 * 60)
                    fail_msg("p %d t %d u %g: elevate %.3g, refine %.3g", p, t, u, d3(A, B),
                             d3(A, C));
            }
            nf_curve_reverse(&r);
            for (int k = 0; k <= 50; k++) {
                double u = 0.5 + 2.5 * k / 50, A[3], B[3];
                ref_curve(&c, u, A);
                nf_curve_eval(&r, 3.5 - u, B);
                assert_true(d3(A, B) <= 1e-12 * 60);
            }
            curve_free(&c);
            curve_free(&e);
            curve_free(&r);
        }
}

/* --------------------------------------------------------- bilinear */

/* Coons of the true surface's boundary, curves given shuffled and some
 * reversed: on the boundary it is the surface, to 1e-12. */
static void check_boundary(const nf_surf_t *coons, const nf_surf_t *truth, double tol)
{
    double u0, u1, v0, v1;
    nf_surf_domain(truth, &u0, &u1, &v0, &v1);
    for (int k = 0; k <= 100; k++) {
        double s = k / 100.0, A[3], B[3];
        double uv[4][4] = {{s, 0, u0 + s * (u1 - u0), v0},
                           {s, 1, u0 + s * (u1 - u0), v1},
                           {0, s, u0, v0 + s * (v1 - v0)},
                           {1, s, u1, v0 + s * (v1 - v0)}};
        for (int e = 0; e < 4; e++) {
            nf_surf_eval(coons, uv[e][0], uv[e][1], A);
            nf_surf_eval(truth, uv[e][2], uv[e][3], B);
            if (d3(A, B) > tol)
                fail_msg("edge %d at %g: |Coons - curve| = %.3g", e, s, d3(A, B));
        }
    }
}

static void test_bilinear_reproduces_boundary(void **state)
{
    (void)state;
    ref_seed(21);
    for (int rational = 0; rational < 2; rational++) {
        nf_surf_t t;
        ref_surf_random(&t, 3, 2, 8, 6, -1.0, 2.0, 0.0, 5.0, rational ? 0.5 : 1.0,
                        rational ? 2.0 : 1.0);
        nf_curve_t b[4], in[4];
        boundary(&t, b);
        /* Shuffle: C1 first (reversed), then D1, C0 reversed, D0; rational
         * curves with their weights scaled by unrelated factors. */
        in[0] = b[1];
        in[1] = b[3];
        in[2] = b[0];
        in[3] = b[2];
        nf_curve_reverse(&in[0]);
        nf_curve_reverse(&in[2]);
        if (rational) {
            nf_curve_scale_weights(&in[1], 3.0);
            nf_curve_scale_weights(&in[3], 0.25);
        }
        nf_coons_t cs;
        int rc;
        double *mem = prep(&cs, in, 1, 1e-9, &rc);
        assert_int_equal(rc, NF_OK);
        nf_surf_t s;
        surf_for(&cs, &s);
        assert_int_equal(nf_coons_bilinear(&cs, &s), NF_OK);
        assert_int_equal(nf_surf_check(&s), NF_OK);
        /* in[0] (C1 reversed) became C0: the pairing starts from it. */
        assert_int_equal(cs.from[0], 0);
        nf_surf_t tr; /* the truth seen from the Coons orientation */
        ref_surf_random(&tr, 3, 2, 8, 6, -1.0, 2.0, 0.0, 5.0, 1, 1); /* storage only */
        /* C0 = reversed C1 of t: Coons (s, 0) = t(u1 - s du, v1); check via
         * a flipped copy of t. */
        memcpy(tr.cp, t.cp, sizeof(double) * 3 * 48);
        memcpy(tr.w, t.w, sizeof(double) * 48);
        memcpy(tr.U, t.U, sizeof(double) * 12);
        memcpy(tr.V, t.V, sizeof(double) * 9);
        for (int j = 0; j < 6; j++)
            for (int i = 0; i < 8; i++) {
                long a = i + 8L * j, bb = (7 - i) + 8L * (5 - j);
                memcpy(tr.cp + 3 * a, t.cp + 3 * bb, 3 * sizeof(double));
                tr.w[a] = t.w[bb];
            }
        for (int i = 0; i < 12; i++)
            tr.U[i] = 1.0 - t.U[11 - i]; /* -1 + 2 - u */
        for (int j = 0; j < 9; j++)
            tr.V[j] = 5.0 - t.V[8 - j];
        check_boundary(&s, &tr, 1e-12 * 100);
        free(mem);
        free(s.U);
        for (int k = 0; k < 4; k++)
            curve_free(&b[k]);
        ref_surf_free(&t);
        ref_surf_free(&tr);
    }
}

/* Curves of different degrees and knots (a line, a quadratic, two cubics
 * with their own knots): made compatible, still reproduced exactly. */
static void test_bilinear_mixed_curves(void **state)
{
    (void)state;
    ref_seed(22);
    nf_curve_t c[4];
    random_curve(&c[0], 3, 7, 0.0, 1.0, 1, 1);
    random_curve(&c[1], 2, 5, 0.0, 4.0, 1, 1);
    random_curve(&c[2], 1, 2, 0.0, 1.0, 1, 1);
    random_curve(&c[3], 3, 6, -2.0, 0.0, 1, 1);
    /* Corners: C0(0) = D0(0), C0(1) = D1(0), C1(0) = D0(1), C1(1) = D1(1). */
    double *c0s = c[0].cp, *c0e = c[0].cp + 3 * 6, *c1s = c[1].cp, *c1e = c[1].cp + 3 * 4;
    for (int k = 0; k < 3; k++) {
        c1s[k] += 5.0 * (k == 1);
        c1e[k] = c0e[k] + 4.0 * (k == 1) + 1.0 * (k == 2);
        c[2].cp[k] = c0s[k];
        c[2].cp[3 + k] = c1s[k];
        c[3].cp[k] = c0e[k];
        c[3].cp[15 + k] = c1e[k];
    }
    nf_coons_t cs;
    int rc;
    double *mem = prep(&cs, c, 1, 1e-12, &rc);
    assert_int_equal(rc, NF_OK);
    nf_surf_t s;
    surf_for(&cs, &s);
    assert_int_equal(s.p, 3);
    assert_int_equal(s.q, 3);
    assert_int_equal(nf_coons_bilinear(&cs, &s), NF_OK);
    for (long i = 0; i < (long)s.nu * s.nv; i++)
        assert_true(s.w[i] == 1.0); /* polynomial curves: a polynomial patch */
    for (int k = 0; k <= 200; k++) {
        double t = k / 200.0, A[3], B[3];
        static const double a[4] = {0, 0, 0, -2}, len[4] = {1, 4, 1, 2};
        for (int e = 0; e < 4; e++) {
            nf_surf_eval(&s, e < 2 ? t : (e == 2 ? 0 : 1), e < 2 ? (e ? 1 : 0) : t, A);
            ref_curve(&c[e], a[e] + len[e] * t, B);
            if (d3(A, B) > 1e-12 * 100)
                fail_msg("curve %d at %g: %.3g", e, t, d3(A, B));
        }
    }
    free(mem);
    free(s.U);
    for (int k = 0; k < 4; k++)
        curve_free(&c[k]);
}

/* Four straight lines: the bilinear patch (1-u)(1-v)P00 + u(1-v)P10 + ... */
static void test_bilinear_of_lines(void **state)
{
    (void)state;
    const double P[4][3] = {{0, 0, 0}, {10, 1, 2}, {-1, 8, 1}, {12, 9, -3}}; /* 00 10 01 11 */
    nf_curve_t c[4];
    const int ends[4][2] = {{0, 1}, {2, 3}, {0, 2}, {1, 3}};
    for (int k = 0; k < 4; k++) {
        /* Degree 2 with the middle point at the midpoint: still linear in u. */
        curve_alloc(&c[k], 2, 3);
        double U[6] = {0, 0, 0, 1, 1, 1};
        memcpy(c[k].U, U, sizeof U);
        for (int m = 0; m < 3; m++) {
            c[k].cp[m] = P[ends[k][0]][m];
            c[k].cp[6 + m] = P[ends[k][1]][m];
            c[k].cp[3 + m] = 0.5 * (P[ends[k][0]][m] + P[ends[k][1]][m]);
        }
    }
    nf_coons_t cs;
    int rc;
    double *mem = prep(&cs, c, 1, 1e-12, &rc);
    assert_int_equal(rc, NF_OK);
    nf_surf_t s;
    surf_for(&cs, &s);
    assert_int_equal(nf_coons_bilinear(&cs, &s), NF_OK);
    for (int i = 0; i <= 20; i++)
        for (int j = 0; j <= 20; j++) {
            double u = i / 20.0, v = j / 20.0, S[3], B[3];
            nf_surf_eval(&s, u, v, S);
            for (int m = 0; m < 3; m++)
                B[m] = (1 - u) * (1 - v) * P[0][m] + u * (1 - v) * P[1][m] + (1 - u) * v * P[2][m] +
                       u * v * P[3][m];
            assert_true(d3(S, B) <= 1e-12 * 20);
        }
    free(mem);
    free(s.U);
    for (int k = 0; k < 4; k++)
        curve_free(&c[k]);
}

/* ----------------------------------------------------------- bicubic */

static double max_err(const nf_surf_t *a, const nf_surf_t *truth)
{
    double m = 0.0;
    for (int i = 0; i <= 40; i++)
        for (int j = 0; j <= 40; j++) {
            double A[3], B[3];
            nf_surf_eval(a, i / 40.0, j / 40.0, A);
            nf_surf_eval(truth, i / 40.0, j / 40.0, B);
            m = fmax(m, d3(A, B));
        }
    return m;
}

/* Fit the bicubic Coons of truth's boundary to npts points of truth at
 * random parameters; return the fit in *b (storage in *mem). */
static void bicubic_of(const nf_surf_t *truth, nf_coons_t *cs, nf_coons3_t *b, double **mem,
                       double **mem3, long npts, int scale)
{
    nf_curve_t c[4];
    boundary(truth, c);
    int rc;
    *mem = prep(cs, c, 3, 1e-9, &rc);
    assert_int_equal(rc, NF_OK);
    int K = nf_coons3_unknowns(cs);
    long need = NF_COONS3_DOUBLES(K, cs->c[0].n, cs->c[2].n);
    *mem3 = malloc(sizeof(double) * (size_t)need);
    assert_int_equal(nf_coons3_init(b, cs, *mem3, need), NF_OK);
    for (long k = 0; k < npts; k++) {
        double u = ref_rand(0, 1), v = ref_rand(0, 1), Q[3];
        nf_surf_eval(truth, u, v, Q);
        assert_int_equal(nf_coons3_add(b, u, v, Q), NF_OK);
    }
    assert_int_equal(nf_coons3_solve(b), NF_OK);
    if (scale)
        nf_coons3_scale(b);
    for (int k = 0; k < 4; k++)
        curve_free(&c[k]);
}

/* A single bicubic patch is a bicubic Coons patch: fitted from its own
 * points, the cross derivatives are the surface's, the patch is the
 * surface. */
static void test_bicubic_reproduces_bicubic(void **state)
{
    (void)state;
    ref_seed(31);
    nf_surf_t t;
    ref_surf_random(&t, 3, 3, 4, 4, 0, 1, 0, 1, 1, 1);
    t.w = NULL;
    nf_coons_t cs;
    nf_coons3_t b;
    double *mem, *mem3;
    bicubic_of(&t, &cs, &b, &mem, &mem3, 200, 0);
    nf_surf_t s;
    surf_for(&cs, &s);
    assert_int_equal(nf_coons3_surface(&b, &s), NF_OK);
    assert_true(max_err(&s, &t) <= 1e-9);
    /* Cross derivatives along all four edges match the surface's. */
    for (int k = 0; k <= 20; k++) {
        double x = k / 20.0, dt[27], dc[27];
        double uv[4][2] = {{x, 0}, {x, 1}, {0, x}, {1, x}};
        for (int e = 0; e < 4; e++) {
            nf_surf_derivs(&t, uv[e][0], uv[e][1], 1, dt);
            nf_surf_derivs(&s, uv[e][0], uv[e][1], 1, dc);
            const double *a = e < 2 ? dt + 3 : dt + 9, *c = e < 2 ? dc + 3 : dc + 9;
            assert_true(d3(a, c) <= 1e-8);
        }
    }
    free(mem);
    free(mem3);
    free(s.U);
    ref_surf_free(&t);
}

/* A B-spline surface with interior knots is not a Coons patch, but the
 * bicubic one (derivatives fitted to a 10 % subset) is much nearer to it
 * than the bilinear one; the definition and the NURBS net agree; the
 * corners are twist compatible. */
static void test_bicubic_beats_bilinear(void **state)
{
    (void)state;
    ref_seed(32);
    nf_surf_t t;
    ref_surf_random(&t, 3, 3, 8, 7, 0, 1, 0, 1, 1, 1);
    t.w = NULL;
    /* A bulge in the middle that the boundary does not see. */
    for (int j = 2; j < 5; j++)
        for (int i = 2; i < 6; i++)
            t.cp[3 * (i + 8L * j) + 2] += 3.0;
    nf_coons_t cs;
    nf_coons3_t b;
    double *mem, *mem3;
    bicubic_of(&t, &cs, &b, &mem, &mem3, 2000, 0);
    nf_surf_t s3, s1;
    surf_for(&cs, &s3);
    assert_int_equal(nf_coons3_surface(&b, &s3), NF_OK);
    surf_for(&cs, &s1);
    assert_int_equal(nf_coons_bilinear(&cs, &s1), NF_OK);
    double e3 = max_err(&s3, &t), e1 = max_err(&s1, &t);
    print_message("bicubic Coons max error %.4g, bilinear %.4g (ratio %.1f)\n", e3, e1, e1 / e3);
    assert_true(e3 * 4 < e1);
    check_boundary(&s3, &t, 1e-12 * 100);
    for (int i = 0; i <= 10; i++)
        for (int j = 0; j <= 10; j++) {
            double A[3], B[3];
            nf_surf_eval(&s3, i / 10.0, j / 10.0, A);
            nf_coons3_eval(&b, i / 10.0, j / 10.0, B);
            assert_true(d3(A, B) <= 1e-10);
        }
    /* Twist compatibility: at each corner S_uv of the patch equals the
     * derivative of both cross-derivative curves meeting there. */
    nf_curve_t E0 = {s3.p, s3.nu, s3.U, b.e0, NULL}, E1 = {s3.p, s3.nu, s3.U, b.e1, NULL};
    nf_curve_t F0 = {s3.q, s3.nv, s3.V, b.f0, NULL}, F1 = {s3.q, s3.nv, s3.V, b.f1, NULL};
    const nf_curve_t *ec[4] = {&E0, &E0, &E1, &E1}, *fc[4] = {&F0, &F1, &F0, &F1};
    for (int c = 0; c < 4; c++) {
        double u = c & 1, v = c >> 1, sd[27], de[9], df[9];
        nf_surf_derivs(&s3, u, v, 2, sd);
        nf_curve_derivs(ec[c], u, 1, de);
        nf_curve_derivs(fc[c], v, 1, df);
        const double *suv = sd + 3 * (1 * 3 + 1);
        if (d3(suv, de + 3) > 1e-8 * (1 + d3(suv, (double[3]){0, 0, 0})) ||
            d3(suv, df + 3) > 1e-8 * (1 + d3(suv, (double[3]){0, 0, 0})))
            fail_msg("corner %d: S_uv %g %g %g, E' %g %g %g, F' %g %g %g", c, suv[0], suv[1],
                     suv[2], de[3], de[4], de[5], df[3], df[4], df[5]);
    }
    free(mem);
    free(mem3);
    free(s1.U);
    free(s3.U);
    ref_surf_free(&t);
}

/* The paper's derivative scaling changes the cross derivatives, not the
 * boundary curves. */
static void test_bicubic_scaled_keeps_boundary(void **state)
{
    (void)state;
    ref_seed(33);
    nf_surf_t t;
    ref_surf_random(&t, 3, 3, 7, 6, 0, 1, 0, 1, 1, 1);
    t.w = NULL;
    nf_coons_t cs;
    nf_coons3_t b;
    double *mem, *mem3;
    bicubic_of(&t, &cs, &b, &mem, &mem3, 1000, 1);
    nf_surf_t s;
    surf_for(&cs, &s);
    assert_int_equal(nf_coons3_surface(&b, &s), NF_OK);
    check_boundary(&s, &t, 1e-12 * 100);
    for (int k = 0; k < 4; k++)
        assert_true(b.s[k] > 0.0 && b.s[k] != 1.0);
    free(mem);
    free(mem3);
    free(s.U);
    ref_surf_free(&t);
}

static void test_bicubic_refusals(void **state)
{
    (void)state;
    ref_seed(34);
    nf_surf_t t;
    ref_surf_random(&t, 3, 3, 5, 5, 0, 1, 0, 1, 0.5, 2.0); /* rational */
    nf_curve_t c[4];
    boundary(&t, c);
    nf_coons_t cs;
    int rc;
    double *mem = prep(&cs, c, 3, 1e-9, &rc);
    assert_int_equal(rc, NF_OK);
    int K = nf_coons3_unknowns(&cs);
    long need = NF_COONS3_DOUBLES(K, cs.c[0].n, cs.c[2].n);
    double *m3 = malloc(sizeof(double) * (size_t)need);
    nf_coons3_t b;
    assert_int_equal(nf_coons3_init(&b, &cs, m3, need), NF_COONS_ERATIONAL);
    free(mem);
    /* Polynomial, but too few points for the unknowns: singular. */
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < c[k].n; i++)
            c[k].w[i] = 1.0;
    mem = prep(&cs, c, 3, 1e-9, &rc);
    assert_int_equal(rc, NF_OK);
    assert_int_equal(nf_coons3_init(&b, &cs, m3, need - 1), NF_COONS_EWORK);
    assert_int_equal(nf_coons3_init(&b, &cs, m3, need), NF_OK);
    double Q[3] = {0, 0, 0};
    assert_int_equal(nf_coons3_add(&b, 1.5, 0.5, Q), NF_EDOMAIN);
    assert_int_equal(nf_coons3_add(&b, 0.5, 0.5, Q), NF_OK);
    assert_int_equal(nf_coons3_solve(&b), NF_ESINGULAR);
    free(mem);
    free(m3);
    for (int k = 0; k < 4; k++)
        curve_free(&c[k]);
    ref_surf_free(&t);
}

/* ---------------------------------------------------- refused curves */

static void test_bad_curves_refused(void **state)
{
    (void)state;
    ref_seed(41);
    nf_surf_t t;
    ref_surf_random(&t, 2, 2, 5, 4, 0, 1, 0, 1, 1, 1);
    nf_curve_t c[4];
    boundary(&t, c);
    nf_coons_t cs;
    int rc;
    /* A corner off by 0.1: refused at tol 0.01 naming the corner, taken at 0.2. */
    c[3].cp[3 * (c[3].n - 1) + 2] += 0.1;
    double *mem = prep(&cs, c, 1, 0.01, &rc);
    assert_int_equal(rc, NF_COONS_ECORNER);
    assert_int_equal(cs.corner, 3);
    assert_near(cs.gap, 0.1, 1e-12);
    free(mem);
    mem = prep(&cs, c, 1, 0.2, &rc);
    assert_int_equal(rc, NF_OK);
    free(mem);
    c[3].cp[3 * (c[3].n - 1) + 2] -= 0.1;
    /* Decreasing knots. */
    double k = c[2].U[3];
    c[2].U[3] = c[2].U[2] - 0.5;
    assert_int_equal(nf_coons_doubles(c, 1), NF_EKNOTS);
    long len = 100000;
    double *big = malloc(sizeof(double) * (size_t)len);
    assert_int_equal(nf_coons_prepare(&cs, c, 1, 1.0, big, len), NF_EKNOTS);
    c[2].U[3] = k;
    /* A zero weight. */
    c[1].w[2] = 0.0;
    assert_int_equal(nf_coons_prepare(&cs, c, 1, 1.0, big, len), NF_EWEIGHT);
    c[1].w[2] = 1.0;
    /* Too little storage. */
    assert_int_equal(nf_coons_prepare(&cs, c, 1, 1.0, big, nf_coons_doubles(c, 1) - 1),
                     NF_COONS_EWORK);
    /* Rational curves whose end weights cannot agree around the loop. */
    c[0].w[c[0].n - 1] = 2.0;
    assert_int_equal(nf_coons_prepare(&cs, c, 1, 1.0, big, len), NF_COONS_EWEIGHTS);
    assert_string_equal(nf_coons_strerror(NF_COONS_EWEIGHTS),
                        "rational boundary curves: end weights cannot be made to agree at the "
                        "corners");
    free(big);
    for (int i = 0; i < 4; i++)
        curve_free(&c[i]);
    ref_surf_free(&t);
}

/* -------------------------------------------------------------- plane */

/* Rotation by angle a about the unit axis n (Rodrigues), row-major. */
static void rotation(const double n[3], double a, double R[9])
{
    double c = cos(a), s = sin(a), C = 1 - c;
    double x = n[0], y = n[1], z = n[2];
    double r[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s,
                   y * x * C + z * s, c + y * y * C,     y * z * C - x * s,
                   z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    memcpy(R, r, sizeof r);
}

static void test_power_closed_form(void **state)
{
    (void)state;
    /* M = R diag(5, 2, 0.5) R^T: eigenvectors are R's columns. */
    double ax[3] = {1 / sqrt(3.0), 1 / sqrt(3.0), 1 / sqrt(3.0)}, R[9];
    rotation(ax, 0.7, R);
    const double lam[3] = {5.0, 2.0, 0.5};
    double M[3][3] = {{0}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++)
                M[i][j] += R[3 * i + k] * lam[k] * R[3 * j + k];
    double m6[6] = {M[0][0], M[0][1], M[0][2], M[1][1], M[1][2], M[2][2]}, e[3][3], l[3];
    int it = nf_base_power(m6, e, l);
    assert_true(it > 0);
    for (int k = 0; k < 3; k++) {
        double col[3] = {R[k], R[3 + k], R[6 + k]};
        double d = fabs(e[k][0] * col[0] + e[k][1] * col[1] + e[k][2] * col[2]);
        assert_near(d, 1.0, 1e-12); /* same direction up to sign */
        assert_near(l[k], lam[k], 1e-12 * 5);
    }
}

/* Every point projects strictly inside the affine patch s: its
 * coordinates along the patch's edges are in (0, 1). Returns the area of
 * the patch's parallelogram. */
static double assert_projects_inside(const nf_surf_t *s, const double *pts, int m)
{
    double S00[3], S10[3], S01[3], eu[3], ev[3], lu = 0, lv = 0;
    nf_surf_eval(s, 0, 0, S00);
    nf_surf_eval(s, 1, 0, S10);
    nf_surf_eval(s, 0, 1, S01);
    for (int i = 0; i < 3; i++) {
        eu[i] = S10[i] - S00[i];
        ev[i] = S01[i] - S00[i];
        lu += eu[i] * eu[i];
        lv += ev[i] * ev[i];
    }
    for (int k = 0; k < m; k++) {
        const double *P = pts + 3 * k;
        double a = 0, b = 0;
        for (int i = 0; i < 3; i++) {
            a += (P[i] - S00[i]) * eu[i] / lu;
            b += (P[i] - S00[i]) * ev[i] / lv;
        }
        assert_true(a > 0 && a < 1 && b > 0 && b < 1);
    }
    return sqrt(lu) * sqrt(lv);
}

/* A square footprint (a 60 x 60 grid, equal spreads: the scatter's axes
 * are arbitrary in the plane) turned 30 degrees in a tilted plane: the
 * patch hugs it (issue 14: holes' base came out turned 45 degrees, the data
 * a diamond over half the domain). Its edges are within 1 degree of the
 * square's, so its area, margin aside, is at most (cos 1 + sin 1)^2 =
 * 1.0355 times the square's; every point still projects inside. */
static void test_plane_square_turned(void **state)
{
    (void)state;
    double ax[3] = {0.6, -0.8, 0.0}, R[9];
    rotation(ax, 0.4, R);
    const double c0[3] = {10, 20, 5}, th = 30.0 * 3.14159265358979323846 / 180.0;
    nf_base_plane_t pl;
    nf_base_plane_init(&pl);
    enum { G = 60, M = G * G };
    double *pts = malloc(sizeof(double) * 3 * M);
    for (int k = 0; k < M; k++) {
        double a = 100.0 * (k % G) / (G - 1), b = 100.0 * (k / G) / (G - 1);
        double x = cos(th) * a - sin(th) * b, y = sin(th) * a + cos(th) * b, *P = pts + 3 * k;
        for (int i = 0; i < 3; i++)
            P[i] = c0[i] + R[3 * i] * x + R[3 * i + 1] * y;
        assert_int_equal(nf_base_plane_add(&pl, P), NF_OK);
    }
    assert_int_equal(nf_base_plane_axes(&pl), NF_OK);
    for (int k = 0; k < M; k++)
        nf_base_plane_extent(&pl, pts + 3 * k);
    nf_surf_t s;
    nf_surf_wire(&s, 3, 3, 4, 4, malloc(sizeof(double) * NF_SURF_DOUBLES(4, 4, 3, 3)));
    const double m = 0.01;
    assert_int_equal(nf_base_plane_patch(&pl, m, &s), NF_OK);
    double area = assert_projects_inside(&s, pts, M) / ((1 + 2 * m) * (1 + 2 * m));
    assert_true(area <= 1.0355 * 100.0 * 100.0);
    free(s.U);
    free(pts);
}

/* Points on a tilted plane (any spread in it): the plane comes back, the
 * patch lies in it, covers every point's projection and is affine. */
static void test_plane_patch(void **state)
{
    (void)state;
    ref_seed(51);
    double ax[3] = {0.6, -0.8, 0.0}, R[9];
    rotation(ax, 0.4, R);
    const double c0[3] = {100, -50, 20};
    const double nrm[3] = {R[2], R[5], R[8]}; /* the rotated z axis */
    nf_base_plane_t pl;
    nf_base_plane_init(&pl);
    enum { M = 5000 };
    double *pts = malloc(sizeof(double) * 3 * M);
    for (int k = 0; k < M; k++) {
        double x = ref_rand(-80, 80), y = ref_rand(-30, 30), *P = pts + 3 * k;
        for (int i = 0; i < 3; i++)
            P[i] = c0[i] + R[3 * i] * x + R[3 * i + 1] * y;
        assert_int_equal(nf_base_plane_add(&pl, P), NF_OK);
    }
    assert_int_equal(nf_base_plane_axes(&pl), NF_OK);
    double d = fabs(pl.e[2][0] * nrm[0] + pl.e[2][1] * nrm[1] + pl.e[2][2] * nrm[2]);
    assert_near(d, 1.0, 1e-12);
    assert_true(pl.e[2][2] > 0);
    for (int k = 0; k < M; k++)
        nf_base_plane_extent(&pl, pts + 3 * k);
    nf_surf_t s;
    nf_surf_wire(&s, 3, 2, 9, 7, malloc(sizeof(double) * NF_SURF_DOUBLES(9, 7, 3, 2)));
    assert_int_equal(nf_base_plane_patch(&pl, 0.01, &s), NF_OK);
    assert_int_equal(nf_surf_check(&s), NF_OK);
    for (int i = 0; i < 63; i++) {
        const double *P = s.cp + 3 * i;
        double off = (P[0] - c0[0]) * nrm[0] + (P[1] - c0[1]) * nrm[1] + (P[2] - c0[2]) * nrm[2];
        assert_true(fabs(off) <= 1e-9);
    }
    /* Affine: S(u, v) = S00 + u (S10 - S00) + v (S01 - S00). */
    double S00[3], S10[3], S01[3];
    nf_surf_eval(&s, 0, 0, S00);
    nf_surf_eval(&s, 1, 0, S10);
    nf_surf_eval(&s, 0, 1, S01);
    for (int k = 0; k < 50; k++) {
        double u = ref_rand(0, 1), v = ref_rand(0, 1), S[3], A[3];
        nf_surf_eval(&s, u, v, S);
        for (int i = 0; i < 3; i++)
            A[i] = S00[i] + u * (S10[i] - S00[i]) + v * (S01[i] - S00[i]);
        assert_true(d3(S, A) <= 1e-10);
    }
    (void)assert_projects_inside(&s, pts, M);
    /* Points on a line give no plane; two points are too few. */
    nf_base_plane_init(&pl);
    for (int k = 0; k < 10; k++) {
        double P[3] = {k, 2.0 * k, -1.0 * k};
        nf_base_plane_add(&pl, P);
    }
    assert_int_equal(nf_base_plane_axes(&pl), NF_ESINGULAR);
    nf_base_plane_init(&pl);
    nf_base_plane_add(&pl, c0);
    nf_base_plane_add(&pl, nrm);
    assert_int_equal(nf_base_plane_axes(&pl), NF_ENODATA);
    double bad[3] = {0, NAN, 0};
    assert_int_equal(nf_base_plane_add(&pl, bad), NF_ENONFINITE);
    free(pts);
    free(s.U);
}

/* ---------------------------------------------------------- IGES 126 */

/* A 128 at DE 1, a rational quarter circle (D exponents, parameters over
 * four P lines) at DE 3, a line at DE 5. */
static const char *const fixture[] = {
    "Hand-written fixture: a 128 and two 126 curves (cellfit test_coons).    S      1",
    "1H,,1H;,4Hpart,8Hcurv.igs,7HFooCAD,3Hv1,32,38,6,308,15,4Hpart,1.D0,     G      1",
    "2,2HMM,1,1.,15H20240105.101500,1.0D-08,20.,1Ha,1Hb,11,0,                G      2",
    "15H20240105.101500;                                                     G      3",
    "     128       1       0       0       0       0       0       000000000D      1",
    "     128       0       0       2       0                    SURF       0D      2",
    "     126       3       0       0       0       0       0       000000000D      3",
    "     126       0       0       4       0                     ARC       0D      4",
    "     126       7       0       0       0       0       0       000000000D      5",
    "     126       0       0       2       0                    LINE       0D      6",
    "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,             1P      1",
    "0.,0.,0.,1.,0.,0.,0.,1.,0.,1.,1.,0.,0.,1.,0.,1.;                       1P      2",
    "126,2,2,1,0,0,0,0.D0,0.D0,0.D0,1.D0,1.D0,1.D0,1.0D0,                   3P      3",
    "7.0710678118654752D-01,1.0D0,1.0D+01,0.0D+00,0.0D+00,                  3P      4",
    "1.0D+01,1.0D+01,0.0D+00,0.0D+00,1.0D+01,0.0D+00,0.D0,1.D0,             3P      5",
    "0.D0,0.D0,1.D0;                                                        3P      6",
    "126,1,1,0,0,1,0,0.,0.,1.,1.,1.,1.,-1.,2.,3.,4.,5.,                     5P      7",
    "6.,0.,1.,0.,0.,0.;                                                     5P      8",
    "S      1G      3D      6P      8                                        T      1",
    NULL};

static char tmpdir[512];

static void tmp_path(char *buf, size_t n, const char *name)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", d && *d ? d : "/tmp");
    for (char *p = tmpdir + 1; *p; p++) /* mkdir -p */
        if (*p == '/') {
            *p = '\0';
            mkdir(tmpdir, 0777);
            *p = '/';
        }
    mkdir(tmpdir, 0777);
    snprintf(buf, n, "%s/cf_coons_%ld_%s", tmpdir, (long)getpid(), name);
}

static void test_iges126_read_fixture(void **state)
{
    (void)state;
    char path[600], msg[1024];
    tmp_path(path, sizeof path, "fix.igs");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (int i = 0; fixture[i]; i++)
        fprintf(f, "%s\n", fixture[i]);
    fclose(f);
    nf_curve_t c;
    assert_int_equal(cf_iges_read_curve(path, 0, 0, &c, msg, sizeof msg), CF_OK);
    assert_int_equal(c.p, 2);
    assert_int_equal(c.n, 3);
    assert_near(c.w[1], 0.70710678118654752, 0);
    for (int k = 0; k <= 10; k++) { /* on the circle of radius 10 */
        double P[3];
        nf_curve_eval(&c, k / 10.0, P);
        assert_near(sqrt(P[0] * P[0] + P[1] * P[1]), 10.0, 1e-12);
        assert_near(P[2], 0.0, 0);
    }
    double P[3];
    nf_curve_eval(&c, 0.5, P); /* the symmetric arc's midpoint: 45 degrees */
    assert_near(P[0], 10.0 / sqrt(2.0), 1e-12);
    cf_curve_free(&c);
    assert_int_equal(cf_iges_read_curve(path, 5, 0, &c, msg, sizeof msg), CF_OK);
    assert_int_equal(c.p, 1);
    nf_curve_eval(&c, 1.0, P);
    assert_near(P[0], 4.0, 0);
    assert_near(P[2], 6.0, 0);
    cf_curve_free(&c);
    assert_int_equal(cf_iges_read_curve(path, 0, 1, &c, msg, sizeof msg), CF_OK);
    assert_int_equal(c.p, 1);
    cf_curve_free(&c);
    assert_int_equal(cf_iges_read_curve(path, 0, 2, &c, msg, sizeof msg), CF_ENOTFOUND);
    assert_non_null(strstr(msg, "only 2"));
    assert_int_equal(cf_iges_read_curve(path, 1, 0, &c, msg, sizeof msg), CF_ENOTFOUND);
    assert_non_null(strstr(msg, "not a rational B-spline curve (126)"));
    /* The 128 in the same file still reads. */
    nf_surf_t s;
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_OK);
    assert_int_equal(s.nu, 2);
    cf_surf_free(&s);
    remove(path);
}

static void test_iges126_roundtrip(void **state)
{
    (void)state;
    ref_seed(61);
    char path[600], msg[1024];
    tmp_path(path, sizeof path, "rt.igs");
    nf_curve_t c[3];
    random_curve(&c[0], 3, 40, -1.0, 2.0, 0.3, 3.0); /* parameters over many P lines */
    random_curve(&c[1], 1, 2, 0.0, 1.0, 1.0, 1.0);
    random_curve(&c[2], 5, 9, 1e-3, 7.0, 1.0, 1.0);
    c[0].cp[7] = 1.0 / 3.0;
    c[0].w[3] = 1e-300 * 1e290; /* a small but positive weight */
    assert_int_equal(cf_iges_write_curves(path, c, 3, "rt", msg, sizeof msg), CF_OK);
    for (int k = 0; k < 3; k++) {
        nf_curve_t r;
        assert_int_equal(cf_iges_read_curve(path, 2 * k + 1, 0, &r, msg, sizeof msg), CF_OK);
        assert_int_equal(r.p, c[k].p);
        assert_int_equal(r.n, c[k].n);
        assert_memory_equal(r.U, c[k].U, sizeof(double) * (size_t)(r.n + r.p + 1));
        assert_memory_equal(r.cp, c[k].cp, sizeof(double) * 3 * (size_t)r.n);
        assert_memory_equal(r.w, c[k].w, sizeof(double) * (size_t)r.n);
        cf_curve_free(&r);
    }
    /* Every line 80 columns, P lines pointing back at their DE. */
    FILE *f = fopen(path, "r");
    char line[256];
    long lines = 0;
    while (fgets(line, sizeof line, f)) {
        assert_int_equal(strlen(line), 81);
        if (line[72] == 'P') {
            long de = strtol(line + 64, NULL, 10);
            assert_true(de == 1 || de == 3 || de == 5);
        }
        lines++;
    }
    fclose(f);
    assert_true(lines > 20);
    /* Invalid curves are not written. */
    c[1].U[1] = 0.5;
    assert_int_equal(cf_iges_write_curves(path, &c[1], 1, "x", msg, sizeof msg), NF_EKNOTS);
    remove(path);
    for (int k = 0; k < 3; k++)
        curve_free(&c[k]);
}

/* Bad curves in a file: refused with the nf code, naming file and line. */
static void test_iges126_bad(void **state)
{
    (void)state;
    char path[600], msg[1024];
    tmp_path(path, sizeof path, "bad.igs");
    nf_curve_t c;
    curve_alloc(&c, 1, 3);
    double U[5] = {0, 0, 0.5, 1, 1};
    memcpy(c.U, U, sizeof U);
    for (int i = 0; i < 9; i++)
        c.cp[i] = i;
    assert_int_equal(cf_iges_write_curves(path, &c, 1, "bad", msg, sizeof msg), CF_OK);
    /* Edit the written file: parameter 13 (weight W(1)) to 0.0, then
     * parameter 9 (knot T(1) = 0.5) to 2.0 (all on the first P line). */
    static const int field[2] = {13, 9};
    static const char *const val[2] = {"0.0,", "2.0,"};
    for (int what = 0; what < 2; what++) {
        FILE *f = fopen(path, "r+");
        char buf[8192];
        size_t n = fread(buf, 1, sizeof buf - 1, f);
        buf[n] = 0;
        char *k = strstr(buf, "126,2,1,");
        assert_non_null(k);
        for (int cm = 0; cm < field[what]; cm++)
            k = strchr(k, ',') + 1;
        if (what)
            assert_memory_equal(k, "0.5,", 4);
        else
            assert_memory_equal(k, "1.0,", 4);
        memcpy(k, val[what], 4);
        if (what) { /* the weight back to 1 first */
            char *w = strstr(buf, "126,2,1,");
            for (int cm = 0; cm < field[0]; cm++)
                w = strchr(w, ',') + 1;
            memcpy(w, "1.0,", 4);
        }
        rewind(f);
        fwrite(buf, 1, n, f);
        fclose(f);
        nf_curve_t r;
        int rc = cf_iges_read_curve(path, 0, 0, &r, msg, sizeof msg);
        assert_int_equal(rc, what ? NF_EKNOTS : NF_EWEIGHT);
        assert_non_null(strstr(msg, "line "));
        assert_non_null(strstr(msg, what ? "knot vector decreases" : "weight W(1)"));
    }
    remove(path);
    curve_free(&c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_curve_eval_and_derivs),
        cmocka_unit_test(test_curve_elevate_refine_reverse),
        cmocka_unit_test(test_bilinear_reproduces_boundary),
        cmocka_unit_test(test_bilinear_mixed_curves),
        cmocka_unit_test(test_bilinear_of_lines),
        cmocka_unit_test(test_bicubic_reproduces_bicubic),
        cmocka_unit_test(test_bicubic_beats_bilinear),
        cmocka_unit_test(test_bicubic_scaled_keeps_boundary),
        cmocka_unit_test(test_bicubic_refusals),
        cmocka_unit_test(test_bad_curves_refused),
        cmocka_unit_test(test_power_closed_form),
        cmocka_unit_test(test_plane_patch),
        cmocka_unit_test(test_plane_square_turned),
        cmocka_unit_test(test_iges126_read_fixture),
        cmocka_unit_test(test_iges126_roundtrip),
        cmocka_unit_test(test_iges126_bad),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
