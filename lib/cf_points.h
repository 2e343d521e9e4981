/* SPDX-License-Identifier: MIT */
/* cf_points.h: streaming reader of point files. Memory stays fixed whatever
 * the file size: one read buffer, lines of at most CF_POINTS_MAX_LINE bytes.
 *   ASCII: one point per line, numbers separated by blanks or one comma, '#'
 *          starts a comment, blank lines skipped, CRLF accepted.
 *   PLY:   ascii or binary_little_endian, vertex element with float/double
 *          x y z and optionally u v (or s t); other elements are skipped.
 *   raw:   by extension, no header: .xyz.bin (x y z) and .uvxyz.bin
 *          (u v x y z), little-endian IEEE float64, point after point
 *          (docs/formats.md); read by memcpy, values checked finite.
 * Values are bit-identical to strtod's. */
#ifndef CF_POINTS_H
#define CF_POINTS_H

#include <stddef.h>

#define CF_POINTS_MAX_COLS 8
#define CF_POINTS_MAX_LINE 4096

typedef struct cf_points cf_points_t; /* opaque */

/* Open path ("-": stdin). want_cols 1..CF_POINTS_MAX_COLS holds every data
 * line to that many values (3: x y z, 5: u v x y z, 2: u v); 0 takes the
 * count of the first data line, which must be 3 or 5. Returns CF_OK, CF_EIO,
 * CF_EPARSE (the first data line is unusable), CF_EUNSUPPORTED, CF_ENOMEM or
 * CF_EARG; msg says "file:line: ...". */
int cf_points_open(cf_points_t **r, const char *path, int want_cols, char *msg, size_t msglen);

/* Values per point: want_cols, or what the first data line had (0 while the
 * file has shown no data line, i.e. it is empty). */
int cf_points_cols(const cf_points_t *r);

/* Up to max_points points into buf (row-major, cols doubles each). Returns
 * the number read, 0 at the end of the file, or CF_EPARSE / CF_EIO with
 * "file:line: ..." in msg. After an error every later call repeats it. */
long cf_points_read(cf_points_t *r, double *buf, long max_points, char *msg, size_t msglen);

/* Line of the last point returned (binary PLY and raw: its point number). */
long cf_points_line(const cf_points_t *r);

/* Start again from the first point. CF_EUNSUPPORTED for stdin, CF_EIO if
 * the file cannot seek. */
int cf_points_rewind(cf_points_t *r);

/* Parse on a second thread from now on (host only; cf_points_mt.h): the
 * text formats (ASCII, PLY ascii) are parsed into a ring of row blocks of
 * fixed size (1.5 MiB at 5 columns) while the caller works on the rows it
 * has; reads, line numbers, errors and rewinds give exactly what they give
 * on one thread. Raw and binary PLY stay on the caller's thread (they read
 * at memory speed). Call it before the first read or after a rewind:
 * CF_EARG otherwise; CF_ENOMEM or CF_EIO (no thread) leave the reader on
 * one thread, working. cf_points_close stops the thread. */
int cf_points_thread(cf_points_t *r);

void cf_points_close(cf_points_t *r);

#endif
