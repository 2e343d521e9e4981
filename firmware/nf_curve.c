/* SPDX-License-Identifier: MIT */
/* nf_curve.c: NURBS curve evaluation and exact transformations (The NURBS
 * Book A2.1-A2.3, A4.2, A5.4, A5.9), on homogeneous points. */
#include "nf_curve.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <string.h>

void nf_curve_wire(nf_curve_t *c, int p, int n, double *mem)
{
    c->p = p;
    c->n = n;
    c->U = mem;
    c->cp = c->U + n + p + 1;
    c->w = c->cp + 3L * n;
    for (int i = 0; i < n; i++)
        c->w[i] = 1.0;
}

int nf_curve_check(const nf_curve_t *c)
{
    if (!c || !c->U || !c->cp)
        return NF_EARG;
    if (c->p < 1 || c->p > NF_MAX_DEGREE)
        return NF_EDEGREE;
    if (c->n < c->p + 1 || c->n > NF_MAX_CP)
        return NF_ESIZE;
    if (nf_knots_check(c->n - 1, c->p, c->U))
        return NF_EKNOTS;
    for (long i = 0; i < 3L * c->n; i++)
        if (!(c->cp[i] - c->cp[i] == 0.0))
            return NF_ENONFINITE;
    if (c->w)
        for (int i = 0; i < c->n; i++)
            if (!(c->w[i] > 0.0) || !(c->w[i] - c->w[i] == 0.0))
                return NF_EWEIGHT;
    return NF_OK;
}

void nf_curve_domain(const nf_curve_t *c, double *u0, double *u1)
{
    *u0 = c->U[c->p];
    *u1 = c->U[c->n];
}

static double wt(const nf_curve_t *c, int i)
{
    return c->w ? c->w[i] : 1.0;
}

void nf_curve_derivs(const nf_curve_t *c, double u, int d, double ck[9])
{
    double ders[3 * NF_MAX_ORDER], A[3][4] = {{0}};
    const int p = c->p;
    if (d > 2)
        d = 2;
    if (d < 0)
        d = 0;
    u = u < c->U[p] ? c->U[p] : (u > c->U[c->n] ? c->U[c->n] : u);
    int l = nf_find_span(c->n - 1, p, u, c->U), nd = d < p ? d : p;
    nf_ders_basis_funs(l, u, p, nd, c->U, ders);
    for (int a = 0; a <= p; a++) {
        int i = l - p + a;
        double w = wt(c, i),
               h[4] = {c->cp[3 * i] * w, c->cp[3 * i + 1] * w, c->cp[3 * i + 2] * w, w};
        for (int k = 0; k <= nd; k++)
            for (int m = 0; m < 4; m++)
                A[k][m] += ders[k * (p + 1) + a] * h[m];
    }
    /* C^(k) = (A^(k) - sum_i binom(k,i) w^(i) C^(k-i)) / w  (Eq. 4.8) */
    for (int m = 0; m < 3; m++) {
        double c0 = A[0][m] / A[0][3];
        double c1 = (A[1][m] - A[1][3] * c0) / A[0][3];
        double c2 = (A[2][m] - 2.0 * A[1][3] * c1 - A[2][3] * c0) / A[0][3];
        ck[m] = c0;
        ck[3 + m] = d >= 1 ? c1 : 0.0;
        ck[6 + m] = d >= 2 ? c2 : 0.0;
    }
}

void nf_curve_eval(const nf_curve_t *c, double u, double out[3])
{
    double ck[9];
    nf_curve_derivs(c, u, 0, ck);
    out[0] = ck[0];
    out[1] = ck[1];
    out[2] = ck[2];
}

void nf_curve_copy(const nf_curve_t *in, nf_curve_t *out)
{
    memcpy(out->U, in->U, sizeof(double) * (size_t)(in->n + in->p + 1));
    memcpy(out->cp, in->cp, sizeof(double) * 3 * (size_t)in->n);
    for (int i = 0; i < in->n; i++)
        out->w[i] = wt(in, i);
}

void nf_curve_reverse(nf_curve_t *c)
{
    const int m = c->n + c->p; /* last knot index */
    const double a = c->U[0], b = c->U[m];
    for (int i = 0, j = m; i <= j; i++, j--) {
        double ui = c->U[i], uj = c->U[j];
        c->U[i] = a + b - uj;
        c->U[j] = a + b - ui;
    }
    for (int i = 0, j = c->n - 1; i < j; i++, j--) {
        for (int k = 0; k < 3; k++) {
            double t = c->cp[3 * i + k];
            c->cp[3 * i + k] = c->cp[3 * j + k];
            c->cp[3 * j + k] = t;
        }
        if (c->w) {
            double t = c->w[i];
            c->w[i] = c->w[j];
            c->w[j] = t;
        }
    }
    /* Clamped ends stay exact: a + b - b = a only up to rounding. */
    for (int i = 0; i <= c->p; i++) {
        c->U[i] = a;
        c->U[m - i] = b;
    }
}

