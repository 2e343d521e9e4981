/* SPDX-License-Identifier: MIT */
/* cf_accum.c: a chunk of points split between the job and its shard, the
 * shard's half on a second thread (firmware/ has no threads). */
#include "cf_accum.h"
#include "cf_pair.h"

typedef struct half {
    nf_fit_t *f;
    const double *rows;
    long n, bad;
    int rc;
    int id;
    cf_accum_hook_t hook;
    void *ctx;
} half_t;

static void *run_half(void *arg)
{
    half_t *h = arg;
    h->bad = -1;
    h->rc = nf_fit_add_rows(h->f, h->rows, h->n, &h->bad);
    if (!h->rc && h->hook)
        h->hook(h->ctx, h->id, h->rows, h->n);
    return 0;
}

int cf_accum_rows(nf_fit_t *f, nf_fit_t *sh, int serial, const double *rows, long n, long *bad)
{
    return cf_accum_rows_hook(f, sh, serial, rows, n, bad, NULL, NULL);
}

int cf_accum_rows_hook(nf_fit_t *f, nf_fit_t *sh, int serial, const double *rows, long n, long *bad,
                       cf_accum_hook_t hook, void *ctx)
{
    if (!sh || n < 2) {
        half_t a = {f, rows, n, -1, 0, 0, hook, ctx};
        run_half(&a);
        if (a.rc && bad)
            *bad = a.bad;
        return a.rc;
    }
    const long n1 = n / 2;
    half_t a = {f, rows, n1, -1, 0, 0, hook, ctx},
           b = {sh, rows + 5 * n1, n - n1, -1, 0, 1, hook, ctx};
    cf_pair_t th;
    /* Without a thread the halves run in turn: the grouping stays. */
    const int on = !serial && !cf_pair_start(&th, run_half, &b);
    run_half(&a);
    if (on)
        cf_pair_join(&th);
    else if (!a.rc)
        run_half(&b);
    if (a.rc) {
        if (bad)
            *bad = a.bad;
        return a.rc;
    }
    if (b.rc && bad)
        *bad = n1 + b.bad;
    return b.rc;
}
