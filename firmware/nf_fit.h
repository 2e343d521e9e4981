/* SPDX-License-Identifier: MIT */
/* nf_fit.h: one fitting job. Measured points stream in one row of R at a
 * time (Section 3.1); the job assembles the generalised normal equations
 *   [R^T R + alpha (B - I)^T (B - I) + beta I] P = R^T Q + beta P0   (Eq. 7)
 * in stripe storage and solves them. Knots, weights and P0 come from the
 * base surface. Nothing per point is kept: memory is nf_fit_bytes(). */
#ifndef NF_FIT_H
#define NF_FIT_H

#include "nf_accum.h"
#include "nf_arena.h"
#include "nf_budget.h"
#include "nf_stripe.h"
#include "nf_surf.h"
#include <stdint.h>

typedef struct nf_fit_params {
    double alpha;       /* Greville criterion weight (paper default 0.1) */
    double beta;        /* stay-near-nominal weight (paper default 0.001) */
    nf_solver_t solver; /* sizes the budget; nf_fit_solve may pick again */
} nf_fit_params_t;

#define NF_ALPHA_DEFAULT 0.1
#define NF_BETA_DEFAULT 0.001

typedef struct nf_solve_opts {
    double tol;   /* relative residual ||b - A P|| / ||b|| to stop at, per coordinate */
    int max_iter; /* iteration limit of the iterative solvers */
    int probe;    /* 1: check that the data determine the net (iterative solvers) */
} nf_solve_opts_t;

#define NF_SOLVE_OPTS_DEFAULT                                                                      \
    {                                                                                              \
        1e-12, 20000, 1                                                                            \
    }

typedef struct nf_solve_stats {
    nf_solver_t solver;  /* the solver that ran */
    int iterations;      /* sweeps or CG steps (0 for Cholesky) */
    double rel_residual; /* max over x, y, z of ||b - A P|| / ||b|| */
} nf_solve_stats_t;

typedef struct nf_fit {
    const nf_surf_t *base;
    nf_fit_params_t prm;
    nf_stripe_t A;
    double *rhs; /* 3N: R^T Q, then + beta P0 at finish */
    double *P;   /* 3N: solution, starts at P0 */
    nf_arena_t *arena;
    long n;                   /* control points */
    long npoints;             /* points accumulated */
    double sumw;              /* sum of point weights */
    int finished;             /* alpha and beta terms added */
    long bad_index;           /* control point named by NF_ENODATA / NF_ESINGULAR, else -1 */
    long need_bytes;          /* bytes the job needs (set by nf_fit_init even on refusal) */
    double dom[4];            /* u0 u1 v0 v1 */
    double dtol[2];           /* rounding allowance at the domain ends */
    nf_accum_t acc;           /* hot-loop state: fixed size, see nf_accum.h */
    int prefetch;             /* nf_fit_add_rows prefetches stripe rows ahead */
    int pf_l, pf_k;           /* spans of the last point prepared (nf_fit_add_rows) */
    size_t row_mark, row_top; /* arena marks around the lent buffers (0: none) */
    uint32_t *bin_key, *bin_idx, *bin_cnt; /* random order: tile per point, order, counts */
    long bin_cap, bin_tiles;               /* points per window (0: no bins), tiles */
    int bin_tx;                            /* tiles along u */
    int shard;                             /* 1: a shard (nf_fit_shard_init), no P, no solve */
    size_t shard_mark;                     /* its arena mark before its storage */
} nf_fit_t;

/* Check the base surface and the budget, then take the job's storage from
 * the arena. NF_EBUDGET if the job exceeds the board (need_bytes says how
 * many it needed), NF_EARENA if this arena is too small. */
int nf_fit_init(nf_fit_t *f, const nf_surf_t *base, const nf_fit_params_t *prm, nf_arena_t *a);

/* Accumulate one measured point with parameters (u, v) and weight wgt > 0.
 * NF_EDOMAIN outside the knot domain, NF_ENONFINITE for NaN/Inf. */
int nf_fit_add(nf_fit_t *f, double u, double v, const double xyz[3], double wgt);

/* Accumulate n points given as rows of 5 doubles (u v x y z). On error,
 * *bad is the index of the offending row; the rows before it are in, none
 * after. Spans are found 8 points ahead (their stripe rows prefetched when
 * the store exceeds the cache), and windows of random order are sorted by
 * tiles of 16 x 16 spans first (nf_fit.c): larger n bins better. */
int nf_fit_add_rows(nf_fit_t *f, const double *rows, long n, long *bad);

/* A shard: a further accumulator of job f over its own stripes and R^T Q,
 * for a second core (threads live in host code: each calls nf_fit_add_rows
 * on its own nf_fit_t). Its storage comes from arena a (the job's arena or
 * another): NF_EBUDGET when the job plus the shard exceed the board
 * (f->need_bytes + nf_fit_shard_bytes), NF_EARENA when a lacks the room.
 * The shard accepts nf_fit_add and nf_fit_add_rows only. */
int nf_fit_shard_init(nf_fit_t *sh, const nf_fit_t *f, nf_arena_t *a);

/* Sum shard sh into job f (Eq. 9: R^T R and R^T Q are sums over points, in
 * any grouping) and return sh's storage to its arena. Before nf_fit_finish. */
int nf_fit_shard_merge(nf_fit_t *f, nf_fit_t *sh);

/* Add the alpha and beta terms (Eq. 7). Refuses (NF_ENODATA, bad_index set)
 * when alpha = beta = 0 and a control point has no data under it. */
int nf_fit_finish(nf_fit_t *f);

/* A per-control-point beta (issue 14, honest edges): after nf_fit_finish
 * and before nf_fit_solve, add beta to the diagonal of control point i and
 * beta P0_i to its right-hand side, i.e. beta_i in the beta I term of
 * Eq. 7, so that a control point no data determine follows the nominal
 * (nf_footprint_pin, NF_FOOTPRINT_BETA). NF_ESTATE before nf_fit_finish or
 * on a shard, NF_EARG for i outside the net or beta < 0 / not finite. */
int nf_fit_pin(nf_fit_t *f, long i, double beta);

/* nf_fit_pin toward q (x y z) instead of P0_i: beta_i (P_i - q) in Eq. 7.
 * The loop's P0 is the previous round's fit; outside the footprint the
 * surface must follow the nominal itself (the nominal refined into this
 * net's knots), not an earlier round's extrapolation. Same errors, and
 * NF_EARG for a null q. */
int nf_fit_pin_to(nf_fit_t *f, long i, double beta, const double q[3]);

/* Solve Eq. 7 into f->P. NF_ESINGULAR / NF_ENOCONV leave no answer. */
int nf_fit_solve(nf_fit_t *f, nf_solver_t solver, const nf_solve_opts_t *opt, nf_solve_stats_t *st);

#endif
