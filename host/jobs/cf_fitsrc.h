/* SPDX-License-Identifier: MIT */
/* cf_fitsrc.h: where the fit job's points come from, behind one small
 * interface it can rewind and read in batches: a points file (x y z, or
 * u v x y z with the parameters given) or a journal of measured points
 * (its valid point records, x y z). A live scan adds its points to the job
 * as they arrive (cf_fitjob_add) and hands the journal as the source of
 * every later pass. Nothing is kept per point, but for a points file's
 * optional cache (cf_fitsrc_points_cache). */
#ifndef CF_FITSRC_H
#define CF_FITSRC_H

#include "cf_points.h"
#include "jnl.h"
#include <stddef.h>
#include <stdint.h>

typedef struct cf_fitsrc {
    int cols;         /* 3: x y z (parameters by projection), 5: u v x y z (given) */
    long total;       /* points, when known before reading (journal); -1 otherwise */
    const char *name; /* the file, for messages */
    /* Back to the first point: 0, or a negative error with msg. */
    int (*rewind)(void *ctx, char *msg, size_t ml);
    /* Up to max points (cols doubles each) into rows: the count, 0 at the
     * end, or a negative error with msg naming file and line or record. */
    long (*read)(void *ctx, double *rows, long max, char *msg, size_t ml);
    /* "FILE:LINE" or "FILE: record N" of point k (0-based), for messages. */
    void (*where)(void *ctx, long k, char *buf, size_t n);
    void *ctx;
    /* Optional (NULL: one reader only). The points in two halves, one per
     * thread: half[0] the first, half[1] the rest, each a source of its own
     * (no split). 0, or a negative code: read the whole on one thread. */
    int (*split)(void *ctx, struct cf_fitsrc *half, char *msg, size_t ml);
    /* After half[0] was read to its end with no error: half[1]'s lines (in
     * its errors and where) counted from the file's start from now on. */
    void (*join)(void *ctx);
    /* Points at most when total is not known (a small points file's lines,
     * cf_points_bound): the job's batch buffers take no more; <= 0: not
     * known either. */
    long bound;
} cf_fitsrc_t;

/* Points s holds at most: total when known, else bound (<= 0: not known). */
static inline long cf_fitsrc_most(const cf_fitsrc_t *s)
{
    return s->total >= 0 ? s->total : s->bound;
}

/* One half of a points file (cf_points_split). */
typedef struct cf_fitsrc_part {
    cf_points_t *r;
    const char *path;
} cf_fitsrc_part_t;

/* An open points file (cf_points_open; its column count decides cols). A
 * regular ASCII or raw file splits into halves (part; their readers are
 * r's, closed with it). Optionally its rows kept in memory after the first
 * whole pass (cf_fitsrc_points_cache). */
typedef struct cf_fitsrc_points {
    cf_points_t *r;
    const char *path;
    cf_fitsrc_part_t part[2];
    double *rows;    /* the cache: cols doubles a point (heap), NULL when none */
    long n, cap;     /* points in it, room */
    long limit;      /* most points it may hold; 0: no cache (off, or dropped) */
    long at;         /* next point a cached pass serves */
    int cols, state; /* values a point; CF_FITSRC_CACHE_* (cf_fitsrc.c) */
} cf_fitsrc_points_t;
void cf_fitsrc_points(cf_fitsrc_t *s, cf_fitsrc_points_t *ctx, cf_points_t *r, const char *path);

/* The bound callers running a tolerance loop give the cache: every point of
 * the project's ASCII fields (10^4-10^5 points: 0.24-4 MB at 5 columns) and
 * 2.8 million x y z points, while a file of 10^7 or 10^8 points (the
 * streaming fits) is read from the file each pass as before, its memory
 * flat. */
#define CF_FITSRC_CACHE_MAX (64L << 20)

/* Keep the rows in memory, up to max_bytes (off by default). The first
 * whole pass (a rewind, then reads up to the 0 at the end) reads the file
 * and copies its rows; every later rewind + read serves them from memory:
 * the same rows, order and batches (up to max a call, 0 at the end), no
 * file read and no parse thread. A pass rewound before its end starts the
 * copy again at the next pass (split or where too: they move the reader);
 * rows beyond max_bytes or a read error drop the cache for good (the file
 * read as without it). where and split read the file as always. */
void cf_fitsrc_points_cache(cf_fitsrc_points_t *ctx, size_t max_bytes);

/* The cache's memory back (ctx stays usable, without a cache). */
void cf_fitsrc_points_free(cf_fitsrc_points_t *ctx);

/* An open journal reader: its point records without JNL_F_NOSURF. */
typedef struct cf_fitsrc_jnl {
    jnl_reader_t *rd;
    const char *path;
} cf_fitsrc_jnl_t;
void cf_fitsrc_journal(cf_fitsrc_t *s, cf_fitsrc_jnl_t *ctx, jnl_reader_t *rd, const char *path,
                       long points);

/* 1 for a journal record that holds a measured point. */
int cf_fitsrc_jnl_valid(const jnl_rec_t *r);

/* FNV-1a 64 of a file's bytes and its base name: the nominal's identity in
 * a journal header, checked before a journal is fitted. CF_EIO. */
int cf_fitsrc_nominal_id(const char *path, uint64_t *hash, char name[JNL_NAME_LEN]);

#endif
