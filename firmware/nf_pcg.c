/* nf_pcg.c: conjugate gradients on the stripes, preconditioned by symmetric
 * Gauss-Seidel M = (D + L) D^-1 (D + U) = C C^T, C = (D + L) D^-1/2, in
 * split form with Eisenstat's trick: since A = (D + L) + (D + U) - D,
 *   C^-1 A C^-T v = D^1/2 [t + (D + L)^-1 (D^1/2 v - D t)],  t = (D + U)^-1 D^1/2 v,
 * one backward and one forward sweep per iteration and no separate product
 * with A: two passes over S instead of three. t = C^-T v is also the step
 * in the original unknowns, so the iterate P is updated directly. The
 * three coordinates run as three CG recurrences sharing every pass. */
#include "nf_err.h"
#include "nf_solve.h"
#include <math.h>

typedef struct pcg_ws {
    const nf_stripe_t *A;
    const double *dh;      /* D^1/2 */
    const double *invd;    /* D^-1 */
    double *r, *d, *q, *t; /* transformed residual, direction, C^-1 A C^-T d, C^-T d */
} pcg_ws_t;

/* v = (D + L)^-1 v in place: finish v_i, then scatter row i's upper entries
 * (A[j][i] = A[i][j], j > i) into the later unknowns. */
