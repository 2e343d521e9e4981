/* SPDX-License-Identifier: MIT */
/* nf_accum.c: streaming accumulation of R^T R and R^T Q (Eq. 9-11). */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

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

/* The bicubic kernels use GCC's generic vectors of 4 doubles (AVX2 on the
 * cell controller, lowered to pairs or scalars elsewhere). */
#if defined(__GNUC__) && !defined(NF_NO_VECTOR)
#define NF_ACCUM_VECTOR 1
typedef double nf_v4 __attribute__((vector_size(32)));
/* 4 doubles at any 8-byte aligned address, aliasing the doubles there. */
typedef double nf_v4u __attribute__((vector_size(32), aligned(8), may_alias));
#define V4(ptr) (*(nf_v4u *)(ptr))
#define V4C(ptr) (*(const nf_v4u *)(ptr))
/* GCC at -O2 does not unroll the short constant loops of the kernels. */
#define NF_UNROLL _Pragma("GCC unroll 4")
#define NF_UNROLL8 _Pragma("GCC unroll 8") /* a buffer's rows (NF_ACCUM_BUF) */
#else
#define NF_ACCUM_VECTOR 0
#endif

#if NF_ISA_COLD
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
    ac->mode = 0;
    ac->G = ac->Gq = 0;
    ac->rtu = ac->rtv = 0;
    ac->vk = -1;
    ac->vlast = 0.0;
    ac->hu = (s->nu - s->p) / (s->U[s->nu] - s->U[s->p]);
    ac->hv = (s->nv - s->q) / (s->V[s->nv] - s->V[s->q]);
#if NF_ACCUM_VECTOR
    ac->fast = s->p == 3 && s->q == 3;
#else
    ac->fast = 0;
#endif
}
#endif

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
#if NF_ACCUM_VECTOR && defined(__AVX__)
/* Row t1 from the vector holding column t1 on: the upper triangle plus at
 * most three entries below it, which the flush ignores. nb is a constant
 * in every call (block_rows' switch), so the k loop unrolls. */
NF_INLINE void block_rows_nb(nf_accum_t *ac, int nl, int nlp, const int nb)
{
    for (int t1 = 0; t1 < nl; t1++) {
        double *row = ac->blk + t1 * nlp;
        for (int T = t1 & ~3; T < nlp; T += 4) {
            nf_v4 acc = V4C(row + T);
            NF_UNROLL8
            for (int k = 0; k < nb; k++)
                acc += ac->Rb[k][t1] * V4C(ac->Rb[k] + T);
            V4(row + T) = acc;
        }
    }
}

/* brhs += sum_k qb[k][c] Rb[k], a padded row of brhs per coordinate. */
NF_INLINE void block_rhs_nb(nf_accum_t *ac, int nlp, const int nb)
{
    for (int c = 0; c < 3; c++)
        for (int T = 0; T < nlp; T += 4) {
            double *r = ac->brhs + c * NF_LOCAL_PAD + T;
            nf_v4 acc = V4C(r);
            NF_UNROLL8
            for (int k = 0; k < nb; k++)
                acc += ac->qb[k][c] * V4C(ac->Rb[k] + T);
            V4(r) = acc;
        }
}

_Static_assert(NF_ACCUM_BUF == 8, "block_rows' switch has a case per buffer length");
/* Every buffer length a constant: a raster row visits a span for a few
 * points, so the last, partial buffer of a run is the common case
 * (callgrind: its loop counter cost as much as its products). */
#define NF_BLOCK_NB(n)                                                                             \
    case n:                                                                                        \
        block_rows_nb(ac, nl, nlp, n);                                                             \
        block_rhs_nb(ac, nlp, n);                                                                  \
        break
NF_INLINE void block_rows(nf_accum_t *ac, int nl, int nlp)
{
    switch (ac->nb) {
        NF_BLOCK_NB(1);
        NF_BLOCK_NB(2);
        NF_BLOCK_NB(3);
        NF_BLOCK_NB(4);
        NF_BLOCK_NB(5);
        NF_BLOCK_NB(6);
        NF_BLOCK_NB(7);
        NF_BLOCK_NB(8);
    default: block_rows_nb(ac, nl, nlp, ac->nb); block_rhs_nb(ac, nlp, ac->nb);
    }
}
#undef NF_BLOCK_NB
#define NF_BLOCK_RHS_DONE 1
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
#define NF_BLOCK_RHS_DONE 0
#endif

