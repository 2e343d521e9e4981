/* SPDX-License-Identifier: MIT */
/* cf_trim.c: trim loops in parameter space and their 3-D edges (cf_trim.h). */
#include "cf_trim.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "nf_basis.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void free_curves(nf_curve_t *c, int n)
{
    for (int i = 0; c && i < n; i++)
        cf_curve_free(&c[i]);
    free(c);
}

void cf_trim_free(cf_trim_t *t)
{
    if (!t)
        return;
    for (int k = 0; k < t->nloops; k++)
        free_curves(t->loop[k].c, t->loop[k].n);
    free(t->loop);
    memset(t, 0, sizeof *t);
}

int cf_trim_add_loop(cf_trim_t *t, nf_curve_t *c, int n)
{
    if (n < 1 || n > CF_TRIM_MAX_CURVES || t->nloops >= CF_TRIM_MAX_LOOPS) {
        free_curves(c, n);
        return CF_EARG;
    }
    cf_trim_loop_t *nl = realloc(t->loop, sizeof *nl * (size_t)(t->nloops + 1));
    if (!nl) {
        free_curves(c, n);
        return CF_ENOMEM;
    }
    t->loop = nl;
    t->loop[t->nloops].n = n;
    t->loop[t->nloops++].c = c;
    return CF_OK;
}

int cf_trim_add_domain(cf_trim_t *t, const nf_surf_t *s)
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    const double P[5][2] = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}, {u0, v0}};
    nf_curve_t *c = calloc(4, sizeof *c);
    if (!c)
        return CF_ENOMEM;
    for (int i = 0; i < 4; i++) {
        if (cf_curve_alloc(&c[i], 1, 2)) {
            free_curves(c, 4);
            return CF_ENOMEM;
        }
        const double U[4] = {0, 0, 1, 1};
        memcpy(c[i].U, U, sizeof U);
        c[i].cp[0] = P[i][0];
        c[i].cp[1] = P[i][1];
        c[i].cp[3] = P[i + 1][0];
        c[i].cp[4] = P[i + 1][1];
    }
    return cf_trim_add_loop(t, c, 4);
}

static int copy_curve(nf_curve_t *dst, const nf_curve_t *src)
{
    if (cf_curve_alloc(dst, src->p, src->n))
        return CF_ENOMEM;
    nf_curve_copy(src, dst);
    return CF_OK;
}

int cf_trim_copy(cf_trim_t *dst, const cf_trim_t *src)
{
    memset(dst, 0, sizeof *dst);
    for (int k = 0; k < src->nloops; k++) {
        const cf_trim_loop_t *l = &src->loop[k];
        nf_curve_t *c = calloc((size_t)l->n, sizeof *c);
        int rc = c ? CF_OK : CF_ENOMEM;
        for (int i = 0; !rc && i < l->n; i++)
            rc = copy_curve(&c[i], &l->c[i]);
        if (!rc)
            rc = cf_trim_add_loop(dst, c, l->n);
        else
            free_curves(c, l->n);
        if (rc) {
            cf_trim_free(dst);
            return rc;
        }
    }
    return CF_OK;
}

static int same(const double *a, const double *b, long n)
{
    return !memcmp(a, b, sizeof(double) * (size_t)n);
}

int cf_trim_equal(const cf_trim_t *a, const cf_trim_t *b)
{
    if (a->nloops != b->nloops)
        return 0;
    for (int k = 0; k < a->nloops; k++) {
        if (a->loop[k].n != b->loop[k].n)
            return 0;
        for (int i = 0; i < a->loop[k].n; i++) {
            const nf_curve_t *x = &a->loop[k].c[i], *y = &b->loop[k].c[i];
            if (x->p != y->p || x->n != y->n || !same(x->U, y->U, x->n + x->p + 1) ||
                !same(x->cp, y->cp, 3L * x->n) || !same(x->w, y->w, x->n))
                return 0;
        }
    }
    return 1;
}

