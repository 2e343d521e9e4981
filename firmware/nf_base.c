/* SPDX-License-Identifier: MIT */
/* nf_base.c: the points' plane by power iteration on their scatter matrix,
 * and the plane patch over their extent (Piegl & Tiller 2001, Section 3.2). */
#include "nf_base.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

#define POWER_MAX_ITERS 2000

void nf_base_plane_init(nf_base_plane_t *pl)
{
    memset(pl, 0, sizeof *pl);
}

int nf_base_plane_add(nf_base_plane_t *pl, const double Q[3])
{
    for (int k = 0; k < 3; k++)
        if (!(Q[k] - Q[k] == 0.0))
            return NF_ENONFINITE;
    if (pl->n == 0)
        memcpy(pl->o, Q, sizeof pl->o);
    double d[3] = {Q[0] - pl->o[0], Q[1] - pl->o[1], Q[2] - pl->o[2]};
    for (int k = 0; k < 3; k++)
        pl->s1[k] += d[k];
    pl->s2[0] += d[0] * d[0];
    pl->s2[1] += d[0] * d[1];
    pl->s2[2] += d[0] * d[2];
    pl->s2[3] += d[1] * d[1];
    pl->s2[4] += d[1] * d[2];
    pl->s2[5] += d[2] * d[2];
    pl->n++;
    return NF_OK;
}

