/* SPDX-License-Identifier: MIT */
/* nf_fold.h: a cheap proof that a polynomial B-spline surface does not
 * fold over a plane. The normal Su x Sv faces the plane's normal N where
 * det(Su, Sv, N) = (Su.e1)(Sv.e2) - (Su.e2)(Sv.e1) > 0 ((e1, e2) axes of
 * the plane); on one knot span Su and Sv lie in the convex hulls of their
 * own control points (the hodographs, p (P_i+1,j - P_ij) / (u_i+p+1 -
 * u_i+1), likewise in v), which bounds each factor. When every span's
 * bound is positive no part of the surface faces away from N: nf_quad's
 * blanket would find no fold (its test, quadrilateral by quadrilateral,
 * costs a blanket of the surface; this one O(N)). The bound is loose, so
 * 0 means "not proven", never "folded". Memory: none. */
#ifndef NF_FOLD_H
#define NF_FOLD_H

#include "nf_surf.h"

/* 1 when s (passed nf_surf_check) provably does not fold over the plane
 * whose normal is the net's mean normal, (sum of the u edges of the net) x
 * (sum of the v edges); 0 when that is not proven (a rational surface, a
 * bound that does not hold, a degenerate net). */
int nf_fold_free(const nf_surf_t *s);

#endif