NF_INLINE void block_rank(nf_accum_t *ac, int nl, int nlp)
{
    if (!ac->open) {
        for (int t = 0; t < nl * nlp; t++)
            ac->blk[t] = 0.0;
        for (int t = 0; t < 3 * NF_LOCAL_PAD; t++)
            ac->brhs[t] = 0.0;
        ac->open = 1;
    }
    block_rows(ac, nl, nlp);
    if (!NF_BLOCK_RHS_DONE)
        for (int k = 0; k < ac->nb; k++)
            for (int c = 0; c < 3; c++)
                for (int t1 = 0; t1 < nl; t1++)
                    ac->brhs[c * NF_LOCAL_PAD + t1] += ac->Rb[k][t1] * ac->qb[k][c];
    ac->nb = 0;
}

static void block_rank_any(nf_accum_t *ac)
{
    if (ac->nl == 16)
        block_rank(ac, 16, 16);
    else
        block_rank(ac, ac->nl, ac->nlp);
}

#if NF_ACCUM_VECTOR
/* Bicubic stripe rows, 4-wide (Eq. 9-11, slots of nf_stripe_slot with
 * p = q = 3, K = 25): control point (a, b) of the span's 4 x 4 receives, for
 * v-offset f = d - b > 0, 4 consecutive slots 4 + 7 (f - 1) + 3 - a + c,
 * c = 0..3, and for f = 0 the slots c - a, c >= a. The latter are written as
 * a whole vector at row - a with lanes c < a zeroed: those lanes add +-0 to
 * the previous row's last slots, which changes no value. */
static const double nf_lane_mask[4][4] = {{1, 1, 1, 1}, {0, 1, 1, 1}, {0, 0, 1, 1}, {0, 0, 0, 1}};

#define NF_SLOT33(a, f) (4 + 7 * ((f)-1) + 3 - (a))

/* S += wgt-free sum: stripe row (a, b) gets row a of X times C[b][d] for the
 * factored run (X = Su, C = Nv Nv^T), or the rows of a buffered R. */
NF_INLINE void expand33(nf_accum_t *ac, long base)
{
    const long nu = ac->s->nu;
    const double *Nv = ac->fNv;
    double *S = ac->A->S;
    NF_UNROLL
    for (int b = 0; b < 4; b++) {
        NF_UNROLL
        for (int a = 0; a < 4; a++) {
            const nf_v4 su = V4C(ac->Su + 4 * a);
            double *row = S + (base + a + b * nu) * 25;
            const nf_v4 m = V4C(nf_lane_mask[a]) * (Nv[b] * Nv[b]);
            V4(row - a) += (su * m);
            NF_UNROLL
            for (int d = b + 1; d < 4; d++) {
                double *sl = row + NF_SLOT33(a, d - b);
                V4(sl) += (su * (Nv[b] * Nv[d]));
            }
        }
        double *r = ac->rhs + 3 * (base + b * nu);
        NF_UNROLL
        for (int t = 0; t < 12; t += 4)
            V4(r + t) += (V4C(ac->Sq + t) * Nv[b]);
    }
}

/* One row R (16 values, row-major in (a, b)) with its point q straight into
 * the stripes: the same as nf_stripe_add_outer + rhs_add, 4-wide. */
NF_INLINE void scatter33(nf_accum_t *ac, long base, const double *R, const double *q)
{
    const long nu = ac->s->nu;
    double *S = ac->A->S;
    nf_v4 Rv[4];
    NF_UNROLL
    for (int d = 0; d < 4; d++)
        Rv[d] = V4C(R + 4 * d);
    NF_UNROLL
    for (int b = 0; b < 4; b++) {
        NF_UNROLL
        for (int a = 0; a < 4; a++) {
            const double ra = R[a + 4 * b];
            double *row = S + (base + a + b * nu) * 25;
            V4(row - a) += ((ra * Rv[b]) * V4C(nf_lane_mask[a]));
            NF_UNROLL
            for (int d = b + 1; d < 4; d++) {
                double *sl = row + NF_SLOT33(a, d - b);
                V4(sl) += (ra * Rv[d]);
            }
        }
        double *r = ac->rhs + 3 * (base + b * nu);
        NF_UNROLL
        for (int a = 0; a < 4; a++) {
            r[3 * a] += R[a + 4 * b] * q[0];
            r[3 * a + 1] += R[a + 4 * b] * q[1];
            r[3 * a + 2] += R[a + 4 * b] * q[2];
        }
    }
}

