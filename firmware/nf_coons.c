/* SPDX-License-Identifier: MIT */
/* nf_coons.c: four boundary curves made compatible, and the bilinearly
 * blended Coons patch as an exact NURBS surface (Piegl & Tiller 2001,
 * Section 2.1; The NURBS Book 10.5). */
#include "nf_coons.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

#define KNOT_EPS 1e-12 /* knots of a pair closer than this (domain [0, 1]) are one knot */

const char *nf_coons_strerror(int err)
{
    switch (err) {
    case NF_COONS_ECORNER: return "boundary curves do not meet at a corner";
    case NF_COONS_EWEIGHTS:
        return "rational boundary curves: end weights cannot be made to agree at the corners";
    case NF_COONS_ERATIONAL: return "bicubic Coons needs polynomial (non-rational) boundary curves";
    case NF_COONS_EWORK: return "storage given is smaller than the Coons construction needs";
    default: return nf_strerror(err);
    }
}

static int imax(int a, int b)
{
    return a > b ? a : b;
}

long nf_coons_doubles(const nf_curve_t in[4], int pmin)
{
    int P = pmin;
    for (int k = 0; k < 4; k++) {
        int rc = nf_curve_check(&in[k]);
        if (rc)
            return rc;
        P = imax(P, in[k].p);
    }
    if (P > NF_MAX_DEGREE)
        return NF_EDEGREE;
    long tot = 0, esum = 0;
    for (int k = 0; k < 4; k++) {
        long e = in[k].n + (long)(P - in[k].p) * (in[k].n - in[k].p);
        tot += NF_CURVE_DOUBLES(in[k].n, in[k].p) + NF_CURVE_DOUBLES(e, P);
        esum += e;
    }
    return tot + 4 * NF_CURVE_DOUBLES(esum, P) + 2 * esum;
}

static void endpt(const nf_curve_t *c, int end, double P[3])
{
    const double *q = c->cp + (end ? 3L * (c->n - 1) : 0);
    P[0] = q[0];
    P[1] = q[1];
    P[2] = q[2];
}

static double dist3(const double a[3], const double b[3])
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* The curve among the unused ones with an end nearest X: index, which end. */
static int nearest_end(const nf_curve_t in[4], const int *used, const double X[3], int *end,
                       double *d)
{
    int best = -1;
    *d = HUGE_VAL;
    for (int k = 0; k < 4; k++) {
        if (used[k])
            continue;
        for (int e = 0; e < 2; e++) {
            double P[3];
            endpt(&in[k], e, P);
            double dd = dist3(P, X);
            if (dd < *d) {
                *d = dd;
                best = k;
                *end = e;
            }
        }
    }
    return best;
}

/* C0 is in[0]; D0 starts at C0's start, D1 at C0's end; C1 joins their ends. */
static int orient(nf_coons_t *cs, const nf_curve_t in[4], double tol)
{
    int used[4] = {1, 0, 0, 0}, end = 0;
    double a[3], b[3], d;
    cs->from[0] = 0;
    cs->rev[0] = 0;
    cs->gap = 0.0;
    endpt(&in[0], 0, a);
    endpt(&in[0], 1, b);
    static const int slot[2] = {2, 3};
    const double *X[2] = {a, b};
    static const int corner_of[2] = {0, 1};
    for (int s = 0; s < 2; s++) {
        int k = nearest_end(in, used, X[s], &end, &d);
        cs->gap = d > cs->gap ? d : cs->gap;
        if (!(d <= tol)) {
            cs->corner = corner_of[s];
            return NF_COONS_ECORNER;
        }
        used[k] = 1;
        cs->from[slot[s]] = k;
        cs->rev[slot[s]] = end; /* starts at the corner when its start is there */
    }
    int k = 1;
    while (used[k])
        k++;
    cs->from[1] = k;
    double d0e[3], d1e[3], c1s[3], c1e[3];
    const nf_curve_t *D0 = &in[cs->from[2]], *D1 = &in[cs->from[3]];
    endpt(D0, !cs->rev[2], d0e);
    endpt(D1, !cs->rev[3], d1e);
    endpt(&in[k], 0, c1s);
    endpt(&in[k], 1, c1e);
    int r = dist3(c1e, d0e) + dist3(c1s, d1e) < dist3(c1s, d0e) + dist3(c1e, d1e);
    cs->rev[1] = r;
    double g0 = r ? dist3(c1e, d0e) : dist3(c1s, d0e), g1 = r ? dist3(c1s, d1e) : dist3(c1e, d1e);
    cs->gap = fmax(cs->gap, fmax(g0, g1));
    if (!(g0 <= tol) || !(g1 <= tol)) {
        cs->corner = !(g0 <= tol) ? 2 : 3;
        return NF_COONS_ECORNER;
    }
    return NF_OK;
}

