/* SPDX-License-Identifier: MIT */
/* nf_stripe.h: stripe storage of the symmetric normal matrix (Section 3.1).
 * A = R^T R has non-zeros only at offsets delta = e + f Nu, |e| <= p,
 * |f| <= q (Eq. 11): 2q+1 stripes of width 2p+1. By symmetry we keep the
 * offsets delta >= 0 only: f = 0, e = 0..p and f = 1..q, e = -p..p, i.e.
 * K = (p+1) + q(2p+1) slots per row, row-major: S[i*K + slot] = A[i][i+delta].
 * Row-major keeps everything a point or a sweep touches for control point i
 * in one contiguous run. Vectors hold three right-hand sides interleaved
 * (x, y, z of control point i at 3i..3i+2), so one pass over S serves all three. */
#ifndef NF_STRIPE_H
#define NF_STRIPE_H

#include "nf_config.h"

#define NF_MAX_SLOTS ((NF_MAX_DEGREE + 1) + NF_MAX_DEGREE * (2 * NF_MAX_DEGREE + 1))

typedef struct nf_stripe {
    long n; /* N = nu nv rows */
    int nu, p, q;
    int K;                    /* slots per row */
    double *S;                /* n*K */
    long delta[NF_MAX_SLOTS]; /* column offset j - i of each slot */
} nf_stripe_t;

/* Slot of offset (e, f) with f > 0, or f == 0 and e >= 0. */
static inline int nf_stripe_slot(int p, int e, int f)
{
    return f == 0 ? e : (p + 1) + (f - 1) * (2 * p + 1) + (e + p);
}

/* Lay out the structure (S must hold n*K doubles, zeroed). */
void nf_stripe_init(nf_stripe_t *st, int nu, int nv, int p, int q, double *S);

/* A[i][j] for any i, j (0 outside the pattern); for tests and diagnostics. */
double nf_stripe_get(const nf_stripe_t *st, long i, long j);

/* Add wgt * r r^T where r has (p+1)(q+1) non-zeros R[a + b(p+1)] at columns
 * base + a + b Nu (Eq. 9), the contribution of one row of R. */
void nf_stripe_add_outer(nf_stripe_t *st, long base, const double *R, double wgt);

/* y = A x for three interleaved vectors. */
void nf_stripe_matvec(const nf_stripe_t *st, const double *x, double *y);

#endif
