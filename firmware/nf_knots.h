/* SPDX-License-Identifier: MIT */
/* nf_knots.h: where to insert knots in the fitting loop (Brujic et al. 2010,
 * Section 2.2: fit, reparameterise, insert knots until the tolerance holds).
 * Residual-driven refinement: per knot span in u and per span in v, the
 * points out of tolerance and their squared excess (|d| - tol)^2 are
 * accumulated while the points stream by (O(spans) memory, never O(points));
 * the spans holding most of the excess are then halved, so that control
 * points go where the fit misses instead of everywhere (uniform
 * refinement, nf_refine_uniform). A span is split only when measured
 * points lie on both sides of its midpoint: a span narrower than the
 * spacing of the data would leave control points that no point determines,
 * free to wiggle between the scan lines.
 * Storage is the caller's: NF_SPANRES_DOUBLES(nu, nv, p, q) doubles. */
#ifndef NF_KNOTS_H
#define NF_KNOTS_H

#include "nf_surf.h"

/* Share of the total squared excess the chosen spans of one direction hold
 * (the worst spans first), and the largest share of its spans a direction
 * may pick and still count as concentrated (see nf_spanres_pick). */
#define NF_KNOTS_SHARE 0.8
#define NF_KNOTS_SPREAD 0.5

/* Per span slot: points out of tolerance, their sum of e^2 (e = |d| - tol),
 * and the smallest and largest parameter of all points in the span. */
#define NF_SPANRES_SLOT 4
/* Per cell (span in u x span in v): points, and the points out of tolerance
 * that a robust fit rejected with their sum of e^2 (nf_spanres_fold). */
#define NF_SPANRES_CELL 3
#define NF_SPANRES_DOUBLES(nu, nv, p, q)                                                           \
    (NF_SPANRES_SLOT * ((long)(nu) - (p) + (long)(nv) - (q)) +                                     \
     NF_SPANRES_CELL * ((long)(nu) - (p)) * ((long)(nv) - (q)))

/* Rejected points of a cell are a feature the net cannot follow yet, not
 * spikes, when there are at least NF_KNOTS_MIN_REJ of them and their share
 * of the cell's points is NF_KNOTS_COHERENT times the share over all cells
 * (spikes fall everywhere alike; a feature's misfit is in one place). */
#define NF_KNOTS_COHERENT 4.0
#define NF_KNOTS_MIN_REJ 4

typedef struct nf_spanres {
    const nf_surf_t *s; /* the surface whose knot spans are counted */
    double tol;         /* |d| above tol is out of tolerance */
    double *su, *sv;    /* slots of spans l = p .. nu-1 (index l - p), k = q .. nv-1 */
    double *cell;       /* cells (l - p) + (k - q)(nu - p) */
    long out;           /* points out of tolerance counted in the slots */
    double e2;          /* their total squared excess */
    long all, rej;      /* points seen; rejected ones out of tolerance */
} nf_spanres_t;

/* Clear the counts for s (after nf_surf_check) and tolerance tol > 0;
 * mem holds NF_SPANRES_DOUBLES(s->nu, s->nv, s->p, s->q) doubles.
 * NF_EARG for a null pointer or tol not > 0. */
int nf_spanres_init(nf_spanres_t *r, const nf_surf_t *s, double tol, double *mem);

/* One point at parameters (u, v) (clamped to the domain) with distance d
 * to the surface: its parameters widen the data range of its spans, and it
 * is counted out of tolerance when |d| > tol. Non-finite parameters are
 * ignored; so is a non-finite d, except for the data range. */
void nf_spanres_add(nf_spanres_t *r, double u, double v, double d);

/* A point a robust fit rejected (weight 0): data range and cell counts as
 * nf_spanres_add, but its excess goes to its cell only, not to the spans:
 * a spike is not a shape. */
void nf_spanres_add_rejected(nf_spanres_t *r, double u, double v, double d);

/* After the pass: the rejected excess of the cells where it is coherent
 * (NF_KNOTS_COHERENT) is added to their spans after all, and cleared from
 * the cells (a second call adds nothing). Returns the cells folded in. */
int nf_spanres_fold(nf_spanres_t *r);

/* Knots to insert in one direction (dir 0: u, 1: v) into X (room for max),
 * ascending; returns how many (0 .. max). The non-empty spans with excess
 * are taken worst first until they hold NF_KNOTS_SHARE of the direction's
 * excess (or max are taken), among the spans whose data lie on both
 * sides of the midpoint; each gets one knot at its midpoint. *spread (if not NULL) is 1 when
 * the pick took more than NF_KNOTS_SPREAD of the direction's non-empty
 * spans: the excess is spread along that direction, which then says little
 * about where knots help. */
int nf_spanres_pick(const nf_spanres_t *r, int dir, int max, double *X, int *spread);

/* Both directions: picks in u and v (X room for maxu, maxv). When one
 * direction is concentrated and the other spread (a ridge across the
 * spread direction: its excess repeats along it), only the concentrated one
 * is refined; otherwise both. *ru, *rv: the knot counts (0 when the points
 * are all within tolerance). */
void nf_spanres_choose(const nf_spanres_t *r, int maxu, double *Xu, int *ru, int maxv, double *Xv,
                       int *rv);

#endif