/* Knots to insert into a and into b (same degree, both on [0, 1]) so that
 * their knot vectors agree; NULL outputs only count. */
static void merge_plan(const nf_curve_t *a, const nf_curve_t *b, double *Xa, int *ra, double *Xb,
                       int *rb)
{
    const int p = a->p;
    int ia = p + 1, ea = a->n, eb = b->n; /* interior knots [p+1, n) */
    int ib = ia;
    *ra = *rb = 0;
    while (ia < ea || ib < eb) {
        double va = ia < ea ? a->U[ia] : HUGE_VAL, vb = ib < eb ? b->U[ib] : HUGE_VAL;
        double v = va < vb ? va : vb;
        int ma = 0, mb = 0;
        while (ia < ea && fabs(a->U[ia] - v) <= KNOT_EPS)
            ia++, ma++;
        while (ib < eb && fabs(b->U[ib] - v) <= KNOT_EPS)
            ib++, mb++;
        int m = imax(ma, mb);
        double xa = mb ? b->U[ib - 1] : v, xb = ma ? a->U[ia - 1] : v;
        for (int t = ma; t < m; t++, (*ra)++)
            if (Xa)
                Xa[*ra] = xa;
        for (int t = mb; t < m; t++, (*rb)++)
            if (Xb)
                Xb[*rb] = xb;
    }
}

/* Carve n doubles off the work area. */
static double *take(double **mem, long *left, long n)
{
    if (n > *left)
        return NULL;
    double *r = *mem;
    *mem += n;
    *left -= n;
    return r;
}

/* Elevate a and b to degree P and merge their knots into oa and ob. */
static int pair_compat(const nf_curve_t *a, const nf_curve_t *b, int P, nf_curve_t *oa,
                       nf_curve_t *ob, double **mem, long *left)
{
    nf_curve_t e[2];
    const nf_curve_t *src[2] = {a, b};
    for (int k = 0; k < 2; k++) {
        int n = nf_curve_elevate_size(src[k], P - src[k]->p);
        double *m = take(mem, left, NF_CURVE_DOUBLES(n, P));
        if (!m)
            return NF_COONS_EWORK;
        nf_curve_wire(&e[k], P, n, m);
        int rc = nf_curve_elevate(src[k], P - src[k]->p, &e[k]);
        if (rc)
            return rc;
    }
    int ra, rb;
    merge_plan(&e[0], &e[1], NULL, &ra, NULL, &rb);
    double *Xa = take(mem, left, ra + 1), *Xb = take(mem, left, rb + 1);
    double *ma = take(mem, left, NF_CURVE_DOUBLES(e[0].n + ra, P));
    double *mb = take(mem, left, NF_CURVE_DOUBLES(e[1].n + rb, P));
    if (!Xa || !Xb || !ma || !mb)
        return NF_COONS_EWORK;
    merge_plan(&e[0], &e[1], Xa, &ra, Xb, &rb);
    nf_curve_wire(oa, P, e[0].n + ra, ma);
    nf_curve_wire(ob, P, e[1].n + rb, mb);
    int rc = nf_curve_refine(&e[0], Xa, ra, oa);
    if (!rc)
        rc = nf_curve_refine(&e[1], Xb, rb, ob);
    if (rc)
        return rc;
    if (oa->n != ob->n)
        return NF_EKNOTS; /* cannot happen: the plan equalises the knot vectors */
    memcpy(ob->U, oa->U, sizeof(double) * (size_t)(oa->n + P + 1)); /* snap within KNOT_EPS */
    return NF_OK;
}

