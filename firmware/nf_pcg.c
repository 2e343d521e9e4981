/* SPDX-License-Identifier: MIT */
/* nf_pcg.c: conjugate gradients on the stripes, preconditioned by symmetric
 * Gauss-Seidel M = (D + L) D^-1 (D + U) = C C^T, C = (D + L) D^-1/2, in
 * split form with Eisenstat's trick: since A = (D + L) + (D + U) - D,
 *   C^-1 A C^-T v = D^1/2 [t + (D + L)^-1 (D^1/2 v - D t)],  t = (D + U)^-1 D^1/2 v,
 * one backward and one forward sweep per iteration and no separate product
 * with A: two passes over S instead of three. t = C^-T v is also the step
 * in the original unknowns, so the iterate P is updated directly. The
 * three coordinates run as three CG recurrences sharing every pass.
 *
 * The sweep vectors t and q hold 4 doubles per point, x y z and in the
 * fourth lane D^-1 (t) or D^1/2 (q), so one neighbour is one 4-wide
 * multiply-add and the diagonal factors cost no extra bytes. Bicubic rows
 * whose every neighbour is in range take unrolled 4-wide kernels; the last
 * rows, other degrees and other compilers take the generic loops. */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_err.h"
#include "nf_solve.h"
#include <math.h>

#if defined(__GNUC__) && !defined(NF_NO_VECTOR)
#define NF_PCG_VECTOR 1
typedef double nf_v4 __attribute__((vector_size(32)));
/* 4 doubles at any 8-byte aligned address, aliasing the doubles there. */
typedef double nf_v4u __attribute__((vector_size(32), aligned(8), may_alias));
#define V4(ptr) (*(nf_v4u *)(ptr))
#define NF_UNROLL7 _Pragma("GCC unroll 7")
#else
#define NF_PCG_VECTOR 0
#endif

typedef struct pcg_ws {
    const nf_stripe_t *A;
    double *x;     /* the iterate: 3 per point */
    double *r, *d; /* transformed residual, direction: 3 per point */
    double *q, *t; /* C^-1 A C^-T d and C^-T d: 4 per point, lane 3 D^1/2 (q), D^-1 (t) */
    long hi;       /* last row of the bicubic kernels, -1: generic loops only */
} pcg_ws_t;

/* v = (D + L)^-1 v in place (v 3 per point, D^-1 from t's fourth lane):
 * finish v_i, then scatter row i's upper entries (A[j][i] = A[i][j], j > i)
 * into the later unknowns. */
