/* SPDX-License-Identifier: MIT */
/* cf_surf.h: heap-owned NURBS surfaces for the host tools. */
#ifndef CF_SURF_H
#define CF_SURF_H

#include "nf_surf.h"

/* Allocate storage for a surface of this shape (weights 1, knots and points
 * zero). CF_ENOMEM on failure. Free with cf_surf_free. */
int cf_surf_alloc(nf_surf_t *s, int p, int q, int nu, int nv);
void cf_surf_free(nf_surf_t *s);
/* The benchmarks' square net: side x side control points of degree p both
 * ways (side raised to p + 1), uniform clamped knots on [0, 1], points on
 * the plane z = 0 at x = 100 i / (side - 1), y = 100 j / (side - 1).
 * CF_ENOMEM on failure. */
int cf_surf_square(nf_surf_t *s, int p, int side);
/* Deep copy of src into dst (allocated here). */
int cf_surf_copy(nf_surf_t *dst, const nf_surf_t *src);

#endif
