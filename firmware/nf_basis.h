/* SPDX-License-Identifier: MIT */
/* nf_basis.h: B-spline basis on one knot vector (The NURBS Book, A2.1-A2.3)
 * and Greville abscissae. Knots are clamped: U[0..p] equal, U[n+1..n+p+1]
 * equal, with n+1 control points. */
#ifndef NF_BASIS_H
#define NF_BASIS_H

#include "nf_config.h"

/* Knot span index l with U[l] <= u < U[l+1], p <= l <= n; u = U[n+1] gives n
 * (A2.1). u must lie in [U[p], U[n+1]]. */
int nf_find_span(int n, int p, double u, const double *U);

/* nf_find_span's result, fast: a guess from uniform spacing (h = spans per
 * unit parameter), else the span last or the next (raster scans on uneven
 * knots), else the guess walked a few steps, else the binary search. Each step keeps
 * p <= g <= n (U[p] < u < U[n+1] there) and moves toward the unique g with
 * U[g] <= u < U[g+1]: the result is nf_find_span's. */
static inline int nf_find_span_from(int last, int n, int p, double u, const double *U, double h)
{
    if (u >= U[n + 1])
        return n;
    if (u <= U[p])
        return p;
    /* The guess first: on near-uniform knots it is the span, raster or not. */
    double x = (u - U[p]) * h;
    int g = x < (double)(n - p) ? p + (int)x : n;
    if (U[g] <= u && u < U[g + 1])
        return g;
    if (last >= 0) {
        if (U[last] <= u && u < U[last + 1])
            return last;
        if (last < n && U[last + 1] <= u && u < U[last + 2])
            return last + 1;
    }
    for (int t = 0; t < 4; t++) {
        if (u < U[g])
            g--;
        else if (u >= U[g + 1])
            g++;
        else
            return g;
    }
    return nf_find_span(n, p, u, U);
}

/* The p+1 non-zero basis functions N[l-p..l] at u (A2.2). */
void nf_basis_funs(int l, double u, int p, const double *U, double *N);

/* Reciprocals of the knot differences A2.2 divides by on span l, so that a
 * stream of points in one span evaluates its basis with multiplications
 * only: recip[j*(j-1)/2 + r] = 1 / (U[l+r+1] - U[l+1-j+r]), j = 1..p, r < j. */
#define NF_RECIP_LEN (NF_MAX_DEGREE * (NF_MAX_DEGREE + 1) / 2)
void nf_basis_recip(int l, int p, const double *U, double *recip);
/* nf_basis_funs with the reciprocals of span l (same values to rounding).
 * Inline so that callers with a constant degree get unrolled code. */
static inline void nf_basis_funs_r(int l, double u, int p, const double *U, const double *recip,
                                   double *N)
{
    double left[NF_MAX_ORDER], right[NF_MAX_ORDER];
    N[0] = 1.0;
    for (int j = 1; j <= p; j++) {
        left[j] = u - U[l + 1 - j];
        right[j] = U[l + j] - u;
        const double *rc = recip + j * (j - 1) / 2;
        double saved = 0.0;
        for (int r = 0; r < j; r++) {
            double temp = N[r] * rc[r];
            N[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        N[j] = saved;
    }
}

/* Basis functions and derivatives up to order nd <= p (A2.3):
 * ders[k*(p+1) + j] = k-th derivative of N[l-p+j]. */
void nf_ders_basis_funs(int l, double u, int p, int nd, const double *U, double *ders);

/* Greville abscissa of control point i: mean of U[i+1..i+p]. */
double nf_greville(int i, int p, const double *U);

/* 0 when U (length n+p+2) is non-decreasing, clamped at both ends, has a
 * non-empty domain and interior multiplicity <= p; NF_EKNOTS otherwise. */
int nf_knots_check(int n, int p, const double *U);

#endif
