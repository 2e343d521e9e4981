/* nf_pcg.c: conjugate gradients on the stripes, preconditioned by symmetric
 * Gauss-Seidel M = (D + L) D^-1 (D + U). The three coordinates run as three
 * independent CG recurrences sharing every pass over S. */
#include "nf_err.h"
#include "nf_solve.h"
#include <math.h>

/* z = M^-1 r in place (z holds r on entry): forward (D + L) y = r with the
 * lower part scattered from rows, then backward (D + U) z = D y. */
static void sgs_apply(const nf_stripe_t *A, const double *invd, double *z)
{
    const long n = A->n;
    const int K = A->K;
    const long *dl = A->delta;
    for (long i = 0; i < n; i++) {
        const double *row = A->S + i * K;
        const double y0 = z[3 * i] * invd[i], y1 = z[3 * i + 1] * invd[i],
                     y2 = z[3 * i + 2] * invd[i];
        z[3 * i] = y0;
        z[3 * i + 1] = y1;
        z[3 * i + 2] = y2;
        for (int s = 1; s < K; s++) {
            const double v = row[s];
            if (v != 0.0) {
                const long j = i + dl[s];
                z[3 * j] -= v * y0;
                z[3 * j + 1] -= v * y1;
                z[3 * j + 2] -= v * y2;
            }
        }
    }
    for (long i = n - 1; i >= 0; i--) {
        const double *row = A->S + i * K;
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (int s = 1; s < K; s++) {
            const double v = row[s];
            if (v != 0.0) {
                const long j = i + dl[s];
                s0 += v * z[3 * j];
                s1 += v * z[3 * j + 1];
                s2 += v * z[3 * j + 2];
            }
        }
        z[3 * i] -= s0 * invd[i];
        z[3 * i + 1] -= s1 * invd[i];
        z[3 * i + 2] -= s2 * invd[i];
    }
}

static void dot3(long n, const double *a, const double *b, double out[3])
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (long i = 0; i < n; i++) {
        s0 += a[3 * i] * b[3 * i];
        s1 += a[3 * i + 1] * b[3 * i + 1];
        s2 += a[3 * i + 2] * b[3 * i + 2];
    }
    out[0] = s0;
    out[1] = s1;
    out[2] = s2;
}

/* PCG on A x = b (b NULL: zero). Stops when ||r_c|| <= tol * ref_c for every
 * coordinate, ref_c = ||b_c|| (or ||r0_c|| when b_c = 0), or after max_iter.
 * Returns iterations, or -1 on breakdown (d^T A d <= 0: not positive definite). */
static int pcg_run(const nf_stripe_t *A, const double *b, double *x, double tol, int max_iter,
                   const double *invd, double *r, double *z, double *d, double *Ad)
{
    const long n = A->n;
    double rz[3], ref[3], rr[3], dAd[3];
    int live[3] = {1, 1, 1};
    nf_stripe_matvec(A, x, Ad);
    for (long i = 0; i < 3 * n; i++)
        r[i] = (b ? b[i] : 0.0) - Ad[i];
    if (b)
        dot3(n, b, b, ref);
    else
        ref[0] = ref[1] = ref[2] = 0.0;
    dot3(n, r, r, rr);
    for (int c = 0; c < 3; c++) {
        ref[c] = sqrt(ref[c] > 0.0 ? ref[c] : rr[c]);
        live[c] = sqrt(rr[c]) > tol * ref[c];
    }
    for (long i = 0; i < 3 * n; i++)
        z[i] = r[i];
    sgs_apply(A, invd, z);
    for (long i = 0; i < 3 * n; i++)
        d[i] = z[i];
    dot3(n, r, z, rz);
    int it = 0;
    while ((live[0] || live[1] || live[2]) && it < max_iter) {
        nf_stripe_matvec(A, d, Ad);
        dot3(n, d, Ad, dAd);
        double al[3];
        for (int c = 0; c < 3; c++) {
            if (live[c] && !(dAd[c] > 0.0))
                return -1;
            al[c] = live[c] ? rz[c] / dAd[c] : 0.0;
        }
        for (long i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) {
                x[3 * i + c] += al[c] * d[3 * i + c];
                r[3 * i + c] -= al[c] * Ad[3 * i + c];
            }
        it++;
        dot3(n, r, r, rr);
        for (int c = 0; c < 3; c++)
            live[c] = live[c] && sqrt(rr[c]) > tol * ref[c];
        for (long i = 0; i < 3 * n; i++)
            z[i] = r[i];
        sgs_apply(A, invd, z);
        double rzn[3], be[3];
        dot3(n, r, z, rzn);
        for (int c = 0; c < 3; c++) {
            be[c] = live[c] && rz[c] != 0.0 ? rzn[c] / rz[c] : 0.0;
            rz[c] = rzn[c];
        }
        for (long i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                d[3 * i + c] = z[3 * i + c] + be[c] * d[3 * i + c];
    }
    return it;
}

int nf_pcg_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                 nf_arena_t *ar, nf_solve_stats_t *st, long *bad)
{
    const long n = A->n;
    double *r = nf_arena_doubles(ar, (size_t)(3 * n));
    double *z = nf_arena_doubles(ar, (size_t)(3 * n));
    double *d = nf_arena_doubles(ar, (size_t)(3 * n));
    double *Ad = nf_arena_doubles(ar, (size_t)(3 * n));
    double *invd = nf_arena_doubles(ar, (size_t)n);
    double *e = nf_arena_doubles(ar, (size_t)(3 * n));
    if (!r || !z || !d || !Ad || !invd || !e)
        return NF_EARENA;
    for (long i = 0; i < n; i++) {
        double dii = A->S[i * A->K];
        if (!(dii > 0.0)) {
            *bad = i;
            return NF_ESINGULAR;
        }
        invd[i] = 1.0 / dii;
    }
    int it = pcg_run(A, b, x, o->tol, o->max_iter, invd, r, z, d, Ad);
    if (it < 0)
        return NF_ESINGULAR;
    st->iterations = it;
    st->rel_residual = nf_residual(A, b, x, r);
    if (st->rel_residual != st->rel_residual)
        return NF_ESINGULAR;
    if (st->rel_residual > o->tol) {
        /* The recurrence residual drifts from the true one; a restart from
         * the current iterate recovers the last digits. */
        int more = pcg_run(A, b, x, o->tol, o->max_iter - it, invd, r, z, d, Ad);
        if (more < 0)
            return NF_ESINGULAR;
        st->iterations += more;
        st->rel_residual = nf_residual(A, b, x, r);
        if (st->rel_residual > o->tol)
            return NF_ENOCONV;
    }
    if (o->probe) {
        /* Homogeneous solve from a random start: see nf_probe. */
        nf_probe_fill(e, n);
        double e0 = nf_probe_max(e, n);
        int iters = st->iterations < 20 ? 40 : 2 * st->iterations;
        if (pcg_run(A, NULL, e, 1e-14, iters, invd, r, z, d, Ad) < 0)
            return NF_ESINGULAR;
        return nf_probe_judge(e, n, e0, bad);
    }
    return NF_OK;
}