/* The summed 16 x 16 block (rows from column 4b on, see block_rows). */
NF_INLINE void block_flush33(nf_accum_t *ac, long base)
{
    const long nu = ac->s->nu;
    double *S = ac->A->S;
    NF_UNROLL
    for (int b = 0; b < 4; b++)
        NF_UNROLL
    for (int a = 0; a < 4; a++) {
        const int t1 = a + 4 * b;
        const double *br = ac->blk + t1 * 16;
        double *row = S + (base + a + b * nu) * 25;
        V4(row - a) += (V4C(br + 4 * b) * V4C(nf_lane_mask[a]));
        NF_UNROLL
        for (int d = b + 1; d < 4; d++) {
            double *sl = row + NF_SLOT33(a, d - b);
            V4(sl) += (V4C(br + 4 * d));
        }
        double *r = ac->rhs + 3 * (base + a + b * nu);
        r[0] += ac->brhs[t1];
        r[1] += ac->brhs[NF_LOCAL_PAD + t1];
        r[2] += ac->brhs[2 * NF_LOCAL_PAD + t1];
    }
}

/* Row mode: the band G (x) N(v) N(v)^T into the stripes of the row's four
 * v rows, column by column: slots 0..3 get G_i,i..i+3 C_bb, slots of
 * offset f = d - b > 0 get G_i,i-3..i+3 C_bd (two vectors, the second
 * without its first lane); then G is cleared where it was used. */
NF_INLINE void row_expand33(nf_accum_t *ac)
{
    const long nu = ac->s->nu;
    const double *Nv = ac->rowNv;
    double C[4][4];
    NF_UNROLL
    for (int b = 0; b < 4; b++)
        NF_UNROLL
    for (int d = 0; d < 4; d++)
        C[b][d] = Nv[b] * Nv[d];
    const nf_v4 m1 = V4C(nf_lane_mask[1]);
    /* the four v rows' first stripe row and right-hand side, stepped per column */
    const long pt0 = ac->g0 + (ac->rowk - 3) * nu;
    double *S = ac->A->S + pt0 * 25, *rh = ac->rhs + 3 * pt0;
    double *g = ac->G + 7 * (long)ac->g0, *gq = ac->Gq + 3 * (long)ac->g0;
    for (int i = ac->g0; i <= ac->g1; i++, S += 25, rh += 3, g += 7, gq += 3) {
        const nf_v4 glo = V4C(g), ghi = V4C(g + 3) * m1, gd = V4C(g + 3);
        const double q0 = gq[0], q1 = gq[1], q2 = gq[2];
        NF_UNROLL
        for (int b = 0; b < 4; b++) {
            double *row = S + b * nu * 25;
            V4(row) += gd * C[b][b];
            NF_UNROLL
            for (int d = b + 1; d < 4; d++) {
                double *sl = row + 4 + 7 * (d - b - 1);
                V4(sl) += glo * C[b][d];
                V4(sl + 3) += ghi * C[b][d];
            }
            double *r = rh + b * nu * 3;
            r[0] += q0 * Nv[b];
            r[1] += q1 * Nv[b];
            r[2] += q2 * Nv[b];
        }
        NF_UNROLL
        for (int t = 0; t < 7; t++)
            g[t] = 0.0;
        gq[0] = gq[1] = gq[2] = 0.0;
    }
}

/* The 12 products Nu[a] qw[c] at 3a + c, as 3 vectors, added to dst or
 * stored (add = 0). */
NF_INLINE void nq12(double *dst, const double *Nu, const double *qw, const int add)
{
    const nf_v4 n0 = {Nu[0], Nu[0], Nu[0], Nu[1]}, n1 = {Nu[1], Nu[1], Nu[2], Nu[2]},
                n2 = {Nu[2], Nu[3], Nu[3], Nu[3]};
    const nf_v4 q0 = {qw[0], qw[1], qw[2], qw[0]}, q1 = {qw[1], qw[2], qw[0], qw[1]},
                q2 = {qw[2], qw[0], qw[1], qw[2]};
    if (add) {
        V4(dst) += n0 * q0;
        V4(dst + 4) += n1 * q1;
        V4(dst + 8) += n2 * q2;
    } else {
        V4(dst) = n0 * q0;
        V4(dst + 4) = n1 * q1;
        V4(dst + 8) = n2 * q2;
    }
}