static void sweep_fwd(const nf_stripe_t *A, const double *invd, double *v)
{
    const int K = A->K;
    const long *dl = A->delta;
    for (long i = 0; i < A->n; i++) {
        const double *row = A->S + i * K;
        const double y0 = v[3 * i] * invd[i], y1 = v[3 * i + 1] * invd[i],
                     y2 = v[3 * i + 2] * invd[i];
        v[3 * i] = y0;
        v[3 * i + 1] = y1;
        v[3 * i + 2] = y2;
        for (int s = 1; s < K; s++) {
            const double a = row[s];
            if (a != 0.0) {
                const long j = i + dl[s];
                v[3 * j] -= a * y0;
                v[3 * j + 1] -= a * y1;
                v[3 * j + 2] -= a * y2;
            }
        }
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

/* q = C^-1 A C^-T d and t = C^-T d (Eisenstat), dq = d . q, in two passes:
 * the backward sweep forms t and the forward sweep's input D^1/2 d - D t,
 * the forward sweep finishes q and the dot product as each row completes. */
static void apply(pcg_ws_t *w, double dq[3])
{
    const nf_stripe_t *A = w->A;
    const int K = A->K;
    const long *dl = A->delta;
    double *t = w->t, *q = w->q;
    const double *d = w->d, *dh = w->dh, *invd = w->invd;
    for (long i = A->n - 1; i >= 0; i--) {
        const double *row = A->S + i * K;
        double s0 = dh[i] * d[3 * i], s1 = dh[i] * d[3 * i + 1], s2 = dh[i] * d[3 * i + 2];
        const double w0 = s0, w1 = s1, w2 = s2;
        for (int s = 1; s < K; s++) {
            const double a = row[s];
            if (a != 0.0) {
                const long j = i + dl[s];
                s0 -= a * t[3 * j];
                s1 -= a * t[3 * j + 1];
                s2 -= a * t[3 * j + 2];
            }
        }
        t[3 * i] = s0 * invd[i];
        t[3 * i + 1] = s1 * invd[i];
        t[3 * i + 2] = s2 * invd[i];
        /* D^1/2 d - D t = w - s: what the forward sweep starts from. */
        q[3 * i] = w0 - s0;
        q[3 * i + 1] = w1 - s1;
        q[3 * i + 2] = w2 - s2;
    }
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (long i = 0; i < A->n; i++) {
        const double *row = A->S + i * K;
        const double y0 = q[3 * i] * invd[i], y1 = q[3 * i + 1] * invd[i],
                     y2 = q[3 * i + 2] * invd[i];
        for (int s = 1; s < K; s++) {
            const double a = row[s];
            if (a != 0.0) {
                const long j = i + dl[s];
                q[3 * j] -= a * y0;
                q[3 * j + 1] -= a * y1;
                q[3 * j + 2] -= a * y2;
            }
        }
        q[3 * i] = dh[i] * (t[3 * i] + y0);
        q[3 * i + 1] = dh[i] * (t[3 * i + 1] + y1);
        q[3 * i + 2] = dh[i] * (t[3 * i + 2] + y2);
        a0 += d[3 * i] * q[3 * i];
        a1 += d[3 * i + 1] * q[3 * i + 1];
        a2 += d[3 * i + 2] * q[3 * i + 2];
    }
    dq[0] = a0;
    dq[1] = a1;
    dq[2] = a2;
}

/* CG on the split system for A x = b (b NULL: zero) from x. Stops when the
 * transformed residual of every coordinate fell below tol times its start
 * scaled to ||b|| (or below tol of its start when b = 0), or at max_iter.
 * Returns iterations, or -1 on breakdown (d^T A d <= 0: not positive definite). */
static int pcg_run(pcg_ws_t *w, const double *b, double *x, double tol, int max_iter)
{
    const nf_stripe_t *A = w->A;
    const long n = A->n;
    double rr[3], r0[3], bb[3] = {0, 0, 0}, lim[3], dq[3];
    int live[3];
    nf_stripe_matvec(A, x, w->q);
    for (long i = 0; i < 3 * n; i++)
        w->r[i] = (b ? b[i] : 0.0) - w->q[i];
    double tr[3];
    dot3(n, w->r, w->r, tr); /* ||b - A x0|| */
    if (b)
        dot3(n, b, b, bb);
    sweep_fwd(A, w->invd, w->r); /* r^ = C^-1 r = D^1/2 (D + L)^-1 r */
    for (long i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            w->r[3 * i + c] *= w->dh[i];
    dot3(n, w->r, w->r, r0);
    for (int c = 0; c < 3; c++) {
        /* ||r^|| and ||r|| shrink alike; aim a little below the target and
         * let the caller check the true residual. */
        double ref = bb[c] > 0.0 ? sqrt(bb[c]) : sqrt(tr[c]);
        double scale = tr[c] > 0.0 ? sqrt(r0[c] / tr[c]) : 0.0;
        lim[c] = 0.5 * tol * ref * scale;
        live[c] = sqrt(r0[c]) > lim[c];
        rr[c] = r0[c];
    }
    for (long i = 0; i < 3 * n; i++)
        w->d[i] = w->r[i];
    int it = 0;
    while ((live[0] || live[1] || live[2]) && it < max_iter) {
        apply(w, dq);
        double al[3], be[3];
        for (int c = 0; c < 3; c++) {
            if (live[c] && !(dq[c] > 0.0))
                return -1;
            al[c] = live[c] ? rr[c] / dq[c] : 0.0;
        }
        double rn[3] = {0, 0, 0};
        for (long i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) {
                x[3 * i + c] += al[c] * w->t[3 * i + c];
                const double ri = w->r[3 * i + c] - al[c] * w->q[3 * i + c];
                w->r[3 * i + c] = ri;
                rn[c] += ri * ri;
            }
        it++;
        for (int c = 0; c < 3; c++) {
            be[c] = live[c] && rr[c] > 0.0 ? rn[c] / rr[c] : 0.0;
            live[c] = live[c] && sqrt(rn[c]) > lim[c];
            rr[c] = rn[c];
        }
        for (long i = 0; i < n; i++)
            for (int c = 0; c < 3; c++)
                w->d[3 * i + c] = w->r[3 * i + c] + be[c] * w->d[3 * i + c];
    }
    return it;
}

int nf_pcg_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                 nf_arena_t *ar, nf_solve_stats_t *st, long *bad)
{
    const long n = A->n;
    pcg_ws_t w;
    double *dh = nf_arena_doubles(ar, (size_t)n);
    double *invd = nf_arena_doubles(ar, (size_t)n);
    w.r = nf_arena_doubles(ar, (size_t)(3 * n));
    w.d = nf_arena_doubles(ar, (size_t)(3 * n));
    w.q = nf_arena_doubles(ar, (size_t)(3 * n));
    w.t = nf_arena_doubles(ar, (size_t)(3 * n));
    double *e = nf_arena_doubles(ar, (size_t)(3 * n));
    if (!dh || !invd || !w.r || !w.d || !w.q || !w.t || !e)
        return NF_EARENA;
    for (long i = 0; i < n; i++) {
        double dii = A->S[i * A->K];
        if (!(dii > 0.0)) {
            *bad = i;
            return NF_ESINGULAR;
        }
        dh[i] = sqrt(dii);
        invd[i] = 1.0 / dii;
    }
    w.A = A;
    w.dh = dh;
    w.invd = invd;
    int it = 0;
    st->rel_residual = nf_residual(A, b, x, w.q);
    /* The true residual decides; the recurrence only steers. A restart
     * from the current iterate recovers digits the recurrence lost. */
    for (int pass = 0; pass < 4 && st->rel_residual > o->tol && it < o->max_iter; pass++) {
        int k = pcg_run(&w, b, x, o->tol, o->max_iter - it);
        if (k < 0)
            return NF_ESINGULAR;
        it += k;
        st->rel_residual = nf_residual(A, b, x, w.q);
        if (st->rel_residual != st->rel_residual)
            return NF_ESINGULAR;
    }
    st->iterations = it;
    if (st->rel_residual > o->tol)
        return NF_ENOCONV;
    if (o->probe) {
        /* Homogeneous solve from a random start: see nf_probe.c. */
        nf_probe_fill(e, n);
        double e0 = nf_probe_max(e, n);
        int iters = it < 20 ? 40 : 2 * it;
        if (pcg_run(&w, NULL, e, 1e-14, iters) < 0)
            return NF_ESINGULAR;
        return nf_probe_judge(e, n, e0, bad);
    }
    return NF_OK;
}
