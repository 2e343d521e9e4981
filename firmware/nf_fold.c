/* SPDX-License-Identifier: MIT */
/* nf_fold.c: hodograph bounds against folds (nf_fold.h). */
#include "nf_fold.h"

#include <math.h>

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Bounds of a hodograph control point d (already scaled) on the axes:
 * lo of its e-coordinate, the largest |.| of its f-coordinate. */
static void bound(const double *d, const double *e, const double *f, double *lo, double *fmx)
{
    const double x = dot3(d, e), y = fabs(dot3(d, f));
    *lo = x < *lo ? x : *lo;
    *fmx = y > *fmx ? y : *fmx;
}

int nf_fold_free(const nf_surf_t *s)
{
    const int p = s->p, q = s->q;
    const long nu = s->nu, nv = s->nv;
    if (p < 1 || q < 1 || nu < 2 || nv < 2)
        return 0;
    if (s->w)
        for (long k = 1; k < nu * nv; k++)
            if (s->w[k] != s->w[0])
                return 0; /* rational: the hodographs are not these */
    const double *P = s->cp;
    /* The plane: the net's summed edges in u and in v span it. */
    double A[3] = {0, 0, 0}, B[3] = {0, 0, 0}, N[3], e1[3], e2[3];
    for (long j = 0; j < nv; j++)
        for (int c = 0; c < 3; c++)
            A[c] += P[3 * (nu - 1 + j * nu) + c] - P[3 * (j * nu) + c];
    for (long i = 0; i < nu; i++)
        for (int c = 0; c < 3; c++)
            B[c] += P[3 * (i + (nv - 1) * nu) + c] - P[3 * i + c];
    cross3(A, B, N);
    const double nn = sqrt(dot3(N, N));
    if (!(nn > 0.0 && nn < INFINITY))
        return 0;
    for (int c = 0; c < 3; c++)
        N[c] /= nn;
    const double an = dot3(A, N);
    for (int c = 0; c < 3; c++)
        e1[c] = A[c] - an * N[c];
    const double el = sqrt(dot3(e1, e1));
    if (!(el > 0.0))
        return 0;
    for (int c = 0; c < 3; c++)
        e1[c] /= el;
    cross3(N, e1, e2);
    const double *U = s->U, *V = s->V;
    for (long k = q; k < nv; k++) {
        if (!(V[k + 1] > V[k]))
            continue; /* an empty span */
        for (long l = p; l < nu; l++) {
            if (!(U[l + 1] > U[l]))
                continue;
            /* Su on span (l, k): control points (i, j), i = l-p .. l-1,
             * j = k-q .. k; Sv: i = l-p .. l, j = k-q .. k-1. */
            double alo = INFINITY, bmx = 0.0, dlo = INFINITY, cmx = 0.0;
            for (long j = k - q; j <= k; j++)
                for (long i = l - p; i <= l; i++) {
                    const double *Pij = P + 3 * (i + j * nu);
                    double d[3];
                    if (i < l) {
                        const double h = U[i + p + 1] - U[i + 1];
                        if (!(h > 0.0))
                            return 0;
                        for (int c = 0; c < 3; c++)
                            d[c] = p * (Pij[3 + c] - Pij[c]) / h;
                        bound(d, e1, e2, &alo, &bmx);
                    }
                    if (j < k) {
                        const double h = V[j + q + 1] - V[j + 1];
                        if (!(h > 0.0))
                            return 0;
                        for (int c = 0; c < 3; c++)
                            d[c] = q * (Pij[3 * nu + c] - Pij[c]) / h;
                        bound(d, e2, e1, &dlo, &cmx);
                    }
                }
            /* det >= alo dlo - bmx cmx for every (u, v) of the span */
            if (!(alo > 0.0 && dlo > 0.0 && alo * dlo > bmx * cmx))
                return 0;
        }
    }
    return 1;
}