static void mul(const double M[6], const double x[3], double y[3])
{
    y[0] = M[0] * x[0] + M[1] * x[1] + M[2] * x[2];
    y[1] = M[1] * x[0] + M[3] * x[1] + M[4] * x[2];
    y[2] = M[2] * x[0] + M[4] * x[1] + M[5] * x[2];
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static int normalise(double x[3])
{
    double n = sqrt(dot(x, x));
    if (!(n > 0.0))
        return -1;
    for (int k = 0; k < 3; k++)
        x[k] /= n;
    return 0;
}

/* Orthonormal pair from y1, y2 (Gram-Schmidt, twice for accuracy); -1
 * when y2 is (numerically) parallel to y1: what is left of it would be
 * rounding noise, whose direction means nothing. */
static int orth(double y1[3], double y2[3])
{
    double n2 = sqrt(dot(y2, y2));
    if (normalise(y1))
        return -1;
    for (int pass = 0; pass < 2; pass++) {
        double d = dot(y1, y2);
        for (int k = 0; k < 3; k++)
            y2[k] -= d * y1[k];
    }
    if (!(sqrt(dot(y2, y2)) > 1e-12 * n2))
        return -1;
    return normalise(y2);
}

/* Subspace iteration from the pair x1, x2; returns iterations, the trace
 * of the Ritz matrix in *tr. */
static int power_pair(const double M[6], double x1[3], double x2[3], double *tr)
{
    double nrm[3], prev[3] = {0, 0, 0};
    int it = 0;
    orth(x1, x2);
    while (it < POWER_MAX_ITERS) {
        double y1[3], y2[3];
        mul(M, x1, y1);
        mul(M, x2, y2);
        it++;
        if (orth(y1, y2))
            break; /* rank < 2 on this start: keep the last pair */
        memcpy(x1, y1, sizeof y1);
        memcpy(x2, y2, sizeof y2);
        cross(x1, x2, nrm);
        if (dot(nrm, prev) < 0)
            for (int k = 0; k < 3; k++)
                nrm[k] = -nrm[k];
        double ch = fabs(nrm[0] - prev[0]) + fabs(nrm[1] - prev[1]) + fabs(nrm[2] - prev[2]);
        memcpy(prev, nrm, sizeof prev);
        if (ch < 1e-16)
            break;
    }
    double y[3];
    mul(M, x1, y);
    *tr = dot(x1, y);
    mul(M, x2, y);
    *tr += dot(x2, y);
    return it;
}

int nf_base_power(const double M0[6], double e[3][3], double lam[3])
{
    double M[6], s = 0.0;
    for (int k = 0; k < 6; k++)
        s = fmax(s, fabs(M0[k]));
    for (int k = 0; k < 6; k++)
        M[k] = s > 0 ? M0[k] / s : 0.0;
    static const double st[3][2][3] = {
        {{1, 1, 1}, {1, -1, 0}}, {{1, 0, 0}, {0, 1, 0}}, {{0, 1, 0}, {0, 0, 1}}};
    double best = -1.0, b1[3] = {1, 0, 0}, b2[3] = {0, 1, 0};
    int iters = 0;
    for (int t = 0; t < 3; t++) {
        double x1[3], x2[3], tr;
        memcpy(x1, st[t][0], sizeof x1);
        memcpy(x2, st[t][1], sizeof x2);
        iters += power_pair(M, x1, x2, &tr);
        if (tr > best * (1 + 1e-14)) {
            best = tr;
            memcpy(b1, x1, sizeof b1);
            memcpy(b2, x2, sizeof b2);
        }
    }
    /* Rayleigh-Ritz on the pair: the 2 x 2 [a b; b c] diagonalised. */
    double y1[3], y2[3];
    mul(M, b1, y1);
    mul(M, b2, y2);
    double a = dot(b1, y1), b = dot(b1, y2), c = dot(b2, y2);
    double th = 0.5 * atan2(2 * b, a - c), cs = cos(th), sn = sin(th);
    for (int k = 0; k < 3; k++) {
        e[0][k] = cs * b1[k] + sn * b2[k];
        e[1][k] = -sn * b1[k] + cs * b2[k];
    }
    orth(e[0], e[1]);
    cross(e[0], e[1], e[2]);
    normalise(e[2]);
    for (int r = 0; r < 3; r++) {
        double y[3];
        mul(M, e[r], y);
        lam[r] = dot(e[r], y) * s;
    }
    if (lam[1] > lam[0]) { /* atan2 picked the other branch */
        double t[3];
        memcpy(t, e[0], sizeof t);
        memcpy(e[0], e[1], sizeof t);
        memcpy(e[1], t, sizeof t);
        for (int k = 0; k < 3; k++)
            e[1][k] = -e[1][k]; /* keep e[0] x e[1] = e[2] */
        double l = lam[0];
        lam[0] = lam[1];
        lam[1] = l;
    }
    return iters;
}

/* Turn k of the axes: the angle, -45 degrees + 90 k / NF_BASE_ANGLES. */
static double turn(int k)
{
    return (-0.25 + 0.5 * k / NF_BASE_ANGLES) * 3.14159265358979323846;
}

int nf_base_plane_axes(nf_base_plane_t *pl)
{
    if (pl->n < 3)
        return NF_ENODATA;
    const double n = (double)pl->n, *s1 = pl->s1;
    double M[6] = {pl->s2[0] - s1[0] * s1[0] / n, pl->s2[1] - s1[0] * s1[1] / n,
                   pl->s2[2] - s1[0] * s1[2] / n, pl->s2[3] - s1[1] * s1[1] / n,
                   pl->s2[4] - s1[1] * s1[2] / n, pl->s2[5] - s1[2] * s1[2] / n};
    for (int k = 0; k < 3; k++)
        pl->c[k] = pl->o[k] + s1[k] / n;
    pl->iters = nf_base_power(M, pl->e, pl->lam);
    for (int k = 0; k < 3; k++)
        pl->lam[k] /= n;
    if (!(pl->lam[1] > 1e-12 * pl->lam[0]))
        return NF_ESINGULAR;
    /* Deterministic orientation: e[0]'s largest component positive, the
     * normal towards +z (a part measured from above). */
    int big = 0;
    for (int k = 1; k < 3; k++)
        big = fabs(pl->e[0][k]) > fabs(pl->e[0][big]) ? k : big;
    if (pl->e[0][big] < 0)
        for (int k = 0; k < 3; k++)
            pl->e[0][k] = -pl->e[0][k], pl->e[2][k] = -pl->e[2][k];
    if (pl->e[2][2] < 0)
        for (int k = 0; k < 3; k++)
            pl->e[1][k] = -pl->e[1][k], pl->e[2][k] = -pl->e[2][k];
    for (int k = 0; k < NF_BASE_ANGLES; k++) {
        pl->rcs[k][0] = cos(turn(k));
        pl->rcs[k][1] = sin(turn(k));
    }
    pl->next = 0;
    return NF_OK;
}

void nf_base_plane_extent(nf_base_plane_t *pl, const double Q[3])
{
    double d[3] = {Q[0] - pl->c[0], Q[1] - pl->c[1], Q[2] - pl->c[2]};
    double x[2];
    for (int a = 0; a < 2; a++) {
        x[a] = dot(d, pl->e[a]);
        if (pl->next == 0 || x[a] < pl->lo[a])
            pl->lo[a] = x[a];
        if (pl->next == 0 || x[a] > pl->hi[a])
            pl->hi[a] = x[a];
    }
    for (int k = 0; k < NF_BASE_ANGLES; k++) {
        double c = pl->rcs[k][0], s = pl->rcs[k][1];
        double r[2] = {c * x[0] + s * x[1], -s * x[0] + c * x[1]};
        for (int a = 0; a < 2; a++) {
            if (pl->next == 0 || r[a] < pl->rlo[k][a])
                pl->rlo[k][a] = r[a];
            if (pl->next == 0 || r[a] > pl->rhi[k][a])
                pl->rhi[k][a] = r[a];
        }
    }
    pl->next++;
}

static void uniform_knots(double *U, int n, int p)
{
    for (int i = 0; i <= p; i++) {
        U[i] = 0.0;
        U[n + i] = 1.0;
    }
    for (int i = p + 1; i < n; i++)
        U[i] = (double)(i - p) / (n - p);
}

int nf_base_plane_patch(const nf_base_plane_t *pl, double margin, nf_surf_t *out)
{
    if (!out || !out->U || !out->V || !out->cp || out->p < 1 || out->q < 1 ||
        out->nu < out->p + 1 || out->nv < out->q + 1 || !(margin >= 0))
        return NF_EARG;
    if (pl->next < 1)
        return NF_ENODATA;
    uniform_knots(out->U, out->nu, out->p);
    uniform_knots(out->V, out->nv, out->q);
    /* The smallest rectangle of the turns; the axes' own unless one is 3 %
     * smaller, so that a footprint the axes fit keeps them exactly. */
    double area0 = (pl->hi[0] - pl->lo[0]) * (pl->hi[1] - pl->lo[1]), best = area0;
    int kb = -1;
    for (int k = 0; k < NF_BASE_ANGLES; k++) {
        double area = (pl->rhi[k][0] - pl->rlo[k][0]) * (pl->rhi[k][1] - pl->rlo[k][1]);
        if (area < 0.97 * area0 && area < best)
            best = area, kb = k;
    }
    double e[2][3], lo[2], hi[2];
    const double c = kb < 0 ? 1.0 : pl->rcs[kb][0], s = kb < 0 ? 0.0 : pl->rcs[kb][1];
    for (int k = 0; k < 3; k++) {
        e[0][k] = c * pl->e[0][k] + s * pl->e[1][k];
        e[1][k] = -s * pl->e[0][k] + c * pl->e[1][k];
    }
    for (int a = 0; a < 2; a++) {
        double l = kb < 0 ? pl->lo[a] : pl->rlo[kb][a], h = kb < 0 ? pl->hi[a] : pl->rhi[kb][a];
        double w = h - l;
        lo[a] = l - margin * w;
        hi[a] = h + margin * w;
    }
    /* Greville placement: sum_i N_i(u) g_i = u, so S is affine in (u, v). */
    for (int j = 0; j < out->nv; j++) {
        double y = lo[1] + (hi[1] - lo[1]) * nf_greville(j, out->q, out->V);
        for (int i = 0; i < out->nu; i++) {
            double x = lo[0] + (hi[0] - lo[0]) * nf_greville(i, out->p, out->U);
            double *P = out->cp + 3 * (i + (long)j * out->nu);
            for (int k = 0; k < 3; k++)
                P[k] = pl->c[k] + x * e[0][k] + y * e[1][k];
            if (out->w)
                out->w[i + (long)j * out->nu] = 1.0;
        }
    }
    return NF_OK;
}
