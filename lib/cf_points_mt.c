/* SPDX-License-Identifier: MIT */
/* cf_points_mt.c: the parse thread and its ring of row blocks
 * (cf_points_mt.h). One mutex and two condition variables: the thread
 * waits for a free block, the reader for a full one; a block changes hands
 * once per `block` rows, so the locking costs nothing beside the parsing. */
#include "cf_points_mt.h"
#include "cf_bigmem.h"
#include "cf_err.h"
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct pmt_blk {
    double *rows;
    long *lines;
    long n;
    int err, last; /* last: the end of the data or an error follows the rows */
    char msg[720];
} pmt_blk_t;

struct cf_pmt {
    int cols, nblk;
    long cap;
    pmt_blk_t *blk;
    void *mem; /* every block's rows and lines, one piece (cf_bigmem) */
    cf_pmt_fill_fn fill;
    void *ctx;
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t data, space;
    int head, tail, full, stop; /* under mu: the thread fills head, the reader takes tail */
    int running;                /* the thread started and not yet joined */
    /* the reader's own */
    long off, line;
    int done, err;
    char msg[720];
};

static void *pmt_main(void *arg)
{
    cf_pmt_t *t = arg;
    for (;;) {
        pthread_mutex_lock(&t->mu);
        while (t->full == t->nblk && !t->stop)
            pthread_cond_wait(&t->space, &t->mu);
        int stop = t->stop;
        pmt_blk_t *b = &t->blk[t->head];
        pthread_mutex_unlock(&t->mu);
        if (stop)
            return NULL;
        b->err = 0;
        b->msg[0] = '\0';
        b->n = t->fill(t->ctx, b->rows, b->lines, t->cap, &b->err, b->msg, sizeof b->msg);
        b->last = b->err != 0 || b->n < t->cap;
        pthread_mutex_lock(&t->mu);
        t->head = (t->head + 1) % t->nblk;
        t->full++;
        pthread_cond_signal(&t->data);
        pthread_mutex_unlock(&t->mu);
        if (b->last)
            return NULL;
    }
}

static void pmt_free(cf_pmt_t *t)
{
    cf_bigmem_free(t->mem);
    free(t->blk);
    free(t);
}

int cf_pmt_start(cf_pmt_t **tp, int cols, long block, int nblocks, cf_pmt_fill_fn fill, void *ctx)
{
    if (!tp || cols < 1 || block < 1 || nblocks < 2 || !fill)
        return CF_EARG;
    *tp = NULL;
    cf_pmt_t *t = calloc(1, sizeof *t);
    if (!t)
        return CF_ENOMEM;
    t->cols = cols;
    t->cap = block;
    t->nblk = nblocks;
    t->fill = fill;
    t->ctx = ctx;
    /* One piece for the ring (on a huge page when large enough: one first
     * touch instead of hundreds), touched now: not a lazy calloc. */
    const size_t nr = (size_t)block * (size_t)cols * sizeof(double),
                 nl = (size_t)block * sizeof(long);
    t->blk = calloc((size_t)nblocks, sizeof *t->blk);
    t->mem = cf_bigmem_alloc((nr + nl) * (size_t)nblocks);
    if (!t->blk || !t->mem) {
        pmt_free(t);
        return CF_ENOMEM;
    }
    memset(t->mem, 0xff, (nr + nl) * (size_t)nblocks);
    for (int i = 0; i < nblocks; i++) {
        char *b = (char *)t->mem + (nr + nl) * (size_t)i; /* nr, nl: multiples of 8 */
        t->blk[i].rows = (double *)(void *)b;
        t->blk[i].lines = (long *)(void *)(b + nr);
    }
    pthread_mutex_init(&t->mu, NULL);
    pthread_cond_init(&t->data, NULL);
    pthread_cond_init(&t->space, NULL);
    if (pthread_create(&t->th, NULL, pmt_main, t)) {
        pthread_cond_destroy(&t->space);
        pthread_cond_destroy(&t->data);
        pthread_mutex_destroy(&t->mu);
        pmt_free(t);
        return CF_EIO;
    }
    t->running = 1;
    *tp = t;
    return CF_OK;
}

/* Stop the thread (it finishes the block it is filling) and join it. */
static void pmt_join(cf_pmt_t *t)
{
    if (!t->running)
        return;
    pthread_mutex_lock(&t->mu);
    t->stop = 1;
    pthread_cond_signal(&t->space);
    pthread_mutex_unlock(&t->mu);
    pthread_join(t->th, NULL);
    t->running = 0;
}

void cf_pmt_pause(cf_pmt_t *t)
{
    pmt_join(t);
    t->head = t->tail = t->full = t->stop = 0;
    t->off = t->line = 0;
    t->done = t->err = 0;
    t->msg[0] = '\0';
}

int cf_pmt_resume(cf_pmt_t *t)
{
    if (t->running)
        return CF_OK;
    if (pthread_create(&t->th, NULL, pmt_main, t))
        return CF_EIO;
    t->running = 1;
    return CF_OK;
}

long cf_pmt_read(cf_pmt_t *t, double *out, long max, char *msg, size_t ml)
{
    long k = 0;
    while (!t->done && k < max) {
        pthread_mutex_lock(&t->mu);
        while (!t->full)
            pthread_cond_wait(&t->data, &t->mu);
        pthread_mutex_unlock(&t->mu);
        pmt_blk_t *b = &t->blk[t->tail]; /* ours until released below */
        long take = b->n - t->off < max - k ? b->n - t->off : max - k;
        if (take > 0) {
            memcpy(out + (size_t)k * (size_t)t->cols, b->rows + (size_t)t->off * (size_t)t->cols,
                   (size_t)take * (size_t)t->cols * sizeof(double));
            k += take;
            t->off += take;
            t->line = b->lines[t->off - 1];
        }
        if (t->off < b->n)
            break; /* max reached inside the block */
        if (b->last) {
            t->done = 1;
            t->err = b->err;
            memcpy(t->msg, b->msg, sizeof t->msg);
        }
        t->off = 0;
        pthread_mutex_lock(&t->mu);
        t->tail = (t->tail + 1) % t->nblk;
        t->full--;
        pthread_cond_signal(&t->space);
        pthread_mutex_unlock(&t->mu);
    }
    /* One thread would have met the error before filling max rows (or, at
     * max exactly, on the next call): the same here. */
    if (t->done && t->err && (k < max || !max))
        return cf_fail(msg, ml, t->err, "%s", t->msg);
    return k;
}

long cf_pmt_line(const cf_pmt_t *t)
{
    return t->line;
}

void cf_pmt_stop(cf_pmt_t *t)
{
    if (!t)
        return;
    pmt_join(t);
    pthread_cond_destroy(&t->space);
    pthread_cond_destroy(&t->data);
    pthread_mutex_destroy(&t->mu);
    pmt_free(t);
}
