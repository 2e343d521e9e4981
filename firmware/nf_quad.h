/* SPDX-License-Identifier: MIT */
/* nf_quad.h: fast projection by a quadrilateral decomposition (Piegl &
 * Tiller 2001, Section 3): a crack-free blanket of quadrilaterals within a
 * relative tolerance of the surface (3.1), the maximum-area plane and a 2-D
 * grid over the quadrilaterals in it (3.2), the start parameters of a point
 * from the nearest quadrilateral's mid-plane (3.4), then Newton point
 * inversion to 1e-9 of the domain (nf_project); and thinning to the nearest
 * point per vertex (3.3). Memory: caller storage of NF_QUAD_BYTES(maxq, nu,
 * nv) bytes for at most maxq quadrilaterals of an nu x nv net, whatever the
 * number of points. */
#ifndef NF_QUAD_H
#define NF_QUAD_H

#include "nf_affine.h"
#include "nf_basis.h"
#include "nf_project.h"
#include <stddef.h>

/* The paper's relative tolerance (0.5 % of the surface's size). */
#define NF_QUAD_REL_TOL 0.005
/* For projection starts: quadrilaterals flat to 0.1 % put the starts
 * closer, and Newton takes about 2 steps to 1e-9 instead of 3 on a fine
 * smooth net (8 quadrilaterals at 0.5 % on bench project's 316 x 316 part,
 * 380 at 0.1 %); callers fall back to NF_QUAD_REL_TOL when the finer
 * blanket exceeds their room. */
#define NF_QUAD_SEED_TOL 0.001

/* Doubles kept per quadrilateral: mid-plane frame (centroid, two in-plane
 * axes), the planar corners in it, the box in the maximum-area plane. */
#define NF_QUAD_QD 21
/* Grid entries (quadrilateral references) per quadrilateral at most; the
 * grid is coarsened until the references fit. */
#define NF_QUAD_ITEMS 12
/* Bytes for at most maxq quadrilaterals of a surface with nu x nv control
 * points: parameter lists (maxq + 2 each), vertices (at most 3 maxq + 2 of
 * them), per-quadrilateral data, the knot reciprocals of every span (so
 * that Newton's basis functions take no division), grid cells (at most
 * 2 maxq + 2) and references, alignment slack. */
#define NF_QUAD_DOUBLES_(maxq, nu, nv)                                                             \
    (2L * ((long)(maxq) + 2) + 3L * (3L * (long)(maxq) + 2) + (long)NF_QUAD_QD * (long)(maxq) +    \
     ((long)(nu) + (long)(nv) + 2) * (long)NF_RECIP_LEN)
#define NF_QUAD_BYTES(maxq, nu, nv)                                                                \
    (sizeof(double) * (size_t)NF_QUAD_DOUBLES_(maxq, nu, nv) +                                     \
     sizeof(int) * (size_t)(2L * (long)(maxq) + 3 + (long)NF_QUAD_ITEMS * (long)(maxq)) + 64)

typedef struct nf_quad_params {
    double rel_tol; /* flatness tolerance relative to the bounding-box diagonal of
                     * the control net (NF_QUAD_REL_TOL), in (0, 1) */
    double limit;   /* points further than this from the surface are flagged
                     * (model units); <= 0: 5 % of the diagonal */
    int drop_far;   /* 1: nf_quad_project returns NF_QUAD_DROPPED for them */
} nf_quad_params_t;

/* nf_quad_project's positive result for a far point with drop_far set. */
#define NF_QUAD_DROPPED 1

typedef struct nf_quad {
    const nf_surf_t *s;
    double dom[4]; /* u0, u1, v0, v1 */
    double tol;    /* absolute flatness tolerance */
    double limit;  /* far-point distance */
    int drop_far;
    int nu, nv; /* parameter lines: (nu - 1)(nv - 1) quadrilaterals */
    long maxq;
    double *ul, *vl;     /* the sorted parameter lists */
    double *xyz;         /* vertex (i, j) at 3 (i + j nu) */
    double *qd;          /* NF_QUAD_QD doubles per quadrilateral (i + j (nu - 1)) */
    double *ru, *rv;     /* knot reciprocals (nf_basis_recip) of span l at l * NF_RECIP_LEN */
    double N[3];         /* normal of the maximum-area plane */
    double e1[3], e2[3]; /* axes in it */
    int folded;          /* 1: some quadrilateral faces away from N (the surface
                        * folds over in the plane, e.g. a cylinder beyond 180
                        * degrees): the plane's 2-D search is not one-to-one */
    int rational;        /* weights not all equal */
    const double *pf;    /* NULL, or the power form of every span (nf_quad_power) */
    int creased;         /* a C0 knot line: Newton goes through nf_project alone */
    double x0, y0, cell; /* grid origin and cell size in (e1, e2) */
    int gx, gy;          /* cells */
    int *cstart, *citem; /* cell c holds citem[cstart[c] .. cstart[c + 1]) */
    long n_clamped, n_far, n_slow; /* counts: feet on the boundary, points beyond
                                    * limit, points nf_project had to finish */
    nf_affine_t aff;               /* aff.ok: s is a flat affine map, projected in closed form */
} nf_quad_t;