/* One point of the row into G: column l - 3 + a, band offsets c - a. */
NF_INLINE void row_add33(nf_accum_t *ac, int l, const double *Nu, const double *qw)
{
    const nf_v4 nu4 = {Nu[0], Nu[1], Nu[2], Nu[3]};
    double *g = ac->G + 7 * (long)(l - 3) + 3;
    NF_UNROLL
    for (int a = 0; a < 4; a++)
        V4(g + 6 * a) += Nu[a] * nu4; /* row l-3+a starts at g + 7a - a */
    nq12(ac->Gq + 3 * (long)(l - 3), Nu, qw, 1);
    if (l - 3 < ac->g0)
        ac->g0 = l - 3;
    if (l > ac->g1)
        ac->g1 = l;
}
#endif

#if NF_ISA_COLD
void nf_accum_rowbuf(nf_accum_t *ac, double *G, double *Gq)
{
    ac->G = G && Gq ? G : 0;
    ac->Gq = G && Gq ? Gq : 0;
}

void nf_accum_rtab(nf_accum_t *ac, double *tu, double *tv)
{
    ac->rtu = ac->rtv = 0;
    if (!tu || !tv || ac->s->p != 3 || ac->s->q != 3)
        return;
    for (int l = 3; l < ac->s->nu; l++)
        nf_basis_recip(l, 3, ac->s->U, tu + 6 * l);
    for (int k = 3; k < ac->s->nv; k++)
        nf_basis_recip(k, 3, ac->s->V, tv + 6 * k);
    ac->rtu = tu;
    ac->rtv = tv;
}
#endif

/* Runs of at most this many rows skip the block: straight to the stripes. */
#define NF_ACCUM_DIRECT 2

void nf_accum_flush(nf_accum_t *ac)
{
    if (ac->npend == 0)
        return;
    const nf_surf_t *s = ac->s;
    const int p = s->p, q = s->q, o = p + 1, K = ac->A->K;
    const long base = (ac->bl - p) + (long)(ac->bk - q) * s->nu;
#if NF_ACCUM_VECTOR
    if (ac->mode == 3) {
        row_expand33(ac);
    } else if (ac->mode == 1) {
        expand33(ac, base);
    } else if (ac->fast) {
        if (!ac->open && ac->npend <= NF_ACCUM_DIRECT) {
            for (int t = 0; t < ac->nb; t++)
                scatter33(ac, base, ac->Rb[t], ac->qb[t]);
        } else {
            if (ac->nb)
                block_rank(ac, 16, 16);
            block_flush33(ac, base);
        }
    } else
#endif
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
                r[0] += ac->brhs[t1];
                r[1] += ac->brhs[NF_LOCAL_PAD + t1];
                r[2] += ac->brhs[2 * NF_LOCAL_PAD + t1];
            }
    }
    ac->npend = 0;
    ac->nb = 0;
    ac->open = 0;
    ac->mode = 0;
    ac->bl = ac->bk = -1;
}

/* Row of R into the span's buffer (rank-NF_ACCUM_BUF block updates). */
NF_INLINE void buffer_row(nf_accum_t *ac, const double *R, const double *qw, const int nl)
{
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

NF_INLINE void point_pq(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3],
                        double wgt, const int p, const int q)
{
    const nf_surf_t *s = ac->s;
    const int o = p + 1, nl = o * (q + 1);
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER], R[NF_MAX_LOCAL];
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
    buffer_row(ac, R, qw, nl);
}

#if NF_ACCUM_VECTOR
/* The 6 reciprocals of a cubic span's knot differences in basis3's order
 * (nf_basis_recip, p = 3): two vector divisions. */
static inline void recip3(const double *U, int l, double *rc)
{
    const nf_v4 one = {1.0, 1.0, 1.0, 1.0};
    const nf_v4 d0 = {U[l + 1] - U[l], U[l + 1] - U[l - 1], U[l + 2] - U[l], U[l + 1] - U[l - 2]};
    const nf_v4 d1 = {U[l + 2] - U[l - 1], U[l + 3] - U[l], 1.0, 1.0};
    const nf_v4 r0 = one / d0, r1 = one / d1;
    rc[0] = r0[0];
    rc[1] = r0[1];
    rc[2] = r0[2];
    rc[3] = r0[3];
    rc[4] = r1[0];
    rc[5] = r1[1];
}

