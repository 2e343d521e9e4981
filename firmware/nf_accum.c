/* nf_accum.c: streaming accumulation of R^T R and R^T Q (Eq. 9-11). */
#include "nf_accum.h"
#include <math.h>

/* The per-point work is written once, inline, with the degrees as
 * parameters; common degrees get copies where they are constants, so every
 * loop below unrolls and the block update vectorises. */
#if defined(__GNUC__)
#define NF_INLINE static inline __attribute__((always_inline))
#else
#define NF_INLINE static inline
#endif

void nf_accum_init(nf_accum_t *ac, const nf_surf_t *s, nf_stripe_t *A, double *rhs)
{
    ac->s = s;
    ac->A = A;
    ac->rhs = rhs;
    ac->lu = ac->lv = -1;
    ac->bl = ac->bk = -1;
    ac->npend = 0;
    ac->nb = 0;
    ac->open = 0;
    ac->nl = (s->p + 1) * (s->q + 1);
    ac->nlp = (ac->nl + 3) / 4 * 4;
    /* Equal weights cancel in R_ij = N_i N_j w_ij / sum N N w: polynomial. */
    ac->rational = 0;
    if (s->w)
        for (long i = 1; i < (long)s->nu * s->nv && !ac->rational; i++)
            ac->rational = s->w[i] != s->w[0];
    for (int k = 0; k < NF_ACCUM_BUF; k++)
        for (int t = 0; t < NF_LOCAL_PAD; t++)
            ac->Rb[k][t] = 0.0; /* the tails past nl stay zero */
}

/* Span of u given the last one: raster scans stay in it or step to the next. */
static int span_near(int last, int n, int p, double u, const double *U)
{
    if (last >= 0) {
        if (U[last] <= u && (u < U[last + 1] || (last == n && u <= U[n + 1])))
            return last;
        if (last < n && U[last + 1] <= u && (u < U[last + 2] || (last + 1 == n)))
            return last + 1;
    }
    return nf_find_span(n, p, u, U);
}

static void rhs_add(nf_accum_t *ac, int l, int k, const double *R, const double *q)
{
    const nf_surf_t *s = ac->s;
    const int p = s->p, q_ = s->q, o = p + 1;
    const long base = (l - p) + (long)(k - q_) * s->nu;
    for (int b = 0; b <= q_; b++) {
        double *r = ac->rhs + 3 * (base + (long)b * s->nu);
        for (int a = 0; a <= p; a++) {
            const double w = R[a + b * o];
            r[3 * a] += w * q[0];
            r[3 * a + 1] += w * q[1];
            r[3 * a + 2] += w * q[2];
        }
    }
}

/* blk += sum_k Rb[k] Rb[k]^T and brhs += sum_k Rb[k] qb[k] over the buffer.
 * Whole padded rows are updated (the flush reads the upper triangle): with
 * the accumulator of a row segment held in a register across the buffered
 * points, the block is loaded and stored once per NF_ACCUM_BUF points. */
#if defined(__GNUC__) && defined(__AVX__) && !defined(NF_NO_VECTOR)
typedef double nf_v4 __attribute__((vector_size(32)));
static inline nf_v4 v4_load(const double *p)
{
    nf_v4 v;
    __builtin_memcpy(&v, p, sizeof v);
    return v;
}
static inline void v4_store(double *p, nf_v4 v)
{
    __builtin_memcpy(p, &v, sizeof v);
}
/* Row t1 from the vector holding column t1 on: the upper triangle plus at
 * most three entries below it, which the flush ignores. nb is a constant
 * (NF_ACCUM_BUF) for the full-buffer call, so the k loop unrolls there. */
NF_INLINE void block_rows_nb(nf_accum_t *ac, int nl, int nlp, const int nb)
{
    for (int t1 = 0; t1 < nl; t1++) {
        double *row = ac->blk + t1 * nlp;
        for (int T = t1 & ~3; T < nlp; T += 4) {
            nf_v4 acc = v4_load(row + T);
            for (int k = 0; k < nb; k++)
                acc += ac->Rb[k][t1] * v4_load(ac->Rb[k] + T);
            v4_store(row + T, acc);
        }
    }
}

NF_INLINE void block_rows(nf_accum_t *ac, int nl, int nlp)
{
    if (ac->nb == NF_ACCUM_BUF)
        block_rows_nb(ac, nl, nlp, NF_ACCUM_BUF);
    else
        block_rows_nb(ac, nl, nlp, ac->nb);
}
#else
NF_INLINE void block_rows(nf_accum_t *ac, int nl, int nlp)
{
    const int nb = ac->nb;
    for (int t1 = 0; t1 < nl; t1++) {
        double *row = ac->blk + t1 * nlp;
        for (int k = 0; k < nb; k++) {
            const double r1 = ac->Rb[k][t1];
            for (int t2 = 0; t2 < nlp; t2++)
                row[t2] += r1 * ac->Rb[k][t2];
        }
    }
}
#endif

NF_INLINE void block_rank(nf_accum_t *ac, int nl, int nlp)
{
    if (!ac->open) {
        for (int t = 0; t < nl * nlp; t++)
            ac->blk[t] = 0.0;
        for (int t = 0; t < 3 * nl; t++)
            ac->brhs[t] = 0.0;
        ac->open = 1;
    }
    block_rows(ac, nl, nlp);
    for (int k = 0; k < ac->nb; k++)
        for (int t1 = 0; t1 < nl; t1++) {
            ac->brhs[3 * t1] += ac->Rb[k][t1] * ac->qb[k][0];
            ac->brhs[3 * t1 + 1] += ac->Rb[k][t1] * ac->qb[k][1];
            ac->brhs[3 * t1 + 2] += ac->Rb[k][t1] * ac->qb[k][2];
        }
    ac->nb = 0;
}