static void sweep_fwd(const nf_stripe_t *A, const double *t, double *v)
{
    const int K = A->K;
    const long *dl = A->delta;
    for (long i = 0; i < A->n; i++) {
        const double *row = A->S + i * K;
        const double invd = t[4 * i + 3];
        const double y0 = v[3 * i] * invd, y1 = v[3 * i + 1] * invd, y2 = v[3 * i + 2] * invd;
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

#if defined(__GNUC__)
#define NF_INLINE static inline __attribute__((always_inline))
#else
#define NF_INLINE static inline
#endif

/* The previous iteration's vector updates, done as the backward sweep
 * reaches point i and before it overwrites t_i: x_i += alpha t_i and
 * d_i = r_i + beta d_i (ab = alpha[3], beta[3]). Same operations as
 * separate passes, one pass over x, t and d fewer. */
NF_INLINE void fold_row(const pcg_ws_t *w, long i, const double ab[6])
{
    double *x = w->x + 3 * i, *d = w->d + 3 * i;
    const double *r = w->r + 3 * i, *t = w->t + 4 * i;
    for (int c = 0; c < 3; c++) {
        x[c] += ab[c] * t[c];
        d[c] = r[c] + ab[3 + c] * d[c];
    }
}

/* Backward sweep, rows from..to descending: t_i = D^-1 s_i with
 * s_i = D^1/2 d_i - sum_{j > i} A_ij t_j. The zero test skips the slots
 * that fall outside the grid (and so outside the vectors near the end). */
static void bwd_rows(const pcg_ws_t *w, const double ab[6], long from, long to)
{
    const nf_stripe_t *A = w->A;
    const int K = A->K;
    const long *dl = A->delta;
    const double *d = w->d, *q = w->q;
    double *t = w->t;
    for (long i = from; i >= to; i--) {
        const double *row = A->S + i * K;
        const double dh = q[4 * i + 3], invd = t[4 * i + 3];
        fold_row(w, i, ab);
        double s0 = dh * d[3 * i], s1 = dh * d[3 * i + 1], s2 = dh * d[3 * i + 2];
        for (int s = 1; s < K; s++) {
            const double a = row[s];
            if (a != 0.0) {
                const long j = i + dl[s];
                s0 -= a * t[4 * j];
                s1 -= a * t[4 * j + 1];
                s2 -= a * t[4 * j + 2];
            }
        }
        t[4 * i] = s0 * invd;
        t[4 * i + 1] = s1 * invd;
        t[4 * i + 2] = s2 * invd;
    }
}

/* Forward sweep, rows from..n-1, on q_i zeroed before the first row that
 * reaches it: y_i = D^-1 (D^1/2 d_i - D t_i + q_i), D^1/2 d - D t being the
 * sweep's input and q_i the sum scattered so far from the earlier rows;
 * y_i scattered into the later rows, then q_i = D^1/2 (t_i + y_i) and
 * dq += d_i q_i. Forming the input here spares the backward sweep a store. */
static void fwd_rows(const nf_stripe_t *A, const double *d, const double *t, double *q, long from,
                     double dq[3])
{
    const int K = A->K;
    const long *dl = A->delta;
    double a0 = dq[0], a1 = dq[1], a2 = dq[2];
    for (long i = from; i < A->n; i++) {
        const double *row = A->S + i * K;
        const double dh = q[4 * i + 3], invd = t[4 * i + 3];
        const double y0 = (dh * d[3 * i] - row[0] * t[4 * i] + q[4 * i]) * invd;
        const double y1 = (dh * d[3 * i + 1] - row[0] * t[4 * i + 1] + q[4 * i + 1]) * invd;
        const double y2 = (dh * d[3 * i + 2] - row[0] * t[4 * i + 2] + q[4 * i + 2]) * invd;
        for (int s = 1; s < K; s++) {
            const double a = row[s];
            if (a != 0.0) {
                const long j = i + dl[s];
                q[4 * j] -= a * y0;
                q[4 * j + 1] -= a * y1;
                q[4 * j + 2] -= a * y2;
            }
        }
        q[4 * i] = dh * (t[4 * i] + y0);
        q[4 * i + 1] = dh * (t[4 * i + 1] + y1);
        q[4 * i + 2] = dh * (t[4 * i + 2] + y2);
        a0 += d[3 * i] * q[4 * i];
        a1 += d[3 * i + 1] * q[4 * i + 1];
        a2 += d[3 * i + 2] * q[4 * i + 2];
    }
    dq[0] = a0;
    dq[1] = a1;
    dq[2] = a2;
}

#if NF_PCG_VECTOR
/* The bicubic slots (nf_stripe_slot, p = q = 3): 1..3 couple i with
 * i+1..i+3; for f = 1..3, the 7 slots from 4 + 7 (f-1) couple i with the 7
 * consecutive points from i + f Nu - 3. Slots outside the grid hold zeros
 * and multiply finite values, so rows i <= hi = N - 3 Nu - 4 need no tests. */
/* Rows ahead of the current one whose stripes are fetched early. */
#define NF_PCG_AHEAD 16
#define G33(f) (4 + 7 * ((f)-1))

/* Backward sweep, bicubic rows hi..0. t_{i+1..i+3}, the last rows done,
 * ride in registers; three more sums split the 24-term chain. */
static void bwd_33(const pcg_ws_t *w, const double ab[6], long hi)
{
    const nf_stripe_t *A = w->A;
    const long nu = A->nu;
    const double *d = w->d, *q = w->q;
    double *t = w->t;
    nf_v4 t1 = V4(t + 4 * (hi + 1)), t2 = V4(t + 4 * (hi + 2)), t3 = V4(t + 4 * (hi + 3));
    for (long i = hi; i >= 0; i--) {
        const double *a = A->S + 25 * i;
        const double dh = q[4 * i + 3], invd = t[4 * i + 3];
        for (int l = 0; l < 4; l++) /* the stripes run ahead of the hardware prefetcher */
            __builtin_prefetch(a - NF_PCG_AHEAD * 25 + 8 * l);
        fold_row(w, i, ab);
        const double *g1 = t + 4 * (i + nu - 3), *g2 = g1 + 4 * nu, *g3 = g2 + 4 * nu;
        nf_v4 s1 = a[G33(1)] * V4(g1), s2 = a[G33(2)] * V4(g2), s3 = a[G33(3)] * V4(g3);
        NF_UNROLL7
        for (int k = 1; k < 7; k++) {
            s1 += a[G33(1) + k] * V4(g1 + 4 * k);
            s2 += a[G33(2) + k] * V4(g2 + 4 * k);
            s3 += a[G33(3) + k] * V4(g3 + 4 * k);
        }
        const nf_v4 wi = {dh * d[3 * i], dh * d[3 * i + 1], dh * d[3 * i + 2], 0.0};
        const nf_v4 s = (wi - a[3] * t3 - a[2] * t2 - (s1 + s2 + s3)) - a[1] * t1;
        nf_v4 ti = s * invd;
        ti[3] = invd;
        V4(t + 4 * i) = ti;
        t3 = t2;
        t2 = t1;
        t1 = ti;
    }
}

/* Forward sweep, bicubic rows 0..hi. q_{i+1..i+3}, which row i and the two
 * before it update, ride in registers; with Nu >= 7 no group slot of those
 * rows reaches them, so memory holds every other update. Row i is the
 * first to reach q_{i+3Nu+3}: it stores its term there instead of adding. */
static void fwd_33(const nf_stripe_t *A, const double *d, const double *t, double *q, long hi,
                   double dq[3])
{
    const long nu = A->nu;
    nf_v4 q0 = V4(q), q1 = V4(q + 4), q2 = V4(q + 8), acc = {0.0, 0.0, 0.0, 0.0};
    for (long i = 0; i <= hi; i++) {
        const double *a = A->S + 25 * i;
        const double dh = q[4 * i + 3], invd = t[4 * i + 3];
        for (int l = 0; l < 4; l++)
            __builtin_prefetch(a + NF_PCG_AHEAD * 25 + 8 * l);
        const nf_v4 di = {d[3 * i], d[3 * i + 1], d[3 * i + 2], 0.0}, ti = V4(t + 4 * i);
        nf_v4 y = (dh * di - a[0] * ti + q0) * invd;
        y[3] = 0.0; /* keeps the fourth lanes of the targets */
        q0 = q1 - a[1] * y;
        q1 = q2 - a[2] * y;
        q2 = V4(q + 4 * (i + 3)) - a[3] * y;
        double *g1 = q + 4 * (i + nu - 3), *g2 = g1 + 4 * nu, *g3 = g2 + 4 * nu;
        nf_v4 last = -a[G33(3) + 6] * y;
        last[3] = g3[4 * 6 + 3];
        V4(g3 + 4 * 6) = last;
        NF_UNROLL7
        for (int k = 0; k < 7; k++) {
            V4(g1 + 4 * k) -= a[G33(1) + k] * y;
            V4(g2 + 4 * k) -= a[G33(2) + k] * y;
            if (k < 6)
                V4(g3 + 4 * k) -= a[G33(3) + k] * y;
        }
        nf_v4 qi = dh * (ti + y);
        qi[3] = dh;
        V4(q + 4 * i) = qi;
        acc += di * qi;
    }
    V4(q + 4 * (hi + 1)) = q0;
    V4(q + 4 * (hi + 2)) = q1;
    V4(q + 4 * (hi + 3)) = q2;
    dq[0] = acc[0];
    dq[1] = acc[1];
    dq[2] = acc[2];
}
#endif

/* Last row the bicubic kernels take, or -1 when they take none. */
static long fast_rows(const nf_stripe_t *A)
{
#if NF_PCG_VECTOR
    if (A->p == 3 && A->q == 3 && A->nu >= 7 && A->n - 3L * A->nu - 4 >= 0)
        return A->n - 3L * A->nu - 4;
#endif
    (void)A;
    return -1;
}

/* q = C^-1 A C^-T d and t = C^-T d (Eisenstat), dq = d . q, in two passes:
 * the backward sweep forms t and the forward sweep's input D^1/2 d - D t,
 * the forward sweep finishes q and the dot product as each row completes.
 * First x += alpha t, d = r + beta d (fold_row). */
static void apply(pcg_ws_t *w, const double ab[6], double dq[3])
{
    const nf_stripe_t *A = w->A;
    const long hi = w->hi;
    bwd_rows(w, ab, A->n - 1, hi + 1);
    dq[0] = dq[1] = dq[2] = 0.0;
    /* The forward sweep's sums start at zero: all of them for the generic
     * loops, those no bicubic row is the first to reach otherwise. */
    const long nz = hi >= 0 ? 3L * A->nu + 3 : A->n;
    for (long i = 0; i < nz; i++)
        for (int c = 0; c < 3; c++)
            w->q[4 * i + c] = 0.0;
#if NF_PCG_VECTOR
    if (hi >= 0) {
        bwd_33(w, ab, hi);
        fwd_33(A, w->d, w->t, w->q, hi, dq);
    }
#endif
    fwd_rows(A, w->d, w->t, w->q, hi + 1, dq);
}

/* CG on the split system for A x = b (b NULL: zero) from x, with w->r = b - A x
 * on entry. Stops when the transformed residual of every coordinate fell
 * below tol times its start scaled to ||b|| (or below tol of its start when
 * b = 0), or at max_iter. Returns iterations, or -1 on breakdown
 * (d^T A d <= 0: not positive definite). */
static int pcg_run(pcg_ws_t *w, const double *b, double *x, double tol, int max_iter)
{
    const nf_stripe_t *A = w->A;
    const long n = A->n;
    double *r = w->r, *d = w->d;
    w->x = x;
    const double *t = w->t, *q = w->q;
    double rr[3], r0[3], bb[3] = {0, 0, 0}, lim[3], dq[3];
    int live[3];
    double tr[3];
    dot3(n, r, r, tr); /* ||b - A x0|| */
    if (b)
        dot3(n, b, b, bb);
    sweep_fwd(A, t, r); /* r^ = C^-1 r = D^1/2 (D + L)^-1 r */
    for (long i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            r[3 * i + c] *= q[4 * i + 3];
    dot3(n, r, r, r0);
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
        d[i] = r[i];
    int it = 0;
    double ab[6] = {0, 0, 0, 0, 0, 0}; /* alpha, beta: nothing to fold yet */
    while ((live[0] || live[1] || live[2]) && it < max_iter) {
        apply(w, ab, dq);
        double *al = ab, *be = ab + 3;
        for (int c = 0; c < 3; c++) {
            if (live[c] && !(dq[c] > 0.0))
                return -1;
            al[c] = live[c] ? rr[c] / dq[c] : 0.0;
        }
        double rn0 = 0.0, rn1 = 0.0, rn2 = 0.0;
        for (long i = 0; i < n; i++) {
            const double e0 = r[3 * i] - al[0] * q[4 * i];
            const double e1 = r[3 * i + 1] - al[1] * q[4 * i + 1];
            const double e2 = r[3 * i + 2] - al[2] * q[4 * i + 2];
            r[3 * i] = e0;
            r[3 * i + 1] = e1;
            r[3 * i + 2] = e2;
            rn0 += e0 * e0;
            rn1 += e1 * e1;
            rn2 += e2 * e2;
        }
        const double rn[3] = {rn0, rn1, rn2};
        it++;
        for (int c = 0; c < 3; c++) {
            be[c] = live[c] && rr[c] > 0.0 ? rn[c] / rr[c] : 0.0;
            live[c] = live[c] && sqrt(rn[c]) > lim[c];
            rr[c] = rn[c];
        }
    }
    /* The last step, which no further backward sweep folds in. */
    for (long i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            x[3 * i + c] += ab[c] * t[4 * i + c];
    return it;
}

/* The work vectors from the arena, D^1/2 and D^-1 into the fourth lanes;
 * NF_ESINGULAR with *bad at the first diagonal that is not positive. */
static int ws_init(pcg_ws_t *w, const nf_stripe_t *A, nf_arena_t *ar, long *bad)
{
    const long n = A->n;
    w->A = A;
    w->r = nf_arena_doubles(ar, (size_t)(3 * n));
    w->d = nf_arena_doubles(ar, (size_t)(3 * n));
    w->q = nf_arena_doubles(ar, (size_t)(4 * n));
    w->t = nf_arena_doubles(ar, (size_t)(4 * n));
    if (!w->r || !w->d || !w->q || !w->t)
        return NF_EARENA;
    for (long i = 0; i < n; i++) {
        double dii = A->S[i * A->K];
        if (!(dii > 0.0)) {
            *bad = i;
            return NF_ESINGULAR;
        }
        w->q[4 * i + 3] = sqrt(dii);
        w->t[4 * i + 3] = 1.0 / dii;
    }
    w->hi = fast_rows(A);
    return NF_OK;
}

int nf_pcg_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                 nf_arena_t *ar, nf_solve_stats_t *st, long *bad)
{
    const long n = A->n;
    pcg_ws_t w;
    int rc = ws_init(&w, A, ar, bad);
    if (rc)
        return rc;
    double *e = nf_arena_doubles(ar, (size_t)(3 * n));
    if (!e)
        return NF_EARENA;
    int it = 0;
    /* r = b - A x here is also where each pass below starts from. */
    st->rel_residual = nf_residual(A, b, x, w.r);
    /* The true residual decides; the recurrence only steers. A restart
     * from the current iterate recovers digits the recurrence lost. */
    for (int pass = 0; pass < 4 && st->rel_residual > o->tol && it < o->max_iter; pass++) {
        int k = pcg_run(&w, b, x, o->tol, o->max_iter - it);
        if (k < 0)
            return NF_ESINGULAR;
        it += k;
        st->rel_residual = nf_residual(A, b, x, w.r);
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
        nf_stripe_matvec(A, e, w.r);
        for (long i = 0; i < 3 * n; i++)
            w.r[i] = -w.r[i];
        if (pcg_run(&w, NULL, e, 1e-14, iters) < 0)
            return NF_ESINGULAR;
        return nf_probe_judge(e, n, e0, bad);
    }
    return NF_OK;
}

int nf_pcg_apply(const nf_stripe_t *A, const double *d, double *t, double *q, double dq[3],
                 int generic, nf_arena_t *ar)
{
    pcg_ws_t w;
    long bad;
    int rc = ws_init(&w, A, ar, &bad);
    if (rc)
        return rc;
    if (generic)
        w.hi = -1;
    for (long i = 0; i < 3 * A->n; i++)
        w.r[i] = d[i]; /* folded into d = r + 0 d */
    /* q holds the last iteration's values on entry: a sum the forward sweep
     * failed to start from zero shows as NaN. */
    for (long i = 0; i < A->n; i++)
        for (int c = 0; c < 3; c++)
            w.q[4 * i + c] = NAN;
    const double ab[6] = {0, 0, 0, 0, 0, 0};
    w.x = w.d; /* x += 0 t: a harmless target */
    apply(&w, ab, dq);
    for (long i = 0; i < A->n; i++)
        for (int c = 0; c < 3; c++) {
            t[3 * i + c] = w.t[4 * i + c];
            q[3 * i + c] = w.q[4 * i + c];
        }
    return NF_OK;
}
