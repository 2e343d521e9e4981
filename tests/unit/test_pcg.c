/* SPDX-License-Identifier: MIT */
/* test_pcg.c: the split PCG operator of nf_pcg.c (bicubic 4-wide kernels and
 * generic sweeps) against a dense forward/backward substitution, the stripe
 * product against the dense one, and the whole PCG solve against a dense
 * Gaussian elimination, on nets with and without rows the bicubic kernels
 * take (Nu, Nv < 7, other degrees). */
#include "cf_test.h"
#include "nf_arena.h"
#include "nf_err.h"
#include "nf_solve.h"
#include "ref_dense.h"
#include <stdlib.h>

/* A random symmetric positive definite matrix in the stripe pattern: a
 * few random outer products per span (rows of R, Eq. 9) plus 0.05 I. */
static double *random_store(nf_stripe_t *A, int p, int q, int nu, int nv)
{
    const int K = (p + 1) + q * (2 * p + 1);
    double *S = calloc((size_t)nu * nv * K, sizeof(double));
    nf_stripe_init(A, nu, nv, p, q, S);
    double R[(NF_MAX_DEGREE + 1) * (NF_MAX_DEGREE + 1)];
    for (int b = 0; b + q < nv; b++)
        for (int a = 0; a + p < nu; a++)
            for (int k = 0; k < 3; k++) {
                for (int l = 0; l < (p + 1) * (q + 1); l++)
                    R[l] = ref_rand(-1.0, 1.0);
                nf_stripe_add_outer(A, a + (long)b * nu, R, ref_rand(0.5, 2.0));
            }
    for (long i = 0; i < A->n; i++)
        S[i * K] += 0.05;
    return S;
}

/* t = C^-T d = (D + U)^-1 D^1/2 d, q = C^-1 A t = D^1/2 (D + L)^-1 A t, dense. */
static void dense_apply(const nf_stripe_t *A, const double *d, double *t, double *q, double dq[3])
{
    const long n = A->n;
    double *M = malloc(sizeof(double) * (size_t)(n * n)), *z = malloc(sizeof(double) * 3 * n);
    for (long i = 0; i < n; i++)
        for (long j = 0; j < n; j++)
            M[i * n + j] = nf_stripe_get(A, i, j);
    for (int c = 0; c < 3; c++) {
        for (long i = n - 1; i >= 0; i--) {
            double s = sqrt(M[i * n + i]) * d[3 * i + c];
            for (long j = i + 1; j < n; j++)
                s -= M[i * n + j] * t[3 * j + c];
            t[3 * i + c] = s / M[i * n + i];
        }
        for (long i = 0; i < n; i++) {
            double s = 0.0;
            for (long j = 0; j < n; j++)
                s += M[i * n + j] * t[3 * j + c];
            z[3 * i + c] = s;
        }
        for (long i = 0; i < n; i++) {
            double s = z[3 * i + c];
            for (long j = 0; j < i; j++)
                s -= M[i * n + j] * z[3 * j + c]; /* z_j already holds y_j */
            z[3 * i + c] = s / M[i * n + i];
        }
        dq[c] = 0.0;
        for (long i = 0; i < n; i++) {
            q[3 * i + c] = sqrt(M[i * n + i]) * z[3 * i + c];
            dq[c] += d[3 * i + c] * q[3 * i + c];
        }
    }
    free(M);
    free(z);
}

static double max_abs(const double *a, long n)
{
    double m = 0.0;
    for (long i = 0; i < n; i++)
        m = fabs(a[i]) > m ? fabs(a[i]) : m;
    return m;
}

static void check_apply(int p, int q, int nu, int nv)
{
    nf_stripe_t A;
    double *S = random_store(&A, p, q, nu, nv);
    const long n = A.n;
    double *d = malloc(sizeof(double) * 3 * n);
    double *t[3], *qq[3], dq[3][3];
    for (int k = 0; k < 3; k++) {
        t[k] = malloc(sizeof(double) * 3 * n);
        qq[k] = malloc(sizeof(double) * 3 * n);
    }
    for (long i = 0; i < 3 * n; i++)
        d[i] = ref_rand(-1.0, 1.0);
    size_t bytes = sizeof(double) * (size_t)(14 * n) + 8 * NF_ARENA_ALIGN;
    void *mem = malloc(bytes);
    for (int g = 0; g < 2; g++) { /* 0: bicubic kernels where they apply, 1: generic */
        nf_arena_t ar;
        nf_arena_init(&ar, mem, bytes);
        assert_int_equal(nf_pcg_apply(&A, d, t[g], qq[g], dq[g], g, &ar), NF_OK);
    }
    dense_apply(&A, d, t[2], qq[2], dq[2]);
    const double ts = max_abs(t[2], 3 * n), qs = max_abs(qq[2], 3 * n);
    for (int g = 0; g < 2; g++) {
        for (long i = 0; i < 3 * n; i++) {
            assert_near(t[g][i], t[2][i], 1e-11 * ts);
            assert_near(qq[g][i], qq[2][i], 1e-11 * qs);
        }
        for (int c = 0; c < 3; c++)
            assert_near(dq[g][c], dq[2][c], 1e-11 * fabs(dq[2][c]));
    }
    /* The kernels only reorder sums: far closer to the generic sweeps. */
    for (long i = 0; i < 3 * n; i++) {
        assert_near(t[0][i], t[1][i], 1e-13 * ts);
        assert_near(qq[0][i], qq[1][i], 1e-13 * qs);
    }
    for (int k = 0; k < 3; k++) {
        free(t[k]);
        free(qq[k]);
    }
    free(mem);
    free(d);
    free(S);
}

