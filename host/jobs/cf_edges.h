/* SPDX-License-Identifier: MIT */
/* cf_edges.h: honest edges for a fit pass (issue 14): the footprint of the
 * rows a pass fits (nf_footprint on the pass's net), and, before the
 * solve, the control points whose support holds no point pinned to the
 * nominal refined into the pass's knots (cf_fitpass's pin, nf_fit_pin_to
 * with NF_FOOTPRINT_BETA), so that outside the data the surface follows
 * the nominal instead of extrapolating the data. A pinned control point
 * touches no measured point (its support holds none): the fit of the data
 * moves only through the alpha term of its neighbours.
 *
 * Memory: the footprint's NF_BYTES_FOOTPRINT and, when anything is pinned,
 * a copy of the nominal on the pass's net; O(net), nothing per point. */
#ifndef CF_EDGES_H
#define CF_EDGES_H

#include "cf_fitpass.h"
#include "nf_footprint.h"

/* Points a control point's support must hold not to be pinned. */
#define CF_EDGES_MIN_POINTS 1

typedef struct cf_edges {
    nf_footprint_t fp;
    void *mem;     /* the footprint's cells and flags (heap) */
    nf_surf_t nom; /* the nominal on the pass's net (heap; nu 0: none) */
    long pinned;   /* control points pinned by the last cf_edges_pin */
} cf_edges_t;

/* The footprint of a pass on cur's net (cur stays the caller's). 0 or
 * CF_ENOMEM; an nf_err_t for a net without a byte formula. */
int cf_edges_begin(cf_edges_t *e, const nf_surf_t *cur);

/* A row fitted at (u, v) (outside the domain or not finite: not counted). */
void cf_edges_add(cf_edges_t *e, double u, double v);
/* The rows' u, v (the first two of every stride doubles), n of them. */
void cf_edges_add_rows(cf_edges_t *e, const double *rows, long n, int stride);

/* Flag the control points of cur with no point in their support, and pin
 * them to nominal refined into cur's knots (nominal's knots must be a
 * sub-multiset of cur's: the loop only inserts). Sets ps->pin, pin_to and
 * pin_beta; returns the count pinned (>= 0) or CF_ENOMEM, CF_EARG (knots
 * not nested), an nf_err_t of the refinement. e must outlive the solve. */
long cf_edges_pin(cf_edges_t *e, const nf_surf_t *nominal, cf_fitpass_t *ps);

/* nominal refined by Boehm insertion into the knots of cur (out on the
 * heap, cur's shape): the same surface, in cur's space. 0, CF_EARG when
 * the degrees differ or nominal's knots are not all among cur's,
 * CF_ENOMEM, or the refinement's nf_err_t. */
int cf_edges_nominal(const nf_surf_t *nominal, const nf_surf_t *cur, nf_surf_t *out);

void cf_edges_free(cf_edges_t *e);

#endif
