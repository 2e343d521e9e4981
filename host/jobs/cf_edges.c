/* SPDX-License-Identifier: MIT */
/* cf_edges.c: the footprint of a fit pass and the pins of the control
 * points no data determine, to the nominal in the pass's knots (cf_edges.h). */
#include "cf_edges.h"
#include "cf_err.h"
#include "cf_surf.h"
#include "nf_refine.h"
#include <stdlib.h>
#include <string.h>

int cf_edges_begin(cf_edges_t *e, const nf_surf_t *cur)
{
    memset(e, 0, sizeof *e);
    long b = nf_footprint_bytes(cur->nu, cur->nv, cur->p, cur->q);
    if (b < 0)
        return (int)b;
    if (!(e->mem = malloc((size_t)b)))
        return CF_ENOMEM;
    int rc = nf_footprint_init(&e->fp, cur, e->mem, (size_t)b);
    if (rc) {
        free(e->mem);
        e->mem = NULL;
    }
    return rc;
}

void cf_edges_add(cf_edges_t *e, double u, double v)
{
    if (e->mem)
        nf_footprint_add(&e->fp, u, v); /* NF_EDOMAIN, NF_ENONFINITE: not counted */
}

void cf_edges_add_rows(cf_edges_t *e, const double *rows, long n, int stride)
{
    if (e->mem)
        nf_footprint_add_rows(&e->fp, rows, n, stride);
}

/* The knots of B not in A (both non-decreasing, A's a sub-multiset of
 * B's), at most r of them into X; the count, or -1 when A is not nested. */
static int knot_diff(const double *A, int na, const double *B, int nb, double *X)
{
    int i = 0, r = 0;
    for (int k = 0; k < nb; k++) {
        if (i < na && A[i] == B[k]) {
            i++;
            continue;
        }
        if (i < na && A[i] < B[k])
            return -1; /* a knot of A missing from B */
        X[r++] = B[k];
    }
    return i == na ? r : -1;
}

/* s refined in one direction by the knots X (r of them). */
static int insert(nf_surf_t *s, const double *X, int r, int in_v)
{
    if (r == 0)
        return 0;
    nf_surf_t out;
    if (cf_surf_alloc(&out, s->p, s->q, in_v ? s->nu : s->nu + r, in_v ? s->nv + r : s->nv))
        return CF_ENOMEM;
    int rc = in_v ? nf_refine_v(s, X, r, &out) : nf_refine_u(s, X, r, &out);
    if (rc) {
        cf_surf_free(&out);
        return rc;
    }
    cf_surf_free(s);
    *s = out;
    return 0;
}

int cf_edges_nominal(const nf_surf_t *nominal, const nf_surf_t *cur, nf_surf_t *out)
{
    memset(out, 0, sizeof *out);
    if (nominal->p != cur->p || nominal->q != cur->q)
        return CF_EARG;
    int nu = cur->nu + cur->p + 1, nv = cur->nv + cur->q + 1;
    double *X = malloc(sizeof(double) * (size_t)(nu > nv ? nu : nv));
    if (!X)
        return CF_ENOMEM;
    int rc = cf_surf_copy(out, nominal) ? CF_ENOMEM : 0;
    int ru = knot_diff(nominal->U, nominal->nu + nominal->p + 1, cur->U, nu, X);
    if (!rc && (ru < 0 || ru != cur->nu - nominal->nu))
        rc = CF_EARG;
    if (!rc)
        rc = insert(out, X, ru, 0);
    int rv = knot_diff(nominal->V, nominal->nv + nominal->q + 1, cur->V, nv, X);
    if (!rc && (rv < 0 || rv != cur->nv - nominal->nv))
        rc = CF_EARG;
    if (!rc)
        rc = insert(out, X, rv, 1);
    free(X);
    if (rc)
        cf_surf_free(out);
    return rc;
}

long cf_edges_pin(cf_edges_t *e, const nf_surf_t *nominal, cf_fitpass_t *ps)
{
    e->pinned = 0;
    if (!e->mem)
        return 0;
    long n = nf_footprint_pin(&e->fp, CF_EDGES_MIN_POINTS);
    if (n == 0)
        return 0;
    cf_surf_free(&e->nom);
    int rc = cf_edges_nominal(nominal, e->fp.s, &e->nom);
    if (rc)
        return rc;
    ps->pin = e->fp.pin;
    ps->pin_to = e->nom.cp;
    ps->pin_beta = NF_FOOTPRINT_BETA;
    return e->pinned = n;
}

void cf_edges_free(cf_edges_t *e)
{
    free(e->mem);
    e->mem = NULL;
    cf_surf_free(&e->nom);
}
