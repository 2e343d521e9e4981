/* SPDX-License-Identifier: MIT */
/* nf_budget.h: the public byte formula. Every byte the fitter uses comes
 * from the arena, and the arena a job needs is a function of the control
 * net (Nu, Nv, p, q) and the solver alone, never of the number of points.
 *
 *   K      = (p+1) + q(2p+1)              stripe slots per control point:
 *                                          the upper half of the 2q+1 stripes
 *                                          of width 2p+1 (Eq. 11), diagonal kept
 *   N      = Nu Nv
 *   base   = 8 N (K + 6)                  stripes S, right-hand side R^T Q + beta P0 (3N),
 *                                          solution P (3N)
 *   gs     = base + 8 (6N)                residual and rank-probe vectors
 *   pcg    = base + 8 (17N)               r, d (3N each), q, t (4N each: x y z and
 *                                          D^1/2 or D^-1), determinacy probe (3N)
 *   chol   = base + 8 (N (q Nu + p + 1) + 3N)   upper band of half bandwidth q Nu + p
 *   bytes  = solver term + NF_ARENA_SLACK  alignment of at most 16 blocks
 *   shard  = 8 N (K + 3) + 4 NF_ARENA_ALIGN  each further accumulator (a second
 *                                          core's stripes and R^T Q, summed
 *                                          into the job's at the end)
 *   footprint = 4 NF_FP_SUB^2 (Nu - p)(Nv - q) + N + NF_ARENA_ALIGN
 *                                          the data footprint's cell counts and
 *                                          pin flags (caller storage, optional)
 * The raster row buffers (10 Nu doubles per accumulator) are lent from the
 * solver term, idle while points stream in: they add nothing.
 */
#ifndef NF_BUDGET_H
#define NF_BUDGET_H

#include "nf_arena.h"
#include "nf_config.h"

typedef enum nf_solver {
    NF_SOLVER_AUTO = 0, /* Cholesky when the band is small, else PCG */
    NF_SOLVER_GS = 1,   /* Gauss-Seidel on the stripes (the paper's Section 3.2) */
    NF_SOLVER_CHOL = 2, /* banded Cholesky, half bandwidth q Nu + p */
    NF_SOLVER_PCG = 3   /* conjugate gradients, symmetric Gauss-Seidel preconditioner */
} nf_solver_t;

#define NF_STRIPE_SLOTS(p, q) ((p) + 1 + (q) * (2 * (p) + 1))
#define NF_ARENA_SLACK (16L * NF_ARENA_ALIGN)
#define NF_BYTES_BASE(n, p, q) (8L * (long)(n) * (NF_STRIPE_SLOTS(p, q) + 6L))
#define NF_BYTES_GS(n, p, q) (NF_BYTES_BASE(n, p, q) + 8L * 6L * (long)(n) + NF_ARENA_SLACK)
#define NF_BYTES_PCG(n, p, q) (NF_BYTES_BASE(n, p, q) + 8L * 17L * (long)(n) + NF_ARENA_SLACK)
#define NF_BYTES_CHOL(nu, nv, p, q)                                                                \
    (NF_BYTES_BASE((long)(nu) * (nv), p, q) +                                                      \
     8L * (long)(nu) * (nv) * ((long)(q) * (nu) + (p) + 1 + 3) + NF_ARENA_SLACK)

#define NF_BYTES_SHARD(n, p, q)                                                                    \
    (8L * (long)(n) * (NF_STRIPE_SLOTS(p, q) + 3L) + 4L * NF_ARENA_ALIGN)

/* The data footprint (nf_footprint.h): NF_FP_SUB x NF_FP_SUB cells per knot
 * span pair, a 32-bit count each, and one flag byte per control point,
 *   footprint = 4 NF_FP_SUB^2 (Nu - p)(Nv - q) + N + NF_ARENA_ALIGN
 * (the last for the alignment of the flags after the counts). */
#define NF_FP_SUB 2
#define NF_BYTES_FOOTPRINT(nu, nv, p, q)                                                           \
    (4L * NF_FP_SUB * NF_FP_SUB * ((long)(nu) - (p)) * ((long)(nv) - (q)) +                        \
     (long)(nu) * (long)(nv) + NF_ARENA_ALIGN)

/* The board's arena must hold the largest net it advertises, at its design
 * degree, with the iterative solvers (Cholesky is refused when it would not fit). */
_Static_assert(NF_ARENA_BYTES >= NF_BYTES_PCG(NF_MAX_CP, NF_DESIGN_DEGREE, NF_DESIGN_DEGREE),
               "board arena smaller than the byte formula at NF_MAX_CP");
_Static_assert(NF_BYTES_GS(1, 1, 1) <= NF_BYTES_PCG(1, 1, 1), "PCG is the larger iterative term");

/* Bytes a fit of this net needs with this solver (AUTO: the one nf_solver_pick
 * chooses), or -1 when the sizes overflow. */
long nf_fit_bytes(int nu, int nv, int p, int q, nf_solver_t solver);

/* Bytes of one further accumulator (nf_fit_shard_init), or -1 on overflow:
 * a job accumulating on T cores needs nf_fit_bytes + (T - 1) of these. */
long nf_fit_shard_bytes(int nu, int nv, int p, int q);

/* Bytes of the data footprint of this net (NF_BYTES_FOOTPRINT), or -1 for
 * sizes that are invalid or overflow. */
long nf_footprint_bytes(int nu, int nv, int p, int q);

/* The solver AUTO resolves to: Cholesky when its band fits the board and its
 * cost N (q Nu + p)^2 stays small, otherwise PCG. */
nf_solver_t nf_solver_pick(int nu, int nv, int p, int q);

/* Largest square net (Nu = Nv) of degree p = q a board of this arena can fit. */
long nf_budget_max_square(long arena_bytes, int p, nf_solver_t solver);

const char *nf_solver_name(nf_solver_t s);

#endif