int cf_trim_check(const cf_trim_t *t, const nf_surf_t *s, double tol, char *msg, size_t ml)
{
    double u0, u1, v0, v1, slack;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    slack = 1e-9 * fmax(u1 - u0, v1 - v0);
    for (int k = 0; k < t->nloops; k++) {
        const cf_trim_loop_t *l = &t->loop[k];
        for (int i = 0; i < l->n; i++) {
            const nf_curve_t *c = &l->c[i], *nx = &l->c[(i + 1) % l->n];
            for (int j = 0; j < c->n; j++) {
                const double *P = c->cp + 3 * j;
                if (P[0] < u0 - slack || P[0] > u1 + slack || P[1] < v0 - slack ||
                    P[1] > v1 + slack)
                    return cf_fail(msg, ml, CF_EARG,
                                   "trim loop %d curve %d: point (%.17g, %.17g) outside the "
                                   "surface's domain [%g, %g] x [%g, %g]",
                                   k + 1, i + 1, P[0], P[1], u0, u1, v0, v1);
            }
            double a, b, e[3], st[3];
            nf_curve_domain(c, &a, &b);
            nf_curve_eval(c, b, e);
            nf_curve_domain(nx, &a, &b);
            nf_curve_eval(nx, a, st);
            if (hypot(e[0] - st[0], e[1] - st[1]) > tol)
                return cf_fail(msg, ml, CF_EARG,
                               "trim loop %d is open: curve %d ends %.3g from where the next "
                               "starts",
                               k + 1, i + 1, hypot(e[0] - st[0], e[1] - st[1]));
        }
    }
    return CF_OK;
}

/* S(c(t)). */
static void on_surf(const nf_surf_t *s, const nf_curve_t *c, double t, double out[3])
{
    double uv[3];
    nf_curve_eval(c, t, uv);
    nf_surf_eval(s, uv[0], uv[1], out);
}

/* Solve the dense n x n system A X = B (3 right-hand sides) by Gaussian
 * elimination with partial pivoting; A and B are overwritten. */
static int solve3(double *A, double *B, int n)
{
    for (int k = 0; k < n; k++) {
        int piv = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[(size_t)i * n + k]) > fabs(A[(size_t)piv * n + k]))
                piv = i;
        if (!(fabs(A[(size_t)piv * n + k]) > 1e-300))
            return CF_EARG;
        if (piv != k) {
            for (int j = 0; j < n; j++) {
                double x = A[(size_t)k * n + j];
                A[(size_t)k * n + j] = A[(size_t)piv * n + j];
                A[(size_t)piv * n + j] = x;
            }
            for (int j = 0; j < 3; j++) {
                double x = B[3 * k + j];
                B[3 * k + j] = B[3 * piv + j];
                B[3 * piv + j] = x;
            }
        }
        for (int i = k + 1; i < n; i++) {
            double f = A[(size_t)i * n + k] / A[(size_t)k * n + k];
            if (f == 0.0)
                continue;
            for (int j = k; j < n; j++)
                A[(size_t)i * n + j] -= f * A[(size_t)k * n + j];
            for (int j = 0; j < 3; j++)
                B[3 * i + j] -= f * B[3 * k + j];
        }
    }
    for (int i = n - 1; i >= 0; i--)
        for (int j = 0; j < 3; j++) {
            double x = B[3 * i + j];
            for (int k = i + 1; k < n; k++)
                x -= A[(size_t)i * n + k] * B[3 * k + j];
            B[3 * i + j] = x / A[(size_t)i * n + i];
        }
    return CF_OK;
}

/* Cubic interpolation of S(c(t)) at m parameters uniform on [a, b] (A9.1,
 * knots by averaging, Eq. 9.8): knots into U (m + 4), points into P (3 m). */
