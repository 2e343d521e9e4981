/* SPDX-License-Identifier: MIT */
/* nf_fold.h: a cheap proof that a polynomial B-spline surface is a height
 * field: that every line along one direction N (the net's mean normal)
 * meets it at most once, so no part of it lies over another (the paper's
 * "projectable to a plane", Section 3.2). The proof: the map F from the
 * parameters to the surface's shadow in the plane across N, F(u, v) =
 * (e1.S, e2.S), scaled per parameter by fixed s, t > 0, has a Jacobian J
 * whose symmetric part is positive definite everywhere; then for any two
 * parameter points x != y of the (convex) domain, (x - y).(F(x) - F(y)) is
 * the integral of (x - y)^T J (x - y) along the segment between them, > 0,
 * so F(x) != F(y). On one knot span the columns of J (Su and Sv) lie in
 * the convex hulls of their own control points (the hodographs,
 * p (P_i+1,j - P_ij) / (u_i+p+1 - u_i+1), likewise in v): interval bounds
 * of their coordinates decide it. The bounds are loose, so 0 means "not
 * proven", never "folded". It asks nothing of the surface's slope along N.
 * It is not nf_quad's fold test (every quadrilateral of a blanket facing
 * the normal of its maximum-area plane: local, and in another plane);
 * neither implies the other. The blanket costs a decomposition of the
 * surface, this O(N). Memory: none. */
#ifndef NF_FOLD_H
#define NF_FOLD_H

#include "nf_surf.h"

/* 1 when s (passed nf_surf_check) is proven a height field along N = (sum
 * of the u edges of the net) x (sum of the v edges); 0 when that is not
 * proven (a rational surface, a bound that does not hold, a degenerate
 * net). */
int nf_fold_free(const nf_surf_t *s);

#endif
