/* SPDX-License-Identifier: MIT */
/* nf_basis.c: B-spline basis functions (The NURBS Book A2.1-A2.3). */
#include "nf_basis.h"
#include "nf_err.h"

int nf_find_span(int n, int p, double u, const double *U)
{
    if (u >= U[n + 1])
        return n; /* right end belongs to the last non-empty span */
    if (u <= U[p])
        return p;
    int lo = p, hi = n + 1;
    while (hi - lo > 1) { /* invariant: U[lo] <= u < U[hi] */
        int mid = (lo + hi) >> 1;
        if (u < U[mid])
            hi = mid;
        else
            lo = mid;
    }
    return lo;
}

void nf_basis_funs(int l, double u, int p, const double *U, double *N)
{
    double left[NF_MAX_ORDER], right[NF_MAX_ORDER];
    N[0] = 1.0;
    for (int j = 1; j <= p; j++) {
        left[j] = u - U[l + 1 - j];
        right[j] = U[l + j] - u;
        double saved = 0.0;
        for (int r = 0; r < j; r++) {
            double temp = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        N[j] = saved;
    }
}

void nf_basis_recip(int l, int p, const double *U, double *recip)
{
    for (int j = 1; j <= p; j++)
        for (int r = 0; r < j; r++)
            recip[j * (j - 1) / 2 + r] = 1.0 / (U[l + r + 1] - U[l + 1 - j + r]);
}

void nf_ders_basis_funs(int l, double u, int p, int nd, const double *U, double *ders)
{
    double ndu[NF_MAX_ORDER][NF_MAX_ORDER];
    double a[2][NF_MAX_ORDER];
    double left[NF_MAX_ORDER], right[NF_MAX_ORDER];
    const int o = p + 1;

    ndu[0][0] = 1.0;
    for (int j = 1; j <= p; j++) {
        left[j] = u - U[l + 1 - j];
        right[j] = U[l + j] - u;
        double saved = 0.0;
        for (int r = 0; r < j; r++) {
            ndu[j][r] = right[r + 1] + left[j - r]; /* lower triangle: knot differences */
            double temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; j++)
        ders[j] = ndu[j][p];
    for (int r = 0; r <= p; r++) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (int k = 1; k <= nd; k++) {
            double d = 0.0;
            int rk = r - k, pk = p - k;
            if (r >= k) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                d = a[s2][0] * ndu[rk][pk];
            }
            int j1 = (rk >= -1) ? 1 : -rk;
            int j2 = (r - 1 <= pk) ? k - 1 : p - r;
            for (int j = j1; j <= j2; j++) {
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
                d += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k * o + r] = d;
            int t = s1;
            s1 = s2;
            s2 = t;
        }
    }
    int f = p;
    for (int k = 1; k <= nd; k++) {
        for (int j = 0; j <= p; j++)
            ders[k * o + j] *= f;
        f *= p - k;
    }
}

double nf_greville(int i, int p, const double *U)
{
    double s = 0.0;
    for (int k = 1; k <= p; k++)
        s += U[i + k];
    return s / p;
}

int nf_knots_check(int n, int p, const double *U)
{
    const int m = n + p + 1; /* last knot index */
    for (int i = 0; i <= m; i++)
        if (!(U[i] - U[i] == 0.0)) /* NaN or Inf */
            return NF_EKNOTS;
    for (int i = 0; i < m; i++)
        if (U[i + 1] < U[i])
            return NF_EKNOTS;
    for (int i = 1; i <= p; i++)
        if (U[i] != U[0] || U[m - i] != U[m])
            return NF_EKNOTS;
    if (!(U[p] < U[n + 1]))
        return NF_EKNOTS;
    int mult = 1;
    for (int i = p + 1; i <= n; i++) { /* interior knots U[p+1..n] */
        mult = (U[i] == U[i - 1] && i - 1 > p) ? mult + 1 : 1;
        if (U[i] == U[p] || U[i] == U[n + 1] || mult > p)
            return NF_EKNOTS;
    }
    return NF_OK;
}
