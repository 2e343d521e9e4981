/* SPDX-License-Identifier: MIT */
/* ref_dense.h: independent reference results for the tests. The B-spline
 * basis here is the recursive Cox-de Boor definition over all functions
 * (not the span algorithms of firmware/), the normal equations of Eq. 7 are
 * built as dense matrices from an explicit R and B, and solved by Gaussian
 * elimination with partial pivoting. Heap use is fine here: tests only. */
#ifndef REF_DENSE_H
#define REF_DENSE_H

#include "nf_surf.h"

/* N_{i,p}(u) by the recursive definition; the last non-empty knot interval
 * is closed on the right so that u = U[end] is covered. */
double ref_bspline(int i, int p, const double *U, int nknots, double u);

/* The full row of rational basis values at (u, v): out[N]. */
void ref_rbasis_row(const nf_surf_t *s, double u, double v, double *out);

/* Dense Eq. 7: A (N x N, row-major) and b (N x 3) from M points (rows of
 * u v x y z). Returns allocated arrays through A and b. */
void ref_eq7(const nf_surf_t *s, const double *pts, long M, double alpha, double beta, double **A,
             double **b);

/* Solve A x = b (n x n, 3 right-hand sides, row-major x[3i+c]) by Gaussian
 * elimination with partial pivoting on copies. Returns 0, or -1 if a pivot
 * is exactly zero. */
int ref_solve(const double *A, const double *b, long n, double *x);

/* Deterministic random numbers in [lo, hi). */
void ref_seed(unsigned long long s);
double ref_rand(double lo, double hi);

/* A random clamped surface: degrees p, q, net nu x nv, non-uniform interior
 * knots on [u0,u1] x [v0,v1], control points a perturbed grid, weights in
 * [wlo, whi] (rational when wlo < whi). Heap-allocated: free with ref_surf_free. */
void ref_surf_random(nf_surf_t *s, int p, int q, int nu, int nv, double u0, double u1, double v0,
                     double v1, double wlo, double whi);
void ref_surf_free(nf_surf_t *s);

#endif
