/* SPDX-License-Identifier: MIT */
/* nf_coons3.c: the bicubically blended Coons patch of Piegl & Tiller (2001,
 * Section 2.2): cross-boundary derivative curves fitted to points, twist
 * compatibility at the corners, derivative scaling, and the patch as an
 * exact NURBS surface. Domain [0, 1]^2, so du = dv = 1 in the paper's
 * Hermite forms. */
#include "nf_basis.h"
#include "nf_coons.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

/* Cubic Hermite basis on [0, 1] (the paper's H1..H4). */
static void hermite(double t, double H[4])
{
    double t2 = t * t, t3 = t2 * t;
    H[0] = 1 - 3 * t2 + 2 * t3;
    H[1] = 3 * t2 - 2 * t3;
    H[2] = t - 2 * t2 + t3;
    H[3] = -t2 + t3;
}

int nf_coons3_unknowns(const nf_coons_t *cs)
{
    return 4 + 2 * (cs->c[0].n - 4) + 2 * (cs->c[2].n - 4);
}

static int is_poly(const nf_curve_t *c)
{
    for (int i = 1; i < c->n; i++)
        if (c->w[i] != c->w[0])
            return 0;
    return 1;
}

int nf_coons3_init(nf_coons3_t *b, const nf_coons_t *cs, double *mem, long len)
{
    if (!b || !cs || !mem)
        return NF_EARG;
    memset(b, 0, sizeof *b);
    for (int k = 0; k < 4; k++)
        if (!is_poly(&cs->c[k]))
            return NF_COONS_ERATIONAL;
    if (cs->c[0].p < 3 || cs->c[2].p < 3)
        return NF_EDEGREE;
    const int nu = cs->c[0].n, nv = cs->c[2].n, K = nf_coons3_unknowns(cs);
    if (len < NF_COONS3_DOUBLES(K, nu, nv))
        return NF_COONS_EWORK;
    memset(mem, 0, sizeof(double) * (size_t)NF_COONS3_DOUBLES(K, nu, nv));
    b->cs = cs;
    b->K = K;
    b->A = mem;
    b->rhs = b->A + (long)K * K;
    b->e0 = b->rhs + 3L * K;
    b->e1 = b->e0 + 3L * nu;
    b->f0 = b->e1 + 3L * nu;
    b->f1 = b->f0 + 3L * nv;
    b->tw = b->f1 + 3L * nv;
    for (int k = 0; k < 4; k++)
        b->s[k] = 1.0;
    /* Fixed ends (compatibility with the boundary tangents): dS/dv along
     * C0 starts with D0'(0) and ends with D1'(0), and so on; with zero
     * twists the second vectors equal the first. */
    const nf_curve_t *c = cs->c;
    double d[9];
    double *ends[4][2] = {{b->e0, b->e0 + 3L * (nu - 1)},
                          {b->e1, b->e1 + 3L * (nu - 1)},
                          {b->f0, b->f0 + 3L * (nv - 1)},
                          {b->f1, b->f1 + 3L * (nv - 1)}};
    /* e0: D0'(0), D1'(0); e1: D0'(1), D1'(1); f0: C0'(0), C1'(0); f1: C0'(1), C1'(1) */
    static const int src[4][2][2] = {
        {{2, 0}, {3, 0}}, {{2, 1}, {3, 1}}, {{0, 0}, {1, 0}}, {{0, 1}, {1, 1}}};
    for (int k = 0; k < 4; k++)
        for (int e = 0; e < 2; e++) {
            nf_curve_derivs(&c[src[k][e][0]], (double)src[k][e][1], 1, d);
            memcpy(ends[k][e], d + 3, 3 * sizeof(double));
            memcpy(ends[k][e] + (e ? -3 : 3), d + 3, 3 * sizeof(double));
        }
    return NF_OK;
}

/* First and last non-empty spans of a clamped knot vector over p: the
 * knot spans du_s, du_e of the paper's twist equations, divided by p. */
