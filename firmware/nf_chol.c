/* SPDX-License-Identifier: MIT */
/* nf_chol.c: banded Cholesky (George and Liu; the paper's Table 4 method).
 * A = U^T U with U upper, half bandwidth bw = q Nu + p, stored row-major
 * with bw + 1 entries per row: band[i*(bw+1) + t] = U[i][i+t]. Fill-in
 * stays inside the band, so the factor needs N (bw + 1) doubles. */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_err.h"
#include "nf_solve.h"
#include <math.h>

/* The factorisation's row update four doubles at a time (GCC's generic
 * vectors: AVX2 in the v3 copy, pairs in the baseline), the same products
 * and sums per element as one at a time: the same factor to the bit. */
#if defined(__GNUC__) && !defined(NF_NO_VECTOR)
#define NF_CHOL_VECTOR 1
typedef double nf_cv4u __attribute__((vector_size(32), aligned(8), may_alias));
#else
#define NF_CHOL_VECTOR 0
#endif

/* A pivot below this fraction of its original diagonal means the column is
 * (numerically) a combination of earlier ones: the data do not determine it. */
#define NF_CHOL_PIVOT_REL 1e-13

static void band_solve(const double *band, long n, long bw, double *y)
{
    const long W = bw + 1;
    for (long i = 0; i < n; i++) { /* U^T y = b: scatter column i forward */
        const double *row = band + i * W;
        const long m = (bw < n - 1 - i) ? bw : n - 1 - i;
        for (int c = 0; c < 3; c++)
            y[3 * i + c] /= row[0];
        const double y0 = y[3 * i], y1 = y[3 * i + 1], y2 = y[3 * i + 2];
        for (long t = 1; t <= m; t++) {
            const double u = row[t];
            y[3 * (i + t)] -= u * y0;
            y[3 * (i + t) + 1] -= u * y1;
            y[3 * (i + t) + 2] -= u * y2;
        }
    }
    for (long i = n - 1; i >= 0; i--) { /* U x = y: gather row i */
        const double *row = band + i * W;
        const long m = (bw < n - 1 - i) ? bw : n - 1 - i;
        double s0 = y[3 * i], s1 = y[3 * i + 1], s2 = y[3 * i + 2];
        for (long t = 1; t <= m; t++) {
            const double u = row[t];
            s0 -= u * y[3 * (i + t)];
            s1 -= u * y[3 * (i + t) + 1];
            s2 -= u * y[3 * (i + t) + 2];
        }
        y[3 * i] = s0 / row[0];
        y[3 * i + 1] = s1 / row[0];
        y[3 * i + 2] = s2 / row[0];
    }
}

int nf_chol_solve(const nf_stripe_t *A, const double *b, double *x, nf_arena_t *ar,
                  nf_solve_stats_t *st, long *bad)
{
    const long n = A->n, bw = (long)A->q * A->nu + A->p, W = bw + 1;
    const int K = A->K;
    double *band = nf_arena_doubles(ar, (size_t)(n * W));
    double *w = nf_arena_doubles(ar, (size_t)(3 * n));
    if (!band || !w)
        return NF_EARENA;
    for (long i = 0; i < n; i++)
        for (int s = 0; s < K; s++) {
            const long d = A->delta[s];
            /* Add: when Nu < 2p+1 two slots can share one offset (only one
             * of them is a real grid neighbour, the other stays zero). */
            if (i + d < n)
                band[i * W + d] += A->S[i * K + s];
        }
    /* Right-looking factorisation: row i of U, then its rank-1 update of
     * the trailing rows inside the band (contiguous inner loop). */
    for (long i = 0; i < n; i++) {
        double *ri = band + i * W;
        const double orig = A->S[i * K];
        if (!(ri[0] > NF_CHOL_PIVOT_REL * orig) || !(orig > 0.0)) {
            *bad = i;
            return NF_ESINGULAR;
        }
        const double u = sqrt(ri[0]), inv = 1.0 / u;
        ri[0] = u;
        const long m = (bw < n - 1 - i) ? bw : n - 1 - i;
        long last = 0; /* trailing zeros of the row need no update */
        for (long t = 1; t <= m; t++) {
            ri[t] *= inv;
            if (ri[t] != 0.0)
                last = t;
        }
        for (long t = 1; t <= last; t++) {
            const double f = ri[t];
            if (f == 0.0)
                continue;
            double *rj = band + (i + t) * W - t; /* rj[t2] = U[i+t][i+t2] */
            long t2 = t;
#if NF_CHOL_VECTOR
            for (; t2 + 3 <= last; t2 += 4)
                *(nf_cv4u *)(rj + t2) -= f * *(const nf_cv4u *)(ri + t2);
#endif
            for (; t2 <= last; t2++)
                rj[t2] -= f * ri[t2];
        }
    }
    for (long i = 0; i < 3 * n; i++)
        x[i] = b[i];
    band_solve(band, n, bw, x);
    /* One step of iterative refinement against the stripes recovers the
     * digits the factorisation lost. */
    nf_residual(A, b, x, w);
    band_solve(band, n, bw, w);
    for (long i = 0; i < 3 * n; i++)
        x[i] += w[i];
    st->iterations = 0;
    st->rel_residual = nf_residual(A, b, x, w);
    if (st->rel_residual != st->rel_residual)
        return NF_ESINGULAR;
    return NF_OK;
}
