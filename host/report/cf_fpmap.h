/* SPDX-License-Identifier: MIT */
/* cf_fpmap.h: the data footprint of an inspection report (issue 14, honest
 * edges): the points' feet on the surface counted per footprint cell
 * (nf_footprint: NF_FP_SUB x NF_FP_SUB cells per knot span pair of the
 * surface), the counts a report gives (cells, with data, "no data",
 * outline, the share with data), and the marks on the deviation map: each
 * "no data" cell hatched, the edges between a cell with data and one
 * without drawn as the footprint's outline (the surface sampled finer than
 * the map's raster, cf_devmap_mark). Feet clamped to the boundary are not
 * counted (the point lies beyond the surface, not on it).
 *
 * Memory: NF_BYTES_FOOTPRINT of the surface's net; nothing per point. */
#ifndef CF_FPMAP_H
#define CF_FPMAP_H

#include "cf_devmap.h"
#include "nf_footprint.h"

typedef struct cf_fpmap {
    nf_footprint_t fp;
    void *mem;
} cf_fpmap_t;

/* The footprint of surface s (s stays the caller's). 0, CF_ENOMEM, or the
 * footprint's nf_err_t. */
int cf_fpmap_init(cf_fpmap_t *f, const nf_surf_t *s);

/* A foot at (u, v); clamped feet (clamped != 0) are not counted. */
void cf_fpmap_add(cf_fpmap_t *f, double u, double v, int clamped);

/* cells, filled, empty ("no data") and outline (filled cells with an empty
 * 4-neighbour) of the non-empty knot spans (nf_footprint_stats). */
void cf_fpmap_stats(const cf_fpmap_t *f, nf_footprint_stats_t *st);

/* Hatch the "no data" cells and draw the outline on m (after
 * cf_devmap_begin). 0 or CF_EARG. */
int cf_fpmap_mark(const cf_fpmap_t *f, cf_devmap_t *m);

void cf_fpmap_free(cf_fpmap_t *f);

#endif
