/* SPDX-License-Identifier: MIT */
/* cf_fitsrc.c: point sources of the fit job: points file, journal (cf_fitsrc.h). */
#include "cf_fitsrc.h"
#include "cf_err.h"
#include "rig_err.h"
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The cache's states: off (or dropped), idle (the next rewind starts a
 * copy), fill (this pass's rows are copied), full (passes from memory). */
enum { CF_FITSRC_CACHE_OFF, CF_FITSRC_CACHE_IDLE, CF_FITSRC_CACHE_FILL, CF_FITSRC_CACHE_FULL };

static void cache_drop(cf_fitsrc_points_t *p)
{
    free(p->rows);
    p->rows = NULL;
    p->n = p->cap = p->limit = p->at = 0;
    p->state = CF_FITSRC_CACHE_OFF;
}

/* got rows read from the file appended (fill): 0, or -1 when they would
 * pass the bound or memory is short (the cache dropped). */
static int cache_add(cf_fitsrc_points_t *p, const double *rows, long got)
{
    if (got > p->limit - p->n)
        return -1;
    if (p->n + got > p->cap) {
        long cap = p->cap ? p->cap : p->limit < 4096 ? p->limit : 4096;
        while (cap < p->n + got)
            cap = cap > p->limit / 2 ? p->limit : 2 * cap;
        double *q = realloc(p->rows, sizeof(double) * (size_t)p->cols * (size_t)cap);
        if (!q)
            return -1;
        p->rows = q;
        p->cap = cap;
    }
    memcpy(p->rows + (size_t)p->n * (size_t)p->cols, rows,
           sizeof(double) * (size_t)p->cols * (size_t)got);
    p->n += got;
    return 0;
}

/* The whole file from its first point (after a split too); a text file
 * is parsed on a second thread while the job accumulates (or evaluates)
 * the rows it has: the same rows, lines and errors (cf_points.h). Without
 * a thread it reads on this one. A full cache serves instead; a pass
 * rewound before its end (fill) is copied again from the start. */
static int pts_rewind(void *ctx, char *msg, size_t ml)
{
    cf_fitsrc_points_t *p = ctx;
    if (p->state == CF_FITSRC_CACHE_FULL) {
        p->at = 0;
        return 0;
    }
    int rc = cf_points_whole(p->r);
    if (!rc)
        (void)cf_points_thread(p->r);
    if (p->state != CF_FITSRC_CACHE_OFF) {
        p->n = 0;
        p->state = rc ? CF_FITSRC_CACHE_IDLE : CF_FITSRC_CACHE_FILL;
    }
    return rc ? cf_fail(msg, ml, rc, "%s: cannot read the points again", p->path) : 0;
}

static long pts_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    cf_fitsrc_points_t *p = ctx;
    if (p->state == CF_FITSRC_CACHE_FULL) {
        if ((!rows && max > 0) || max < 0)
            return cf_fail(msg, ml, CF_EARG, "cf_points_read: bad arguments");
        long got = p->n - p->at < max ? p->n - p->at : max;
        if (got > 0)
            memcpy(rows, p->rows + (size_t)p->at * (size_t)p->cols,
                   sizeof(double) * (size_t)p->cols * (size_t)got);
        p->at += got;
        return got;
    }
    long got = cf_points_read(p->r, rows, max, msg, ml);
    if (p->state == CF_FITSRC_CACHE_FILL) {
        if (got < 0 || (got > 0 && cache_add(p, rows, got)))
            cache_drop(p);
        else if (got == 0 && max > 0)
            p->state = CF_FITSRC_CACHE_FULL, p->at = p->n;
    }
    return got;
}

static long part_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    return cf_points_read(((cf_fitsrc_part_t *)ctx)->r, rows, max, msg, ml);
}

/* A half from its first point (the split stays). */
static int part_rewind(void *ctx, char *msg, size_t ml)
{
    cf_fitsrc_part_t *p = ctx;
    int rc = cf_points_rewind(p->r);
    return rc ? cf_fail(msg, ml, rc, "%s: cannot read the points again", p->path) : 0;
}

/* The line of point k of r, read again one point at a time (error path
 * only; a half's rewind keeps the split). */
static void where_in(cf_points_t *r, const char *path, long k, char *buf, size_t n)
{
    double row[8];
    char msg[16];
    long line = -1;
    if (!cf_points_rewind(r)) {
        long i = 0;
        while (i <= k && cf_points_read(r, row, 1, msg, sizeof msg) == 1)
            i++;
        if (i > k)
            line = cf_points_line(r);
    }
    snprintf(buf, n, "%s:%ld", path, line);
}

/* From the whole file (a full cache may have left it split); a pass being
 * copied is copied again at the next (the reader moved). */
static void pts_where(void *ctx, long k, char *buf, size_t n)
{
    cf_fitsrc_points_t *p = ctx;
    if (p->state == CF_FITSRC_CACHE_FILL)
        p->state = CF_FITSRC_CACHE_IDLE;
    (void)cf_points_whole(p->r);
    where_in(p->r, p->path, k, buf, n);
}

static void part_where(void *ctx, long k, char *buf, size_t n)
{
    cf_fitsrc_part_t *p = ctx;
    where_in(p->r, p->path, k, buf, n);
}

