/* cf_seedgrid.h: start points for projection in O(1) per point: the seed
 * samples of nf_seed (a grid of surface points at uniform parameters) are
 * binned into a uniform 3-D cell grid, and the nearest sample to Q is found
 * by searching cells in growing shells around Q's cell. Host memory: one
 * int per cell and per sample, fixed by the seed, never by the points. */
#ifndef CF_SEEDGRID_H
#define CF_SEEDGRID_H

#include "nf_project.h"

typedef struct cf_seedgrid {
    nf_seed_t seed;
    double *pts; /* the seed's samples (owned) */
    int dim[3];
    double lo[3], cell;
    int *head, *next; /* per cell: first sample; per sample: next in its cell, -1 ends */
} cf_seedgrid_t;

/* Samples of s (about `per_span` per knot span and direction, capped) and
 * their cells. CF_ENOMEM on allocation failure. */
int cf_seedgrid_init(cf_seedgrid_t *g, const nf_surf_t *s, int per_span);
/* Parameters of the sample nearest Q (exact nearest among the samples). */
void cf_seedgrid_start(const cf_seedgrid_t *g, const double Q[3], double *u0, double *v0);
void cf_seedgrid_free(cf_seedgrid_t *g);

#endif