static void end_spans(const nf_curve_t *c, double *as, double *ae)
{
    *as = (c->U[c->p + 1] - c->U[c->p]) / c->p;
    *ae = (c->U[c->n] - c->U[c->n - 1]) / c->p;
}

/* Sum of the curve's basis over span l times coefficient vectors v. */
static void combo(const double *N, int l, int p, const double *v, double out[3])
{
    out[0] = out[1] = out[2] = 0.0;
    for (int a = 0; a <= p; a++)
        for (int k = 0; k < 3; k++)
            out[k] += N[a] * v[3 * (l - p + a) + k];
}

/* Everything the definition needs at (u, v). */
typedef struct at {
    double Hs[4], Ht[4];
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER];
    int lu, lv;
} at_t;

static void at_init(const nf_coons_t *cs, double u, double v, at_t *a)
{
    const nf_curve_t *cu = &cs->c[0], *cv = &cs->c[2];
    hermite(u, a->Hs);
    hermite(v, a->Ht);
    a->lu = nf_find_span(cu->n - 1, cu->p, u, cu->U);
    a->lv = nf_find_span(cv->n - 1, cv->p, v, cv->U);
    nf_basis_funs(a->lu, u, cu->p, cu->U, a->Nu);
    nf_basis_funs(a->lv, v, cv->p, cv->U, a->Nv);
}

/* S = L_u + L_v - T at a (the paper's Section 2.2 form), with the current
 * cross-derivative vectors and twists tw (12 doubles). */
static void eval_at(const nf_coons3_t *b, const at_t *a, const double *tw, double out[3])
{
    const nf_coons_t *cs = b->cs;
    const int p = cs->c[0].p, q = cs->c[2].p, nu = cs->c[0].n, nv = cs->c[2].n;
    double C0[3], C1[3], D0[3], D1[3], E0[3], E1[3], F0[3], F1[3];
    combo(a->Nu, a->lu, p, cs->c[0].cp, C0);
    combo(a->Nu, a->lu, p, cs->c[1].cp, C1);
    combo(a->Nv, a->lv, q, cs->c[2].cp, D0);
    combo(a->Nv, a->lv, q, cs->c[3].cp, D1);
    combo(a->Nu, a->lu, p, b->e0, E0);
    combo(a->Nu, a->lu, p, b->e1, E1);
    combo(a->Nv, a->lv, q, b->f0, F0);
    combo(a->Nv, a->lv, q, b->f1, F1);
    const double *P00 = cs->c[0].cp, *P10 = cs->c[0].cp + 3L * (nu - 1);
    const double *P01 = cs->c[1].cp, *P11 = cs->c[1].cp + 3L * (nu - 1);
    /* Hermite data of the corner patch T: rows u-side (pos u0, pos u1,
     * d/du u0, d/du u1), columns the same in v. */
    const double *G[4][4] = {{P00, P01, b->e0, b->e1},
                             {P10, P11, b->e0 + 3L * (nu - 1), b->e1 + 3L * (nu - 1)},
                             {b->f0, b->f0 + 3L * (nv - 1), tw, tw + 6},
                             {b->f1, b->f1 + 3L * (nv - 1), tw + 3, tw + 9}};
    for (int k = 0; k < 3; k++) {
        double Lu = a->Hs[0] * D0[k] + a->Hs[1] * D1[k] + a->Hs[2] * F0[k] + a->Hs[3] * F1[k];
        double Lv = a->Ht[0] * C0[k] + a->Ht[1] * C1[k] + a->Ht[2] * E0[k] + a->Ht[3] * E1[k];
        double T = 0.0;
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++)
                T += a->Hs[i] * a->Ht[j] * G[i][j][k];
        out[k] = Lu + Lv - T;
    }
}

void nf_coons3_eval(const nf_coons3_t *b, double u, double v, double out[3])
{
    at_t a;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    v = v < 0 ? 0 : (v > 1 ? 1 : v);
    at_init(b->cs, u, v, &a);
    double tw[12];
    /* T's twists: the fitted ones, scaled like the two curves that meet. */
    static const int cu[4] = {0, 0, 1, 1}, cv[4] = {2, 3, 2, 3};
    for (int c = 0; c < 4; c++)
        for (int k = 0; k < 3; k++)
            tw[3 * c + k] = b->tw[3 * c + k] * 0.5 * (b->s[cu[c]] + b->s[cv[c]]);
    eval_at(b, &a, tw, out);
}

