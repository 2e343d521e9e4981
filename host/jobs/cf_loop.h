/* SPDX-License-Identifier: MIT */
/* cf_loop.h: the refinement step and the round records of `cellfit fit
 * --tol` (Brujic et al. 2010, Section 2.2: fit, reparameterise, insert
 * knots until the tolerance holds; docs/loop.md). The next net is the fit
 * itself with knots inserted (Boehm: the same surface), so it is both the
 * next round's base and its nominal P0. */
#ifndef CF_LOOP_H
#define CF_LOOP_H

#include "cf_json.h"
#include "nf_budget.h"
#include "nf_knots.h"
#include "nf_knotsel.h"
#include "nf_surf.h"
#include <stddef.h>

typedef enum cf_refine {
    CF_REFINE_UNIFORM = 0,  /* every non-empty span halved (nf_refine_uniform) */
    CF_REFINE_RESIDUAL = 1, /* the spans holding most excess split (nf_spanres_choose) */
    CF_REFINE_AUTO = 2      /* knot lines per control point added where data both sides
                               (nf_knotsel), rules of nf_loopctl: the default */
} cf_refine_t;

/* "uniform", "residual", "auto". */
const char *cf_refine_name(cf_refine_t how);

/* Why the loop cannot go on (cf_loop_next's *stop). */
enum {
    CF_LOOP_GO = 0,
    CF_LOOP_STOP_DATA = 1,  /* no span with data on both sides of its midpoint left to split */
    CF_LOOP_STOP_MAX_CP = 2 /* the next net exceeds max_cp, the board's points or its bytes */
};

/* The next net from fit: uniform, or residual-driven from sr (the span
 * counts of the check pass on fit). CF_OK with *stop = CF_LOOP_GO and *nxt
 * allocated (cf_surf_free), or CF_OK with *stop = CF_LOOP_STOP_* and msg
 * saying why the loop ends: no span to split, more than max_cp (or the
 * board's NF_MAX_CP) control points, more bytes than the board's arena
 * with this solver.
 * CF_ENOMEM, or an nf_err_t of knot insertion, with msg. */
int cf_loop_next(const nf_surf_t *fit, const nf_spanres_t *sr, cf_refine_t how, long max_cp,
                 nf_solver_t solver, nf_surf_t *nxt, int *stop, char *msg, size_t ml);

/* The next net from fit with the knot lines c[0..n-1] of nf_knotsel_choose
 * inserted (Boehm: the same surface). Limits and results as cf_loop_next:
 * *stop = CF_LOOP_STOP_DATA when n is 0, CF_LOOP_STOP_MAX_CP past max_cp,
 * the board's control points or its arena bytes with this solver. */
int cf_loop_insert(const nf_surf_t *fit, const nf_knotsel_cand_t *c, int n, long max_cp,
                   nf_solver_t solver, nf_surf_t *nxt, int *stop, char *msg, size_t ml);

/* --refine auto with robust passes (issue 14): points a robust pass
 * rejected reach ks as data without misfit (a spike is not a shape), and
 * kr with their misfit; sr counts them per cell. Where a cell's rejected
 * share passes nf_spanres_fold's test (NF_KNOTS_COHERENT times the share
 * over all cells, at least NF_KNOTS_MIN_REJ points: a feature the net
 * cannot follow yet, not spikes), kr's misfit of that cell's u and v spans
 * joins ks (nf_knotsel_merge_span), so a narrow feature still draws knots.
 * Returns the spans merged, or CF_ENOMEM. */
int cf_loop_fold_auto(nf_knotsel_t *ks, const nf_knotsel_t *kr, const nf_spanres_t *sr);

/* One round as reported. */
typedef struct cf_round {
    int nu, nv;
    double within_pct; /* points within the tolerance, percent */
    double rms, mx;    /* of the distances to the round's fit */
    double sigma;      /* robust scale of the last reweighting (0: none) */
    long rejected;     /* robust: points of weight 0 in the last pass */
    double seconds;
    int prune;         /* 0: a round of the loop; a pruning trial: 1 kept, -1 undone */
    int prune_dir;     /* the trial's knot line: 0 in u, 1 in v */
    double prune_knot; /* its knot */
    double prune_err;  /* the knot removal error of the fit it was taken from (nf_prune) */
} cf_round_t;

/* "rounds": [{round, nu, nv, control_points, within_tol_pct, rms, max_abs,
 * [sigma, rejected,] seconds [, pruned, removed_dir, removed_knot,
 * removal_error]}, ...] as
 * a field of an open JSON object; a pruning trial has pruned (true: kept,
 * false: undone) and the knot line it took out. */
void cf_rounds_json(cf_json_t *j, const cf_round_t *r, int n, int robust);

/* One line for people: net, share within tol (if tol > 0), rms, max. */
void cf_round_print(FILE *f, int i, const cf_round_t *r, double tol, int robust);

#endif
