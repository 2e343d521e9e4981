/* SPDX-License-Identifier: MIT */
/* ref_dense.c: dense, naive reference computations for the tests. */
#include "ref_dense.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

static unsigned long long rng = 88172645463325252ull;

void ref_seed(unsigned long long s)
{
    rng = s ? s : 1;
}

double ref_rand(double lo, double hi)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return lo + (hi - lo) * (double)(rng >> 11) / 9007199254740992.0;
}

double ref_bspline(int i, int p, const double *U, int nknots, double u)
{
    if (p == 0) {
        if (U[i] <= u && u < U[i + 1])
            return 1.0;
        /* Right end: the last non-empty interval includes its end point. */
        if (u == U[nknots - 1] && U[i] < U[i + 1] && U[i + 1] == U[nknots - 1])
            return 1.0;
        return 0.0;
    }
    double a = 0.0, b = 0.0;
    if (U[i + p] != U[i])
        a = (u - U[i]) / (U[i + p] - U[i]) * ref_bspline(i, p - 1, U, nknots, u);
    if (U[i + p + 1] != U[i + 1])
        b = (U[i + p + 1] - u) / (U[i + p + 1] - U[i + 1]) *
            ref_bspline(i + 1, p - 1, U, nknots, u);
    return a + b;
}

void ref_rbasis_row(const nf_surf_t *s, double u, double v, double *out)
{
    const long n = (long)s->nu * s->nv;
    double W = 0.0;
    for (int j = 0; j < s->nv; j++) {
        double nj = ref_bspline(j, s->q, s->V, s->nv + s->q + 1, v);
        for (int i = 0; i < s->nu; i++) {
            double ni = ref_bspline(i, s->p, s->U, s->nu + s->p + 1, u);
            long idx = i + (long)j * s->nu;
            out[idx] = ni * nj * (s->w ? s->w[idx] : 1.0);
            W += out[idx];
        }
    }
    for (long k = 0; k < n; k++)
        out[k] /= W;
}

void ref_eq7(const nf_surf_t *s, const double *pts, long M, double alpha, double beta,
             double **Aout, double **bout)
{
    const long n = (long)s->nu * s->nv;
    double *A = calloc((size_t)(n * n), sizeof *A);
    double *b = calloc((size_t)(3 * n), sizeof *b);
    double *row = calloc((size_t)n, sizeof *row);
    for (long k = 0; k < M; k++) { /* R^T R and R^T Q, term by term */
        const double *q = pts + 5 * k;
        ref_rbasis_row(s, q[0], q[1], row);
        for (long i = 0; i < n; i++) {
            if (row[i] == 0.0)
                continue;
            for (long j = 0; j < n; j++)
                A[i * n + j] += row[i] * row[j];
            for (int c = 0; c < 3; c++)
                b[3 * i + c] += row[i] * q[2 + c];
        }
    }
    if (alpha > 0.0) { /* (B - I)^T (B - I), B at the Greville points */
        double *B = calloc((size_t)(n * n), sizeof *B);
        for (int j = 0; j < s->nv; j++)
            for (int i = 0; i < s->nu; i++) {
                double ug = 0.0, vg = 0.0;
                for (int t = 1; t <= s->p; t++)
                    ug += s->U[i + t];
                for (int t = 1; t <= s->q; t++)
                    vg += s->V[j + t];
                long r = i + (long)j * s->nu;
                ref_rbasis_row(s, ug / s->p, vg / s->q, B + r * n);
                B[r * n + r] -= 1.0;
            }
        for (long i = 0; i < n; i++)
            for (long j = 0; j < n; j++) {
                double acc = 0.0;
                for (long r = 0; r < n; r++)
                    acc += B[r * n + i] * B[r * n + j];
                A[i * n + j] += alpha * acc;
            }
        free(B);
    }
    for (long i = 0; i < n; i++) {
        A[i * n + i] += beta;
        for (int c = 0; c < 3; c++)
            b[3 * i + c] += beta * s->cp[3 * i + c];
    }
    free(row);
    *Aout = A;
    *bout = b;
}

int ref_solve(const double *A0, const double *b0, long n, double *x)
{
    double *A = malloc(sizeof(double) * (size_t)(n * n));
    memcpy(A, A0, sizeof(double) * (size_t)(n * n));
    memcpy(x, b0, sizeof(double) * (size_t)(3 * n));
    for (long k = 0; k < n; k++) {
        long piv = k;
        for (long i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[piv * n + k]))
                piv = i;
        if (A[piv * n + k] == 0.0) {
            free(A);
            return -1;
        }
        if (piv != k) {
            for (long j = 0; j < n; j++) {
                double t = A[k * n + j];
                A[k * n + j] = A[piv * n + j];
                A[piv * n + j] = t;
            }
            for (int c = 0; c < 3; c++) {
                double t = x[3 * k + c];
                x[3 * k + c] = x[3 * piv + c];
                x[3 * piv + c] = t;
            }
        }
        for (long i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            if (f == 0.0)
                continue;
            for (long j = k; j < n; j++)
                A[i * n + j] -= f * A[k * n + j];
            for (int c = 0; c < 3; c++)
                x[3 * i + c] -= f * x[3 * k + c];
        }
    }
    for (long i = n - 1; i >= 0; i--)
        for (int c = 0; c < 3; c++) {
            double s = x[3 * i + c];
            for (long j = i + 1; j < n; j++)
                s -= A[i * n + j] * x[3 * j + c];
            x[3 * i + c] = s / A[i * n + i];
        }
    free(A);
    return 0;
}

static void random_knots(double *U, int n, int p, double a, double b)
{
    /* n+1 control points: n-p interior knots, spaced unevenly. */
    int m = n + p + 1;
    for (int i = 0; i <= p; i++) {
        U[i] = a;
        U[m - i] = b;
    }
    int ni = n - p;
    double acc = 0.0, *gap = malloc(sizeof(double) * (size_t)(ni + 1));
    for (int i = 0; i <= ni; i++) {
        gap[i] = ref_rand(0.5, 1.5);
        acc += gap[i];
    }
    double t = 0.0;
    for (int i = 1; i <= ni; i++) {
        t += gap[i - 1];
        U[p + i] = a + (b - a) * t / acc;
    }
    free(gap);
}

void ref_surf_random(nf_surf_t *s, int p, int q, int nu, int nv, double u0, double u1, double v0,
                     double v1, double wlo, double whi)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, p, q), sizeof(double));
    nf_surf_wire(s, p, q, nu, nv, mem);
    random_knots(s->U, nu - 1, p, u0, u1);
    random_knots(s->V, nv - 1, q, v0, v1);
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            long k = i + (long)j * nu;
            s->cp[3 * k] = 10.0 * i + ref_rand(-2, 2);
            s->cp[3 * k + 1] = 10.0 * j + ref_rand(-2, 2);
            s->cp[3 * k + 2] = ref_rand(-5, 5);
            s->w[k] = wlo < whi ? ref_rand(wlo, whi) : 1.0;
        }
}

void ref_surf_free(nf_surf_t *s)
{
    free(s->U);
    s->U = NULL;
}
