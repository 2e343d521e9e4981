/* nf_stripe.c: the stripe store S of A = R^T R (Eq. 9-11) and its products. */
#include "nf_stripe.h"

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

void nf_stripe_matvec(const nf_stripe_t *st, const double *x, double *y)
{
    const long n = st->n;
    const int K = st->K;
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