/* nf_basis_funs_r for p = 3, written out (A2.2 with the reciprocals). */
static inline void basis3(int l, double u, const double *U, const double *rc, double *N)
{
    const double l1 = u - U[l], l2 = u - U[l - 1], l3 = u - U[l - 2];
    const double r1 = U[l + 1] - u, r2 = U[l + 2] - u, r3 = U[l + 3] - u;
    double t, sv;
    /* j = 1 */
    double n0 = r1 * rc[0], n1 = l1 * rc[0];
    /* j = 2 */
    t = n0 * rc[1];
    n0 = r1 * t;
    sv = l2 * t;
    t = n1 * rc[2];
    n1 = sv + r2 * t;
    double n2 = l1 * t;
    /* j = 3 */
    t = n0 * rc[3];
    N[0] = r1 * t;
    sv = l3 * t;
    t = n1 * rc[4];
    N[1] = sv + r2 * t;
    sv = l2 * t;
    t = n2 * rc[5];
    N[2] = sv + r3 * t;
    N[3] = l1 * t;
}

/* Bicubic, inline and vectorised. Polynomial points sharing the span and
 * v open a factored run (mode 1); a change of v within the span closes it
 * and buffers rows for the block (mode 2); rational points always buffer. */
static void point33(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3],
                    double wgt)
{
    const nf_surf_t *s = ac->s;
    if (l != ac->lu || k != ac->lv) {
        if (l != ac->lu)
            recip3(s->U, l, ac->ru);
        if (k != ac->lv) {
            recip3(s->V, k, ac->rv);
            ac->vk = -1;
        }
        ac->lu = l;
        ac->lv = k;
    }
    double Nu[4];
    basis3(l, u, s->U, ac->ru, Nu);
    if (v != ac->vlast || ac->vk != k) { /* rows of one v: N(v) once */
        basis3(k, v, s->V, ac->rv, ac->Nvc);
        ac->vlast = v;
        ac->vk = k;
    }
    double qw[3] = {xyz[0], xyz[1], xyz[2]};
    if (wgt != 1.0) { /* sqrt(wgt) on N(u) and on q: wgt R R^T and wgt R q */
        const double sw = sqrt(wgt);
        NF_UNROLL
        for (int a = 0; a < 4; a++)
            Nu[a] *= sw;
        NF_UNROLL
        for (int c = 0; c < 3; c++)
            qw[c] *= sw;
    }
    if (ac->mode == 3) {
        if (k == ac->rowk && v == ac->rowv) {
            row_add33(ac, l, Nu, qw);
            ac->npend++;
            return;
        }
        nf_accum_flush(ac);
    }
    const int same = l == ac->bl && k == ac->bk;
    if (!ac->rational) {
        const nf_v4 nu4 = {Nu[0], Nu[1], Nu[2], Nu[3]};
        if (!same && ac->mode == 1 && ac->G && k == ac->bk && v == ac->fv) {
            /* The next span of a row of one v: the run's sums move to G. */
            double *g = ac->G + 7 * (long)(ac->bl - 3) + 3;
            NF_UNROLL
            for (int a = 0; a < 4; a++)
                V4(g + 6 * a) += V4C(ac->Su + 4 * a);
            double *gq = ac->Gq + 3 * (long)(ac->bl - 3);
            NF_UNROLL
            for (int t = 0; t < 12; t++)
                gq[t] += ac->Sq[t];
            ac->mode = 3;
            ac->rowk = k;
            ac->rowv = v;
            NF_UNROLL
            for (int b = 0; b < 4; b++)
                ac->rowNv[b] = ac->fNv[b];
            ac->g0 = ac->bl - 3;
            ac->g1 = ac->bl;
            row_add33(ac, l, Nu, qw);
            ac->npend++;
            return;
        }
        if (same && ac->mode == 1 && v == ac->fv) {
            NF_UNROLL
            for (int a = 0; a < 4; a++)
                V4(ac->Su + 4 * a) += (Nu[a] * nu4);
            nq12(ac->Sq, Nu, qw, 1);
            ac->npend++;
            return;
        }
        if (!same) { /* a new run, factored until v changes */
            nf_accum_flush(ac);
            ac->bl = l;
            ac->bk = k;
            ac->mode = 1;
            ac->fv = v;
            NF_UNROLL
            for (int b = 0; b < 4; b++)
                ac->fNv[b] = ac->Nvc[b];
            NF_UNROLL
            for (int a = 0; a < 4; a++)
                V4(ac->Su + 4 * a) = Nu[a] * nu4;
            nq12(ac->Sq, Nu, qw, 0);
            ac->npend = 1;
            return;
        }
        if (ac->mode == 1) { /* same span, new v: the factored part goes now */
            nf_accum_flush(ac);
            ac->bl = l;
            ac->bk = k;
        }
        ac->mode = 2;
        double R[16];
        NF_UNROLL
        for (int b = 0; b < 4; b++)
            NF_UNROLL
        for (int a = 0; a < 4; a++)
            R[a + 4 * b] = Nu[a] * ac->Nvc[b];
        buffer_row(ac, R, qw, 16);
        return;
    }
    /* Rational basis R_ij (Eq. 1); sqrt(wgt) is already on N(u). */
    const double *w = s->w + (l - 3) + (long)(k - 3) * s->nu;
    double R[16], W = 0.0;
    NF_UNROLL
    for (int b = 0; b < 4; b++)
        NF_UNROLL
    for (int a = 0; a < 4; a++) {
        const double r = Nu[a] * ac->Nvc[b] * w[a + (long)b * s->nu];
        R[a + 4 * b] = r;
        W += r;
    }
    /* W carries sqrt(wgt) once; R / W must carry it once too. */
    const double inv = (wgt != 1.0 ? sqrt(wgt) : 1.0) / W;
    NF_UNROLL
    for (int t = 0; t < 16; t++)
        R[t] *= inv;
    if (!same) {
        nf_accum_flush(ac);
        ac->bl = l;
        ac->bk = k;
    }
    ac->mode = 2;
    buffer_row(ac, R, qw, 16);
}
#endif

