/* SPDX-License-Identifier: MIT */
/* cf_surfrow.c: fast evaluation of a surface at points in rows of one v
 * (the residual pass of a fit: issue 20). S(u, v) = sum_a N_a(u) C_a(v)
 * with C_a(v) = sum_b N_b(v) P_ab (Eq. 1 with the sums regrouped). */
#include "cf_surfrow.h"
#include "cf_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* The power form of span l's p+1 basis functions (knots U) about its
 * middle m: N_(l-p+a)(m + t) = sum_j M[j (p+1) + a] t^j, by Taylor (A2.3's
 * exact derivatives over j!): exact for a polynomial of degree p. */
static void span_power(const double *U, int p, int l, double *M)
{
    const int o = p + 1;
    double ders[NF_MAX_ORDER * NF_MAX_ORDER];
    nf_ders_basis_funs(l, 0.5 * (U[l] + U[l + 1]), p, p, U, ders);
    double f = 1.0;
    for (int j = 0; j <= p; j++) {
        f = j > 0 ? f * j : 1.0;
        for (int a = 0; a < o; a++)
            M[j * o + a] = ders[j * o + a] / f;
    }
}

int cf_surfrow_init(cf_surfrow_t *e, const nf_surf_t *s)
{
    memset(e, 0, sizeof *e);
    e->s = s;
    e->l = -1;
    e->k = -1;
    e->al = -1;
    /* Rational (weights not all equal): nf_surf_eval. Equal weights cancel
     * in Eq. 1 (the basis sums to 1), so such a net is polynomial. */
    for (long i = 1; s->w && i < (long)s->nu * s->nv; i++)
        if (s->w[i] != s->w[0])
            return CF_OK;
    const size_t o2 = (size_t)(s->p + 1) * (size_t)(s->p + 1);
    e->C = malloc(sizeof(double) * 3 * (size_t)s->nu);
    e->stamp = malloc(sizeof(long) * (size_t)s->nu);
    const size_t q2 = (size_t)(s->q + 1) * (size_t)(s->q + 1);
    e->M = malloc(sizeof(double) * o2 * (size_t)(s->nu - s->p));
    e->Mv = malloc(sizeof(double) * q2 * (size_t)(s->nv - s->q));
    if (!e->C || !e->stamp || !e->M || !e->Mv) {
        cf_surfrow_free(e);
        return CF_ENOMEM;
    }
    for (int i = 0; i < s->nu; i++)
        e->stamp[i] = -1;
    for (int l = s->p; l < s->nu; l++)
        if (s->U[l] < s->U[l + 1]) /* empty spans are never found */
            span_power(s->U, s->p, l, e->M + o2 * (size_t)(l - s->p));
    for (int k = s->q; k < s->nv; k++)
        if (s->V[k] < s->V[k + 1])
            span_power(s->V, s->q, k, e->Mv + q2 * (size_t)(k - s->q));
    e->row = -1;
    /* No row yet: NaN equals no v. (V[q] - 1 did not: at |V[q]| >= 2^53 it
     * is V[q], and a first row there read columns never computed.) */
    e->v = NAN;
    e->umin = s->U[s->p], e->umax = s->U[s->nu];
    e->vmin = s->V[s->q], e->vmax = s->V[s->nv];
    e->lo = 1.0, e->hi = 0.0; /* no span yet: [lo, hi) empty */
    e->hu = (s->nu - s->p) / (s->U[s->nu] - s->U[s->p]);
    e->p3 = s->p == 3;
    e->hv = (s->nv - s->q) / (s->V[s->nv] - s->V[s->q]);
    return CF_OK;
}

/* A: the current row's curve on u span l in power form (columns as needed). */
static void row_span(cf_surfrow_t *e, int l)
{
    const nf_surf_t *s = e->s;
    const int p = s->p, q = s->q, o = p + 1;
    double c[3 * NF_MAX_ORDER];
    for (int a = 0; a <= p; a++) {
        int i = l - p + a;
        double *C = e->C + 3 * i;
        if (e->stamp[i] != e->row) {
            const double *P = s->cp + 3 * (i + (long)(e->k - q) * s->nu);
            double cx = 0.0, cy = 0.0, cz = 0.0;
            for (int b = 0; b <= q; b++, P += 3 * (long)s->nu) {
                cx += e->Nv[b] * P[0];
                cy += e->Nv[b] * P[1];
                cz += e->Nv[b] * P[2];
            }
            C[0] = cx, C[1] = cy, C[2] = cz;
            e->stamp[i] = e->row;
        }
        c[3 * a] = C[0], c[3 * a + 1] = C[1], c[3 * a + 2] = C[2];
    }
    const double *M = e->M + (size_t)o * o * (size_t)(l - p);
    for (int j = 0; j <= p; j++) {
        double x = 0.0, y = 0.0, z = 0.0;
        for (int a = 0; a <= p; a++) {
            x += M[j * o + a] * c[3 * a];
            y += M[j * o + a] * c[3 * a + 1];
            z += M[j * o + a] * c[3 * a + 2];
        }
        e->A[3 * j] = x, e->A[3 * j + 1] = y, e->A[3 * j + 2] = z;
    }
    e->al = l;
    e->arow = e->row;
}

