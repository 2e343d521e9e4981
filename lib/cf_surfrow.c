/* SPDX-License-Identifier: MIT */
/* cf_surfrow.c: fast evaluation of a surface at points in rows of one v
 * (the residual pass of a fit: issue 20). S(u, v) = sum_a N_a(u) C_a(v)
 * with C_a(v) = sum_b N_b(v) P_ab (Eq. 1 with the sums regrouped). */
#include "cf_surfrow.h"
#include "cf_err.h"
#include <stdlib.h>
#include <string.h>

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

int cf_surfrow_init(cf_surfrow_t *e, const nf_surf_t *s)
{
    memset(e, 0, sizeof *e);
    e->s = s;
    e->l = -1;
    e->k = -1;
    /* Rational (weights not all equal): nf_surf_eval. Equal weights cancel
     * in Eq. 1 (the basis sums to 1), so such a net is polynomial. */
    for (long i = 1; s->w && i < (long)s->nu * s->nv; i++)
        if (s->w[i] != s->w[0])
            return CF_OK;
    e->C = malloc(sizeof(double) * 3 * (size_t)s->nu);
    e->stamp = malloc(sizeof(long) * (size_t)s->nu);
    if (!e->C || !e->stamp) {
        cf_surfrow_free(e);
        return CF_ENOMEM;
    }
    for (int i = 0; i < s->nu; i++)
        e->stamp[i] = -1;
    e->row = -1;
    e->v = s->V[s->q] - 1.0; /* no row yet */
    e->hu = (s->nu - s->p) / (s->U[s->nu] - s->U[s->p]);
    e->hv = (s->nv - s->q) / (s->V[s->nv] - s->V[s->q]);
    return CF_OK;
}

void cf_surfrow_eval(cf_surfrow_t *e, double u, double v, double out[3])
{
    const nf_surf_t *s = e->s;
    if (!e->C) {
        nf_surf_eval(s, u, v, out);
        return;
    }
    const int p = s->p, q = s->q;
    u = clampd(u, s->U[p], s->U[s->nu]);
    v = clampd(v, s->V[q], s->V[s->nv]);
    if (v != e->v) { /* a new row: its basis, and every column stale */
        e->v = v;
        e->k = nf_find_span_from(e->k, s->nv - 1, q, v, s->V, e->hv);
        nf_basis_funs(e->k, v, q, s->V, e->Nv);
        e->row++;
    }
    int l = nf_find_span_from(e->l, s->nu - 1, p, u, s->U, e->hu);
    if (l != e->l) {
        nf_basis_recip(l, p, s->U, e->recip);
        e->l = l;
    }
    double Nu[NF_MAX_ORDER];
    nf_basis_funs_r(l, u, p, s->U, e->recip, Nu);
    double x = 0.0, y = 0.0, z = 0.0;
    for (int a = 0; a <= p; a++) {
        int i = l - p + a;
        double *c = e->C + 3 * i;
        if (e->stamp[i] != e->row) {
            const double *P = s->cp + 3 * (i + (long)(e->k - q) * s->nu);
            double cx = 0.0, cy = 0.0, cz = 0.0;
            for (int b = 0; b <= q; b++, P += 3 * (long)s->nu) {
                cx += e->Nv[b] * P[0];
                cy += e->Nv[b] * P[1];
                cz += e->Nv[b] * P[2];
            }
            c[0] = cx, c[1] = cy, c[2] = cz;
            e->stamp[i] = e->row;
        }
        x += Nu[a] * c[0];
        y += Nu[a] * c[1];
        z += Nu[a] * c[2];
    }
    out[0] = x, out[1] = y, out[2] = z;
}

void cf_surfrow_free(cf_surfrow_t *e)
{
    free(e->C);
    free(e->stamp);
    e->C = NULL;
    e->stamp = NULL;
}