int nf_coons3_add(nf_coons3_t *b, double u, double v, const double Q[3])
{
    if (b->solved)
        return NF_ESTATE;
    if (!(Q[0] - Q[0] == 0.0) || !(Q[1] - Q[1] == 0.0) || !(Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    if (!(u >= 0.0 && u <= 1.0 && v >= 0.0 && v <= 1.0))
        return NF_EDOMAIN;
    const nf_coons_t *cs = b->cs;
    const int p = cs->c[0].p, q = cs->c[2].p, nu = cs->c[0].n, nv = cs->c[2].n;
    at_t a;
    at_init(cs, u, v, &a);
    double S0[3];
    eval_at(b, &a, b->tw, S0); /* unknowns at zero: the fixed part */
    double asu, aeu, asv, aev;
    end_spans(&cs->c[0], &asu, &aeu);
    end_spans(&cs->c[2], &asv, &aev);
    /* The row: coefficient of each unknown in S(u, v), sparse. Unknowns:
     * twists 00 10 01 11, then e0[2..nu-3], e1[..], f0[2..nv-3], f1[..]. */
    int idx[4 + 4 * NF_MAX_ORDER];
    double g[4 + 4 * NF_MAX_ORDER];
    int n = 0;
    const double *Hs = a.Hs, *Ht = a.Ht;
    double Nu1 = 0, Nun = 0, Nv1 = 0, Nvn = 0; /* N_1 and N_{n-2} in u and v */
    for (int i = 0; i <= p; i++) {
        int ci = a.lu - p + i;
        Nu1 += ci == 1 ? a.Nu[i] : 0.0;
        Nun += ci == nu - 2 ? a.Nu[i] : 0.0;
    }
    for (int j = 0; j <= q; j++) {
        int cj = a.lv - q + j;
        Nv1 += cj == 1 ? a.Nv[j] : 0.0;
        Nvn += cj == nv - 2 ? a.Nv[j] : 0.0;
    }
    /* e0[1] = e0[0] + tw00 asu, e0[nu-2] = e0[nu-1] - tw10 aeu,
     * e1[1] = e1[0] + tw01 asu, e1[nu-2] = e1[nu-1] - tw11 aeu,
     * f0[1] = f0[0] + tw00 asv, f0[nv-2] = f0[nv-1] - tw01 aev,
     * f1[1] = f1[0] + tw10 asv, f1[nv-2] = f1[nv-1] - tw11 aev:
     * E'(0) = p (e[1] - e[0]) / du_s is the twist (the constraints). */
    g[n] = Ht[2] * Nu1 * asu + Hs[2] * Nv1 * asv - Hs[2] * Ht[2];
    idx[n++] = 0;
    g[n] = -Ht[2] * Nun * aeu + Hs[3] * Nv1 * asv - Hs[3] * Ht[2];
    idx[n++] = 1;
    g[n] = Ht[3] * Nu1 * asu - Hs[2] * Nvn * aev - Hs[2] * Ht[3];
    idx[n++] = 2;
    g[n] = -Ht[3] * Nun * aeu - Hs[3] * Nvn * aev - Hs[3] * Ht[3];
    idx[n++] = 3;
    const int o_e1 = 4 + (nu - 4), o_f0 = 4 + 2 * (nu - 4), o_f1 = o_f0 + (nv - 4);
    for (int i = 0; i <= p; i++) {
        int ci = a.lu - p + i;
        if (ci < 2 || ci > nu - 3)
            continue;
        g[n] = Ht[2] * a.Nu[i];
        idx[n++] = 4 + ci - 2;
        g[n] = Ht[3] * a.Nu[i];
        idx[n++] = o_e1 + ci - 2;
    }
    for (int j = 0; j <= q; j++) {
        int cj = a.lv - q + j;
        if (cj < 2 || cj > nv - 3)
            continue;
        g[n] = Hs[2] * a.Nv[j];
        idx[n++] = o_f0 + cj - 2;
        g[n] = Hs[3] * a.Nv[j];
        idx[n++] = o_f1 + cj - 2;
    }
    const int K = b->K;
    for (int r = 0; r < n; r++) {
        for (int c = 0; c < n; c++)
            b->A[(long)idx[r] * K + idx[c]] += g[r] * g[c];
        for (int k = 0; k < 3; k++)
            b->rhs[3L * idx[r] + k] += g[r] * (Q[k] - S0[k]);
    }
    b->npoints++;
    return NF_OK;
}

/* Dense Cholesky A = L L^T in place (lower), 3 right-hand sides. */
static int cholesky_solve(double *A, double *x, int K)
{
    double dmax = 0.0;
    for (int i = 0; i < K; i++)
        dmax = fmax(dmax, A[(long)i * K + i]);
    for (int j = 0; j < K; j++) {
        double d = A[(long)j * K + j];
        for (int k = 0; k < j; k++)
            d -= A[(long)j * K + k] * A[(long)j * K + k];
        if (!(d > 1e-13 * dmax))
            return NF_ESINGULAR;
        d = sqrt(d);
        A[(long)j * K + j] = d;
        for (int i = j + 1; i < K; i++) {
            double s = A[(long)i * K + j];
            for (int k = 0; k < j; k++)
                s -= A[(long)i * K + k] * A[(long)j * K + k];
            A[(long)i * K + j] = s / d;
        }
    }
    for (int c = 0; c < 3; c++) {
        for (int i = 0; i < K; i++) {
            double s = x[3L * i + c];
            for (int k = 0; k < i; k++)
                s -= A[(long)i * K + k] * x[3L * k + c];
            x[3L * i + c] = s / A[(long)i * K + i];
        }
        for (int i = K - 1; i >= 0; i--) {
            double s = x[3L * i + c];
            for (int k = i + 1; k < K; k++)
                s -= A[(long)k * K + i] * x[3L * k + c];
            x[3L * i + c] = s / A[(long)i * K + i];
        }
    }
    return NF_OK;
}

int nf_coons3_solve(nf_coons3_t *b)
{
    if (b->solved)
        return NF_ESTATE;
    const int K = b->K, nu = b->cs->c[0].n, nv = b->cs->c[2].n;
    int rc = cholesky_solve(b->A, b->rhs, K);
    if (rc)
        return rc;
    const double *x = b->rhs;
    double asu, aeu, asv, aev;
    end_spans(&b->cs->c[0], &asu, &aeu);
    end_spans(&b->cs->c[2], &asv, &aev);
    memcpy(b->tw, x, 12 * sizeof(double));
    const int o_e1 = 4 + (nu - 4), o_f0 = 4 + 2 * (nu - 4), o_f1 = o_f0 + (nv - 4);
    for (int k = 0; k < 3; k++) {
        const double *t = b->tw;
        b->e0[3 + k] = b->e0[k] + t[k] * asu;
        b->e0[3 * (nu - 2) + k] = b->e0[3 * (nu - 1) + k] - t[3 + k] * aeu;
        b->e1[3 + k] = b->e1[k] + t[6 + k] * asu;
        b->e1[3 * (nu - 2) + k] = b->e1[3 * (nu - 1) + k] - t[9 + k] * aeu;
        b->f0[3 + k] = b->f0[k] + t[k] * asv;
        b->f0[3 * (nv - 2) + k] = b->f0[3 * (nv - 1) + k] - t[6 + k] * aev;
        b->f1[3 + k] = b->f1[k] + t[3 + k] * asv;
        b->f1[3 * (nv - 2) + k] = b->f1[3 * (nv - 1) + k] - t[9 + k] * aev;
        for (int i = 2; i <= nu - 3; i++) {
            b->e0[3 * i + k] = x[3 * (4 + i - 2) + k];
            b->e1[3 * i + k] = x[3 * (o_e1 + i - 2) + k];
        }
        for (int j = 2; j <= nv - 3; j++) {
            b->f0[3 * j + k] = x[3 * (o_f0 + j - 2) + k];
            b->f1[3 * j + k] = x[3 * (o_f1 + j - 2) + k];
        }
    }
    b->solved = 1;
    return NF_OK;
}

/* Mean arc length of a curve (chords of 64 samples per knot span). */
static double arc_length(const nf_curve_t *c)
{
    int spans = c->n - c->p, m = 64 * spans;
    double L = 0.0, prev[3], P[3];
    nf_curve_eval(c, 0.0, prev);
    for (int i = 1; i <= m; i++) {
        nf_curve_eval(c, (double)i / m, P);
        L += sqrt((P[0] - prev[0]) * (P[0] - prev[0]) + (P[1] - prev[1]) * (P[1] - prev[1]) +
                  (P[2] - prev[2]) * (P[2] - prev[2]));
        memcpy(prev, P, sizeof prev);
    }
    return L;
}

/* Mean magnitude of a vector field sum_i N_i(t) d_i over uniform samples. */
static double mean_mag(const nf_curve_t *space, const double *d)
{
    int m = 64 * (space->n - space->p);
    double s = 0.0, N[NF_MAX_ORDER], D[3];
    for (int i = 0; i <= m; i++) {
        double t = (double)i / m;
        int l = nf_find_span(space->n - 1, space->p, t, space->U);
        nf_basis_funs(l, t, space->p, space->U, N);
        combo(N, l, space->p, d, D);
        s += sqrt(D[0] * D[0] + D[1] * D[1] + D[2] * D[2]);
    }
    return s / (m + 1);
}

void nf_coons3_scale(nf_coons3_t *b)
{
    const nf_curve_t *c = b->cs->c;
    double Lu = 0.5 * (arc_length(&c[0]) + arc_length(&c[1]));
    double Lv = 0.5 * (arc_length(&c[2]) + arc_length(&c[3]));
    double *d[4] = {b->e0, b->e1, b->f0, b->f1};
    const int nu = c[0].n, nv = c[2].n;
    for (int k = 0; k < 4; k++) {
        const nf_curve_t *space = k < 2 ? &c[0] : &c[2];
        double L = k < 2 ? Lv : Lu, mag = mean_mag(space, d[k]);
        double f = mag > 0.0 ? (L / (Lu + Lv)) * (L / mag) : 1.0;
        int n = k < 2 ? nu : nv;
        for (long i = 0; i < 3L * n; i++)
            d[k][i] *= f;
        b->s[k] *= f;
    }
}

/* The degree-p blossom of the cubic Bernstein polynomials at p knots x:
 * the coefficients of B_{a,3} in the B-spline basis (de Boor-Fix via
 * polar forms): the mean over 3-subsets of x of the cubic polar forms. */
static void bern3_blossom(const double *x, int p, double m[4])
{
    int cnt = 0;
    m[0] = m[1] = m[2] = m[3] = 0.0;
    for (int i = 0; i < p; i++)
        for (int j = i + 1; j < p; j++)
            for (int k = j + 1; k < p; k++) {
                double a[3] = {x[i], x[j], x[k]}, e[4] = {1, 0, 0, 0};
                for (int r = 0; r < 3; r++) /* multiply the polar factors (1 - a_r) + a_r */
                    for (int s = r + 1; s >= 0; s--)
                        e[s] = e[s] * (1 - a[r]) + (s ? e[s - 1] * a[r] : 0.0);
                for (int s = 0; s < 4; s++)
                    m[s] += e[s];
                cnt++;
            }
    for (int s = 0; s < 4; s++)
        m[s] /= cnt;
}

int nf_coons3_surface(const nf_coons3_t *b, nf_surf_t *out)
{
    int p, q, nu, nv;
    const nf_coons_t *cs = b->cs;
    nf_coons_size(cs, &p, &q, &nu, &nv);
    if (!out || out->p != p || out->q != q || out->nu != nu || out->nv != nv || !b->solved)
        return NF_EARG;
    const nf_curve_t *c = cs->c;
    memcpy(out->U, c[0].U, sizeof(double) * (size_t)(nu + p + 1));
    memcpy(out->V, c[2].U, sizeof(double) * (size_t)(nv + q + 1));
    double tw[12];
    static const int cu[4] = {0, 0, 1, 1}, cv[4] = {2, 3, 2, 3};
    for (int k = 0; k < 12; k++)
        tw[k] = b->tw[k] * 0.5 * (b->s[cu[k / 3]] + b->s[cv[k / 3]]);
    const double *P00 = c[0].cp, *P10 = c[0].cp + 3L * (nu - 1);
    const double *P01 = c[1].cp, *P11 = c[1].cp + 3L * (nu - 1);
    const double *G[4][4] = {{P00, P01, b->e0, b->e1},
                             {P10, P11, b->e0 + 3L * (nu - 1), b->e1 + 3L * (nu - 1)},
                             {b->f0, b->f0 + 3L * (nv - 1), tw, tw + 6},
                             {b->f1, b->f1 + 3L * (nv - 1), tw + 3, tw + 9}};
    /* Hermite to Bezier on [0, 1]: b0 = g0, b1 = g0 + g2/3, b2 = g1 - g3/3, b3 = g1. */
    static const double Hm[4][4] = {
        {1, 0, 0, 0}, {1, 0, 1.0 / 3, 0}, {0, 1, 0, -1.0 / 3}, {0, 1, 0, 0}};
    double Tb[4][4][3];
    for (int a = 0; a < 4; a++)
        for (int bb = 0; bb < 4; bb++)
            for (int k = 0; k < 3; k++) {
                double s = 0.0;
                for (int i = 0; i < 4; i++)
                    for (int j = 0; j < 4; j++)
                        s += Hm[a][i] * Hm[bb][j] * G[i][j][k];
                Tb[a][bb][k] = s;
            }
    for (long i = 0; i < (long)nu * nv; i++)
        out->w[i] = 1.0;
    for (int i = 0; i < nu; i++) {
        double mu[4];
        bern3_blossom(out->U + i + 1, p, mu);
        for (int j = 0; j < nv; j++) {
            double mv[4];
            bern3_blossom(out->V + j + 1, q, mv);
            for (int k = 0; k < 3; k++) {
                const double *d0 = c[2].cp, *d1 = c[3].cp, *c0 = c[0].cp, *c1 = c[1].cp;
                /* L_u: cubic in u over the v-space; L_v: cubic in v over the u-space. */
                double Bu[4] = {d0[3 * j + k], d0[3 * j + k] + b->f0[3 * j + k] / 3,
                                d1[3 * j + k] - b->f1[3 * j + k] / 3, d1[3 * j + k]};
                double Bv[4] = {c0[3 * i + k], c0[3 * i + k] + b->e0[3 * i + k] / 3,
                                c1[3 * i + k] - b->e1[3 * i + k] / 3, c1[3 * i + k]};
                double Lu = 0, Lv = 0, T = 0;
                for (int a = 0; a < 4; a++) {
                    Lu += mu[a] * Bu[a];
                    Lv += mv[a] * Bv[a];
                    for (int bb = 0; bb < 4; bb++)
                        T += mu[a] * mv[bb] * Tb[a][bb][k];
                }
                out->cp[3 * (i + (long)j * nu) + k] = Lu + Lv - T;
            }
        }
    }
    /* Boundary rows and columns are the curves (exact, not to rounding). */
    for (int i = 0; i < nu; i++) {
        memcpy(out->cp + 3L * i, c[0].cp + 3L * i, 3 * sizeof(double));
        memcpy(out->cp + 3 * (i + (long)(nv - 1) * nu), c[1].cp + 3L * i, 3 * sizeof(double));
    }
    for (int j = 0; j < nv; j++) {
        memcpy(out->cp + 3L * j * nu, c[2].cp + 3L * j, 3 * sizeof(double));
        memcpy(out->cp + 3 * ((long)j * nu + nu - 1), c[3].cp + 3L * j, 3 * sizeof(double));
    }
    return NF_OK;
}
