/* SPDX-License-Identifier: MIT */
/* cf_holdout.h: every K-th scan row of a point source held out of a fit
 * (`cellfit fit --holdout K`): one source yields the rows kept for the fit,
 * a second over the same points yields the rows held out, measured against
 * the fit afterwards (an independent check that the fit generalises).
 *
 * A row is a run of points, in file order, whose second column (y of
 * x y z, v of u v x y z) stays within CF_HOLDOUT_EPS of the row's first
 * point: for a regular grid file, written row by row, the rows are the lines
 * of equal y; for a line scanner, its scan lines. Rows are numbered from 0;
 * rows K-1, 2K-1, ... are held out. Nothing is kept per point. */
#ifndef CF_HOLDOUT_H
#define CF_HOLDOUT_H

#include "cf_fitsrc.h"

/* Same row while |y - y_row| <= this (mm, or parameter units with u v). */
#define CF_HOLDOUT_EPS 1e-6

typedef struct cf_holdout {
    const cf_fitsrc_t *in;
    long k;      /* every k-th row held out (k >= 2) */
    int held;    /* 0: yield the kept rows, 1: the held-out rows */
    long row;    /* the current row's number */
    double key;  /* its first point's y (or v) */
    int started; /* a row has begun since the rewind */
} cf_holdout_t;

/* s reads in through ctx: the rows kept (held 0) or held out (held 1) of
 * every k-th row (k >= 2). Point indices in messages are of the rows
 * yielded. */
void cf_holdout_src(cf_fitsrc_t *s, cf_holdout_t *ctx, const cf_fitsrc_t *in, long k, int held);

/* 1 when row number `row` is held out of a fit with every k-th row held. */
int cf_holdout_is_held(long row, long k);

#endif
