/* SPDX-License-Identifier: MIT */
/* test_edges.c: honest edges in a fit pass (cf_edges, issue 14). The
 * nominal refined into a finer net's knots against a dense least-squares
 * fit of that net's basis to the nominal's points (the same surface, found
 * without knot insertion); a pass over data on part of the domain, with
 * the control points no point reaches pinned to that nominal, against a
 * dense solve of Eq. 7 with beta_i (P_i - nominal_i) added for the control
 * points whose support (found from the Cox-de Boor basis) holds no point. */
#include "cf_edges.h"
#include "cf_err.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_refine.h"
#include "ref_dense.h"
#include <stdlib.h>
#include <string.h>

/* The nominal (6 x 5, degree 3 x 2, polynomial) and cur: the nominal with
 * knots inserted in u and v, control points moved (P0 of a later round of
 * the loop is not the nominal). */
static void make(nf_surf_t *nom, nf_surf_t *cur)
{
    ref_seed(1414);
    ref_surf_random(nom, 3, 2, 6, 5, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    const double Xu[] = {0.21, 0.6, 0.6, 0.83}, Xv[] = {0.37, 0.71};
    nf_surf_t a;
    assert_int_equal(cf_surf_alloc(&a, 3, 2, 10, 5), 0);
    assert_int_equal(nf_refine_u(nom, Xu, 4, &a), NF_OK);
    assert_int_equal(cf_surf_alloc(cur, 3, 2, 10, 7), 0);
    assert_int_equal(nf_refine_v(&a, Xv, 2, cur), NF_OK);
    cf_surf_free(&a);
    for (long k = 0; k < 3L * cur->nu * cur->nv; k++)
        cur->cp[k] += ref_rand(-0.3, 0.3);
}

/* The net in s's space closest to nominal at a 4 n x 4 n grid of
 * parameters (dense normal equations): nominal itself when it lies in the
 * space. x: 3 N. */
static void lsq_net(const nf_surf_t *s, const nf_surf_t *nominal, double *x)
{
    const long n = (long)s->nu * s->nv;
    const int g = 4 * (s->nu > s->nv ? s->nu : s->nv);
    double *A = calloc((size_t)(n * n), sizeof(double)), *b = calloc((size_t)(3 * n), sizeof *b);
    double *row = malloc(sizeof(double) * (size_t)n);
    assert_true(A && b && row);
    for (int i = 0; i <= g; i++)
        for (int k = 0; k <= g; k++) {
            double u = (double)i / g, v = (double)k / g, P[3];
            nf_surf_eval(nominal, u, v, P);
            ref_rbasis_row(s, u, v, row);
            for (long a = 0; a < n; a++) {
                if (row[a] == 0.0)
                    continue;
                for (long c = 0; c < n; c++)
                    A[a * n + c] += row[a] * row[c];
                for (int d = 0; d < 3; d++)
                    b[3 * a + d] += row[a] * P[d];
            }
        }
    assert_int_equal(ref_solve(A, b, n, x), 0);
    free(A);
    free(b);
    free(row);
}

static void test_nominal_refined(void **state)
{
    (void)state;
    nf_surf_t nom, cur, out;
    make(&nom, &cur);
    assert_int_equal(cf_edges_nominal(&nom, &cur, &out), 0);
    assert_int_equal(out.nu, cur.nu);
    assert_int_equal(out.nv, cur.nv);
    for (int i = 0; i < cur.nu + cur.p + 1; i++)
        assert_true(out.U[i] == cur.U[i]);
    for (int i = 0; i < cur.nv + cur.q + 1; i++)
        assert_true(out.V[i] == cur.V[i]);
    const long n = (long)cur.nu * cur.nv;
    double *x = malloc(sizeof(double) * 3 * (size_t)n), d = 0.0;
    lsq_net(&cur, &nom, x);
    for (long k = 0; k < 3 * n; k++)
        d = fmax(d, fabs(out.cp[k] - x[k]));
    print_message("nominal refined into %d x %d: |P - dense lsq| %.3g\n", cur.nu, cur.nv, d);
    assert_true(d <= 1e-9);
    /* Not nested: cur's knots lack one of the nominal's (the nominal into
     * its own refinement's coarser sibling), or the degrees differ. */
    nf_surf_t bad;
    assert_int_equal(cf_edges_nominal(&cur, &nom, &bad), CF_EARG);
    nf_surf_t deg;
    ref_surf_random(&deg, 2, 2, 6, 5, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    assert_int_equal(cf_edges_nominal(&nom, &deg, &bad), CF_EARG);
    ref_surf_free(&deg);
    free(x);
    cf_surf_free(&out);
    cf_surf_free(&cur);
    ref_surf_free(&nom);
}

/* 1 when the support of control point (a, b) of s holds a point of pts:
 * from the basis itself, N_a,p(u) N_b,q(v) != 0 at some point. */
static int supported(const nf_surf_t *s, int a, int b, const double *pts, long m)
{
    for (long k = 0; k < m; k++) {
        double u = pts[5 * k], v = pts[5 * k + 1];
        if (ref_bspline(a, s->p, s->U, s->nu + s->p + 1, u) != 0.0 &&
            ref_bspline(b, s->q, s->V, s->nv + s->q + 1, v) != 0.0)
            return 1;
    }
    return 0;
}

static void test_pass_pinned_dense(void **state)
{
    (void)state;
    nf_surf_t nom, cur, net;
    make(&nom, &cur);
    const long M = 1500, n = (long)cur.nu * cur.nv;
    double *pts = malloc(sizeof(double) * 5 * (size_t)M);
    assert_non_null(pts);
    for (long k = 0; k < M; k++) { /* data on u < 0.4 only */
        double *q = pts + 5 * k;
        q[0] = ref_rand(0.0, 0.4);
        q[1] = ref_rand(0.0, 1.0);
        nf_surf_eval(&nom, q[0], q[1], q + 2);
        q[4] += 1.0 + 0.5 * sin(6.0 * q[1]); /* the part off the nominal */
    }
    /* The pass: rows, footprint, pins, solve. */
    long bytes = cf_fitpass_bytes(&cur, NF_SOLVER_CHOL, 1);
    void *blk = aligned_alloc(16, ((size_t)bytes + 15) / 16 * 16);
    assert_non_null(blk);
    assert_int_equal(cf_surf_copy(&net, &cur), 0);
    cf_fitpass_t ps;
    cf_edges_t e;
    char msg[256];
    assert_int_equal(cf_fitpass_begin(&ps, blk, (size_t)bytes, &cur, NF_ALPHA_DEFAULT,
                                      NF_BETA_DEFAULT, NF_SOLVER_CHOL, 1, "t", msg, sizeof msg),
                     0);
    assert_int_equal(cf_edges_begin(&e, &cur), 0);
    assert_int_equal(cf_fitpass_rows(&ps, pts, M, 5, NULL), 0);
    for (long k = 0; k < M; k++)
        cf_edges_add(&e, pts[5 * k], pts[5 * k + 1]);
    const long pinned = cf_edges_pin(&e, &nom, &ps);
    assert_int_equal(cf_fitpass_solve(&ps, NULL, &net, "t", msg, sizeof msg), 0);
    /* The reference: the flags from the basis, the targets from the dense
     * least-squares net, Eq. 7 dense. */
    double *tgt = malloc(sizeof(double) * 3 * (size_t)n),
           *X = malloc(sizeof(double) * 3 * (size_t)n);
    double *A, *b;
    lsq_net(&cur, &nom, tgt);
    ref_eq7(&cur, pts, M, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, &A, &b);
    long want = 0;
    for (int bq = 0; bq < cur.nv; bq++)
        for (int a = 0; a < cur.nu; a++) {
            if (supported(&cur, a, bq, pts, M))
                continue;
            const long i = a + (long)bq * cur.nu;
            want++;
            A[i * n + i] += NF_FOOTPRINT_BETA;
            for (int c = 0; c < 3; c++)
                b[3 * i + c] += NF_FOOTPRINT_BETA * tgt[3 * i + c];
        }
    assert_int_equal(ref_solve(A, b, n, X), 0);
    double d = 0.0, sc = 0.0, off = 0.0;
    for (long k = 0; k < 3 * n; k++) {
        d = fmax(d, fabs(net.cp[k] - X[k]));
        sc = fmax(sc, fabs(X[k]));
    }
    /* Beyond the data (u >= 0.85: every control point there pinned) the
     * surface is the nominal, within alpha / beta of the step. */
    for (int i = 0; i <= 20; i++)
        for (int k = 0; k <= 20; k++) {
            double u = 0.85 + 0.15 * i / 20, v = (double)k / 20, P[3], Q[3];
            nf_surf_eval(&net, u, v, P);
            nf_surf_eval(&nom, u, v, Q);
            off = fmax(off, sqrt((P[0] - Q[0]) * (P[0] - Q[0]) + (P[1] - Q[1]) * (P[1] - Q[1]) +
                                 (P[2] - Q[2]) * (P[2] - Q[2])));
        }
    print_message("pinned %ld of %ld (basis: %ld): |P - dense| %.3g (scale %.3g); beyond the "
                  "data %.3g from the nominal\n",
                  pinned, n, want, d, sc, off);
    assert_int_equal(pinned, want);
    assert_true(want > 0 && want < n);
    assert_true(d <= 1e-9 * sc);
    assert_true(off <= 1e-3);
    free(A);
    free(b);
    free(tgt);
    free(X);
    free(pts);
    free(blk);
    cf_edges_free(&e);
    cf_surf_free(&net);
    cf_surf_free(&cur);
    ref_surf_free(&nom);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nominal_refined),
        cmocka_unit_test(test_pass_pinned_dense),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
