/* nf_accum.h: the hot loop of Section 3.1: one measured point (one row of R)
 * into the stripes and R^T Q. Two things make it fast without changing a
 * single sum's terms beyond rounding order:
 *  - points of one knot span share their span search and the reciprocals
 *    of their knot differences (cached per span);
 *  - consecutive points in the same span (what a raster scan delivers) are
 *    summed into a dense (p+1)(q+1) block first, NF_ACCUM_BUF rows at a
 *    time, which the stripes receive once when the span changes: contiguous,
 *    vectorisable work instead of scattered updates. A lone point in its
 *    span goes straight to the stripes.
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
    int bl, bk;   /* span of the open block, -1 none */
    int npend;    /* points seen in this span */
    int nb;       /* of them, still in the buffer */
    int open;     /* blk and brhs hold a sum */
    int nl, nlp;  /* (p+1)(q+1) and its padded row length */
    int rational; /* weights differ: R_ij = N_i N_j w_ij / W (Eq. 1) */
    _Alignas(32) double Rb[NF_ACCUM_BUF][NF_LOCAL_PAD]; /* buffered rows of R, zero tails */
    double qb[NF_ACCUM_BUF][3];
    _Alignas(32) double blk[NF_MAX_LOCAL * NF_LOCAL_PAD]; /* row t1 at t1*nlp, upper used */
    double brhs[3 * NF_MAX_LOCAL];
} nf_accum_t;

void nf_accum_init(nf_accum_t *ac, const nf_surf_t *s, nf_stripe_t *A, double *rhs);

/* One point; (u, v) already checked and clamped to the domain, wgt > 0. */
void nf_accum_point(nf_accum_t *ac, double u, double v, const double xyz[3], double wgt);

/* Empty the open block into the stripes (before solving or reading S). */
void nf_accum_flush(nf_accum_t *ac);

#endif
