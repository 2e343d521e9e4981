/* SPDX-License-Identifier: MIT */
/* cf_fitpass.h: one pass of Eq. 7 (Brujic et al. 2010) over rows of
 * u v x y z [w] in a memory block the caller gives: begin (the fitter on a
 * surface's space, its net as P0, in the block), rows (any number of
 * calls), solve into a surface of that space. Nothing is allocated: the
 * pass lives in the block, so the public API keeps its caller-memory
 * contract and the fit job its byte formula. Refusals come back as the
 * job's messages (the control point left free, the bytes the board
 * allows). On the host, the fit job, libcellfit and base surfaces fit
 * through here; only bench's raw kernels call nf_fit_init themselves.
 * Parameters are the caller's (given, or its projection). */
#ifndef CF_FITPASS_H
#define CF_FITPASS_H

#include "nf_fit.h"
#include <stddef.h>

typedef struct cf_fitpass {
    nf_arena_t ar;
    nf_fit_t f;
    nf_fit_t *sh; /* threads 2: the second core's accumulator (cf_accum), its
                   * state at the start of the block */
    int threads;
    int serial; /* threads 2 on one core: the shard's half after the first's
                         * (the sums two cores give; set by the caller after begin) */
    /* Called on each half's thread after its rows of 5 are in (cf_accum_rows_hook); NULL:
     * none. */
    void (*hook)(void *ctx, int half, const double *rows, long n);
    void *hook_ctx;
    const nf_surf_t *s; /* the space fitted in (names control points in messages) */
    long rejected;      /* rows of weight 0, left out */
    nf_solve_stats_t st;
    double t0;      /* begin */
    double t_acc;   /* begin to the solve: rows, the caller's reading between them, merge */
    double t_rows;  /* of it, inside the fitter's accumulation (and the merge) */
    double t_merge; /* of it, the second core's sums joining the first's */
    double t_solve;
    /* Honest edges (issue 14): per control point a flag (NULL: none), the
     * flagged ones pulled to pin_to[3 i ..] (NULL: P0) with pin_beta
     * between nf_fit_finish and the solve (nf_fit_pin_to); set by the
     * caller before cf_fitpass_solve. */
    const unsigned char *pin;
    const double *pin_to;
    double pin_beta;
} cf_fitpass_t;

/* Bytes of the block for a pass on s's space with solver: nf_fit_bytes,
 * the firmware's public formula; with threads 2 also a second
 * accumulator, its state and nf_fit_shard_bytes. Negative when the net
 * has no formula. */
long cf_fitpass_bytes(const nf_surf_t *s, nf_solver_t solver, int threads);

/* A pass on s's space (s stays the caller's until solve) in block (bytes
 * long, at least cf_fitpass_bytes, aligned to 16), threads 1 or 2. 0, or an nf_err_t
 * with msg: NF_EBUDGET with the bytes needed and allowed, NF_EARENA,
 * NF_EDEGREE, NF_EKNOTS, ... name is the data's name in messages. */
int cf_fitpass_begin(cf_fitpass_t *ps, void *block, size_t bytes, const nf_surf_t *s, double alpha,
                     double beta, nf_solver_t solver, int threads, const char *name, char *msg,
                     size_t ml);

/* n rows of cols doubles: 5 (u v x y z, weight 1) or 6 (u v x y z w; rows
 * of weight 0 counted in rejected and left out). On an error (NF_EDOMAIN,
 * NF_ENONFINITE, NF_EWEIGHT) *bad is the index of the offending row; the
 * rows before it are in. No message: the caller knows where row k came
 * from (cf_fitpass_row_error words it). */
int cf_fitpass_rows(cf_fitpass_t *ps, const double *rows, long n, int cols, long *bad);

/* The message for rc from a row (u v x y z ...) that `at` names
 * ("FILE:LINE"): parameters outside the domain with the domain, else the
 * fitter's word. Returns rc. */
int cf_fitpass_row_error(const cf_fitpass_t *ps, int rc, const double *row, const char *at,
                         char *msg, size_t ml);

/* Merge the second core's sums, add Eq. 7's alpha and beta terms (and
 * the pins, when ps->pin is set), solve
 * with so, and copy the net into out (s's shape). 0, or NF_ENODATA /
 * NF_ESINGULAR naming the control point left free, NF_ENOCONV, ... with
 * msg. Once per pass. */
int cf_fitpass_solve(cf_fitpass_t *ps, const nf_solve_opts_t *so, nf_surf_t *out, const char *name,
                     char *msg, size_t ml);

/* Points accumulated so far. */
long cf_fitpass_points(const cf_fitpass_t *ps);

/* Bytes of the stripe store of Eq. 7's matrix (after begin). */
long cf_fitpass_store_bytes(const cf_fitpass_t *ps);

#endif
