/* SPDX-License-Identifier: MIT */
/* test_basis.c: basis functions, spans, Greville points and surface
 * evaluation against hand-computed values and independent definitions. */

#include "cf_test.h"
#include "nf_basis.h"
#include "nf_err.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <math.h>
#include <stdlib.h>

/* The NURBS Book, Ex. 2.3: U = {0,0,0,1,2,3,4,4,5,5,5}, p = 2, u = 5/2:
 * span 4, N = {1/8, 6/8, 1/8}; derivatives {-1/2, 0, 1/2}; second {1, -2, 1}. */
static const double book_U[] = {0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5};

static void test_book_example(void **state)
{
    (void)state;
    int l = nf_find_span(7, 2, 2.5, book_U);
    assert_int_equal(l, 4);
    double N[3];
    nf_basis_funs(l, 2.5, 2, book_U, N);
    assert_near(N[0], 1.0 / 8, 1e-15);
    assert_near(N[1], 6.0 / 8, 1e-15);
    assert_near(N[2], 1.0 / 8, 1e-15);
    double d[9];
    nf_ders_basis_funs(l, 2.5, 2, 2, book_U, d);
    assert_near(d[0], 1.0 / 8, 1e-15);
    assert_near(d[3], -0.5, 1e-15);
    assert_near(d[4], 0.0, 1e-15);
    assert_near(d[5], 0.5, 1e-15);
    assert_near(d[6], 1.0, 1e-14);
    assert_near(d[7], -2.0, 1e-14);
    assert_near(d[8], 1.0, 1e-14);
}

static void test_find_span_edges(void **state)
{
    (void)state;
    assert_int_equal(nf_find_span(7, 2, 0.0, book_U), 2);
    assert_int_equal(nf_find_span(7, 2, 5.0, book_U), 7); /* right end: last span */
    assert_int_equal(nf_find_span(7, 2, 4.0, book_U), 7); /* double knot at 4: span [4,5) */
    assert_int_equal(nf_find_span(7, 2, 3.999999, book_U), 5);
    assert_int_equal(nf_find_span(7, 2, 1.0, book_U), 3);
}

/* Span basis equals the recursive definition; partition of unity. */
static void test_against_recursive(void **state)
{
    (void)state;
    ref_seed(7);
    for (int p = 1; p <= 5; p++) {
        nf_surf_t s;
        ref_surf_random(&s, p, 1, p + 6, 2, -1.5, 3.0, 0, 1, 1, 1);
        int n = s.nu - 1, nk = s.nu + p + 1;
        for (int t = 0; t <= 200; t++) {
            double u = -1.5 + 4.5 * t / 200.0;
            int l = nf_find_span(n, p, u, s.U);
            double N[NF_MAX_ORDER], sum = 0.0;
            nf_basis_funs(l, u, p, s.U, N);
            for (int i = 0; i <= n; i++) {
                double ref = ref_bspline(i, p, s.U, nk, u);
                double got = (i >= l - p && i <= l) ? N[i - (l - p)] : 0.0;
                assert_near(got, ref, 1e-13);
            }
            for (int a = 0; a <= p; a++)
                sum += N[a];
            assert_near(sum, 1.0, 1e-14);
        }
        ref_surf_free(&s);
    }
}

/* Derivatives against central differences of the basis. */
static void test_derivatives_fd(void **state)
{
    (void)state;
    ref_seed(11);
    for (int p = 2; p <= 5; p++) {
        nf_surf_t s;
        ref_surf_random(&s, p, 1, p + 5, 2, 0, 1, 0, 1, 1, 1);
        for (int t = 1; t < 50; t++) {
            double u = (t + 0.37) / 51.0, h = 1e-6;
            int l = nf_find_span(s.nu - 1, p, u, s.U);
            if (nf_find_span(s.nu - 1, p, u - h, s.U) != l ||
                nf_find_span(s.nu - 1, p, u + h, s.U) != l)
                continue;
            double d[3 * NF_MAX_ORDER], Np[NF_MAX_ORDER], Nm[NF_MAX_ORDER], sum = 0.0;
            nf_ders_basis_funs(l, u, p, 2, s.U, d);
            nf_basis_funs(l, u + h, p, s.U, Np);
            nf_basis_funs(l, u - h, p, s.U, Nm);
            for (int a = 0; a <= p; a++) {
                assert_near(d[(p + 1) + a], (Np[a] - Nm[a]) / (2 * h), 1e-6);
                sum += d[(p + 1) + a];
            }
            assert_near(sum, 0.0, 1e-11);
        }
        ref_surf_free(&s);
    }
}

static void test_greville(void **state)
{
    (void)state;
    assert_near(nf_greville(0, 2, book_U), 0.0, 0);
    assert_near(nf_greville(1, 2, book_U), 0.5, 0);
    assert_near(nf_greville(4, 2, book_U), 3.5, 0);
    assert_near(nf_greville(7, 2, book_U), 5.0, 0);
}