/* Homogeneous end weight of c at its start (end 0) or end (1). */
static double endw(const nf_curve_t *c, int end)
{
    return c->w[end ? c->n - 1 : 0];
}

/* Scale weights so each corner's two curves carry the same weight there
 * (a curve is unchanged by a common factor): C0 sets D0's and D1's, D0's
 * end sets C1's; the fourth corner must then agree by itself. */
static int match_weights(nf_curve_t *c)
{
    nf_curve_scale_weights(&c[2], endw(&c[0], 0) / endw(&c[2], 0));
    nf_curve_scale_weights(&c[3], endw(&c[0], 1) / endw(&c[3], 0));
    nf_curve_scale_weights(&c[1], endw(&c[2], 1) / endw(&c[1], 0));
    double w1 = endw(&c[1], 1), w3 = endw(&c[3], 1);
    if (fabs(w1 - w3) > 1e-12 * fmax(w1, w3))
        return NF_COONS_EWEIGHTS;
    c[3].w[c[3].n - 1] = w1;
    return NF_OK;
}

/* Move the curves' end points onto the corners of C0 and C1 exactly. */
static void snap_corners(nf_coons_t *cs)
{
    nf_curve_t *c = cs->c;
    const double *P00 = c[0].cp, *P10 = c[0].cp + 3L * (c[0].n - 1);
    const double *P01 = c[1].cp, *P11 = c[1].cp + 3L * (c[1].n - 1);
    memcpy(c[2].cp, P00, 3 * sizeof(double));
    memcpy(c[2].cp + 3L * (c[2].n - 1), P01, 3 * sizeof(double));
    memcpy(c[3].cp, P10, 3 * sizeof(double));
    memcpy(c[3].cp + 3L * (c[3].n - 1), P11, 3 * sizeof(double));
    c[2].w[0] = c[0].w[0];
    c[2].w[c[2].n - 1] = c[1].w[0];
    c[3].w[0] = c[0].w[c[0].n - 1];
    c[3].w[c[3].n - 1] = c[1].w[c[1].n - 1];
}

int nf_coons_prepare(nf_coons_t *cs, const nf_curve_t in[4], int pmin, double tol, double *mem,
                     long len)
{
    if (!cs || !in || !mem || !(tol >= 0))
        return NF_EARG;
    memset(cs, 0, sizeof *cs);
    long need = nf_coons_doubles(in, pmin);
    if (need < 0)
        return (int)need;
    if (len < need)
        return NF_COONS_EWORK;
    int rc = orient(cs, in, tol);
    if (rc)
        return rc;
    nf_curve_t o[4];
    for (int k = 0; k < 4; k++) {
        const nf_curve_t *src = &in[cs->from[k]];
        nf_curve_wire(&o[k], src->p, src->n, take(&mem, &len, NF_CURVE_DOUBLES(src->n, src->p)));
        nf_curve_copy(src, &o[k]);
        if (cs->rev[k])
            nf_curve_reverse(&o[k]);
        nf_curve_reparam(&o[k], 0.0, 1.0);
    }
    if ((rc = match_weights(o)))
        return rc;
    int P = imax(pmin, imax(o[0].p, o[1].p)), Q = imax(pmin, imax(o[2].p, o[3].p));
    rc = pair_compat(&o[0], &o[1], P, &cs->c[0], &cs->c[1], &mem, &len);
    if (!rc)
        rc = pair_compat(&o[2], &o[3], Q, &cs->c[2], &cs->c[3], &mem, &len);
    if (rc)
        return rc;
    snap_corners(cs);
    return NF_OK;
}