#if NF_ACCUM_VECTOR

/* A span's sums of the row kernel into G and Gq: Su row a (N_a N_c, c = 0..3)
 * at band offsets c - a of column l - 3 + a; Sq per coordinate (a-major)
 * transposed into Gq's x y z per column (3 vectors of 12 doubles). */
NF_INLINE void row_span_out(double *G, double *Gq, int l, const nf_v4 su[4], const nf_v4 sq[3])
{
    double *g = G + 7 * (long)(l - 3) + 3;
    NF_UNROLL
    for (int a = 0; a < 4; a++)
        V4(g + 6 * a) += su[a];
    double *gq = Gq + 3 * (long)(l - 3);
    const nf_v4 a01 = __builtin_shufflevector(sq[0], sq[1], 0, 4, 1, 5); /* x0 y0 x1 y1 */
    const nf_v4 b23 = __builtin_shufflevector(sq[0], sq[1], 2, 6, 3, 7); /* x2 y2 x3 y3 */
    const nf_v4 c1 = __builtin_shufflevector(a01, sq[2], 3, 5, 0, 0);    /* y1 z1 - - */
    V4(gq) += __builtin_shufflevector(a01, sq[2], 0, 1, 4, 2);           /* x0 y0 z0 x1 */
    V4(gq + 4) += __builtin_shufflevector(c1, b23, 0, 1, 4, 5);          /* y1 z1 x2 y2 */
    V4(gq + 8) += __builtin_shufflevector(b23, sq[2], 6, 2, 3, 7);       /* z2 x3 y3 z3 */
}
#endif

