/* SPDX-License-Identifier: MIT */
/* nf_accum.h: the hot loop of Section 3.1: one measured point (one row of R)
 * into the stripes and R^T Q. Two things make it fast without changing a
 * single sum's terms beyond rounding order:
 *  - points of one knot span share their span search and the reciprocals
 *    of their knot differences (cached per span);
 *  - consecutive points in the same span (what a raster scan delivers) are
 *    summed into a dense (p+1)(q+1) block first, NF_ACCUM_BUF rows at a
 *    time, which the stripes receive once when the span changes: contiguous,
 *    vectorisable work instead of scattered updates. A lone point in its
 *    span goes straight to the stripes;
 *  - bicubic, polynomial: consecutive points of one span that share v
 *    exactly (a raster row of a scan grid) share N(v), and their rows
 *    R = N(u) (x) N(v) sum to (sum N(u) N(u)^T) (x) N(v) N(v)^T: a 4 x 4 sum
 *    per point, expanded into the stripes once per run (Eq. 9-10). When the
 *    span changes and v does not (the next span of a raster row), the sums
 *    go on in a band buffer G of the whole row, G_ij = sum N_i(u) N_j(u)
 *    (7 per control column), expanded as G (x) N(v) N(v)^T once per row.
 *    G (10 Nu doubles) is lent by nf_fit from the solver's arena space,
 *    which is idle while points stream in (nf_accum_rowbuf).
 * Memory: fixed by NF_MAX_DEGREE (sizeof(nf_accum_t)), never by N or M. */
#ifndef NF_ACCUM_H
#define NF_ACCUM_H

#include "nf_basis.h"
#include "nf_stripe.h"
#include "nf_surf.h"

/* Rows of one span buffered before a rank-NF_ACCUM_BUF update of the block:
 * the block is read and written once per that many points. */
#define NF_ACCUM_BUF 8
/* Block rows padded to a multiple of 4 doubles: whole vectors, no tails. */
#define NF_LOCAL_PAD ((NF_MAX_LOCAL + 3) / 4 * 4)

typedef struct nf_accum {
    const nf_surf_t *s;
    nf_stripe_t *A;
    double *rhs;
    int lu, lv; /* span of the cached reciprocals, -1 none */
    double ru[NF_RECIP_LEN], rv[NF_RECIP_LEN];
    int bl, bk;    /* span of the open block, -1 none */
    int npend;     /* points seen in this span */
    int nb;        /* of them, still in the buffer */
    int open;      /* blk and brhs hold a sum */
    int nl, nlp;   /* (p+1)(q+1) and its padded row length */
    int rational;  /* weights differ: R_ij = N_i N_j w_ij / W (Eq. 1) */
    int fast;      /* bicubic vector kernels; nf_accum_init sets it (tests may clear it) */
    int mode;      /* open run: 0 generic, 1 factored (one v), 2 rows buffered */
    double hu, hv; /* spans per unit parameter: the first guess of a span search */
    double vlast;  /* v whose basis Nvc holds (span vk), for rows of one v */
    int vk;        /* -1: Nvc empty */
    double fv;     /* v of the factored run */
    double Nvc[NF_MAX_ORDER], fNv[NF_MAX_ORDER];
    _Alignas(32) double Su[16]; /* factored run: sum of N(u) N(u)^T (4 x 4, full) */
    _Alignas(32) double Sq[12]; /* and of N(u) (x y z), a-major */
    double *G, *Gq;             /* row mode: 7 Nu band and 3 Nu right-hand side, or NULL */
    const double *rtu, *rtv;    /* bicubic: 6 reciprocals per span (at 6 l), or NULL */
    int g0, g1, rowk;           /* columns touched, v span of the row */
    double rowv, rowNv[NF_MAX_ORDER];
    _Alignas(32) double Rb[NF_ACCUM_BUF][NF_LOCAL_PAD]; /* buffered rows of R, zero tails */
    double qb[NF_ACCUM_BUF][3];
    _Alignas(32) double blk[NF_MAX_LOCAL * NF_LOCAL_PAD]; /* row t1 at t1*nlp, upper used */
    /* coordinate c of row t1 at c * NF_LOCAL_PAD + t1 */
    _Alignas(32) double brhs[3 * NF_LOCAL_PAD];
} nf_accum_t;

void nf_accum_init(nf_accum_t *ac, const nf_surf_t *s, nf_stripe_t *A, double *rhs);

/* Lend the row buffers (G: 7 Nu doubles, Gq: 3 Nu, zeroed) or take them
 * back (NULL, after nf_accum_flush). Bicubic polynomial nets use them. */
void nf_accum_rowbuf(nf_accum_t *ac, double *G, double *Gq);

/* Lend tables of the 6 reciprocals of every cubic span (tu: 6 Nu doubles,
 * tv: 6 Nv), filled here, or take them back (NULL). Bicubic nets use them:
 * no division per span change in random order. */
void nf_accum_rtab(nf_accum_t *ac, double *tu, double *tv);

/* One point; (u, v) already checked and clamped to the domain, wgt > 0. */
void nf_accum_point(nf_accum_t *ac, double u, double v, const double xyz[3], double wgt);

/* The knot spans of (u, v) (clamped to the domain), the same as
 * nf_find_span's: a guess from uniform spacing, a few steps, binary search
 * only when the knots are far from uniform. last_l, last_k: the previous
 * point's spans or -1 (a raster stays in them or steps to the next). */
static inline void nf_accum_spans(const nf_accum_t *ac, double u, double v, int last_l, int last_k,
                                  int *l, int *k)
{
    const nf_surf_t *s = ac->s;
    *l = nf_find_span_from(last_l, s->nu - 1, s->p, u, s->U, ac->hu);
    *k = nf_find_span_from(last_k, s->nv - 1, s->q, v, s->V, ac->hv);
}

/* nf_accum_point with the spans already known (nf_accum_spans). */
void nf_accum_point_at(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3],
                       double wgt);

/* Rows of one v (the raster rows of a scan) of a bicubic polynomial net,
 * straight into the row band G with no per-point bookkeeping: rows r of
 * 5 doubles (u v x y z, weight 1), each taken while lim (u0 u1 v0 v1)
 * accepts it, clamped to dom; it stops at the first row lim rejects, or
 * where a row of one v ended after fewer than NF_ROW_MIN points (not a
 * raster: the caller's general path does better). Returns the rows taken,
 * 0 when the net is not bicubic polynomial or G is not lent. Same sums as
 * nf_accum_point, in another grouping (Eq. 9). */
#define NF_ROW_MIN 4
long nf_accum_rows33(nf_accum_t *ac, const double *rows, long n, const double lim[4],
                     const double dom[4]);

/* One point of weight 1 straight into the stripes (random order: a point
 * alone in its span), closing any open run first; bicubic polynomial nets
 * take 40 whole-vector updates of its 16 stripe rows, others
 * nf_accum_point_at. */
void nf_accum_lone33(nf_accum_t *ac, double u, double v, int l, int k, const double xyz[3]);

/* Empty the open block into the stripes (before solving or reading S). */
void nf_accum_flush(nf_accum_t *ac);

#endif
