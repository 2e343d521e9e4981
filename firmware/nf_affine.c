/* SPDX-License-Identifier: MIT */
/* nf_affine.c: closed-form projection onto an affine surface (nf_affine.h). */
#include "nf_affine.h"
#include "nf_vec3.h"

#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>

int nf_affine_init(nf_affine_t *a, const nf_surf_t *s)
{
    a->ok = 0;
    const long nu = s->nu, nv = s->nv, n = nu * nv;
    if (nu < 2 || nv < 2)
        return 0;
    if (s->w)
        for (long k = 1; k < n; k++)
            if (s->w[k] != s->w[0])
                return 0; /* rational: not affine in (u, v) */
    const double g0 = nf_greville(0, s->p, s->U), g1 = nf_greville((int)nu - 1, s->p, s->U);
    const double h0 = nf_greville(0, s->q, s->V), h1 = nf_greville((int)nv - 1, s->q, s->V);
    if (!(g1 > g0 && h1 > h0))
        return 0;
    const double *P = s->cp, *Pu = s->cp + 3 * (nu - 1), *Pv = s->cp + 3 * (n - nu);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (long k = 0; k < n; k++)
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], P[3 * k + c]);
            hi[c] = fmax(hi[c], P[3 * k + c]);
        }
    const double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!(ext > 0.0 && ext < INFINITY))
        return 0;
    for (int c = 0; c < 3; c++) {
        a->A[c] = (Pu[c] - P[c]) / (g1 - g0);
        a->B[c] = (Pv[c] - P[c]) / (h1 - h0);
        a->O[c] = P[c] - g0 * a->A[c] - h0 * a->B[c];
    }
    /* Every control point on the map at its Greville point (linear
     * precision then makes S the map itself). */
    const double tol = NF_AFFINE_REL_TOL * ext;
    for (long j = 0; j < nv; j++) {
        const double h = nf_greville((int)j, s->q, s->V);
        for (long i = 0; i < nu; i++) {
            const double g = nf_greville((int)i, s->p, s->U);
            const double *Pij = P + 3 * (i + j * nu);
            for (int c = 0; c < 3; c++)
                if (!(fabs(Pij[c] - (a->O[c] + g * a->A[c] + h * a->B[c])) <= tol))
                    return 0;
        }
    }
    a->gaa = nf_dot3(a->A, a->A);
    a->gab = nf_dot3(a->A, a->B);
    a->gbb = nf_dot3(a->B, a->B);
    a->det = a->gaa * a->gbb - a->gab * a->gab;
    /* A and B nearly parallel: the 2 x 2 solve loses the digits. */
    if (!(a->det > 1e-12 * a->gaa * a->gbb))
        return 0;
    const double nx[3] = {a->A[1] * a->B[2] - a->A[2] * a->B[1],
                          a->A[2] * a->B[0] - a->A[0] * a->B[2],
                          a->A[0] * a->B[1] - a->A[1] * a->B[0]};
    const double nl = sqrt(nf_dot3(nx, nx));
    for (int c = 0; c < 3; c++)
        a->n[c] = nx[c] / nl;
    nf_surf_domain(s, &a->dom[0], &a->dom[1], &a->dom[2], &a->dom[3]);
    a->ok = 1;
    return 1;
}

/* S(u, v), Q - S and |Q - S|^2. */
static double at(const nf_affine_t *a, const double Q[3], double u, double v, double S[3],
                 double d[3])
{
    for (int c = 0; c < 3; c++) {
        S[c] = a->O[c] + u * a->A[c] + v * a->B[c];
        d[c] = Q[c] - S[c];
    }
    return nf_dot3(d, d);
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

int nf_affine_project(const nf_affine_t *a, const double Q[3], nf_proj_t *out)
{
    if (!a->ok)
        return NF_EARG;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    const double r[3] = {Q[0] - a->O[0], Q[1] - a->O[1], Q[2] - a->O[2]};
    const double ra = nf_dot3(a->A, r), rb = nf_dot3(a->B, r);
    double u = (a->gbb * ra - a->gab * rb) / a->det, v = (a->gaa * rb - a->gab * ra) / a->det;
    double S[3], d[3];
    out->iters = 0;
    out->clamped = 0;
    /* A foot on an edge to rounding is inside (nf_project calls a foot
     * clamped only when the distance falls outward beyond noise). */
    const double eu = NF_AFFINE_EDGE * (a->dom[1] - a->dom[0]);
    const double ev = NF_AFFINE_EDGE * (a->dom[3] - a->dom[2]);
    if (u >= a->dom[0] - eu && u <= a->dom[1] + eu && v >= a->dom[2] - ev && v <= a->dom[3] + ev) {
        u = clampd(u, a->dom[0], a->dom[1]);
        v = clampd(v, a->dom[2], a->dom[3]);
        (void)at(a, Q, u, v, S, d);
    } else {
        /* The plane's nearest point lies outside: the distance, a convex
         * quadratic in (u, v), is least on the boundary, on one of the
         * edges, each a 1-D minimum clamped to its ends. */
        double best = INFINITY;
        for (int e = 0; e < 4; e++) {
            double ue, ve, Se[3], de[3];
            if (e < 2) {
                ue = a->dom[e];
                ve = clampd((rb - ue * a->gab) / a->gbb, a->dom[2], a->dom[3]);
            } else {
                ve = a->dom[e];
                ue = clampd((ra - ve * a->gab) / a->gaa, a->dom[0], a->dom[1]);
            }
            const double dd = at(a, Q, ue, ve, Se, de);
            if (e == 0 || dd < best) { /* the first always: an overflowed dd is inf */
                best = dd;
                u = ue;
                v = ve;
            }
        }
        (void)at(a, Q, u, v, S, d);
        out->clamped = 1;
    }
    out->u = u;
    out->v = v;
    for (int c = 0; c < 3; c++)
        out->foot[c] = S[c];
    /* |d| scaled by its largest component: no overflow for a far point */
    const double m = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
    double len = 0.0;
    if (m > 0.0) {
        const double w[3] = {d[0] / m, d[1] / m, d[2] / m};
        len = m * sqrt(nf_dot3(w, w));
    }
    out->dist = nf_dot3(d, a->n) < 0.0 ? -len : len;
    return NF_OK;
}
