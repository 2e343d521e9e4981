/* SPDX-License-Identifier: MIT */
/* test_curvefit.c: the streamed cubic B-spline curve fit (nf_curvefit):
 * exact reproduction of a curve in the same spline space (sampled by an
 * independent Cox-de Boor recursion), a straight line stays straight,
 * refusals. */
#include "cf_test.h"
#include "nf_curve.h"
#include "nf_curvefit.h"
#include "nf_err.h"
#include <string.h>

#define NCP 8

/* Cox-de Boor recursion (The NURBS Book, Eq. 2.5), the last span closed. */
static double cdb(int i, int p, double u, const double *U, int n)
{
    if (p == 0) {
        if (u == U[n] && i == n - 1)
            return 1.0;
        return U[i] <= u && u < U[i + 1] ? 1.0 : 0.0;
    }
    double a = 0.0, b = 0.0;
    if (U[i + p] > U[i])
        a = (u - U[i]) / (U[i + p] - U[i]) * cdb(i, p - 1, u, U, n);
    if (U[i + p + 1] > U[i + 1])
        b = (U[i + p + 1] - u) / (U[i + p + 1] - U[i + 1]) * cdb(i + 1, p - 1, u, U, n);
    return a + b;
}

static void sample(const double *U, const double *P, int n, double t, double Q[3])
{
    Q[0] = Q[1] = Q[2] = 0.0;
    for (int i = 0; i < n; i++) {
        double N = cdb(i, 3, t, U, n);
        for (int k = 0; k < 3; k++)
            Q[k] += N * P[3 * i + k];
    }
}

static double g_mem[NF_CURVEFIT_DOUBLES(NCP)];
static double g_cmem[NF_CURVE_DOUBLES(NCP, 3)];

static void test_exact_reproduction(void **state)
{
    (void)state;
    double U[NCP + 4], P[3 * NCP];
    for (int i = 0; i <= 3; i++)
        U[i] = 0.0, U[NCP + i] = 1.0;
    for (int i = 4; i < NCP; i++)
        U[i] = (double)(i - 3) / (NCP - 3);
    for (int i = 0; i < NCP; i++) {
        P[3 * i] = 10.0 * i;
        P[3 * i + 1] = 3.0 * sin(1.3 * i);
        P[3 * i + 2] = 0.5 * i * i - 2.0;
    }
    nf_curvefit_t f;
    assert_int_equal(nf_curvefit_init(&f, NCP, g_mem, NF_CURVEFIT_DOUBLES(NCP)), NF_OK);
    unsigned s = 12345u;
    for (int j = 0; j < 500; j++) {
        s = s * 1103515245u + 12345u;
        double t = (double)(s >> 8) / (double)(1u << 24), Q[3];
        if (j < 2)
            t = j; /* both ends of the domain */
        sample(U, P, NCP, t, Q);
        assert_int_equal(nf_curvefit_add(&f, t, Q), NF_OK);
    }
    nf_curve_t c;
    nf_curve_wire(&c, 3, NCP, g_cmem);
    double a[3] = {0, 0, 0}, b[3] = {70, 0, 0};
    /* ridge 1e-13: its pull toward the line is far below 1e-9 */
    assert_int_equal(nf_curvefit_solve(&f, a, b, 1e-13, &c), NF_OK);
    for (int i = 0; i < NCP; i++)
        for (int k = 0; k < 3; k++)
            assert_near(c.cp[3 * i + k], P[3 * i + k], 1e-9);
    for (int i = 0; i < NCP + 4; i++)
        assert_near(c.U[i], U[i], 0.0);
    assert_int_equal(nf_curve_check(&c), NF_OK);
}

static void test_line_stays_straight(void **state)
{
    (void)state;
    const double a[3] = {1, 2, 3}, b[3] = {11, -4, 5};
    nf_curvefit_t f;
    assert_int_equal(nf_curvefit_init(&f, NCP, g_mem, NF_CURVEFIT_DOUBLES(NCP)), NF_OK);
    /* Points only on [0.2, 0.8], unevenly: the ridge keeps the ends defined. */
    for (int j = 0; j < 40; j++) {
        double t = 0.2 + 0.6 * (j * j) / (39.0 * 39.0), Q[3];
        for (int k = 0; k < 3; k++)
            Q[k] = a[k] + t * (b[k] - a[k]);
        assert_int_equal(nf_curvefit_add(&f, t, Q), NF_OK);
    }
    nf_curve_t c;
    nf_curve_wire(&c, 3, NCP, g_cmem);
    assert_int_equal(nf_curvefit_solve(&f, a, b, 1e-6, &c), NF_OK);
    for (int j = 0; j <= 100; j++) {
        double t = j / 100.0, X[3];
        nf_curve_eval(&c, t, X);
        for (int k = 0; k < 3; k++)
            assert_near(X[k], a[k] + t * (b[k] - a[k]), 1e-9);
    }
}

static void test_refusals(void **state)
{
    (void)state;
    nf_curvefit_t f;
    assert_int_equal(nf_curvefit_init(&f, 3, g_mem, NF_CURVEFIT_DOUBLES(3)), NF_ESIZE);
    assert_int_equal(nf_curvefit_init(&f, NCP, g_mem, NF_CURVEFIT_DOUBLES(NCP) - 1), NF_EARG);
    assert_int_equal(nf_curvefit_init(&f, NCP, g_mem, NF_CURVEFIT_DOUBLES(NCP)), NF_OK);
    double Q[3] = {1, 2, 3}, a[3] = {0, 0, 0}, b[3] = {1, 1, 1};
    for (int j = 0; j < NCP - 1; j++)
        assert_int_equal(nf_curvefit_add(&f, j / (double)NCP, Q), NF_OK);
    double bad[3] = {1, NAN, 3};
    assert_int_equal(nf_curvefit_add(&f, 0.5, bad), NF_ENONFINITE);
    nf_curve_t c;
    nf_curve_wire(&c, 3, NCP, g_cmem);
    assert_int_equal(nf_curvefit_solve(&f, a, b, 1e-9, &c), NF_ENODATA);
    nf_curve_t wrong;
    nf_curve_wire(&wrong, 3, NCP - 1, g_cmem);
    assert_int_equal(nf_curvefit_add(&f, 0.9, Q), NF_OK);
    assert_int_equal(nf_curvefit_solve(&f, a, b, 1e-9, &wrong), NF_EARG);
    assert_int_equal(nf_curvefit_solve(&f, a, b, 1e-9, &c), NF_OK);
    assert_int_equal(nf_curvefit_add(&f, 0.5, Q), NF_ESTATE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exact_reproduction),
        cmocka_unit_test(test_line_stays_straight),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
