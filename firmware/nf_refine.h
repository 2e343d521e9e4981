/* SPDX-License-Identifier: MIT */
/* nf_refine.h: knot insertion on NURBS surfaces (Boehm's algorithm; The
 * NURBS Book 5.2-5.3, A5.3 and A5.5), the step of the fitting loop that
 * gives the control net more freedom where the fit needs it (Brujic et al.
 * 2010, Section 2.2: knot insertion keeps the control points near the
 * surface; Piegl & Tiller's loop of fit, check, insert). The surface does
 * not change: the refined net describes the same S(u, v).
 *
 * Output goes to caller storage: wire out with
 *   nf_surf_wire(out, in->p, in->q, nu', nv', mem)   (mem: NF_SURF_DOUBLES(nu', nv', p, q))
 * where nu', nv' come from nf_refine_size / nf_refine_uniform_size. out must
 * not share storage with in. Every check runs before the first byte of out
 * is written: on error out is untouched. Errors: nf_surf_check's for in;
 * NF_EARG for null pointers, r < 0, or out not wired to the expected shape
 * (degrees, nu', nv'; weights when in has them); NF_EKNOTS for a knot not
 * strictly inside the domain, decreasing knots, or a resulting multiplicity
 * above the degree; NF_EBUDGET when the refined net exceeds NF_MAX_CP.
 * Weights: the work is done on the homogeneous points (w x, w y, w z, w), so
 * rational surfaces are refined exactly. A surface without weights (w NULL)
 * gives out->w all 1 (when out has weights). */
#ifndef NF_REFINE_H
#define NF_REFINE_H

#include "nf_surf.h"

/* Net after inserting ru knots in u and rv in v: *nu = in->nu + ru,
 * *nv = in->nv + rv; NF_EBUDGET if (*nu)(*nv) > NF_MAX_CP (outputs set only
 * on NF_OK), NF_EARG for ru or rv < 0, NF_ESIZE for an empty
 * net. */
int nf_refine_size(const nf_surf_t *in, int ru, int rv, int *nu, int *nv);

/* Non-empty knot spans [U[i], U[i+1]) of the domain in u and in v (in must
 * have passed nf_surf_check). */
void nf_refine_spans(const nf_surf_t *in, int *su, int *sv);

/* Net of nf_refine_uniform: nf_refine_size with the span counts, after
 * nf_surf_check(in). */
int nf_refine_uniform_size(const nf_surf_t *in, int *nu, int *nv);

/* Insert the r knots X (non-decreasing, strictly inside the domain, each
 * value's resulting multiplicity <= p) in u: A5.5, the u half of
 * RefineKnotVectSurface (A5.4 on every row of homogeneous points).
 * out: nu + r by nv. */
int nf_refine_u(const nf_surf_t *in, const double *X, int r, nf_surf_t *out);
/* The same in v: out nu by nv + r, multiplicities <= q. */
int nf_refine_v(const nf_surf_t *in, const double *X, int r, nf_surf_t *out);

/* Insert the single knot x `times` times (A5.3 SurfaceKnotIns, built on
 * A5.1): same checks and result as nf_refine_u with X = {x, ..., x}. */
int nf_refine_insert_u(const nf_surf_t *in, double x, int times, nf_surf_t *out);
int nf_refine_insert_v(const nf_surf_t *in, double x, int times, nf_surf_t *out);

/* Uniform refinement: the midpoint of every non-empty knot span inserted in
 * both directions, Nu' = Nu + spans_u, Nv' = Nv + spans_v (every span
 * halved). out wired with nf_refine_uniform_size's net. */
int nf_refine_uniform(const nf_surf_t *in, nf_surf_t *out);

/* Knots that refine one direction to n + r control points: r times the
 * widest span between distinct knots of K[deg..n] (n control points,
 * degree deg), the first of equal ones, halved, counting the knots already
 * chosen (Boehm insertion of X keeps the surface). X (room for r) gets them
 * sorted. Insert them with nf_refine_u / nf_refine_v. This is "refine a
 * net to N control points" for the fit job and for base surfaces. NF_EARG
 * for r < 0 or null pointers with r > 0. */
int nf_refine_widest(const double *K, int n, int deg, int r, double *X);

#endif