static int pts_split(void *ctx, cf_fitsrc_t *half, char *msg, size_t ml)
{
    cf_fitsrc_points_t *p = ctx;
    cf_points_t *r2 = NULL;
    if (p->state == CF_FITSRC_CACHE_FILL)
        p->state = CF_FITSRC_CACHE_IDLE; /* the halves read the file, not this pass */
    int rc = cf_points_split(p->r, &r2, msg, ml);
    if (rc)
        return rc;
    p->part[0] = (cf_fitsrc_part_t){p->r, p->path};
    p->part[1] = (cf_fitsrc_part_t){r2, p->path};
    for (int i = 0; i < 2; i++)
        half[i] = (cf_fitsrc_t){cf_points_cols(p->r) == 5 ? 5 : 3,
                                -1,
                                p->path,
                                part_rewind,
                                part_read,
                                part_where,
                                &p->part[i],
                                NULL,
                                NULL,
                                0};
    return 0;
}

static void pts_join(void *ctx)
{
    cf_fitsrc_points_t *p = ctx;
    cf_points_rebase(p->part[1].r, cf_points_lines(p->part[0].r));
}

void cf_fitsrc_points(cf_fitsrc_t *s, cf_fitsrc_points_t *ctx, cf_points_t *r, const char *path)
{
    memset(ctx, 0, sizeof *ctx);
    ctx->r = r;
    ctx->path = path;
    ctx->cols = cf_points_cols(r); /* the rows' width (0: an empty file, no cache) */
    /* The parse thread starts at the first rewind unless the caller
     * started it already (cellfit fit: at the open, the first rewind then
     * keeps its work); a job that reads the file in halves never starts it
     * (the job rewinds before every pass). */
    *s = (cf_fitsrc_t){cf_points_cols(r) == 5 ? 5 : 3,
                       -1,
                       path,
                       pts_rewind,
                       pts_read,
                       pts_where,
                       ctx,
                       pts_split,
                       pts_join,
                       cf_points_bound(r)};
}

void cf_fitsrc_points_cache(cf_fitsrc_points_t *ctx, size_t max_bytes)
{
    cache_drop(ctx);
    if (ctx->cols <= 0)
        return;
    size_t pts = max_bytes / (sizeof(double) * (size_t)ctx->cols);
    ctx->limit = pts > (size_t)LONG_MAX ? LONG_MAX : (long)pts;
    ctx->state = ctx->limit > 0 ? CF_FITSRC_CACHE_IDLE : CF_FITSRC_CACHE_OFF;
}

void cf_fitsrc_points_free(cf_fitsrc_points_t *ctx)
{
    cache_drop(ctx);
}

int cf_fitsrc_jnl_valid(const jnl_rec_t *r)
{
    return r->type == JNL_T_POINT && !(r->flags & JNL_F_NOSURF);
}

static int jnl_rewind_(void *ctx, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    jnl_reader_rewind(((cf_fitsrc_jnl_t *)ctx)->rd);
    return 0;
}

static long jnl_read_(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    cf_fitsrc_jnl_t *j = ctx;
    jnl_rec_t r;
    long n = 0;
    int rc = 1;
    while (n < max && (rc = jnl_reader_next(j->rd, &r)) == 1)
        if (cf_fitsrc_jnl_valid(&r))
            memcpy(rows + 3 * n++, r.xyz, sizeof r.xyz);
    if (rc < 0) {
        if (rc == RIG_ECORRUPT)
            return cf_fail(msg, ml, rc, "%s: record %llu changed while being read: journal corrupt",
                           j->path, (unsigned long long)j->rd->next);
        return cf_fail(msg, ml, rc, "%s: %s", j->path, rig_strerror(rc));
    }
    return n;
}

/* The sequence number of the k-th valid point (error path only). */
static void jnl_where_(void *ctx, long k, char *buf, size_t n)
{
    cf_fitsrc_jnl_t *j = ctx;
    jnl_rec_t r;
    long i = 0, seq = -1;
    jnl_reader_rewind(j->rd);
    while (jnl_reader_next(j->rd, &r) == 1)
        if (cf_fitsrc_jnl_valid(&r) && i++ == k) {
            seq = (long)r.seq;
            break;
        }
    snprintf(buf, n, "%s: record %ld", j->path, seq);
}

void cf_fitsrc_journal(cf_fitsrc_t *s, cf_fitsrc_jnl_t *ctx, jnl_reader_t *rd, const char *path,
                       long points)
{
    ctx->rd = rd;
    ctx->path = path;
    *s = (cf_fitsrc_t){3, points, path, jnl_rewind_, jnl_read_, jnl_where_, ctx, NULL, NULL, 0};
}

int cf_fitsrc_nominal_id(const char *path, uint64_t *hash, char name[JNL_NAME_LEN])
{
    FILE *f = path ? fopen(path, "rb") : NULL;
    if (!f)
        return CF_EIO;
    uint64_t h = 0xcbf29ce484222325ULL;
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0)
        for (size_t i = 0; i < n; i++)
            h = (h ^ buf[i]) * 0x100000001b3ULL;
    int bad = ferror(f);
    fclose(f);
    if (bad)
        return CF_EIO;
    *hash = h;
    const char *b = strrchr(path, '/');
    memset(name, 0, JNL_NAME_LEN);
    snprintf(name, JNL_NAME_LEN, "%s", b ? b + 1 : path);
    return CF_OK;
}
