/* SPDX-License-Identifier: MIT */
/* nf_surf.h: NURBS surfaces (Eq. 1). The surface does not own memory: knots,
 * control points and weights point into storage the caller provides (a
 * static array on a board, the arena, or the host's heap). */
#ifndef NF_SURF_H
#define NF_SURF_H

#include "nf_config.h"

typedef struct nf_surf {
    int p, q;   /* degrees in u and v */
    int nu, nv; /* control points in u and v: N = nu*nv */
    double *U;  /* nu+p+1 knots */
    double *V;  /* nv+q+1 knots */
    double *cp; /* 3N: x,y,z of P[i + j*nu], u fastest */
    double *w;  /* N weights, or NULL for a non-rational surface */
} nf_surf_t;

/* Doubles of storage a surface of this shape needs (knots, cp, weights). */
#define NF_SURF_DOUBLES(nu, nv, p, q)                                                              \
    ((long)(nu) + (p) + 1 + (long)(nv) + (q) + 1 + 4L * (long)(nu) * (long)(nv))

/* Point the arrays of s into mem (NF_SURF_DOUBLES long); weights are set to 1. */
void nf_surf_wire(nf_surf_t *s, int p, int q, int nu, int nv, double *mem);

/* NF_OK when degrees, sizes, knots and weights are valid for this board. */
int nf_surf_check(const nf_surf_t *s);

/* Parameter domain [U[p], U[nu]] x [V[q], V[nv]]. */
void nf_surf_domain(const nf_surf_t *s, double *u0, double *u1, double *v0, double *v1);

/* Surface point S(u,v). Parameters are clamped to the domain. */
void nf_surf_eval(const nf_surf_t *s, double u, double v, double out[3]);

/* Point and partial derivatives up to order d <= 2 (A4.4, rational):
 * skl[(k*3 + l)*3 + c] = d^(k+l) S / du^k dv^l, component c, k + l <= d. */
void nf_surf_derivs(const nf_surf_t *s, double u, double v, int d, double skl[27]);

/* Non-zero rational basis R at (u,v): spans *l, *k, and R[a + b*(p+1)] for
 * control point (l-p+a, k-q+b). Returns the number of values (p+1)(q+1). */
int nf_surf_rbasis(const nf_surf_t *s, double u, double v, int *l, int *k, double *R);

#endif
