/* SPDX-License-Identifier: MIT */
/* cf_accum.c: a chunk of points split between the job and its shard, the
 * shard's half on a second thread (firmware/ has no threads). */
#include "cf_accum.h"
#include <pthread.h>

typedef struct half {
    nf_fit_t *f;
    const double *rows;
    long n, bad;
    int rc;
} half_t;

static void *run_half(void *arg)
{
    half_t *h = arg;
    h->bad = -1;
    h->rc = nf_fit_add_rows(h->f, h->rows, h->n, &h->bad);
    return 0;
}

int cf_accum_rows(nf_fit_t *f, nf_fit_t *sh, int serial, const double *rows, long n, long *bad)
{
    if (!sh || n < 2)
        return nf_fit_add_rows(f, rows, n, bad);
    const long n1 = n / 2;
    half_t a = {f, rows, n1, -1, 0}, b = {sh, rows + 5 * n1, n - n1, -1, 0};
    pthread_t th;
    /* Without a thread the halves run in turn: the grouping stays. */
    const int on = !serial && !pthread_create(&th, 0, run_half, &b);
    run_half(&a);
    if (on)
        pthread_join(th, 0);
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
