/* SPDX-License-Identifier: MIT */
/* nf_stripe.c: the stripe store S of A = R^T R (Eq. 9-11) and its products. */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_stripe.h"

#if NF_ISA_COLD
void nf_stripe_init(nf_stripe_t *st, int nu, int nv, int p, int q, double *S)
{
    st->n = (long)nu * nv;
    st->nu = nu;
    st->p = p;
    st->q = q;
    st->K = (p + 1) + q * (2 * p + 1);
    st->S = S;
    for (int f = 0; f <= q; f++)
        for (int e = (f == 0 ? 0 : -p); e <= p; e++)
            st->delta[nf_stripe_slot(p, e, f)] = e + (long)f * nu;
}

double nf_stripe_get(const nf_stripe_t *st, long i, long j)
{
    if (i < 0 || j < 0 || i >= st->n || j >= st->n)
        return 0.0;
    if (j < i) {
        long t = i;
        i = j;
        j = t;
    }
    /* Row i holds column j only if their grid positions differ by (e, f)
     * with |e| <= p, 0 <= f <= q: compare grid coordinates, not raw offsets,
     * since one offset value can belong to different (e, f) near the borders. */
    long ei = i % st->nu, fi = i / st->nu, ej = j % st->nu, fj = j / st->nu;
    long e = ej - ei, f = fj - fi;
    if (f < 0 || f > st->q || e < -st->p || e > st->p || (f == 0 && e < 0))
        return 0.0;
    return st->S[i * st->K + nf_stripe_slot(st->p, (int)e, (int)f)];
}
#endif

void nf_stripe_add_outer(nf_stripe_t *st, long base, const double *R, double wgt)
{
    const int p = st->p, q = st->q, o = p + 1, K = st->K;
    const long nu = st->nu;
    for (int b = 0; b <= q; b++) {
        for (int a = 0; a <= p; a++) {
            const double ra = wgt * R[a + b * o];
            double *row = st->S + (base + a + b * nu) * K;
            /* Same v row (d == b): columns c >= a, slots e = c - a from 0. */
            const double *Rb = R + b * o;
            for (int c = a; c <= p; c++)
                row[c - a] += ra * Rb[c];
            /* Rows d > b: slots for e = c - a, c = 0..p, are contiguous. */
            for (int d = b + 1; d <= q; d++) {
                double *s = row + nf_stripe_slot(p, -a, d - b);
                const double *Rd = R + d * o;
                for (int c = 0; c <= p; c++)
                    s[c] += ra * Rd[c];
            }
        }
    }
}

/* The bicubic product uses GCC's generic vectors of 4 doubles (AVX2 on the
 * cell controller, lowered to pairs or scalars elsewhere). */
#if defined(__GNUC__) && !defined(NF_NO_VECTOR)
#define NF_STRIPE_VECTOR 1
typedef double nf_v4 __attribute__((vector_size(32)));
/* 4 doubles at any 8-byte aligned address, aliasing the doubles there. */
typedef double nf_v4u __attribute__((vector_size(32), aligned(8), may_alias));
#define V4C(ptr) (*(const nf_v4u *)(ptr))
#define NF_UNROLL6 _Pragma("GCC unroll 6")
#else
#define NF_STRIPE_VECTOR 0
#endif

/* y_i = (A x)_i for rows lo..hi, gathered: row i's slots against x_{i+delta}
 * and, by symmetry, slot s of row i - delta_s against x_{i-delta_s}. Zero
 * slots are the pairs outside the grid. */
static void matvec_rows(const nf_stripe_t *st, const double *x, double *y, long lo, long hi)
{
    const long n = st->n;
    const int K = st->K;
    for (long i = lo; i <= hi; i++) {
        const double *row = st->S + i * K;
        double a0 = row[0] * x[3 * i], a1 = row[0] * x[3 * i + 1], a2 = row[0] * x[3 * i + 2];
        for (int s = 1; s < K; s++) {
            const long ju = i + st->delta[s], jl = i - st->delta[s];
            const double u = ju < n ? row[s] : 0.0, l = jl >= 0 ? st->S[jl * K + s] : 0.0;
            if (u != 0.0) {
                a0 += u * x[3 * ju];
                a1 += u * x[3 * ju + 1];
                a2 += u * x[3 * ju + 2];
            }
            if (l != 0.0) {
                a0 += l * x[3 * jl];
                a1 += l * x[3 * jl + 1];
                a2 += l * x[3 * jl + 2];
            }
        }
        y[3 * i] = a0;
        y[3 * i + 1] = a1;
        y[3 * i + 2] = a2;
    }
}