/* The p+1 basis functions at t from the span's power form M (Horner). */
static void power_basis(const double *M, int p, double t, double *N)
{
    const int o = p + 1;
    for (int a = 0; a < o; a++) {
        double b = M[p * o + a];
        for (int j = p - 1; j >= 0; j--)
            b = b * t + M[j * o + a];
        N[a] = b;
    }
}

/* S at the current span l and row k from both bases, Eq. 1 as is: a point
 * whose row has no second point costs (p+1)(q+1) x 3 multiply-adds and no
 * row set-up (random order: the row path's columns and power form cost
 * three times that, redone for every point). */
static void direct(const cf_surfrow_t *e, double u, double out[3])
{
    const nf_surf_t *s = e->s;
    const int p = s->p, q = s->q;
    double Nu[NF_MAX_ORDER];
    power_basis(e->M + (size_t)(p + 1) * (p + 1) * (size_t)(e->l - p), p, u - e->mid, Nu);
    const double *P = s->cp + 3 * ((e->l - p) + (long)(e->k - q) * s->nu);
    double x = 0.0, y = 0.0, z = 0.0;
    if (p == 3) { /* the design degree, unrolled over u */
        for (int b = 0; b <= q; b++, P += 3 * (long)s->nu) {
            double cx = Nu[0] * P[0] + Nu[1] * P[3] + Nu[2] * P[6] + Nu[3] * P[9];
            double cy = Nu[0] * P[1] + Nu[1] * P[4] + Nu[2] * P[7] + Nu[3] * P[10];
            double cz = Nu[0] * P[2] + Nu[1] * P[5] + Nu[2] * P[8] + Nu[3] * P[11];
            x += e->Nv[b] * cx, y += e->Nv[b] * cy, z += e->Nv[b] * cz;
        }
    } else {
        for (int b = 0; b <= q; b++, P += 3 * (long)s->nu) {
            double cx = 0.0, cy = 0.0, cz = 0.0;
            for (int a = 0; a <= p; a++) {
                cx += Nu[a] * P[3 * a];
                cy += Nu[a] * P[3 * a + 1];
                cz += Nu[a] * P[3 * a + 2];
            }
            x += e->Nv[b] * cx, y += e->Nv[b] * cy, z += e->Nv[b] * cz;
        }
    }
    out[0] = x, out[1] = y, out[2] = z;
}

void cf_surfrow_eval_any(cf_surfrow_t *e, double u, double v, double out[3])
{
    const nf_surf_t *s = e->s;
    if (!e->C) {
        nf_surf_eval(s, u, v, out);
        return;
    }
    const int p = s->p;
    u = clampd(u, e->umin, e->umax);
    v = clampd(v, e->vmin, e->vmax);
    const int fresh = v != e->v;
    if (fresh) { /* a new row: its basis, and every column stale */
        e->v = v;
        e->k = nf_find_span_from(e->k, s->nv - 1, s->q, v, s->V, e->hv);
        const int q = s->q;
        power_basis(e->Mv + (size_t)(q + 1) * (q + 1) * (size_t)(e->k - q), q,
                    v - 0.5 * (s->V[e->k] + s->V[e->k + 1]), e->Nv);
        e->row++;
    }
    if (!(e->lo <= u && u < e->hi)) {
        const int l = nf_find_span_from(e->l, s->nu - 1, p, u, s->U, e->hu);
        e->l = l;
        e->lo = s->U[l];
        /* The last span's end is in it: u < next(umax) is u <= umax, so
         * the inline case never takes a u past the domain unclamped. */
        e->hi = l == s->nu - 1 ? nextafter(e->umax, INFINITY) : s->U[l + 1];
        e->mid = 0.5 * (s->U[l] + s->U[l + 1]);
    }
    if (fresh) { /* the row's first point: no row set-up until a second */
        direct(e, u, out);
        return;
    }
    if (e->l != e->al || e->row != e->arow)
        row_span(e, e->l);
    const double t = u - e->mid, *A = e->A;
    double x, y, z;
    if (p == 3) { /* the design degree, unrolled */
        x = ((A[9] * t + A[6]) * t + A[3]) * t + A[0];
        y = ((A[10] * t + A[7]) * t + A[4]) * t + A[1];
        z = ((A[11] * t + A[8]) * t + A[5]) * t + A[2];
    } else {
        x = A[3 * p], y = A[3 * p + 1], z = A[3 * p + 2];
        for (int j = p - 1; j >= 0; j--) {
            x = x * t + A[3 * j];
            y = y * t + A[3 * j + 1];
            z = z * t + A[3 * j + 2];
        }
    }
    out[0] = x, out[1] = y, out[2] = z;
}

void cf_surfrow_free(cf_surfrow_t *e)
{
    free(e->C);
    free(e->stamp);
    free(e->M);
    free(e->Mv);
    e->Mv = NULL;
    e->C = NULL;
    e->stamp = NULL;
    e->M = NULL;
}