void nf_coons_size(const nf_coons_t *cs, int *p, int *q, int *nu, int *nv)
{
    *p = cs->c[0].p;
    *q = cs->c[2].p;
    *nu = cs->c[0].n;
    *nv = cs->c[2].n;
}

static void hpt(const nf_curve_t *c, int i, double h[4])
{
    double w = c->w[i];
    h[0] = c->cp[3 * i] * w;
    h[1] = c->cp[3 * i + 1] * w;
    h[2] = c->cp[3 * i + 2] * w;
    h[3] = w;
}

int nf_coons_bilinear(const nf_coons_t *cs, nf_surf_t *out)
{
    int p, q, nu, nv;
    nf_coons_size(cs, &p, &q, &nu, &nv);
    if (!out || out->p != p || out->q != q || out->nu != nu || out->nv != nv || !out->w)
        return NF_EARG;
    const nf_curve_t *c = cs->c;
    memcpy(out->U, c[0].U, sizeof(double) * (size_t)(nu + p + 1));
    memcpy(out->V, c[2].U, sizeof(double) * (size_t)(nv + q + 1));
    /* Polynomial curves give weights 1 exactly (the blend of ones would
     * round to 1 - 2^-52 here and there, and the file would say rational). */
    int poly = 1;
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < c[k].n; i++)
            poly &= c[k].w[i] == 1.0;
    double P00[4], P10[4], P01[4], P11[4];
    hpt(&c[0], 0, P00);
    hpt(&c[0], nu - 1, P10);
    hpt(&c[1], 0, P01);
    hpt(&c[1], nu - 1, P11);
    /* Linear precision: sum_i N_i(u) g_i = u with g_i the Greville
     * abscissae, so (1 - u) A + u B has coefficients (1 - g_i) A + g_i B. */
    for (int j = 0; j < nv; j++) {
        double t = nf_greville(j, q, out->V), d0[4], d1[4];
        hpt(&c[2], j, d0);
        hpt(&c[3], j, d1);
        for (int i = 0; i < nu; i++) {
            double s = nf_greville(i, p, out->U), c0[4], c1[4], h[4];
            hpt(&c[0], i, c0);
            hpt(&c[1], i, c1);
            for (int k = 0; k < 4; k++) {
                double ru = (1 - t) * c0[k] + t * c1[k], rv = (1 - s) * d0[k] + s * d1[k];
                double tt = (1 - s) * (1 - t) * P00[k] + s * (1 - t) * P10[k] +
                            (1 - s) * t * P01[k] + s * t * P11[k];
                h[k] = ru + rv - tt;
            }
            long idx = i + (long)j * nu;
            if (poly)
                h[3] = 1.0;
            if (!(h[3] > 0.0))
                return NF_EWEIGHT;
            out->w[idx] = h[3];
            for (int k = 0; k < 3; k++)
                out->cp[3 * idx + k] = h[k] / h[3];
        }
    }
    /* Exact at the boundary rows: the formula gives them up to rounding. */
    for (int i = 0; i < nu; i++) {
        memcpy(out->cp + 3L * i, c[0].cp + 3L * i, 3 * sizeof(double));
        out->w[i] = c[0].w[i];
        memcpy(out->cp + 3 * (i + (long)(nv - 1) * nu), c[1].cp + 3L * i, 3 * sizeof(double));
        out->w[i + (long)(nv - 1) * nu] = c[1].w[i];
    }
    for (int j = 0; j < nv; j++) {
        memcpy(out->cp + 3L * j * nu, c[2].cp + 3L * j, 3 * sizeof(double));
        out->w[(long)j * nu] = c[2].w[j];
        memcpy(out->cp + 3 * ((long)j * nu + nu - 1), c[3].cp + 3L * j, 3 * sizeof(double));
        out->w[(long)j * nu + nu - 1] = c[3].w[j];
    }
    return NF_OK;
}