static int span_interp(const nf_surf_t *s, const nf_curve_t *c, double a, double b, int m,
                       double *A, double *U, double *P)
{
    const int p = 3;
    double t[CF_TRIM_EDGE_MAXS], N[NF_MAX_DEGREE + 1];
    for (int k = 0; k < m; k++)
        t[k] = k == m - 1 ? b : a + (b - a) * k / (m - 1);
    for (int i = 0; i <= p; i++) {
        U[i] = a;
        U[m + i] = b;
    }
    for (int j = 1; j <= m - p - 1; j++)
        U[j + p] = (t[j] + t[j + 1] + t[j + 2]) / 3.0;
    memset(A, 0, sizeof(double) * (size_t)m * m);
    for (int k = 0; k < m; k++) {
        int l = nf_find_span(m - 1, p, t[k], U);
        nf_basis_funs(l, t[k], p, U, N);
        for (int i = 0; i <= p; i++)
            A[(size_t)k * m + (l - p + i)] = N[i];
        on_surf(s, c, t[k], P + 3 * k);
    }
    return solve3(A, P, m);
}

/* cf_trim_edge3d with m samples per span. */
static int edge_m(const nf_surf_t *s, const nf_curve_t *c, int m, nf_curve_t *out, double *err)
{
    const int p = 3;
    int spans = 0;
    memset(out, 0, sizeof *out);
    for (int i = c->p; i < c->n; i++)
        spans += c->U[i] < c->U[i + 1];
    if (spans < 1)
        return CF_EARG;
    /* One interpolant per knot span of c, joined at knots of multiplicity
     * 3 (C0 there, where S(c(t)) itself may be only C1): within a span the
     * composition is smooth, so the cubic converges at its full order. */
    const int n = 1 + spans * (m - 1);
    double *A = malloc(sizeof(double) * ((size_t)m * m + 4 * (size_t)m + 4));
    if (!A || cf_curve_alloc(out, p, n)) {
        free(A);
        return CF_ENOMEM;
    }
    double *Us = A + (size_t)m * m, *Ps = malloc(sizeof(double) * 3 * (size_t)m);
    int rc = Ps ? CF_OK : CF_ENOMEM, at = 0, ku = 0;
    double e = 0.0;
    for (int i = c->p; i < c->n && !rc; i++) {
        if (!(c->U[i] < c->U[i + 1]))
            continue;
        if ((rc = span_interp(s, c, c->U[i], c->U[i + 1], m, A, Us, Ps)))
            break;
        /* Knots: the first span's clamped start, then each span's interior
         * knots and its end three times (four at the very end). */
        if (at == 0)
            for (int k = 0; k <= p; k++)
                out->U[ku++] = Us[0];
        for (int k = p + 1; k < m; k++)
            out->U[ku++] = Us[k];
        for (int k = 0; k < p; k++)
            out->U[ku++] = Us[m];
        memcpy(out->cp + 3 * (size_t)at, Ps + (at ? 3 : 0), sizeof(double) * 3 * (at ? m - 1 : m));
        at += at ? m - 1 : m;
    }
    if (!rc) {
        out->U[ku] = out->U[ku - 1]; /* the end clamped p + 1 times */
        for (int i = c->p; i < c->n; i++) {
            if (!(c->U[i] < c->U[i + 1]))
                continue;
            double h = (c->U[i + 1] - c->U[i]) / (m - 1);
            for (int k = 0; k + 1 < m; k++) {
                double tm = c->U[i] + (k + 0.5) * h, P[3], Q[3];
                on_surf(s, c, tm, P);
                nf_curve_eval(out, tm, Q);
                e = fmax(e, sqrt((P[0] - Q[0]) * (P[0] - Q[0]) + (P[1] - Q[1]) * (P[1] - Q[1]) +
                                 (P[2] - Q[2]) * (P[2] - Q[2])));
            }
        }
        *err = e;
    } else {
        cf_curve_free(out);
    }
    free(Ps);
    free(A);
    return rc;
}

int cf_trim_edge3d(const nf_surf_t *s, const nf_curve_t *c, double tol, nf_curve_t *out,
                   double *err)
{
    int rc = CF_EARG;
    memset(out, 0, sizeof *out);
    for (int m = 9; m <= CF_TRIM_EDGE_MAXS; m = 2 * m - 1) {
        cf_curve_free(out);
        if ((rc = edge_m(s, c, m, out, err)) || *err <= tol)
            break;
    }
    return rc;
}