void nf_curve_reparam(nf_curve_t *c, double a, double b)
{
    const int m = c->n + c->p;
    const double u0 = c->U[0], u1 = c->U[m];
    for (int i = 0; i <= m; i++)
        c->U[i] = a + (b - a) * ((c->U[i] - u0) / (u1 - u0));
    for (int i = 0; i <= c->p; i++) {
        c->U[i] = a;
        c->U[m - i] = b;
    }
}

void nf_curve_scale_weights(nf_curve_t *c, double f)
{
    for (int i = 0; c->w && i < c->n; i++)
        c->w[i] *= f;
}

int nf_curve_elevate_size(const nf_curve_t *c, int t)
{
    int d = 1;
    for (int i = 1; i < c->n + c->p + 1; i++)
        d += c->U[i] != c->U[i - 1];
    return c->n + t * (d - 1);
}

/* Homogeneous point i of c. */
static void hom(const nf_curve_t *c, int i, double h[4])
{
    double w = wt(c, i);
    h[0] = c->cp[3 * i] * w;
    h[1] = c->cp[3 * i + 1] * w;
    h[2] = c->cp[3 * i + 2] * w;
    h[3] = w;
}

/* out holds homogeneous points in (cp, w) while an algorithm runs; this
 * divides the weight back out. */
static void dehom(nf_curve_t *out)
{
    for (int i = 0; i < out->n; i++)
        for (int k = 0; k < 3; k++)
            out->cp[3 * i + k] /= out->w[i];
}

static void hget(const nf_curve_t *o, int i, double h[4])
{
    h[0] = o->cp[3 * i];
    h[1] = o->cp[3 * i + 1];
    h[2] = o->cp[3 * i + 2];
    h[3] = o->w[i];
}

static void hput(nf_curve_t *o, int i, const double h[4])
{
    o->cp[3 * i] = h[0];
    o->cp[3 * i + 1] = h[1];
    o->cp[3 * i + 2] = h[2];
    o->w[i] = h[3];
}

