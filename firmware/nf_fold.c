/* SPDX-License-Identifier: MIT */
/* nf_fold.c: hodograph bounds against folds (nf_fold.h). */
#include "nf_fold.h"
#include "nf_vec3.h"

#include <math.h>

/* Interval of a coordinate: lo, hi. */
typedef struct iv {
    double lo, hi;
} iv_t;

static void iv_take(iv_t *a, double x)
{
    a->lo = x < a->lo ? x : a->lo;
    a->hi = x > a->hi ? x : a->hi;
}

static double iv_abs(const iv_t *a)
{
    return fmax(fabs(a->lo), fabs(a->hi));
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
    /* The direction: the net's summed edges in u and in v. */
    double A[3] = {0, 0, 0}, B[3] = {0, 0, 0}, N[3], e1[3], e2[3];
    for (long j = 0; j < nv; j++)
        for (int c = 0; c < 3; c++)
            A[c] += P[3 * (nu - 1 + j * nu) + c] - P[3 * (j * nu) + c];
    for (long i = 0; i < nu; i++)
        for (int c = 0; c < 3; c++)
            B[c] += P[3 * (i + (nv - 1) * nu) + c] - P[3 * i + c];
    nf_cross3(A, B, N);
    const double nn = sqrt(nf_dot3(N, N));
    if (!(nn > 0.0 && nn < INFINITY))
        return 0;
    for (int c = 0; c < 3; c++)
        N[c] /= nn;
    const double an = nf_dot3(A, N);
    for (int c = 0; c < 3; c++)
        e1[c] = A[c] - an * N[c];
    const double el = sqrt(nf_dot3(e1, e1));
    if (!(el > 0.0))
        return 0;
    for (int c = 0; c < 3; c++)
        e1[c] /= el;
    nf_cross3(N, e1, e2);
    /* The scales, one pair for the whole domain (the proof integrates
     * across spans): F's Jacobian about the identity for a net near its
     * mean edges, the mean extent per unit of each parameter. */
    const double *U = s->U, *V = s->V;
    const double su = nf_dot3(A, e1) / ((double)nv * (U[nu] - U[p]));
    const double sv = nf_dot3(B, e2) / ((double)nu * (V[nv] - V[q]));
    if (!(su > 0.0 && sv > 0.0 && su < INFINITY && sv < INFINITY))
        return 0;
    const double ks = 1.0 / su, kt = 1.0 / sv;
    for (long k = q; k < nv; k++) {
        if (!(V[k + 1] > V[k]))
            continue; /* an empty span */
        for (long l = p; l < nu; l++) {
            if (!(U[l + 1] > U[l]))
                continue;
            /* Su on span (l, k): control points (i, j), i = l-p .. l-1,
             * j = k-q .. k; Sv: i = l-p .. l, j = k-q .. k-1; their
             * coordinates along e1 and e2, scaled. */
            iv_t a = {INFINITY, -INFINITY}, b = a, c = a, d = a;
            for (long j = k - q; j <= k; j++)
                for (long i = l - p; i <= l; i++) {
                    const double *Pij = P + 3 * (i + j * nu);
                    double h3[3];
                    if (i < l) {
                        const double h = U[i + p + 1] - U[i + 1];
                        if (!(h > 0.0))
                            return 0;
                        for (int m = 0; m < 3; m++)
                            h3[m] = p * (Pij[3 + m] - Pij[m]) / h * ks;
                        iv_take(&a, nf_dot3(h3, e1));
                        iv_take(&b, nf_dot3(h3, e2));
                    }
                    if (j < k) {
                        const double h = V[j + q + 1] - V[j + 1];
                        if (!(h > 0.0))
                            return 0;
                        for (int m = 0; m < 3; m++)
                            h3[m] = q * (Pij[3 * nu + m] - Pij[m]) / h * kt;
                        iv_take(&c, nf_dot3(h3, e1));
                        iv_take(&d, nf_dot3(h3, e2));
                    }
                }
            /* J = [a c; b d]: x^T J x = a x1^2 + (b + c) x1 x2 + d x2^2 > 0
             * for x != 0 when a, d > 0 and (b + c)^2 < 4 a d, on the whole
             * span when it holds for the bounds. */
            const double bc = iv_abs(&b) + iv_abs(&c);
            if (!(a.lo > 0.0 && d.lo > 0.0 && bc * bc < 4.0 * a.lo * d.lo))
                return 0;
        }
    }
    return 1;
}
