/* SPDX-License-Identifier: MIT */
/* nf_knots.c: residual-driven knot choice (per-span excess, worst spans halved). */
#include "nf_knots.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <stddef.h>

int nf_spanres_init(nf_spanres_t *r, const nf_surf_t *s, double tol, double *mem)
{
    if (!r || !s || !mem || !(tol > 0.0))
        return NF_EARG;
    r->s = s;
    r->tol = tol;
    r->su = mem;
    r->sv = mem + NF_SPANRES_SLOT * (long)(s->nu - s->p);
    r->cell = r->sv + NF_SPANRES_SLOT * (long)(s->nv - s->q);
    for (double *c = mem; c < r->cell; c += NF_SPANRES_SLOT) {
        c[0] = c[1] = 0.0;
        c[2] = HUGE_VAL;
        c[3] = -HUGE_VAL;
    }
    for (long i = 0; i < NF_SPANRES_CELL * (long)(s->nu - s->p) * (s->nv - s->q); i++)
        r->cell[i] = 0.0;
    r->out = r->all = r->rej = 0;
    r->e2 = 0.0;
    return NF_OK;
}

/* The point's span slots and cell, its data range and count taken;
 * NULL slots for non-finite parameters. */
static void locate(nf_spanres_t *r, double u, double v, double **a, double **b, double **c)
{
    const nf_surf_t *s = r->s;
    *a = *b = *c = NULL;
    if (!isfinite(u) || !isfinite(v))
        return;
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    u = u < u0 ? u0 : (u > u1 ? u1 : u);
    v = v < v0 ? v0 : (v > v1 ? v1 : v);
    const int l = nf_find_span(s->nu - 1, s->p, u, s->U),
              k = nf_find_span(s->nv - 1, s->q, v, s->V);
    double *sa = r->su + NF_SPANRES_SLOT * (l - s->p), *sb = r->sv + NF_SPANRES_SLOT * (k - s->q);
    sa[2] = u < sa[2] ? u : sa[2];
    sa[3] = u > sa[3] ? u : sa[3];
    sb[2] = v < sb[2] ? v : sb[2];
    sb[3] = v > sb[3] ? v : sb[3];
    *c = r->cell + NF_SPANRES_CELL * ((l - s->p) + (long)(k - s->q) * (s->nu - s->p));
    (*c)[0] += 1.0;
    r->all++;
    *a = sa;
    *b = sb;
}

void nf_spanres_add(nf_spanres_t *r, double u, double v, double d)
{
    double *a, *b, *c;
    locate(r, u, v, &a, &b, &c);
    const double e = fabs(d) - r->tol, e2 = e * e;
    if (!a || !(e > 0.0) || !isfinite(e))
        return;
    a[0] += 1.0;
    a[1] += e2;
    b[0] += 1.0;
    b[1] += e2;
    r->out++;
    r->e2 += e2;
}

void nf_spanres_add_rejected(nf_spanres_t *r, double u, double v, double d)
{
    double *a, *b, *c;
    locate(r, u, v, &a, &b, &c);
    const double e = fabs(d) - r->tol;
    if (!a || !(e > 0.0) || !isfinite(e))
        return;
    c[1] += 1.0;
    c[2] += e * e;
    r->rej++;
}

int nf_spanres_fold(nf_spanres_t *r)
{
    const nf_surf_t *s = r->s;
    const int nsu = s->nu - s->p, nsv = s->nv - s->q;
    const double share = r->all > 0 ? (double)r->rej / (double)r->all : 0.0;
    int folded = 0;
    for (int k = 0; k < nsv; k++)
        for (int l = 0; l < nsu; l++) {
            double *c = r->cell + NF_SPANRES_CELL * (l + (long)k * nsu);
            if (!(c[1] >= NF_KNOTS_MIN_REJ) || !(c[1] >= NF_KNOTS_COHERENT * share * c[0]))
                continue;
            double *a = r->su + NF_SPANRES_SLOT * l, *b = r->sv + NF_SPANRES_SLOT * k;
            a[0] += c[1];
            a[1] += c[2];
            b[0] += c[1];
            b[1] += c[2];
            r->out += (long)c[1];
            r->e2 += c[2];
            c[1] = c[2] = 0.0;
            folded++;
        }
    return folded;
}

/* Span i ranks before span j: more excess, or as much and a lower index
 * (a strict total order, so picks can be found again without marks). */
static int before(const double *slot, int i, int j)
{
    double a = slot[NF_SPANRES_SLOT * i + 1], b = slot[NF_SPANRES_SLOT * j + 1];
    return a > b || (a == b && i < j);
}

int nf_spanres_pick(const nf_spanres_t *r, int dir, int max, double *X, int *spread)
{
    const nf_surf_t *s = r->s;
    const int deg = dir ? s->q : s->p, n = dir ? s->nv : s->nu;
    const double *T = dir ? s->V : s->U, *slot = dir ? r->sv : r->su;
    const int ns = n - deg;
    double total = 0.0, got = 0.0;
    int nonempty = 0, m = 0, last = -1;
    if (spread)
        *spread = 0;
    for (int i = 0; i < ns; i++) {
        total += slot[NF_SPANRES_SLOT * i + 1];
        nonempty += T[deg + i] < T[deg + i + 1];
    }
    if (!(total > 0.0) || max <= 0 || !X)
        return 0;
    /* Selection by rank, O(spans) per pick: the next span is the best
     * eligible one ranked after the last pick. */
    while (m < max && got < NF_KNOTS_SHARE * total) {
        int best = -1;
        for (int i = 0; i < ns; i++) {
            const double *c = slot + NF_SPANRES_SLOT * i;
            const double mid = 0.5 * (T[deg + i] + T[deg + i + 1]);
            if (!(c[1] > 0.0) || !(T[deg + i] < T[deg + i + 1]) || !(c[2] < mid && mid < c[3]))
                continue;
            if (last >= 0 && !before(slot, last, i))
                continue;
            if (best < 0 || before(slot, i, best))
                best = i;
        }
        if (best < 0)
            break;
        const double x = 0.5 * (T[deg + best] + T[deg + best + 1]);
        /* Insertion sort: the picks are few. */
        int j = m;
        while (j > 0 && X[j - 1] > x) {
            X[j] = X[j - 1];
            j--;
        }
        X[j] = x;
        m++;
        got += slot[NF_SPANRES_SLOT * best + 1];
        last = best;
    }
    if (spread)
        *spread = (double)m > NF_KNOTS_SPREAD * (double)nonempty;
    return m;
}

void nf_spanres_choose(const nf_spanres_t *r, int maxu, double *Xu, int *ru, int maxv, double *Xv,
                       int *rv)
{
    int su = 0, sv = 0;
    *ru = nf_spanres_pick(r, 0, maxu, Xu, &su);
    *rv = nf_spanres_pick(r, 1, maxv, Xv, &sv);
    if (*ru > 0 && *rv > 0 && su != sv) {
        if (su)
            *ru = 0;
        else
            *rv = 0;
    }
}