static void block_rank_any(nf_accum_t *ac)
{
    if (ac->nl == 16)
        block_rank(ac, 16, 16);
    else
        block_rank(ac, ac->nl, ac->nlp);
}

void nf_accum_flush(nf_accum_t *ac)
{
    if (ac->npend == 0)
        return;
    const nf_surf_t *s = ac->s;
    const int p = s->p, q = s->q, o = p + 1, K = ac->A->K;
    const long base = (ac->bl - p) + (long)(ac->bk - q) * s->nu;
    if (ac->npend == 1) { /* a lone point: straight to the stripes */
        nf_stripe_add_outer(ac->A, base, ac->Rb[0], 1.0);
        rhs_add(ac, ac->bl, ac->bk, ac->Rb[0], ac->qb[0]);
    } else { /* the block's upper triangle, by the slots of nf_stripe_add_outer */
        if (ac->nb)
            block_rank_any(ac);
        for (int b = 0; b <= q; b++)
            for (int a = 0; a <= p; a++) {
                const int t1 = a + b * o;
                const double *br = ac->blk + t1 * ac->nlp;
                double *row = ac->A->S + (base + a + (long)b * s->nu) * K;
                for (int c = a; c <= p; c++)
                    row[c - a] += br[c + b * o];
                for (int d = b + 1; d <= q; d++) {
                    double *sl = row + nf_stripe_slot(p, -a, d - b);
                    for (int c = 0; c <= p; c++)
                        sl[c] += br[c + d * o];
                }
                double *r = ac->rhs + 3 * (base + a + (long)b * s->nu);
                r[0] += ac->brhs[3 * t1];
                r[1] += ac->brhs[3 * t1 + 1];
                r[2] += ac->brhs[3 * t1 + 2];
            }
    }
    ac->npend = 0;
    ac->nb = 0;
    ac->open = 0;
    ac->bl = ac->bk = -1;
}

NF_INLINE void point_pq(nf_accum_t *ac, double u, double v, const double xyz[3], double wgt,
                        const int p, const int q)
{
    const nf_surf_t *s = ac->s;
    const int o = p + 1, nl = o * (q + 1);
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER], R[NF_MAX_LOCAL];
    const int l = span_near(ac->lu, s->nu - 1, p, u, s->U);
    const int k = span_near(ac->lv, s->nv - 1, q, v, s->V);
    if (l != ac->lu) {
        nf_basis_recip(l, p, s->U, ac->ru);
        ac->lu = l;
    }
    if (k != ac->lv) {
        nf_basis_recip(k, q, s->V, ac->rv);
        ac->lv = k;
    }
    nf_basis_funs_r(l, u, p, s->U, ac->ru, Nu);
    nf_basis_funs_r(k, v, q, s->V, ac->rv, Nv);
    if (ac->rational) { /* rational basis R_ij (Eq. 1) with the base surface's weights */
        const double *w = s->w + (l - p) + (long)(k - q) * s->nu;
        double W = 0.0;
        for (int b = 0; b <= q; b++)
            for (int a = 0; a <= p; a++) {
                const double r = Nu[a] * Nv[b] * w[a + (long)b * s->nu];
                R[a + b * o] = r;
                W += r;
            }
        const double inv = 1.0 / W;
        for (int t = 0; t < nl; t++)
            R[t] *= inv;
    } else {
        for (int b = 0; b <= q; b++)
            for (int a = 0; a <= p; a++)
                R[a + b * o] = Nu[a] * Nv[b];
    }
    double qw[3] = {xyz[0], xyz[1], xyz[2]};
    if (wgt != 1.0) { /* sqrt(wgt) on R and on q: wgt R R^T and wgt R q */
        const double sw = sqrt(wgt);
        for (int t = 0; t < nl; t++)
            R[t] *= sw;
        for (int c = 0; c < 3; c++)
            qw[c] *= sw;
    }
    if (l != ac->bl || k != ac->bk) {
        nf_accum_flush(ac);
        ac->bl = l;
        ac->bk = k;
    }
    double *Rd = ac->Rb[ac->nb];
    for (int t = 0; t < nl; t++)
        Rd[t] = R[t];
    ac->qb[ac->nb][0] = qw[0];
    ac->qb[ac->nb][1] = qw[1];
    ac->qb[ac->nb][2] = qw[2];
    ac->nb++;
    ac->npend++;
    if (ac->nb == NF_ACCUM_BUF) {
        if (nl == 16)
            block_rank(ac, 16, 16);
        else
            block_rank(ac, nl, ac->nlp);
    }
}

void nf_accum_point(nf_accum_t *ac, double u, double v, const double xyz[3], double wgt)
{
    const int p = ac->s->p, q = ac->s->q;
    if (p == 3 && q == 3)
        point_pq(ac, u, v, xyz, wgt, 3, 3);
    else if (p == 2 && q == 2)
        point_pq(ac, u, v, xyz, wgt, 2, 2);
    else
        point_pq(ac, u, v, xyz, wgt, p, q);
}
