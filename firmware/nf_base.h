/* SPDX-License-Identifier: MIT */
/* nf_base.h: the base surface when nothing but the points is given: a plane
 * patch over the points (Piegl & Tiller 2001, Section 3.2: project onto the
 * maximum-area plane). The plane comes from the points' 3 x 3 scatter
 * matrix, accumulated one point at a time (memory fixed, whatever the
 * count), by the paper's power iteration N <- M N, normalised, run on a
 * pair of vectors (orthonormalised each step) so that it converges to the
 * two dominant directions: the plane on which the points spread most, its
 * normal their cross product. A second pass over the points gives their
 * extent in the plane, along the two axes and along NF_BASE_ANGLES pairs of
 * axes turned in the plane (issue 14: on a square footprint the two spreads
 * are equal and the axes arbitrary; holes' came out at 45 degrees, its data
 * a diamond over half the domain, knot lines across it); the patch is the
 * smallest of those rectangles (the axes' own unless another is 3 %
 * smaller), slightly enlarged so
 * that every point projects inside, with any degree and net (control
 * points at the Greville points: the parametrisation is affine). */
#ifndef NF_BASE_H
#define NF_BASE_H

#include "nf_surf.h"

#ifndef NF_BASE_ANGLES
#define NF_BASE_ANGLES 45 /* turns of the axes tried, 2 degrees apart over [-45, 45) */
#endif

typedef struct nf_base_plane {
    long n;                        /* points accumulated */
    double o[3];                   /* shift (the first point), for a well-conditioned sum */
    double s1[3];                  /* sum of (Q - o) */
    double s2[6];                  /* sum of (Q - o)(Q - o)^T: xx xy xz yy yz zz */
    double c[3];                   /* centroid (nf_base_plane_axes) */
    double e[3][3];                /* e[0], e[1]: in-plane axes, most spread first; e[2] normal */
    double lam[3];                 /* scatter along e[0], e[1], e[2] (per point) */
    int iters;                     /* power iterations taken */
    long next;                     /* points seen by nf_base_plane_extent */
    double lo[2], hi[2];           /* extent along e[0] and e[1] */
    double rcs[NF_BASE_ANGLES][2]; /* cos, sin of each turn (nf_base_plane_axes) */
    double rlo[NF_BASE_ANGLES][2], rhi[NF_BASE_ANGLES][2]; /* along the turned axes */
} nf_base_plane_t;

void nf_base_plane_init(nf_base_plane_t *pl);

/* Pass 1: one point into the scatter matrix. NF_ENONFINITE for NaN/Inf. */
int nf_base_plane_add(nf_base_plane_t *pl, const double Q[3]);

/* The plane: centroid, axes, normal. NF_ENODATA for fewer than 3 points,
 * NF_ESINGULAR when the points are (numerically) on a line. The normal is
 * turned to point to +z when it has a z component. */
int nf_base_plane_axes(nf_base_plane_t *pl);

/* Pass 2: one point into the extent (after nf_base_plane_axes). */
void nf_base_plane_extent(nf_base_plane_t *pl, const double Q[3]);

/* The patch into out (wired by the caller with its degrees and net, p, q
 * >= 1): uniform knots on [0, 1], the rectangle of the extent grown by
 * margin (a fraction of each side, e.g. 0.01) on every side. NF_ENODATA
 * before pass 2. */
int nf_base_plane_patch(const nf_base_plane_t *pl, double margin, nf_surf_t *out);

/* Dominant two eigenvectors of the symmetric 3 x 3 matrix M (xx xy xz yy yz
 * zz) by power iteration on a pair (from (1,1,1), and two other starts
 * whose best is kept), then the 2 x 2 Rayleigh-Ritz rotation: e[0], e[1]
 * the eigenvectors of the two largest eigenvalues lam[0] >= lam[1], e[2]
 * = e[0] x e[1] the third (lam[2] its Rayleigh quotient). Returns the
 * iterations taken. */
int nf_base_power(const double M[6], double e[3][3], double lam[3]);

#endif
