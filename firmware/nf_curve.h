/* SPDX-License-Identifier: MIT */
/* nf_curve.h: NURBS curves (The NURBS Book, Ch. 2-5): evaluation, first and
 * second derivatives (A4.2), reversal, affine reparametrisation, knot
 * refinement (A5.4) and degree elevation (A5.9). Like nf_surf_t, a curve does
 * not own memory: knots, control points and weights point into caller
 * storage (NF_CURVE_DOUBLES). Operations that make a new curve write into a
 * curve the caller wired to the size the matching *_size function gives;
 * they work on homogeneous points (w x, w y, w z, w), so rational curves
 * come out exact. The base surfaces of Piegl & Tiller (2001, Section 2) are
 * built from four of them. */
#ifndef NF_CURVE_H
#define NF_CURVE_H

#include "nf_config.h"

typedef struct nf_curve {
    int p;      /* degree */
    int n;      /* control points */
    double *U;  /* n+p+1 knots, clamped */
    double *cp; /* 3n: x,y,z of P[i] */
    double *w;  /* n weights, or NULL for a non-rational curve */
} nf_curve_t;

/* Doubles of storage a curve of this shape needs (knots, cp, weights). */
#define NF_CURVE_DOUBLES(n, p) ((long)(n) + (p) + 1 + 4L * (long)(n))

/* Point the arrays of c into mem (NF_CURVE_DOUBLES long); weights set to 1. */
void nf_curve_wire(nf_curve_t *c, int p, int n, double *mem);

/* NF_OK, or NF_EARG (null arrays), NF_EDEGREE, NF_ESIZE (n < p+1),
 * NF_EKNOTS (decreasing, unclamped, empty), NF_ENONFINITE, NF_EWEIGHT
 * (a weight zero, negative or not finite). */
int nf_curve_check(const nf_curve_t *c);

/* Parameter domain [U[p], U[n]]. */
void nf_curve_domain(const nf_curve_t *c, double *u0, double *u1);

/* C(u), u clamped to the domain. */
void nf_curve_eval(const nf_curve_t *c, double u, double out[3]);

/* C and its derivatives up to order d <= 2 (rational quotient rule, A4.2):
 * ck[3k + c] = d^k C / du^k, component c; orders above d are zero. */
void nf_curve_derivs(const nf_curve_t *c, double u, int d, double ck[9]);

/* Copy in into out (wired to in's shape; weights 1 when in has none). */
void nf_curve_copy(const nf_curve_t *in, nf_curve_t *out);

/* Reverse the direction in place: C'(u) = C(a + b - u) on the same domain. */
void nf_curve_reverse(nf_curve_t *c);

/* Map the knots affinely onto [a, b] (a < b) in place; the curve's points
 * are unchanged, the ends land on a and b exactly. */
void nf_curve_reparam(nf_curve_t *c, double a, double b);

/* Multiply every weight by f > 0: the same curve (projective invariance). */
void nf_curve_scale_weights(nf_curve_t *c, double f);

/* Control points after raising the degree by t >= 0: n + t (D - 1), D the
 * number of distinct knot values (every multiplicity grows by t). */
int nf_curve_elevate_size(const nf_curve_t *c, int t);

/* Degree elevation by t (A5.9: Bezier segments by knot insertion, each
 * elevated, the extra knots removed). out: degree p+t (<= NF_MAX_DEGREE),
 * nf_curve_elevate_size points. NF_EDEGREE when p + t is too large, NF_EARG
 * when out is not wired to that shape. */
int nf_curve_elevate(const nf_curve_t *in, int t, nf_curve_t *out);

/* Insert the r knots X (non-decreasing, inside the domain, resulting
 * multiplicities <= p) (A5.4). out: degree p, n + r points. NF_EKNOTS for a
 * knot outside the domain or out of order, NF_EARG for a wrong out. */
int nf_curve_refine(const nf_curve_t *in, const double *X, int r, nf_curve_t *out);

#endif