void nf_accum_lone33(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3])
{
#if NF_ACCUM_VECTOR
    if (!ac->fast || ac->rational) {
        nf_accum_point_at(ac, u, v, l, k, xyz, 1.0);
        return;
    }
    if (ac->npend)
        nf_accum_flush(ac);
    const nf_surf_t *s = ac->s;
    const double *rcu = ac->ru, *rcv = ac->rv;
    if (ac->rtu) {
        rcu = ac->rtu + 6 * l;
        rcv = ac->rtv + 6 * k;
    } else if (l != ac->lu || k != ac->lv) {
        if (l != ac->lu)
            recip3(s->U, l, ac->ru);
        if (k != ac->lv)
            recip3(s->V, k, ac->rv);
        ac->vk = -1;
        ac->lu = l;
        ac->lv = k;
    }
    double Nu[4], Nv[4];
    basis3(l, u, s->U, rcu, Nu);
    basis3(k, v, s->V, rcv, Nv);
    const nf_v4 nu4 = {Nu[0], Nu[1], Nu[2], Nu[3]}, z4 = {0.0, 0.0, 0.0, 0.0};
    nf_v4 su[4], s0[4];
    NF_UNROLL
    for (int a = 0; a < 4; a++)
        su[a] = Nu[a] * nu4;
    /* Slots 0..3-a of row a (offsets c - a, c >= a): su[a] shifted down by
     * a lanes, zeros above: whole vectors at the row's start, so no store
     * of one row overlaps another's. */
    s0[0] = su[0];
    s0[1] = __builtin_shufflevector(su[1], z4, 1, 2, 3, 4);
    s0[2] = __builtin_shufflevector(su[2], z4, 2, 3, 4, 5);
    s0[3] = __builtin_shufflevector(su[3], z4, 3, 4, 5, 6);
    /* x y z of the 4 columns a (a-major, 3a + c), for the right-hand side */
    const nf_v4 q0 = {xyz[0], xyz[1], xyz[2], xyz[0]}, q1 = {xyz[1], xyz[2], xyz[0], xyz[1]},
                q2 = {xyz[2], xyz[0], xyz[1], xyz[2]};
    const nf_v4 n0 = {Nu[0], Nu[0], Nu[0], Nu[1]}, n1 = {Nu[1], Nu[1], Nu[2], Nu[2]},
                n2 = {Nu[2], Nu[3], Nu[3], Nu[3]};
    const nf_v4 nq0 = n0 * q0, nq1 = n1 * q1, nq2 = n2 * q2;
    const long nu = s->nu, base = (l - 3) + (long)(k - 3) * nu;
    double *S = ac->A->S + base * 25, *rh = ac->rhs + 3 * base;
    NF_UNROLL
    for (int b = 0; b < 4; b++) {
        double *rb = S + b * nu * 25;
        const double cbb = Nv[b] * Nv[b];
        NF_UNROLL
        for (int a = 0; a < 4; a++) {
            double *row = rb + 25 * a;
            V4(row) += s0[a] * cbb;
            NF_UNROLL
            for (int d = b + 1; d < 4; d++)
                V4(row + NF_SLOT33(a, d - b)) += su[a] * (Nv[b] * Nv[d]);
        }
        double *r = rh + b * nu * 3;
        V4(r) += nq0 * Nv[b];
        V4(r + 4) += nq1 * Nv[b];
        V4(r + 8) += nq2 * Nv[b];
    }
#else
    nf_accum_point_at(ac, u, v, l, k, xyz, 1.0);
#endif
}

