/* SPDX-License-Identifier: MIT */
/* nf_prune.h: the pruning stage of the fitting loop (issue 14). Once the
 * loop meets its tolerance, knot lines it inserted are tried out again,
 * the one whose removal changes the fit least first: the knot removal of
 * The NURBS Book (A5.8, one knot, the new control points solved from the
 * left and from the right of the knot, the mismatch of the equation left
 * over its error). The removed surface is only the start (parameters and
 * P0) of a fresh fit of the data at the coarser knots: the caller keeps a
 * removal only when that fit still meets the tolerance.
 *
 * Output goes to caller storage, as nf_refine's: wire out with
 *   nf_surf_wire(out, p, q, nu - 1, nv, mem) (a knot in u) or nu, nv - 1. */
#ifndef NF_PRUNE_H
#define NF_PRUNE_H

#include "nf_surf.h"

/* One knot line that may go. */
typedef struct nf_prune_cand {
    int dir;      /* 0: a knot in u (a column of nv control points goes), 1: in v */
    int index;    /* its index in U (dir 0) or V */
    double x;     /* the knot */
    double err;   /* removal error: the largest mismatch over the net's rows */
    double score; /* err per control point saved (ascending: tried first) */
} nf_prune_cand_t;

/* Candidates nf_prune_rank may list for s: its interior knots. */
#define NF_PRUNE_CANDS(nu, nv, p, q) ((nu) - (p)-1 + (nv) - (q)-1)

/* s with the knot U[index] (dir 0) or V[index] (dir 1) removed once: the
 * control points around it from A5.8's two sweeps (homogeneous, so
 * rational surfaces too), *err the largest distance over the rows between
 * the fine control point the left over equation gives and the fine net's
 * (0 when s holds no knot there: the removal is exact). The knot must be
 * interior and simple (multiplicity 1). NF_EARG: null pointers, out not
 * wired to the shape, a knot not interior or not simple; nf_surf_check's
 * errors for s. On error out is untouched. */
int nf_prune_remove(const nf_surf_t *s, int dir, int index, nf_surf_t *out, double *err);

/* The simple interior knots of s not among keep's (keep: the surface the
 * loop started from, whose knots stay; NULL: none), with their removal
 * error, into out (room for cap), ascending by score (err per control point
 * saved: nv for a knot in u, nu for one in v); *n their count. NF_OK,
 * NF_EARG for null pointers or cap < 0, nf_surf_check's errors. */
int nf_prune_rank(const nf_surf_t *s, const nf_surf_t *keep, nf_prune_cand_t *out, int cap, int *n);

#endif
