/* SPDX-License-Identifier: MIT */
/* cf_surfrow.h: many points of one surface, fast, when they come in rows of
 * one v (a scanner's raster; any order works). The v row's basis N(v) is
 * computed once per row, and each control column's sum over it,
 * C_i = sum_b N_b(v) P_(i, k-q+b) (a curve in u), once per row and column
 * when a point first needs it. On a u span the row's curve is one
 * polynomial: its power coefficients about the span's middle (the span's
 * basis in power form, computed once per span at init, times the p+1
 * columns) once per row and span, and a point costs its span and Horner's
 * rule, p x 3 multiply-adds (issue 20: 289 instructions a point before,
 * N(u) per point). A row's first point (every point, in random order) is
 * Eq. 1 itself from both bases in power form: no division, no row set-up.
 * Same surface point as nf_surf_eval up to rounding (sums regrouped).
 * Rational surfaces (weights not all equal) go to nf_surf_eval. Memory:
 * 4 + (p+1)^2 doubles per control column, (q+1)^2 per control row. */
#ifndef CF_SURFROW_H
#define CF_SURFROW_H

#include "nf_basis.h"
#include "nf_config.h"
#include "nf_surf.h"

typedef struct cf_surfrow {
    const nf_surf_t *s;
    double *C;   /* 3 nu: the curve of the current row */
    long *stamp; /* nu: the row each C_i was computed for */
    double *M;   /* (p+1)^2 per u span l (at l - p): N_(l-p+a)(u) = sum_j M[j][a] t^j */
    double *Mv;  /* (q+1)^2 per v span k (at k - q), the same for N(v) */
    long row;    /* rows seen (stamps) */
    double v;    /* the current row's v (clamped); NaN before the first */
    int k;       /* its v span */
    double Nv[NF_MAX_ORDER];
    int l;                         /* the u span of the last point, -1 none */
    int al;                        /* the u span of A, -1 none */
    long arow;                     /* the row of A */
    double A[3 * NF_MAX_ORDER];    /* the row's curve on span al: x y z per power of t */
    double lo, hi, mid;            /* span l: [lo, hi) (hi: just past umax on the last), middle */
    int p3;                        /* polynomial (C set) of degree 3 in u: the inline case */
    double umin, umax, vmin, vmax; /* the domain */
    double hu, hv;                 /* spans per unit parameter (the uniform guess) */
} cf_surfrow_t;

/* CF_OK or CF_ENOMEM. s must outlive e and keep its net. */
int cf_surfrow_init(cf_surfrow_t *e, const nf_surf_t *s);
/* cf_surfrow_eval's general case (any row, span or degree). */
void cf_surfrow_eval_any(cf_surfrow_t *e, double u, double v, double out[3]);

/* S(u, v), the parameters clamped to the domain like nf_surf_eval's.
 * Inline for the common case, a point on the last point's row and u span
 * at degree 3 in u: Horner's rule on the span's power form, no call (the
 * residual pass's cost per point, issue 20). */
static inline void cf_surfrow_eval(cf_surfrow_t *e, double u, double v, double out[3])
{
    if (v == e->v && e->al == e->l && e->arow == e->row && e->lo <= u && u < e->hi && e->p3) {
        const double t = u - e->mid, *A = e->A;
        out[0] = ((A[9] * t + A[6]) * t + A[3]) * t + A[0];
        out[1] = ((A[10] * t + A[7]) * t + A[4]) * t + A[1];
        out[2] = ((A[11] * t + A[8]) * t + A[5]) * t + A[2];
        return;
    }
    cf_surfrow_eval_any(e, u, v, out);
}
void cf_surfrow_free(cf_surfrow_t *e);

#endif
