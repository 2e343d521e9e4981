/* SPDX-License-Identifier: MIT */
/* cf_holdout.c: every K-th scan row held out of a point source
 * (cf_holdout.h): a filter over another source's batches, in place. */
#include "cf_holdout.h"
#include <math.h>
#include <stdio.h>
#include <string.h>

int cf_holdout_is_held(long row, long k)
{
    return k >= 2 && row % k == k - 1;
}

static int ho_rewind(void *ctx, char *msg, size_t ml)
{
    cf_holdout_t *h = ctx;
    h->row = 0;
    h->started = 0;
    return h->in->rewind(h->in->ctx, msg, ml);
}

/* The inner source's batches with the other side's rows removed; a batch
 * that loses every row is followed by the next, so that 0 still means the
 * end. */
static long ho_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    cf_holdout_t *h = ctx;
    int cols = h->in->cols;
    for (;;) {
        long got = h->in->read(h->in->ctx, rows, max, msg, ml), m = 0;
        if (got <= 0)
            return got;
        for (long i = 0; i < got; i++) {
            const double *q = rows + (long)cols * i;
            if (!h->started) {
                h->started = 1;
                h->key = q[1];
            } else if (!(fabs(q[1] - h->key) <= CF_HOLDOUT_EPS)) {
                h->row++;
                h->key = q[1];
            }
            if (cf_holdout_is_held(h->row, h->k) != h->held)
                continue;
            if (m != i)
                memmove(rows + (long)cols * m, q, sizeof(double) * (size_t)cols);
            m++;
        }
        if (m > 0)
            return m;
    }
}

static void ho_where(void *ctx, long k, char *buf, size_t n)
{
    const cf_holdout_t *h = ctx;
    snprintf(buf, n, "%s: point %ld of the rows %s (--holdout %ld)", h->in->name, k + 1,
             h->held ? "held out" : "fitted", h->k);
}

void cf_holdout_src(cf_fitsrc_t *s, cf_holdout_t *ctx, const cf_fitsrc_t *in, long k, int held)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->in = in;
    ctx->k = k;
    ctx->held = held != 0;
    s->cols = in->cols;
    s->total = -1;
    s->bound = cf_fitsrc_most(in); /* a filter keeps no more */
    s->name = in->name;
    s->rewind = ho_rewind;
    s->read = ho_read;
    s->where = ho_where;
    s->ctx = ctx;
    s->split = NULL; /* every k-th row of the whole: one reader */
    s->join = NULL;
}
