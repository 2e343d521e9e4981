/* SPDX-License-Identifier: MIT */
/* cf_seedgrid.h: start points for projection in O(1) per point. First
 * choice: the quadrilateral decomposition of nf_quad (Piegl & Tiller 2001,
 * Section 3: the nearest quadrilateral by a 2-D grid in the maximum-area
 * plane). Fallback, where the quadrilaterals cannot serve (the surface
 * folds over in that plane, or needs more than CF_SEEDGRID_MAXQ of them):
 * the seed samples of nf_seed (a grid of surface points at uniform
 * parameters) binned into a uniform 3-D cell grid, the nearest sample to Q
 * found by searching cells in growing shells around Q's cell, and every
 * valley's start within reach of it (each grid cell's own reach: a long
 * chord at a stretched edge widens only the band there). Host memory:
 * fixed by the surface, never by the points. */
#ifndef CF_SEEDGRID_H
#define CF_SEEDGRID_H

#include "nf_project.h"
#include "nf_quad.h"

/* Quadrilaterals at most (NF_QUAD_BYTES(CF_SEEDGRID_MAXQ, ...), about 20 MB). */
#define CF_SEEDGRID_MAXQ 65536L

typedef struct cf_seedgrid {
    nf_seed_t seed; /* seed.s is the surface in either mode */
    int use_quad;   /* 1: quad holds the decomposition; the rest is unused */
    nf_quad_t quad;
    void *qmem;
    double *pf;  /* the quadrilaterals' Newton: its power form (nf_quad_power) */
    double *pts; /* the seed's samples (owned) */
    int dim[3];
    double lo[3], cell;
    int *head, *next; /* per cell: first sample; per sample: next in its cell, -1 ends */
    /* Reaches, rounded up to float (a cell grid of 4 M cells: 16 MB):
     * per sample twice the longest chord of the grid cells at it, per cell
     * the largest of its samples' (0: none), per row of cells along x
     * (y, z) the largest of its cells'. */
    float *sreach, *breach, *rreach;
} cf_seedgrid_t;

/* Samples of s (about `per_span` per knot span and direction, capped) and
 * their cells. CF_ENOMEM on allocation failure. */
int cf_seedgrid_init(cf_seedgrid_t *g, const nf_surf_t *s, int per_span);
/* Below this many points to project, the quadrilaterals are the paper's
 * (NF_QUAD_REL_TOL), not the finer NF_QUAD_SEED_TOL: building the finer
 * blanket costs more than its closer starts save (callgrind, the loop on
 * 3,833 points: 140 -> 123 M instructions; 15,933: 596 -> 579 M). */
#define CF_SEEDGRID_FINE_POINTS 100000L
/* cf_seedgrid_init for about `points` projections (< 0: not known, the
 * finer blanket). */
int cf_seedgrid_init_n(cf_seedgrid_t *g, const nf_surf_t *s, int per_span, long points);
/* Start parameters for Q: nf_quad_start, or the seed sample nearest Q
 * (exact nearest among the samples). */
void cf_seedgrid_start(const cf_seedgrid_t *g, const double Q[3], double *u0, double *v0);
/* The whole projection to tol of the domain: nf_quad_project, or over a
 * fold nf_project_starts from the nearest sample and the other valleys'
 * starts within its band (the nearest sample alone put 16 in 10^4 feet of
 * a hemmed plate on the wrong layer: tests/unit/test_foot.c). nf_project's
 * codes. */
int cf_seedgrid_project(cf_seedgrid_t *g, const double Q[3], double tol, nf_proj_t *out);
/* Foot *io of Q (Newton's, a local minimum) made the nearest: over a fold
 * the feet from every valley's start within |io->dist| + reach (the
 * search's band: no nearer foot lies outside it) replace it if nearer;
 * Newton in nq (NULL or creased: nf_project_starts). NF_OK, NF_ENOCONV
 * when the foot kept did not converge, or nf_project's errors (io kept). */
int cf_seedgrid_nearer(const cf_seedgrid_t *g, const nf_quad_t *nq, const double Q[3], double tol,
                       nf_proj_t *io);
void cf_seedgrid_free(cf_seedgrid_t *g);

#endif
