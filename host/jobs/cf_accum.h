/* SPDX-License-Identifier: MIT */
/* cf_accum.h: accumulation of a chunk of points on two cores. The job f
 * takes the first half, its shard sh (nf_fit_shard_init) the second, each
 * on its own thread and its own stripes; nf_fit_shard_merge sums them at the
 * end. Halves stay contiguous, so a raster keeps its rows (nf_accum.h). */
#ifndef CF_ACCUM_H
#define CF_ACCUM_H

#include "nf_fit.h"

/* n rows of 5 doubles (u v x y z). sh NULL: f alone, on this thread.
 * serial: both halves on this thread, one after the other: the same sums
 * as two cores give (a fit the same for any core count). On error *bad
 * is the index (into rows) of the first offending row found. */
int cf_accum_rows(nf_fit_t *f, nf_fit_t *sh, int serial, const double *rows, long n, long *bad);

/* After each half's rows are in (half 0: f's, 1: sh's; a chunk not split
 * is half 0), on that half's thread: the caller's own per-row work. */
typedef void (*cf_accum_hook_t)(void *ctx, int half, const double *rows, long n);

/* cf_accum_rows, then hook(ctx, half, ...) on each half accumulated
 * without error (hook NULL: none). */
int cf_accum_rows_hook(nf_fit_t *f, nf_fit_t *sh, int serial, const double *rows, long n, long *bad,
                       cf_accum_hook_t hook, void *ctx);

#endif
