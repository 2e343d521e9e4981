/* SPDX-License-Identifier: MIT */
/* test_fitpass.c: one pass of Eq. 7 in a given block (cf_fitpass) against
 * the dense normal equations of ref_dense.c solved by Gaussian elimination:
 * u v x y z rows on one and two cores, weighted rows (an integer weight
 * is the point repeated, weight 0 left out), the block's exact size, and
 * the refusals in words (the row outside the domain, the control point
 * left free). */
#include "cf_fitpass.h"
#include "cf_test.h"
#include "nf_err.h"
#include "ref_dense.h"
#include <stdlib.h>
#include <string.h>

#define NU 7
#define NV 6
#define M 400

static nf_surf_t g_s;
static double g_pts[5 * M];

static int setup(void **state)
{
    (void)state;
    ref_seed(1301);
    ref_surf_random(&g_s, 3, 2, NU, NV, 0.0, 2.0, -1.0, 1.0, 0.7, 1.4);
    for (long k = 0; k < M; k++) {
        double *r = g_pts + 5 * k;
        r[0] = ref_rand(0.0, 2.0);
        r[1] = ref_rand(-1.0, 1.0);
        nf_surf_eval(&g_s, r[0], r[1], r + 2);
        for (int c = 2; c < 5; c++)
            r[c] += ref_rand(-0.01, 0.01);
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    ref_surf_free(&g_s);
    return 0;
}

/* The dense reference net for pts (M rows) with alpha, beta. */
static void reference(const double *pts, long m, double alpha, double beta, double *x)
{
    double *A, *b;
    ref_eq7(&g_s, pts, m, alpha, beta, &A, &b);
    assert_int_equal(ref_solve(A, b, (long)NU * NV, x), 0);
    free(A);
    free(b);
}

/* A pass in a block of exactly cf_fitpass_bytes, rows in chunks of 37. */
static void run_pass(const double *rows, long n, int cols, int threads, double alpha, double beta,
                     nf_surf_t *out, cf_fitpass_t *ps)
{
    long bytes = cf_fitpass_bytes(&g_s, NF_SOLVER_CHOL, threads);
    assert_true(bytes > 0);
    void *block = aligned_alloc(16, (size_t)(bytes + 15) / 16 * 16);
    char msg[512];
    assert_int_equal(cf_fitpass_begin(ps, block, (size_t)bytes, &g_s, alpha, beta, NF_SOLVER_CHOL,
                                      threads, "test", msg, sizeof msg),
                     0);
    for (long k = 0; k < n; k += 37) {
        long bad = -1;
        assert_int_equal(cf_fitpass_rows(ps, rows + cols * k, n - k < 37 ? n - k : 37, cols, &bad),
                         0);
    }
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    assert_int_equal(cf_fitpass_solve(ps, &so, out, "test", msg, sizeof msg), 0);
    free(block);
}

static void check_net(const nf_surf_t *out, const double *x)
{
    for (long i = 0; i < 3L * NU * NV; i++)
        assert_near(out->cp[i], x[i], 1e-8 * (1.0 + fabs(x[i])));
}

static void test_rows_one_and_two_cores(void **state)
{
    (void)state;
    double x[3 * NU * NV];
    reference(g_pts, M, 0.1, 0.001, x);
    for (int t = 1; t <= 2; t++) {
        nf_surf_t out;
        cf_fitpass_t ps;
        ref_surf_random(&out, 3, 2, NU, NV, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0);
        run_pass(g_pts, M, 5, t, 0.1, 0.001, &out, &ps);
        check_net(&out, x);
        assert_int_equal(cf_fitpass_points(&ps), M);
        assert_int_equal(ps.rejected, 0);
        ref_surf_free(&out);
    }
}

/* Weights 1, 2, 3 against the points repeated that often; 40 rows of
 * weight 0 far off the surface change nothing and are counted. */
static void test_weighted_rows(void **state)
{
    (void)state;
    double *w6 = malloc(sizeof(double) * 6 * (M + 40));
    double *rep = malloc(sizeof(double) * 5 * 3 * M);
    long n6 = 0, nr = 0;
    for (long k = 0; k < M; k++) {
        int w = 1 + (int)(k % 3);
        memcpy(w6 + 6 * n6, g_pts + 5 * k, sizeof(double) * 5);
        w6[6 * n6++ + 5] = w;
        for (int r = 0; r < w; r++)
            memcpy(rep + 5 * nr++, g_pts + 5 * k, sizeof(double) * 5);
        if (k % 10 == 0) {
            double *g = w6 + 6 * n6++;
            g[0] = g_pts[5 * k], g[1] = g_pts[5 * k + 1], g[2] = g[3] = g[4] = 1e6, g[5] = 0.0;
        }
    }
    double x[3 * NU * NV];
    reference(rep, nr, 0.1, 0.001, x);
    nf_surf_t out;
    cf_fitpass_t ps;
    ref_surf_random(&out, 3, 2, NU, NV, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0);
    run_pass(w6, n6, 6, 1, 0.1, 0.001, &out, &ps);
    check_net(&out, x);
    assert_int_equal(ps.rejected, 40);
    assert_int_equal(cf_fitpass_points(&ps), M);
    ref_surf_free(&out);
    free(w6);
    free(rep);
}

/* The block's size is the firmware's formula (on two cores with the
 * second accumulator's state): that many bytes suffice, half of them are
 * refused. */
static void test_block_bytes(void **state)
{
    (void)state;
    for (int t = 1; t <= 2; t++) {
        long want = nf_fit_bytes(NU, NV, 3, 2, NF_SOLVER_PCG) +
                    (t > 1 ? nf_fit_shard_bytes(NU, NV, 3, 2) +
                                 (long)((sizeof(nf_fit_t) + _Alignof(nf_fit_t) - 1 + 15) / 16 * 16)
                           : 0);
        assert_int_equal(cf_fitpass_bytes(&g_s, NF_SOLVER_PCG, t), want);
        void *block = aligned_alloc(16, (size_t)(want + 15) / 16 * 16);
        cf_fitpass_t ps;
        char msg[512];
        assert_int_equal(cf_fitpass_begin(&ps, block, (size_t)want / 2, &g_s, 0.1, 0.001,
                                          NF_SOLVER_PCG, t, "test", msg, sizeof msg),
                         NF_EARENA);
        assert_int_equal(cf_fitpass_begin(&ps, block, (size_t)want, &g_s, 0.1, 0.001, NF_SOLVER_PCG,
                                          t, "test", msg, sizeof msg),
                         0);
        free(block);
    }
}

/* A row outside the domain names its index and the domain; alpha = beta
 * = 0 with data on half the part names a control point left free. */
static void test_refusals(void **state)
{
    (void)state;
    long bytes = cf_fitpass_bytes(&g_s, NF_SOLVER_CHOL, 1);
    void *block = aligned_alloc(16, (size_t)(bytes + 15) / 16 * 16);
    cf_fitpass_t ps;
    char msg[512];
    assert_int_equal(cf_fitpass_begin(&ps, block, (size_t)bytes, &g_s, 0.0, 0.0, NF_SOLVER_CHOL, 1,
                                      "half", msg, sizeof msg),
                     0);
    double rows[5 * 6];
    memcpy(rows, g_pts, sizeof rows);
    rows[5 * 3] = 2.5; /* u beyond [0, 2] */
    long bad = -1;
    int rc = cf_fitpass_rows(&ps, rows, 6, 5, &bad);
    assert_int_equal(rc, NF_EDOMAIN);
    assert_int_equal(bad, 3);
    assert_int_equal(cf_fitpass_row_error(&ps, rc, rows + 5 * bad, "f:4", msg, sizeof msg),
                     NF_EDOMAIN);
    assert_non_null(strstr(msg, "f:4: parameters (2.5, "));
    assert_non_null(strstr(msg, "outside the knot domain [0, 2] x [-1, 1]"));
    for (long k = 0; k < M; k++)
        if (g_pts[5 * k] < 0.6) /* the left part only */
            assert_int_equal(cf_fitpass_rows(&ps, g_pts + 5 * k, 1, 5, NULL), 0);
    nf_surf_t out;
    ref_surf_random(&out, 3, 2, NU, NV, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0);
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    rc = cf_fitpass_solve(&ps, &so, &out, "half", msg, sizeof msg);
    assert_true(rc == NF_ENODATA || rc == NF_ESINGULAR);
    assert_non_null(strstr(msg, "half: "));
    assert_non_null(strstr(msg, "control point ("));
    ref_surf_free(&out);
    free(block);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rows_one_and_two_cores),
        cmocka_unit_test(test_weighted_rows),
        cmocka_unit_test(test_block_bytes),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
