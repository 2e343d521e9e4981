/* SPDX-License-Identifier: MIT */
/* cf_part.c: the synthetic part (nominal panel plus dent, warp, bump, ridge). */
#include "cf_part.h"
#include "nf_basis.h"
#include <math.h>

void cf_part_default(cf_part_t *pt)
{
    pt->len_x = 200.0;
    pt->len_y = 150.0;
    pt->crown = 12.0;
    pt->dent_depth = 0.4;
    pt->dent_x = 130.0;
    pt->dent_y = 60.0;
    pt->dent_r = 15.0;
    pt->warp = 0.3;
    pt->bump_h = pt->bump_x = pt->bump_y = 0.0;
    pt->bump_r = 1.0;
    pt->ridge_h = pt->ridge_x = 0.0;
    pt->ridge_w = 1.0;
}

static double crown_z(const cf_part_t *pt, double x, double y)
{
    double a = 2.0 * x / pt->len_x - 1.0, b = 2.0 * y / pt->len_y - 1.0;
    return pt->crown * (1.0 - 0.6 * a * a - 0.4 * b * b + 0.1 * a * b);
}

void cf_part_nominal(const cf_part_t *pt, nf_surf_t *s)
{
    const int p = s->p, q = s->q;
    for (int i = 0; i <= p; i++) {
        s->U[i] = 0.0;
        s->U[s->nu + i] = 1.0;
    }
    for (int i = p + 1; i < s->nu; i++)
        s->U[i] = (double)(i - p) / (s->nu - p);
    for (int j = 0; j <= q; j++) {
        s->V[j] = 0.0;
        s->V[s->nv + j] = 1.0;
    }
    for (int j = q + 1; j < s->nv; j++)
        s->V[j] = (double)(j - q) / (s->nv - q);
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            /* Greville placement reproduces x and y exactly (linear precision). */
            double x = pt->len_x * nf_greville(i, p, s->U), y = pt->len_y * nf_greville(j, q, s->V);
            double *P = s->cp + 3 * (i + (long)j * s->nu);
            P[0] = x;
            P[1] = y;
            P[2] = crown_z(pt, x, y);
            s->w[i + (long)j * s->nu] = 1.0;
        }
}

double cf_part_deviation(const cf_part_t *pt, double x, double y)
{
    double dx = x - pt->dent_x, dy = y - pt->dent_y;
    double dent = -pt->dent_depth * exp(-2.0 * (dx * dx + dy * dy) / (pt->dent_r * pt->dent_r));
    double warp = pt->warp * (x / pt->len_x - 0.5) * (y / pt->len_y - 0.5) * 4.0;
    double z = dent + warp;
    if (pt->bump_h != 0.0) {
        double bx = x - pt->bump_x, by = y - pt->bump_y;
        z += pt->bump_h * exp(-2.0 * (bx * bx + by * by) / (pt->bump_r * pt->bump_r));
    }
    if (pt->ridge_h != 0.0) {
        double rx = x - pt->ridge_x;
        z += pt->ridge_h * exp(-2.0 * rx * rx / (pt->ridge_w * pt->ridge_w));
    }
    return z;
}

void cf_part_true_point(const cf_part_t *pt, const nf_surf_t *nominal, double u, double v,
                        double out[3])
{
    nf_surf_eval(nominal, u, v, out);
    out[2] += cf_part_deviation(pt, out[0], out[1]);
}
