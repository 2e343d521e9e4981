/* SPDX-License-Identifier: MIT */
/* cf_surf.c: heap storage for surfaces on the host side. */
#include "cf_surf.h"
#include "cf_err.h"
#include <stdlib.h>
#include <string.h>

int cf_surf_alloc(nf_surf_t *s, int p, int q, int nu, int nv)
{
    memset(s, 0, sizeof *s);
    if (p < 1 || q < 1 || nu < 1 || nv < 1)
        return CF_EARG;
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, p, q), sizeof(double));
    if (!mem)
        return CF_ENOMEM;
    nf_surf_wire(s, p, q, nu, nv, mem);
    return CF_OK;
}

void cf_surf_free(nf_surf_t *s)
{
    if (s && s->U)
        free(s->U); /* U is the start of the single block */
    if (s)
        memset(s, 0, sizeof *s);
}

int cf_surf_copy(nf_surf_t *dst, const nf_surf_t *src)
{
    int rc = cf_surf_alloc(dst, src->p, src->q, src->nu, src->nv);
    if (rc)
        return rc;
    long n = (long)src->nu * src->nv;
    memcpy(dst->U, src->U, sizeof(double) * (size_t)(src->nu + src->p + 1));
    memcpy(dst->V, src->V, sizeof(double) * (size_t)(src->nv + src->q + 1));
    memcpy(dst->cp, src->cp, sizeof(double) * (size_t)(3 * n));
    if (src->w)
        memcpy(dst->w, src->w, sizeof(double) * (size_t)n);
    return CF_OK;
}

int cf_surf_square(nf_surf_t *s, int p, int side)
{
    if (side < p + 1)
        side = p + 1;
    int rc = cf_surf_alloc(s, p, p, side, side);
    if (rc)
        return rc;
    for (int i = 0; i <= p; i++) {
        s->U[i] = s->V[i] = 0.0;
        s->U[side + i] = s->V[side + i] = 1.0;
    }
    for (int i = p + 1; i < side; i++)
        s->U[i] = s->V[i] = (double)(i - p) / (side - p);
    for (int j = 0; j < side; j++)
        for (int i = 0; i < side; i++) {
            double *P = s->cp + 3 * (i + (long)j * side);
            P[0] = 100.0 * i / (side - 1);
            P[1] = 100.0 * j / (side - 1);
            P[2] = 0.0;
        }
    return CF_OK;
}
