/* SPDX-License-Identifier: MIT */
/* nf_affine.h: projection onto a flat surface parameterised affinely,
 * S(u, v) = O + u A + v B, in closed form. A B-spline surface is that
 * when its control points lie at O + g_i A + h_j B with g, h the Greville
 * abscissae (linear precision) and its weights are equal: the plane bases
 * of `cellfit base --method plane`. Newton there takes a blanket, a start
 * and two or three derivative evaluations a point; the closed form a 2 x 2
 * solve, or, for a point beyond the domain, the nearest of the four
 * edges. Memory: the struct alone. */
#ifndef NF_AFFINE_H
#define NF_AFFINE_H

#include "nf_project.h"

/* Largest distance of a control point from the affine map, relative to the
 * control net's extent, for the surface to count as affine: rounding of
 * the coordinates only (the foot is then within about that of the
 * surface's, far below nf_project's 1e-9 of the domain). */
#define NF_AFFINE_REL_TOL 1e-12

/* A plane foot within this share of the domain's width outside an edge is
 * on it, not clamped (rounding of the 2 x 2 solve). */
#define NF_AFFINE_EDGE 1e-12

typedef struct nf_affine {
    int ok;                  /* 1: s is affine and the fields below hold */
    double O[3], A[3], B[3]; /* S(u, v) = O + u A + v B on the domain */
    double n[3];             /* A x B, normalised: the sign of the distance */
    double gaa, gab, gbb;    /* the Gram matrix of A, B */
    double det;              /* gaa gbb - gab^2 */
    double dom[4];           /* u0, u1, v0, v1 */
} nf_affine_t;

/* Whether s (passed nf_surf_check) is affine: a->ok and the return value
 * 1, else 0 (a->ok 0). O(N). */
int nf_affine_init(nf_affine_t *a, const nf_surf_t *s);

/* The foot of Q on the affine surface (a->ok): nf_project's result (u, v,
 * foot, signed distance, clamped when the nearest point lies on the
 * boundary with the distance falling outward), iters 0. NF_ENONFINITE
 * for a non-finite Q, NF_EARG when a is not affine. */
int nf_affine_project(const nf_affine_t *a, const double Q[3], nf_proj_t *out);

#endif