long nf_accum_rows33(nf_accum_t *ac, const double *rows, long n, const double lim[4],
                     const double dom[4])
{
#if NF_ACCUM_VECTOR
    if (!ac->fast || ac->rational || !ac->G || n <= 0)
        return 0;
    const nf_surf_t *s = ac->s;
    const double *U = s->U, *V = s->V;
    double *G = ac->G, *Gq = ac->Gq;
    const double *rtu = ac->rtu;
    const int nu1 = s->nu - 1, nv1 = s->nv - 1;
    /* The limits in registers: the stores into G could alias them. */
    const double lo_u = lim[0], hi_u = lim[1], lo_v = lim[2], hi_v = lim[3];
    const double d0 = dom[0], d1 = dom[1], d2 = dom[2], d3 = dom[3];
    /* A row already open in G (mode 3) goes on; its points count as a long run. */
    long run = ac->mode == 3 ? NF_ROW_MIN : 0, t = 0, taken = 0;
    double rowv = ac->rowv, ru[6];
    int l = ac->lu, g0 = ac->g0, g1 = ac->g1, open = ac->mode == 3;
    for (int c = 0; c < 6; c++)
        ru[c] = ac->ru[c];
    const nf_v4 z4 = {0.0, 0.0, 0.0, 0.0};
    nf_v4 su[4] = {z4, z4, z4, z4}, sq[3] = {z4, z4, z4};
    int sl = -1; /* span whose sums su, sq hold, -1 none */
    for (; t < n; t++) {
        const double *r = rows + 5 * t;
        double u = r[0], v = r[1];
        /* NaN fails every comparison; x - x is 0 for a finite x, NaN
         * otherwise: nf_fit_add's test, as branches that are never taken. */
        if (!(u >= lo_u && u <= hi_u && v >= lo_v && v <= hi_v &&
              (r[2] - r[2]) + (r[3] - r[3]) + (r[4] - r[4]) == 0.0))
            break; /* nf_fit_add judges it */
        u = u < d0 ? d0 : (u > d1 ? d1 : u);
        v = v < d2 ? d2 : (v > d3 ? d3 : v);
        if (!open || v != rowv) {
            if (open && run < NF_ROW_MIN)
                break; /* rows of one or two points: not a raster of rows */
            if (sl >= 0)
                row_span_out(G, Gq, sl, su, sq);
            sl = -1;
            if (taken) /* mode 3 only asks whether G holds a sum */
                ac->npend = 1;
            taken = 0;
            ac->g0 = g0;
            ac->g1 = g1;
            nf_accum_flush(ac);
            const int k = nf_find_span_from(ac->lv, nv1, 3, v, V, ac->hv);
            if (k != ac->lv) {
                if (ac->rtv)
                    for (int c = 0; c < 6; c++)
                        ac->rv[c] = ac->rtv[6 * k + c];
                else
                    recip3(V, k, ac->rv);
                ac->lv = k;
            }
            basis3(k, v, V, ac->rv, ac->rowNv);
            NF_UNROLL
            for (int b = 0; b < 4; b++)
                ac->Nvc[b] = ac->rowNv[b];
            ac->vlast = v;
            ac->vk = k;
            ac->mode = 3;
            ac->rowk = k;
            ac->rowv = rowv = v;
            g0 = nu1 + 1;
            g1 = -1;
            open = 1;
            run = 0;
        }
        if (l < 0 || !(U[l] <= u && u < U[l + 1])) {
            l = nf_find_span_from(l, nu1, 3, u, U, ac->hu);
            if (rtu)
                for (int c = 0; c < 6; c++)
                    ru[c] = rtu[6 * l + c];
            else
                recip3(U, l, ru);
        }
        if (l != sl) { /* a new span: the last one's sums into G */
            if (sl >= 0)
                row_span_out(G, Gq, sl, su, sq);
            sl = l;
            su[0] = su[1] = su[2] = su[3] = z4;
            sq[0] = sq[1] = sq[2] = z4;
            g0 = l - 3 < g0 ? l - 3 : g0;
            g1 = l > g1 ? l : g1;
        }
        double Nu[4];
        basis3(l, u, U, ru, Nu);
        const nf_v4 nu4 = {Nu[0], Nu[1], Nu[2], Nu[3]};
        NF_UNROLL
        for (int a = 0; a < 4; a++)
            su[a] += Nu[a] * nu4;
        sq[0] += r[2] * nu4;
        sq[1] += r[3] * nu4;
        sq[2] += r[4] * nu4;
        run++;
        taken++;
    }
    if (sl >= 0)
        row_span_out(G, Gq, sl, su, sq);
    if (taken)
        ac->npend = 1;
    ac->g0 = g0;
    ac->g1 = g1;
    ac->lu = l;
    for (int c = 0; c < 6; c++)
        ac->ru[c] = ru[c];
    return t;
#else
    (void)ac;
    (void)rows;
    (void)n;
    (void)lim;
    (void)dom;
    return 0;
#endif
}

void nf_accum_point_at(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3],
                       double wgt)
{
    const int p = ac->s->p, q = ac->s->q;
#if NF_ACCUM_VECTOR
    if (ac->fast) {
        point33(ac, u, v, l, k, xyz, wgt);
        return;
    }
#endif
    if (p == 3 && q == 3)
        point_pq(ac, u, v, l, k, xyz, wgt, 3, 3);
    else if (p == 2 && q == 2)
        point_pq(ac, u, v, l, k, xyz, wgt, 2, 2);
    else
        point_pq(ac, u, v, l, k, xyz, wgt, p, q);
}

void nf_accum_point(nf_accum_t *ac, double u, double v, const double xyz[3], double wgt)
{
    int l, k;
    nf_accum_spans(ac, u, v, ac->lu, ac->lv, &l, &k);
    nf_accum_point_at(ac, u, v, l, k, xyz, wgt);
}
