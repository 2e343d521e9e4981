/* SPDX-License-Identifier: MIT */
/* cf_fpmap.c: the data footprint of a report, its counts and its marks on
 * the deviation map (cf_fpmap.h). */
#include "cf_fpmap.h"
#include "cf_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Samples along an edge of a cell at most this many (a cell's side on the
 * map is at most the map: about 915 cells of the raster). */
#define FP_MAXS 2048

int cf_fpmap_init(cf_fpmap_t *f, const nf_surf_t *s)
{
    memset(f, 0, sizeof *f);
    long b = nf_footprint_bytes(s->nu, s->nv, s->p, s->q);
    if (b < 0)
        return (int)b;
    if (!(f->mem = malloc((size_t)b)))
        return CF_ENOMEM;
    int rc = nf_footprint_init(&f->fp, s, f->mem, (size_t)b);
    if (rc) {
        free(f->mem);
        f->mem = NULL;
    }
    return rc;
}

void cf_fpmap_add(cf_fpmap_t *f, double u, double v, int clamped)
{
    if (f->mem && !clamped)
        nf_footprint_add(&f->fp, u, v); /* outside the domain, non-finite: not counted */
}

void cf_fpmap_stats(const cf_fpmap_t *f, nf_footprint_stats_t *st)
{
    if (f->mem)
        nf_footprint_stats(&f->fp, st);
    else
        memset(st, 0, sizeof *st);
}

static double dist3(const double a[3], const double b[3])
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* Samples per side of a parameter rectangle so that neighbours lie at most
 * half a raster cell apart (the chords of its sides, the surface being
 * smooth within a cell). */
static int samples(const nf_surf_t *s, const double box[4], double pitch)
{
    double c[4][3];
    nf_surf_eval(s, box[0], box[2], c[0]);
    nf_surf_eval(s, box[1], box[2], c[1]);
    nf_surf_eval(s, box[0], box[3], c[2]);
    nf_surf_eval(s, box[1], box[3], c[3]);
    double len = fmax(fmax(dist3(c[0], c[1]), dist3(c[2], c[3])),
                      fmax(dist3(c[0], c[2]), dist3(c[1], c[3])));
    double n = ceil(2.0 * len / pitch) + 1;
    return n < 2 ? 2 : n > FP_MAXS ? FP_MAXS : (int)n;
}

static int empty_at(const nf_footprint_t *fp, int i, int j)
{
    return nf_footprint_cell(fp, i, j) == 0;
}

int cf_fpmap_mark(const cf_fpmap_t *f, cf_devmap_t *m)
{
    const double pitch = cf_devmap_pitch(m);
    if (!f->mem || !(pitch > 0))
        return CF_EARG;
    const nf_footprint_t *fp = &f->fp;
    const nf_surf_t *s = fp->s;
    for (int j = 0; j < fp->cv; j++)
        for (int i = 0; i < fp->cu; i++) {
            double b[4], P[3];
            nf_footprint_cell_box(fp, i, j, b);
            if (!(b[0] < b[1] && b[2] < b[3]))
                continue; /* a cell of an empty knot span */
            const int n = samples(s, b, pitch);
            if (empty_at(fp, i, j)) { /* hatched all over */
                for (int y = 0; y < n; y++)
                    for (int x = 0; x < n; x++) {
                        nf_surf_eval(s, b[0] + (b[1] - b[0]) * x / (n - 1),
                                     b[2] + (b[3] - b[2]) * y / (n - 1), P);
                        cf_devmap_mark(m, P, CF_DEVMAP_NODATA);
                    }
                continue;
            }
            /* A cell with data: its sides toward an empty neighbour are
             * the outline (left, right, below, above). */
            const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
            for (int t = 0; t < 4; t++) {
                const int a = nb[t][0], c = nb[t][1];
                if (a < 0 || a >= fp->cu || c < 0 || c >= fp->cv || !empty_at(fp, a, c))
                    continue;
                double nbx[4];
                nf_footprint_cell_box(fp, a, c, nbx);
                if (!(nbx[0] < nbx[1] && nbx[2] < nbx[3]))
                    continue;
                for (int k = 0; k < n; k++) {
                    double w = (double)k / (n - 1);
                    double u = t < 2 ? b[t] : b[0] + (b[1] - b[0]) * w;
                    double v = t < 2 ? b[2] + (b[3] - b[2]) * w : b[t];
                    nf_surf_eval(s, u, v, P);
                    cf_devmap_mark(m, P, CF_DEVMAP_OUTLINE);
                }
            }
        }
    return 0;
}

void cf_fpmap_free(cf_fpmap_t *f)
{
    free(f->mem);
    f->mem = NULL;
}
