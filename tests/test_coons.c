/* test_coons.c: boundary curves, Coons base surfaces and the plane base
 * (Piegl & Tiller 2001, Section 2; nf_curve, nf_coons, nf_base), and IGES
 * entity 126. References are independent: the Cox-de Boor recursion for
 * curves, the true surface the curves and points come from, closed forms
 * (bilinear patch of four lines, eigenvectors of a rotated diagonal). */
#include "cf_err.h"
#include "cf_iges.h"
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