static void test_knot_checks(void **state)
{
    (void)state;
    assert_int_equal(nf_knots_check(7, 2, book_U), NF_OK);
    double bad[11];
    for (int i = 0; i < 11; i++)
        bad[i] = book_U[i];
    bad[5] = 1.5; /* 0 0 0 1 2 1.5 ...: decreasing */
    assert_int_equal(nf_knots_check(7, 2, bad), NF_EKNOTS);
    double unclamped[] = {0, 0, 0.1, 1, 2, 3, 4, 4, 5, 5, 5};
    assert_int_equal(nf_knots_check(7, 2, unclamped), NF_EKNOTS);
    double triple[] = {0, 0, 0, 1, 2, 2, 2, 4, 5, 5, 5}; /* multiplicity 3 > p */
    assert_int_equal(nf_knots_check(7, 2, triple), NF_EKNOTS);
    double nanknot[] = {0, 0, 0, 1, NAN, 3, 4, 4, 5, 5, 5};
    assert_int_equal(nf_knots_check(7, 2, nanknot), NF_EKNOTS);
}

/* Rational evaluation against the definition (Eq. 1) with the recursive
 * basis, and derivatives against central differences of the surface. */
static void test_surface_eval(void **state)
{
    (void)state;
    ref_seed(3);
    nf_surf_t s;
    ref_surf_random(&s, 3, 2, 7, 6, 0.5, 2.0, -1, 1, 0.5, 2.0);
    assert_int_equal(nf_surf_check(&s), NF_OK);
    double *row = malloc(sizeof(double) * 42);
    for (int t = 0; t < 100; t++) {
        double u = ref_rand(0.5, 2.0), v = ref_rand(-1, 1);
        double P[3], ref[3] = {0, 0, 0};
        nf_surf_eval(&s, u, v, P);
        ref_rbasis_row(&s, u, v, row);
        for (int k = 0; k < 42; k++)
            for (int c = 0; c < 3; c++)
                ref[c] += row[k] * s.cp[3 * k + c];
        for (int c = 0; c < 3; c++)
            assert_near(P[c], ref[c], 1e-12);
        double skl[27], h = 1e-5, a[3], b[3];
        nf_surf_derivs(&s, u, v, 2, skl);
        for (int c = 0; c < 3; c++)
            assert_near(skl[c], P[c], 1e-12);
        nf_surf_eval(&s, u + h, v, a);
        nf_surf_eval(&s, u - h, v, b);
        if (nf_find_span(6, 3, u + h, s.U) == nf_find_span(6, 3, u - h, s.U))
            for (int c = 0; c < 3; c++) {
                assert_near(skl[(1 * 3 + 0) * 3 + c], (a[c] - b[c]) / (2 * h), 1e-5);
                double P2 = (a[c] - 2 * P[c] + b[c]) / (h * h);
                assert_near(skl[(2 * 3 + 0) * 3 + c], P2, 1e-2 * (1 + fabs(P2)));
            }
        nf_surf_eval(&s, u, v + h, a);
        nf_surf_eval(&s, u, v - h, b);
        if (nf_find_span(5, 2, v + h, s.V) == nf_find_span(5, 2, v - h, s.V))
            for (int c = 0; c < 3; c++)
                assert_near(skl[(0 * 3 + 1) * 3 + c], (a[c] - b[c]) / (2 * h), 1e-5);
    }
    free(row);
    ref_surf_free(&s);
}

static void test_surface_checks(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 5, 5, 0, 1, 0, 1, 1, 1);
    assert_int_equal(nf_surf_check(&s), NF_OK);
    s.w[3] = 0.0;
    assert_int_equal(nf_surf_check(&s), NF_EWEIGHT);
    s.w[3] = -1.0;
    assert_int_equal(nf_surf_check(&s), NF_EWEIGHT);
    s.w[3] = 1.0;
    s.cp[5] = INFINITY;
    assert_int_equal(nf_surf_check(&s), NF_ENONFINITE);
    s.cp[5] = 0.0;
    s.p = NF_MAX_DEGREE + 1;
    assert_int_equal(nf_surf_check(&s), NF_EDEGREE);
    s.p = 3;
    s.nu = 3; /* fewer control points than order */
    assert_int_equal(nf_surf_check(&s), NF_ESIZE);
    ref_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_book_example),      cmocka_unit_test(test_find_span_edges),
        cmocka_unit_test(test_against_recursive), cmocka_unit_test(test_derivatives_fd),
        cmocka_unit_test(test_greville),          cmocka_unit_test(test_knot_checks),
        cmocka_unit_test(test_surface_eval),      cmocka_unit_test(test_surface_checks),
    };
    return cmocka_run_group_tests_name("basis", tests, NULL, NULL);
}
