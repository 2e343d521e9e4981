/* SPDX-License-Identifier: MIT */
/* bd_selftest.h: the built-in job every firmware image runs, so that the
 * image is a complete program and its numbers can be checked: fits of data
 * sampled from a known surface in the fitted spline space. */
#ifndef BD_SELFTEST_H
#define BD_SELFTEST_H

#include <stddef.h>

/* Receives one report line at a time (no newline; the caller adds it). */
typedef void (*bd_emit_fn)(const char *line);

/* Largest error allowed where the fit must reproduce the true net exactly. */
#define BD_EXACT_TOL 1e-9

/* Run every case with the fitter's memory in arena (bytes long) and report
 * through emit, as "key=value" words:
 *   board=... arena=... max_cp=... max_square_gs|chol|pcg=...  (nf_budget_max_square)
 *   case=exact-gs|exact-chol|exact-pcg   alpha = beta = 0 on an 8x8 bicubic net:
 *        the fit must return the true control points (maxerr <= BD_EXACT_TOL)
 *   case=default, default-pcg   alpha = 0.1, beta = 0.001, the board's solver
 *        (BOARD_SOLVER) and PCG: must converge and end nearer the truth than
 *        the nominal (maxerr < dev0)
 *   case=largest   the largest square net the budget allows, PCG, exact data
 *   case=over      one net over NF_MAX_CP: must be refused with NF_EBUDGET
 * Each case line ends ok=1 or ok=0. Returns 1 when every property held; the
 * board's main then adds its own lines (stack use, result=pass|fail). */
int bd_selftest_run(unsigned char *arena, size_t bytes, bd_emit_fn emit);

#endif
