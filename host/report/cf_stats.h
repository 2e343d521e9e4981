/* SPDX-License-Identifier: MIT */
/* cf_stats.h: streaming statistics of signed deviations (normal distances of
 * measured points to a surface, mm) in a fixed-size structure: the memory is
 * the same for ten points or a billion.
 *
 *   exact (to rounding): count, mean, std, RMS, min and max with the index of
 *     their point, the count within tolerance (|d| <= tol), the tolerance
 *     histogram (CF_STATS_HIST_BINS bins over +/- CF_STATS_HIST_K tol, plus
 *     under- and overflow);
 *   estimated: percentiles of d and of |d|, from counts in CF_STATS_PBINS
 *     log-spaced bins of |d| per sign over [1e-9, 1e6) mm. An estimate is the
 *     geometric centre of the bin holding the exact order statistic (clamped
 *     to the observed range), so
 *         |estimate - exact| <= CF_STATS_PCT_RELERR * |exact|   (0.43 %)
 *     for 1e-9 <= |exact| < 1e6 mm; |exact| < 1e-9 mm gives 0 (error below
 *     1e-9 mm); beyond 1e6 mm the estimate is the extreme value seen.
 *     The exact order statistic is the nearest-rank one: the ceil(p/100 * n)-th
 *     smallest value (the smallest for p = 0).
 * Indices count cf_stats_add calls from 0. The structure is about 66 KB. */
#ifndef CF_STATS_H
#define CF_STATS_H

#include "cf_json.h"
#include <stdio.h>

#define CF_STATS_HIST_HALF 7 /* B: the histogram has 2B + 1 bins around 0 */
#define CF_STATS_HIST_K 3    /* the bins cover +/- K tol */
#define CF_STATS_HIST_BINS (2 * CF_STATS_HIST_HALF + 1)
/* With B = 7, K = 3 the bins are 0.4 tol wide and +/- tol falls on a bin
 * edge: the five middle bins hold exactly the points within tolerance. */

#define CF_STATS_PBINS 4096  /* log-spaced |d| bins per sign */
#define CF_STATS_PLO 1e-9    /* mm: smaller |d| counts as 0 */
#define CF_STATS_PHI 1e6     /* mm: larger |d| counts as overflow */
#define CF_STATS_PDECADES 15 /* bins span [PLO, PHI) = [1e-9, 1e6) mm */
/* Half a bin in ratio: 10^(15 / 8192) - 1 = 0.004225, rounded up. */
#define CF_STATS_PCT_RELERR 0.00423

typedef struct cf_stats {
    double tol;                             /* mm, > 0 */
    long long n;                            /* points added */
    long long within;                       /* points with |d| <= tol */
    double sum, sum_c;                      /* sum of d, Neumaier-compensated */
    double sq, sq_c;                        /* sum of d^2, compensated */
    double wmean, m2;                       /* Welford's running mean and squared spread (std) */
    double min, max;                        /* signed extremes (valid when n > 0) */
    double min_abs, max_abs;                /* extremes of |d| */
    long long imin, imax, imaxabs;          /* their indices */
    long long hist[CF_STATS_HIST_BINS + 2]; /* [0] below -K tol, [1..BINS], last above */
    long long zero;                         /* |d| < CF_STATS_PLO */
    long long pos_over, neg_over;           /* |d| >= 1e6 mm */
    long long pos[CF_STATS_PBINS], neg[CF_STATS_PBINS];
} cf_stats_t;

/* tol > 0 and finite, else CF_EARG. */
int cf_stats_init(cf_stats_t *st, double tol);

/* One deviation. CF_EARG (and nothing counted) if d is not finite. */
int cf_stats_add(cf_stats_t *st, double d);

/* Moments; NAN when no point was added (std: when fewer than two). std is
 * the sample standard deviation (n - 1). */
double cf_stats_mean(const cf_stats_t *st);
double cf_stats_rms(const cf_stats_t *st);
double cf_stats_std(const cf_stats_t *st);
double cf_stats_within_pct(const cf_stats_t *st); /* 100 * within / n */

/* Percentile pct in [0, 100] of d (signed) and of |d|; NAN when empty or pct
 * outside [0, 100]. pct 0 and 100 give the exact extremes. */
double cf_stats_percentile(const cf_stats_t *st, double pct);
double cf_stats_percentile_abs(const cf_stats_t *st, double pct);

/* Histogram bin i in 0 .. CF_STATS_HIST_BINS + 1: its limits in mm and its
 * count; bin 0 (underflow) has lo = -INFINITY, the last hi = +INFINITY. Bins
 * above zero hold (lo, hi], the middle one [lo, hi], those below [lo, hi):
 * closed on the side away from zero, like |d| <= tol, so the bins inside
 * the tolerance count exactly the points within it. */
void cf_stats_hist_bin(const cf_stats_t *st, int i, double *lo, double *hi, long long *count);

/* Decimals that show mm values at this tolerance with about three
 * significant digits of tol (0.05 -> 4: "0.0500"); at least 3. */
int cf_stats_decimals(double tol);

/* The statistics as fields of an open JSON object (after cf_json_begin):
 * points, tol, rms, mean, std, min, max, max_abs, min_index, max_index,
 * max_abs_index, within_tol, within_tol_pct, p5, p50, p95, p99, p5_abs,
 * p50_abs, p95_abs, p99_abs, pct_rel_err, and histogram: an array of
 * {"lo", "hi", "count"} with lo null on the underflow bin, hi null on the
 * overflow bin. Undefined values (empty input) are null. */
void cf_stats_json_fields(const cf_stats_t *st, cf_json_t *j);

/* One JSON object holding just those fields, and a newline. */
void cf_stats_json(const cf_stats_t *st, FILE *f);

/* A table for people: the figures, the percentiles and an ASCII histogram
 * with the tolerance limits drawn across it. */
void cf_stats_print(const cf_stats_t *st, FILE *f);

#endif
