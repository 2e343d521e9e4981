/* SPDX-License-Identifier: MIT */
/* nf_footprint.h: the data footprint in parameter space (issue 14, honest
 * edges). An occupancy grid of NF_FP_SUB x NF_FP_SUB cells per knot span
 * pair counts the points as they stream in; from it come the counts a
 * report needs (cells with data, "no data" cells, the outline: cells with
 * data beside a cell without) and the control points whose support holds
 * fewer than a given number of points. Those the fit should keep at the
 * nominal P0 instead of extrapolating the data into them: the caller adds a
 * strong beta on each (nf_fit_pin, a per-control-point beta in the
 * diagonal of Eq. 7) between nf_fit_finish and nf_fit_solve.
 *
 * Memory: caller storage of NF_BYTES_FOOTPRINT(nu, nv, p, q) bytes (in
 * nf_budget.h: 32-bit counts per cell, one flag byte per control point),
 * a function of the net alone; nothing per point is kept. */
#ifndef NF_FOOTPRINT_H
#define NF_FOOTPRINT_H

#include "nf_budget.h"
#include "nf_surf.h"
#include <stddef.h>
#include <stdint.h>

/* A strong beta for pinned control points: 10^5 times the paper's default.
 * They hold no data; what moves them is the alpha term of their
 * data-bearing neighbours, by about alpha / beta of the step between data
 * and nominal (0.05 mm of a 2 mm step at beta 1, 0.1 per cent at 100). */
#define NF_FOOTPRINT_BETA 100.0

typedef struct nf_footprint {
    const nf_surf_t *s;
    int cu, cv;         /* cells in u and in v: NF_FP_SUB (nu - p), NF_FP_SUB (nv - q) */
    uint32_t *count;    /* points per cell, cell (i, j) at i + j cu */
    unsigned char *pin; /* per control point (nf_footprint_pin) */
    long long points;   /* points marked */
    double hu, hv;      /* knot spans per unit parameter (the uniform guess of a span) */
} nf_footprint_t;

typedef struct nf_footprint_stats {
    long cells;   /* cells of non-empty knot spans */
    long filled;  /* of them: holding at least one point */
    long empty;   /* of them: "no data" */
    long outline; /* filled cells with an empty 4-neighbour (the footprint's edge) */
    long pinned;  /* control points flagged by the last nf_footprint_pin */
} nf_footprint_stats_t;

/* Wire the footprint of s into mem (bytes long, at least
 * nf_footprint_bytes(s->nu, s->nv, s->p, s->q)), every count 0. NF_EARG for
 * null pointers, NF_EARENA when bytes is too small. */
int nf_footprint_init(nf_footprint_t *fp, const nf_surf_t *s, void *mem, size_t bytes);

/* Mark a point at parameters (u, v). NF_EDOMAIN outside the knot domain,
 * NF_ENONFINITE for NaN/Inf. */
int nf_footprint_add(nf_footprint_t *fp, double u, double v);

/* b's counts (the same surface's footprint) into a's, saturating as
 * nf_footprint_add does: a pass counted in parts. NF_EARG for null
 * pointers or footprints of different surfaces. */
int nf_footprint_merge(nf_footprint_t *a, const nf_footprint_t *b);

/* Mark n points whose u, v are the first two of every stride doubles from
 * rows: nf_footprint_add's cells, those it refuses skipped. The count
 * marked. (One call per batch: issue 20's pass over every point.) */
long nf_footprint_add_rows(nf_footprint_t *fp, const double *rows, long n, int stride);

/* Points in cell (i, j), 0 <= i < cu, 0 <= j < cv. */
long nf_footprint_cell(const nf_footprint_t *fp, int i, int j);

/* Parameter rectangle of cell (i, j): [u0, u1] x [v0, v1] (a zero-width
 * rectangle for the cells of an empty knot span). */
void nf_footprint_cell_box(const nf_footprint_t *fp, int i, int j, double box[4]);

/* Flag every control point whose support (its (p + 1) x (q + 1) knot spans)
 * holds fewer than min_points points; returns how many are flagged, the
 * flags in fp->pin[i + j nu]. */
long nf_footprint_pin(nf_footprint_t *fp, long min_points);

/* 1 when every control point whose basis function is non-zero somewhere in
 * cell (i, j) is pinned: there the fit follows the nominal alone. */
int nf_footprint_cell_pinned(const nf_footprint_t *fp, int i, int j);

/* Counts of cells, filled, empty, outline and pinned control points. */
void nf_footprint_stats(const nf_footprint_t *fp, nf_footprint_stats_t *st);

#endif
