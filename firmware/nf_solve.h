/* SPDX-License-Identifier: MIT */
/* nf_solve.h: solvers of A P = b on the stripe store (three right-hand sides
 * interleaved). Each takes its scratch from the arena per nf_budget.h, leaves
 * the solution in x (which holds the starting guess on entry) and reports the
 * final relative residual, computed afresh from the stripes. On
 * NF_ESINGULAR, *bad names the control point found undetermined. */
#ifndef NF_SOLVE_H
#define NF_SOLVE_H

#include "nf_arena.h"
#include "nf_fit.h"
#include "nf_stripe.h"

/* Gauss-Seidel sweeps (Eq. 8, Section 3.2), stopped on the residual. */
int nf_gs_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                nf_arena_t *ar, nf_solve_stats_t *st, long *bad);

/* Banded Cholesky A = U^T U, half bandwidth q Nu + p, one refinement step. */
int nf_chol_solve(const nf_stripe_t *A, const double *b, double *x, nf_arena_t *ar,
                  nf_solve_stats_t *st, long *bad);

/* Conjugate gradients preconditioned by symmetric Gauss-Seidel. */
int nf_pcg_solve(const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o,
                 nf_arena_t *ar, nf_solve_stats_t *st, long *bad);

/* One step of nf_pcg_solve's operator, for tests: from d, t = C^-T d and
 * q = C^-1 A C^-T d (C C^T the symmetric Gauss-Seidel preconditioner,
 * C = (D + L) D^-1/2), dq = d . q per coordinate; all 3 per point. generic
 * takes the generic sweeps for every row. Scratch: 14N doubles of ar. */
int nf_pcg_apply(const nf_stripe_t *A, const double *d, double *t, double *q, double dq[3],
                 int generic, nf_arena_t *ar);

/* r = b - A x; returns max over the three coordinates of ||r|| / ||b||
 * (||r|| alone where b = 0). */
double nf_residual(const nf_stripe_t *A, const double *b, const double *x, double *r);

/* One forward Gauss-Seidel sweep on A x = b (b NULL: zero); t is 3N scratch. */
void nf_gs_sweep(const nf_stripe_t *A, const double *b, double *x, double *t);

/* Determinacy probe (nf_probe.c): a homogeneous solve A e = 0 from a seeded
 * random start keeps the start's component in the null space of A. */
void nf_probe_fill(double *e, long n);
double nf_probe_max(const double *e, long n);
/* NF_ESINGULAR, *bad = control point of the largest survivor, when some
 * |e_i| > 1e-4 e0 (e0: largest start value); NF_OK otherwise. */
int nf_probe_judge(const double *e, long n, double e0, long *bad);

#endif