#if NF_STRIPE_VECTOR
/* Bicubic rows lo..hi, every neighbour i +- delta within 0..N-2 (a 4-wide
 * load at x_j reads one double past it): slots 1..3 couple i with i+1..i+3,
 * for f = 1..3 the 7 slots from 4 + 7 (f-1) the 7 points from i + f Nu - 3
 * (nf_stripe_slot); slots outside the grid hold zeros. */
/* The 7 points from i + f Nu - 3 and the 7 to i - f Nu + 3 of row i. */
static inline __attribute__((always_inline)) void group33(const double *S, const double *x, long i,
                                                          long nu, int f, nf_v4 *out)
{
    const int g = 4 + 7 * (f - 1);
    const long ju = i + f * nu - 3, jl = i - f * nu + 3;
    nf_v4 su = S[25 * i + g] * V4C(x + 3 * ju), sl = S[25 * jl + g] * V4C(x + 3 * jl);
    NF_UNROLL6
    for (int k = 1; k < 7; k++) {
        su += S[25 * i + g + k] * V4C(x + 3 * (ju + k));
        sl += S[25 * (jl - k) + g + k] * V4C(x + 3 * (jl - k));
    }
    *out = su + sl; /* through a pointer: no vector return value (psabi) */
}

static void matvec_33(const nf_stripe_t *st, const double *x, double *y, long lo, long hi)
{
    const long nu = st->nu;
    const double *S = st->S;
    for (long i = lo; i <= hi; i++) {
        const double *a = S + 25 * i;
        for (int l = 0; l < 4; l++) /* the stripes run ahead of the hardware prefetcher */
            __builtin_prefetch(a + 16 * 25 + 8 * l);
        const nf_v4 s0 = a[0] * V4C(x + 3 * i) + a[1] * V4C(x + 3 * (i + 1)) +
                         a[2] * V4C(x + 3 * (i + 2)) + a[3] * V4C(x + 3 * (i + 3));
        const nf_v4 l0 = S[25 * (i - 1) + 1] * V4C(x + 3 * (i - 1)) +
                         S[25 * (i - 2) + 2] * V4C(x + 3 * (i - 2)) +
                         S[25 * (i - 3) + 3] * V4C(x + 3 * (i - 3));
        nf_v4 s1, s2, s3;
        group33(S, x, i, nu, 1, &s1);
        group33(S, x, i, nu, 2, &s2);
        group33(S, x, i, nu, 3, &s3);
        const nf_v4 sum = ((s0 + l0) + s1) + (s2 + s3);
        y[3 * i] = sum[0];
        y[3 * i + 1] = sum[1];
        y[3 * i + 2] = sum[2];
    }
}
#endif

void nf_stripe_matvec(const nf_stripe_t *st, const double *x, double *y)
{
    const long n = st->n;
    const int K = st->K;
#if NF_STRIPE_VECTOR
    const long lo = 3L * st->nu + 3, hi = n - 3L * st->nu - 5;
    if (st->p == 3 && st->q == 3 && hi >= lo) {
        matvec_rows(st, x, y, 0, lo - 1);
        matvec_33(st, x, y, lo, hi);
        matvec_rows(st, x, y, hi + 1, n - 1);
        return;
    }
#endif
    for (long i = 0; i < 3 * n; i++)
        y[i] = 0.0;
    for (long i = 0; i < n; i++) {
        const double *row = st->S + i * K;
        const double xi0 = x[3 * i], xi1 = x[3 * i + 1], xi2 = x[3 * i + 2];
        double a0 = row[0] * xi0, a1 = row[0] * xi1, a2 = row[0] * xi2;
        for (int s = 1; s < K; s++) {
            const long j = i + st->delta[s];
            const double v = row[s];
            if (v == 0.0 || j >= n)
                continue; /* unused slot: outside the grid */
            a0 += v * x[3 * j];
            a1 += v * x[3 * j + 1];
            a2 += v * x[3 * j + 2];
            y[3 * j] += v * xi0; /* symmetric half: A[j][i] = A[i][j] */
            y[3 * j + 1] += v * xi1;
            y[3 * j + 2] += v * xi2;
        }
        y[3 * i] += a0;
        y[3 * i + 1] += a1;
        y[3 * i + 2] += a2;
    }
}
