/* SPDX-License-Identifier: MIT */
/* sim_part.c: the part under the simulated probe: a nominal surface (the
 * built-in panel or an IGES entity 128) plus cf_part's dent and warp, and
 * its height above a point (x, y): the nominal's (u, v) with S_xy(u, v) =
 * (x, y) by Newton from the nearest sample of a seed grid. */
#include "cf_iges.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "sim.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SIM_SEED_NS 64

static int seed_grid(sim_part_t *p, char *msg, size_t len)
{
    p->ns = SIM_SEED_NS;
    p->seed = malloc(sizeof(double) * 4 * (size_t)(p->ns * p->ns));
    if (!p->seed) {
        snprintf(msg, len, "out of memory");
        return -1;
    }
    double u0, u1, v0, v1;
    nf_surf_domain(&p->s, &u0, &u1, &v0, &v1);
    for (int j = 0; j < p->ns; j++)
        for (int i = 0; i < p->ns; i++) {
            double u = u0 + (u1 - u0) * i / (p->ns - 1), v = v0 + (v1 - v0) * j / (p->ns - 1);
            double P[3], *q = p->seed + 4 * (i + j * p->ns);
            nf_surf_eval(&p->s, u, v, P);
            q[0] = P[0];
            q[1] = P[1];
            q[2] = u;
            q[3] = v;
        }
    return 0;
}

int sim_part_builtin(sim_part_t *p, char *msg, size_t len)
{
    memset(p, 0, sizeof *p);
    cf_part_default(&p->pt);
    if (cf_surf_alloc(&p->s, 3, 3, 40, 30)) { /* as `cellfit gen` writes it */
        snprintf(msg, len, "out of memory");
        return -1;
    }
    cf_part_nominal(&p->pt, &p->s);
    return seed_grid(p, msg, len);
}

int sim_part_iges(sim_part_t *p, const char *path, char *msg, size_t len)
{
    memset(p, 0, sizeof *p);
    cf_part_default(&p->pt);
    if (cf_surfio_read(path, 0, &p->s, msg, len))
        return -1;
    return seed_grid(p, msg, len);
}

void sim_part_free(sim_part_t *p)
{
    cf_surf_free(&p->s);
    free(p->seed);
    p->seed = NULL;
}

/* The seed sample nearest to (x, y): a start for Newton. */
static void seed_near(const sim_part_t *p, double x, double y, double uv[2])
{
    double best = INFINITY;
    for (int k = 0; k < p->ns * p->ns; k++) {
        const double *q = p->seed + 4 * k;
        double d = (q[0] - x) * (q[0] - x) + (q[1] - y) * (q[1] - y);
        if (d < best) {
            best = d;
            uv[0] = q[2];
            uv[1] = q[3];
        }
    }
}

int sim_part_z(const sim_part_t *p, double x, double y, double *z)
{
    double uv[2] = {NAN, NAN};
    return sim_part_z_near(p, x, y, uv, z);
}

int sim_part_z_near(const sim_part_t *p, double x, double y, double uv[2], double *z)
{
    if (!isfinite(uv[0]) || !isfinite(uv[1]))
        seed_near(p, x, y, uv);
    double u = uv[0], v = uv[1];
    double u0, u1, v0, v1;
    nf_surf_domain(&p->s, &u0, &u1, &v0, &v1);
    double r = INFINITY, skl[27];
    for (int it = 0; it < 40; it++) {
        nf_surf_derivs(&p->s, u, v, 1, skl);
        double fx = skl[0] - x, fy = skl[1] - y;
        r = hypot(fx, fy);
        if (r < 1e-9)
            break;
        /* S_u = skl[9..11], S_v = skl[3..5] (nf_surf.h's layout). */
        double a = skl[9], b = skl[3], c = skl[10], d = skl[4], det = a * d - b * c;
        if (fabs(det) < 1e-300)
            break;
        double du = (d * fx - b * fy) / det, dv = (-c * fx + a * fy) / det;
        u = fmin(fmax(u - du, u0), u1);
        v = fmin(fmax(v - dv, v0), v1);
    }
    nf_surf_derivs(&p->s, u, v, 0, skl);
    r = hypot(skl[0] - x, skl[1] - y);
    uv[0] = u;
    uv[1] = v;
    if (!(r < 1e-6))
        return 1; /* (x, y) is off the part's footprint */
    *z = skl[2] + cf_part_deviation(&p->pt, x, y);
    return 0;
}
