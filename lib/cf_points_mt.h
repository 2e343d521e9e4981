/* SPDX-License-Identifier: MIT */
/* cf_points_mt.h: the point reader's parse thread (host only): a producer
 * thread fills a bounded ring of row blocks (each row's line number kept,
 * the last block marked by the end of the data or an error) and the
 * caller takes rows from it in order, in batches of any size. The rows, the
 * line numbers, where an error falls and its message are those the
 * producer's fill function gives, i.e. those of reading on one thread:
 * cf_points_thread (cf_points.h) uses it for the text formats. */
#ifndef CF_POINTS_MT_H
#define CF_POINTS_MT_H

#include <stddef.h>

typedef struct cf_pmt cf_pmt_t; /* opaque */

/* Fills up to max rows (cols doubles each) and their line numbers: the
 * count. *err 0 and a count below max: the end of the data; *err < 0: an
 * error after the count's rows, its text in msg. Runs on the thread. */
typedef long (*cf_pmt_fill_fn)(void *ctx, double *rows, long *lines, long max, int *err, char *msg,
                               size_t ml);

/* Allocate nblocks blocks of block rows (every page touched now, so the
 * footprint is fixed) and start the thread. CF_OK, CF_ENOMEM, CF_EIO (no
 * thread), CF_EARG. */
int cf_pmt_start(cf_pmt_t **t, int cols, long block, int nblocks, cf_pmt_fill_fn fill, void *ctx);

/* Up to max rows into out: the count, 0 at the end, or the error (with the
 * rows of this call before it dropped, and repeated by every later call),
 * exactly as one thread reading would. */
long cf_pmt_read(cf_pmt_t *t, double *out, long max, char *msg, size_t ml);

/* Line of the last row returned (0 before the first). */
long cf_pmt_line(const cf_pmt_t *t);

/* Stop the thread (it finishes the block it is filling), join it, free
 * (a paused ring too). */
void cf_pmt_stop(cf_pmt_t *t);

/* A rewind without a new ring: pause stops and joins the thread and empties
 * the ring (its rows dropped); the caller moves the data's start; resume
 * starts the thread again on the same blocks (no allocation, no first
 * touch: a fresh ring every pass was half the page faults of a fitting
 * loop on a small file). resume: CF_OK, or CF_EIO when no thread starts
 * (t stays paused: cf_pmt_stop frees it). */
void cf_pmt_pause(cf_pmt_t *t);
int cf_pmt_resume(cf_pmt_t *t);

#endif