static double binom(int n, int k)
{
    double r = 1.0;
    for (int i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}

#define LIN(dst, a, x, b, y)                                                                       \
    do {                                                                                           \
        for (int c_ = 0; c_ < 4; c_++)                                                             \
            (dst)[c_] = (a) * (x)[c_] + (b) * (y)[c_];                                             \
    } while (0)

int nf_curve_elevate(const nf_curve_t *in, int t, nf_curve_t *out)
{
    const int p = in->p, ph = p + t, ph2 = ph / 2, m = in->n + p; /* m: last knot index */
    if (t < 0)
        return NF_EARG;
    if (ph > NF_MAX_DEGREE)
        return NF_EDEGREE;
    if (!out || out->p != ph || out->n != nf_curve_elevate_size(in, t) || !out->w)
        return NF_EARG;
    if (t == 0) {
        nf_curve_copy(in, out);
        return NF_OK;
    }
    const double *U = in->U;
    double *Uh = out->U;
    double bezalfs[NF_MAX_ORDER][NF_MAX_ORDER], bpts[NF_MAX_ORDER][4], ebpts[NF_MAX_ORDER][4];
    double nextb[NF_MAX_ORDER][4], alfs[NF_MAX_ORDER];
    memset(bezalfs, 0, sizeof bezalfs);
    bezalfs[0][0] = bezalfs[ph][p] = 1.0;
    for (int i = 1; i <= ph2; i++) {
        double inv = 1.0 / binom(ph, i);
        int mpi = p < i ? p : i;
        for (int j = i - t > 0 ? i - t : 0; j <= mpi; j++)
            bezalfs[i][j] = inv * binom(p, j) * binom(t, i - j);
    }
    for (int i = ph2 + 1; i <= ph - 1; i++) {
        int mpi = p < i ? p : i;
        for (int j = i - t > 0 ? i - t : 0; j <= mpi; j++)
            bezalfs[i][j] = bezalfs[ph - i][p - j];
    }
    int mh = ph, kind = ph + 1, r = -1, a = p, b = p + 1, cind = 1;
    double ua = U[0], h[4];
    hom(in, 0, h);
    hput(out, 0, h);
    for (int i = 0; i <= ph; i++)
        Uh[i] = ua;
    for (int i = 0; i <= p; i++)
        hom(in, i, bpts[i]);
    while (b < m) {
        int i = b;
        while (b < m && U[b] == U[b + 1])
            b++;
        int mul = b - i + 1;
        mh += mul + t;
        double ub = U[b];
        int oldr = r;
        r = p - mul;
        int lbz = oldr > 0 ? (oldr + 2) / 2 : 1;
        int rbz = r > 0 ? ph - (r + 1) / 2 : ph;
        if (r > 0) { /* insert ub r times: Bezier segment [ua, ub] */
            double numer = ub - ua;
            for (int k = p; k > mul; k--)
                alfs[k - mul - 1] = numer / (U[a + k] - ua);
            for (int j = 1; j <= r; j++) {
                int save = r - j, s = mul + j;
                for (int k = p; k >= s; k--)
                    LIN(bpts[k], alfs[k - s], bpts[k], 1.0 - alfs[k - s], bpts[k - 1]);
                memcpy(nextb[save], bpts[p], sizeof nextb[save]);
            }
        }
        for (int k = lbz; k <= ph; k++) { /* elevate the Bezier segment */
            int mpi = p < k ? p : k;
            memset(ebpts[k], 0, sizeof ebpts[k]);
            for (int j = k - t > 0 ? k - t : 0; j <= mpi; j++)
                for (int c = 0; c < 4; c++)
                    ebpts[k][c] += bezalfs[k][j] * bpts[j][c];
        }
        if (oldr > 1) { /* remove ua oldr - 1 times */
            int first = kind - 2, last = kind;
            double den = ub - ua, bet = (ub - Uh[kind - 1]) / den;
            for (int tr = 1; tr < oldr; tr++) {
                int ii = first, jj = last, kj = jj - kind + 1;
                while (jj - ii > tr) {
                    if (ii < cind) {
                        double alf = (ub - Uh[ii]) / (ua - Uh[ii]), q0[4], q1[4];
                        hget(out, ii, q0);
                        hget(out, ii - 1, q1);
                        LIN(h, alf, q0, 1.0 - alf, q1);
                        hput(out, ii, h);
                    }
                    if (jj >= lbz) {
                        double g = jj - tr <= kind - ph + oldr ? (ub - Uh[jj - tr]) / den : bet;
                        LIN(ebpts[kj], g, ebpts[kj], 1.0 - g, ebpts[kj + 1]);
                    }
                    ii++;
                    jj--;
                    kj--;
                }
                first--;
                last++;
            }
        }
        if (a != p)
            for (int k = 0; k < ph - oldr; k++)
                Uh[kind++] = ua;
        for (int j = lbz; j <= rbz; j++)
            hput(out, cind++, ebpts[j]);
        if (b < m) {
            for (int j = 0; j < r; j++)
                memcpy(bpts[j], nextb[j], sizeof bpts[j]);
            for (int j = r; j <= p; j++)
                hom(in, b - p + j, bpts[j]);
            a = b;
            b++;
            ua = ub;
        } else {
            for (int k = 0; k <= ph; k++)
                Uh[kind + k] = ub;
        }
    }
    dehom(out);
    return mh - ph == out->n ? NF_OK : NF_EARG;
}

int nf_curve_refine(const nf_curve_t *in, const double *X, int r, nf_curve_t *out)
{
    const int p = in->p, n = in->n - 1, m = n + p + 1;
    if (r < 0 || !out || out->p != p || out->n != in->n + r || !out->w)
        return NF_EARG;
    for (int j = 0; j < r; j++)
        if (!(X[j] > in->U[p] && X[j] < in->U[n + 1]) || (j && X[j] < X[j - 1]))
            return NF_EKNOTS;
    if (r == 0) {
        nf_curve_copy(in, out);
        return NF_OK;
    }
    const double *U = in->U;
    double *Ub = out->U, h[4], h1[4];
    const int rr = r - 1; /* A5.4 counts X[0..rr] */
    int a = nf_find_span(n, p, X[0], U), b = nf_find_span(n, p, X[rr], U) + 1;
    for (int j = 0; j <= a - p; j++) {
        hom(in, j, h);
        hput(out, j, h);
    }
    for (int j = b - 1; j <= n; j++) {
        hom(in, j, h);
        hput(out, j + rr + 1, h);
    }
    for (int j = 0; j <= a; j++)
        Ub[j] = U[j];
    for (int j = b + p; j <= m; j++)
        Ub[j + rr + 1] = U[j];
    int i = b + p - 1, k = b + p + rr;
    for (int j = rr; j >= 0; j--) {
        while (X[j] <= U[i] && i > a) {
            hom(in, i - p - 1, h);
            hput(out, k - p - 1, h);
            Ub[k] = U[i];
            k--;
            i--;
        }
        hget(out, k - p, h);
        hput(out, k - p - 1, h);
        for (int l = 1; l <= p; l++) {
            int ind = k - p + l;
            double alfa = Ub[k + l] - X[j];
            hget(out, ind, h1);
            if (alfa == 0.0) {
                hput(out, ind - 1, h1);
            } else {
                alfa /= Ub[k + l] - U[i - p + l]; /* U[i-p+l], as nf_refine.c (not U[i-l+1]) */
                hget(out, ind - 1, h);
                LIN(h, alfa, h, 1.0 - alfa, h1);
                hput(out, ind - 1, h);
            }
        }
        Ub[k] = X[j];
        k--;
    }
    dehom(out);
    return nf_knots_check(out->n - 1, p, out->U) ? NF_EKNOTS : NF_OK;
}