/* Decompose s (passed nf_surf_check) into at most maxq quadrilaterals in
 * mem (bytes long, at least NF_QUAD_BYTES(maxq, s->nu, s->nv)). NF_EARG for null pointers
 * or a tolerance outside (0, 1); NF_EARENA when bytes is too small;
 * NF_EBUDGET when the tolerance needs more than maxq quadrilaterals. */
int nf_quad_init(nf_quad_t *q, const nf_surf_t *s, const nf_quad_params_t *prm, long maxq,
                 void *mem, size_t bytes);

long nf_quad_count(const nf_quad_t *q); /* quadrilaterals */

/* Start parameters for Q: the nearest quadrilateral among those binned in
 * Q's cell (a ring search when the cell is empty), improved by walking to
 * a neighbour while that is nearer; Q projected onto its mid-plane and the
 * parameters recovered by bilinear inversion inside it. */
void nf_quad_start(const nf_quad_t *q, const double Q[3], double *u0, double *v0);

/* Projection of Q: nf_quad_start, then Newton to tol of the domain (inline
 * for interior feet, nf_project otherwise); on an affine surface (a plane
 * base, nf_affine.h) the closed form instead. Counts clamped, far and slow
 * points in q. Returns nf_project's codes, or NF_QUAD_DROPPED. */
int nf_quad_project(nf_quad_t *q, const double Q[3], double tol, nf_proj_t *out);

/* Newton alone, for callers with starts of their own (the foot on the
 * surface before knot insertion, or on the previous fit): q holds the
 * domain and the knot reciprocals of s in mem (at least
 * NF_QUAD_NEWTON_BYTES(s->nu, s->nv) bytes), no blanket; only
 * nf_quad_newton may use it. NF_EARG for null pointers, NF_EARENA when
 * bytes is too small. */
#define NF_QUAD_NEWTON_BYTES(nu, nv)                                                               \
    (sizeof(double) * (size_t)(((long)(nu) + (long)(nv) + 2) * (long)NF_RECIP_LEN) + 64)
int nf_quad_newton_init(nf_quad_t *q, const nf_surf_t *s, void *mem, size_t bytes);

/* nf_quad_project's inline Newton from (*u, *v) (q from either init): 1
 * when it converged to an interior foot (out set, as nf_project would
 * from there to rounding); 0 when it gave up (a bound, no progress, a
 * crease), *u, *v then the nearest iterate, for nf_project or a search. */
int nf_quad_newton(const nf_quad_t *q, const double Q[3], double tol, double *u, double *v,
                   nf_proj_t *out);

/* Newton's derivatives from the power form of each knot span (a bicubic
 * polynomial surface only: 16 coefficients of x, y, z a span in the
 * span's own coordinates), in place of the basis functions at every step:
 * about a third of the work. Optional, after either init: pf holds at
 * least NF_QUAD_POWER_BYTES(s->nu, s->nv) bytes (8-byte aligned) and
 * outlives q's use. NF_OK also when s is not a polynomial bicubic (q then
 * keeps the basis path); NF_EARG for null pointers, NF_EARENA when bytes
 * is too small. */
#define NF_QUAD_POWER_SPAN 64 /* doubles a span: C[n][m][x y z 0] of s^m t^n */
#define NF_QUAD_POWER_BYTES(nu, nv)                                                                \
    (sizeof(double) * (size_t)NF_QUAD_POWER_SPAN * (size_t)((long)(nu) > 3 ? (long)(nu)-3 : 0) *   \
     (size_t)((long)(nv) > 3 ? (long)(nv)-3 : 0))
int nf_quad_power(nf_quad_t *q, double *pf, size_t bytes);

/* Thinning (Section 3.3) as a stream: per vertex, the nearest point seen so
 * far among those within radius r of it. Caller storage: NF_THIN_DOUBLES
 * doubles (distance^2 and x y z per vertex) and NF_THIN_LONGS longs (point
 * index per vertex, -1 for none). */
#define NF_THIN_VERTS(maxq) (3L * (long)(maxq) + 2)
#define NF_THIN_DOUBLES(maxq) (4L * NF_THIN_VERTS(maxq))
#define NF_THIN_LONGS(maxq) NF_THIN_VERTS(maxq)
typedef struct nf_thin {
    const nf_quad_t *q;
    double r;
    double *best; /* per vertex: d^2, x, y, z */
    long *idx;
} nf_thin_t;

/* NF_EARG for a radius not > 0 or null pointers. */
int nf_thin_init(nf_thin_t *t, const nf_quad_t *q, double r, double *best, long *idx);
/* Offer point P (index k >= 0); NF_ENONFINITE for a non-finite point. */
int nf_thin_add(nf_thin_t *t, const double P[3], long k);
long nf_thin_verts(const nf_thin_t *t); /* vertices: entries of best / idx */

#endif
