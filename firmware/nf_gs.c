/* SPDX-License-Identifier: MIT */
/* nf_gs.c: Gauss-Seidel on the stripes (Eq. 8, Section 3.2). The paper
 * stops when no control point moved by more than a relative 1e-4; we stop
 * on the residual ||b - A P|| / ||b|| instead, which bounds what matters. */
#include "nf_err.h"
#include "nf_solve.h"

/* Upper storage keeps A[i][j] for j > i in row i. The lower sum of Eq. 8,
 * sum_{j<i} A[i][j] P_j(new), is scattered forward into t as each P_j is
 * finished, so the sweep reads every row once, contiguously. */
void nf_gs_sweep(const nf_stripe_t *A, const double *b, double *x, double *t)
{
    const long n = A->n;
    const int K = A->K;
    const long *dl = A->delta;
    for (long i = 0; i < 3 * n; i++)
        t[i] = b ? b[i] : 0.0;
    for (long i = 0; i < n; i++) {
        const double *row = A->S + i * K;
        double s0 = t[3 * i], s1 = t[3 * i + 1], s2 = t[3 * i + 2];
        for (int s = 1; s < K; s++) {
            const long j = i + dl[s];
            const double v = row[s];
            if (v != 0.0) {
                s0 -= v * x[3 * j];
                s1 -= v * x[3 * j + 1];
                s2 -= v * x[3 * j + 2];
            }
        }
        const double inv = 1.0 / row[0];
        s0 *= inv;
        s1 *= inv;
        s2 *= inv;
        x[3 * i] = s0;
        x[3 * i + 1] = s1;
        x[3 * i + 2] = s2;
        for (int s = 1; s < K; s++) {
            const long j = i + dl[s];
            const double v = row[s];
            if (v != 0.0) {
                t[3 * j] -= v * s0;
                t[3 * j + 1] -= v * s1;
                t[3 * j + 2] -= v * s2;
            }
        }
    }
}

int nf_gs_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                nf_arena_t *ar, nf_solve_stats_t *st, long *bad)
{
    const long n = A->n;
    double *t = nf_arena_doubles(ar, (size_t)(3 * n));
    double *e = nf_arena_doubles(ar, (size_t)(3 * n));
    if (!t || !e)
        return NF_EARENA;
    for (long i = 0; i < n; i++)
        if (!(A->S[i * A->K] > 0.0)) {
            *bad = i;
            return NF_ESINGULAR;
        }
    /* The residual costs a pass like a sweep: test every few sweeps. */
    const int every = n > 4096 ? 4 : 1;
    int it = 0;
    double rel = nf_residual(A, b, x, t);
    while (rel > o->tol && it < o->max_iter) {
        for (int k = 0; k < every && it < o->max_iter; k++, it++)
            nf_gs_sweep(A, b, x, t);
        rel = nf_residual(A, b, x, t);
        if (rel != rel)
            return NF_ESINGULAR;
    }
    st->iterations = it;
    st->rel_residual = rel;
    if (rel > o->tol)
        return NF_ENOCONV;
    if (o->probe) {
        int iters = it < 20 ? 20 : 2 * it;
        if (iters > o->max_iter)
            iters = o->max_iter;
        nf_probe_fill(e, n);
        double e0 = nf_probe_max(e, n);
        for (int k = 0; k < iters; k++)
            nf_gs_sweep(A, NULL, e, t);
        return nf_probe_judge(e, n, e0, bad);
    }
    return NF_OK;
}