static void test_apply_bicubic(void **state)
{
    (void)state;
    ref_seed(61);
    check_apply(3, 3, 12, 9);  /* interior rows and generic last rows */
    check_apply(3, 3, 31, 23); /* most rows interior */
    check_apply(3, 3, 7, 5);   /* Nu = 7: the smallest the kernels take */
    check_apply(3, 3, 16, 4);  /* Nv = 4: interior rows in the first v row only */
}

static void test_apply_small_and_other_degrees(void **state)
{
    (void)state;
    ref_seed(62);
    check_apply(3, 3, 6, 12); /* Nu < 7: generic sweeps throughout */
    check_apply(3, 3, 4, 9);
    check_apply(3, 3, 4, 4);
    check_apply(2, 3, 10, 9);
    check_apply(3, 2, 10, 9);
    check_apply(1, 1, 8, 6);
    check_apply(5, 4, 9, 8);
}

/* nf_stripe_matvec (bicubic 4-wide rows and generic rows) against the
 * dense product. */
static void check_matvec(int p, int q, int nu, int nv)
{
    nf_stripe_t A;
    double *S = random_store(&A, p, q, nu, nv);
    const long n = A.n;
    double *x = malloc(sizeof(double) * 3 * n), *y = malloc(sizeof(double) * 3 * n);
    for (long i = 0; i < 3 * n; i++)
        x[i] = ref_rand(-1.0, 1.0);
    nf_stripe_matvec(&A, x, y);
    double ys = 0.0;
    for (long i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double s = 0.0, m = 0.0;
            for (long j = 0; j < n; j++) {
                s += nf_stripe_get(&A, i, j) * x[3 * j + c];
                m += fabs(nf_stripe_get(&A, i, j));
            }
            assert_near(y[3 * i + c], s, 1e-14 * m);
            ys = fmax(ys, fabs(s));
        }
    assert_true(ys > 0.0);
    free(x);
    free(y);
    free(S);
}

static void test_matvec(void **state)
{
    (void)state;
    ref_seed(64);
    check_matvec(3, 3, 12, 9); /* 4-wide rows in the middle */
    check_matvec(3, 3, 31, 23);
    check_matvec(3, 3, 5, 20); /* Nu < 7 */
    check_matvec(3, 3, 4, 30); /* Nu = p + 1 */
    check_matvec(3, 3, 16, 4); /* no row far enough from both ends */
    check_matvec(2, 3, 10, 9);
    check_matvec(3, 2, 10, 9);
    check_matvec(5, 4, 9, 8);
}

/* The whole solve on a random store against Gaussian elimination. */
static void check_solve(int p, int q, int nu, int nv)
{
    nf_stripe_t A;
    double *S = random_store(&A, p, q, nu, nv);
    const long n = A.n;
    double *M = malloc(sizeof(double) * (size_t)(n * n)), *b = malloc(sizeof(double) * 3 * n);
    double *x = calloc((size_t)(3 * n), sizeof(double)), *ref = malloc(sizeof(double) * 3 * n);
    for (long i = 0; i < n; i++)
        for (long j = 0; j < n; j++)
            M[i * n + j] = nf_stripe_get(&A, i, j);
    for (long i = 0; i < 3 * n; i++)
        b[i] = ref_rand(-1.0, 1.0);
    assert_int_equal(ref_solve(M, b, n, ref), 0);
    size_t bytes = sizeof(double) * (size_t)(17 * n) + 16 * NF_ARENA_ALIGN;
    void *mem = malloc(bytes);
    nf_arena_t ar;
    nf_arena_init(&ar, mem, bytes);
    nf_solve_opts_t o = {1e-13, 100000, 1};
    nf_solve_stats_t st;
    long bad = -1;
    assert_int_equal(nf_pcg_solve(&A, b, x, &o, &ar, &st, &bad), NF_OK);
    assert_true(st.rel_residual <= 1e-13);
    const double sc = max_abs(ref, 3 * n);
    for (long i = 0; i < 3 * n; i++)
        assert_near(x[i], ref[i], 1e-8 * sc);
    free(mem);
    free(ref);
    free(x);
    free(b);
    free(M);
    free(S);
}

static void test_solve_against_dense(void **state)
{
    (void)state;
    ref_seed(63);
    check_solve(3, 3, 20, 14);
    check_solve(3, 3, 5, 20);
    check_solve(2, 2, 15, 12);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_apply_bicubic),
        cmocka_unit_test(test_apply_small_and_other_degrees),
        cmocka_unit_test(test_matvec),
        cmocka_unit_test(test_solve_against_dense),
    };
    return cmocka_run_group_tests_name("pcg", tests, NULL, NULL);
}
