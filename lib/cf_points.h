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

/* Points the file holds at most, known at open for a raw file (its size)
 * and a text file (ASCII, PLY ascii) small enough to be read whole then
 * (its lines); -1 otherwise (binary PLY, standard input, a larger text
 * file). Callers size their buffers by it. */
long cf_points_bound(const cf_points_t *r);

/* Up to max_points points into buf (row-major, cols doubles each). Returns
 * the number read, 0 at the end of the file, or CF_EPARSE / CF_EIO with
 * "file:line: ..." in msg. After an error every later call repeats it. */
long cf_points_read(cf_points_t *r, double *buf, long max_points, char *msg, size_t msglen);

/* Line of the last point returned (binary PLY and raw: its point number). */
long cf_points_line(const cf_points_t *r);

/* Start again from the first point. CF_EUNSUPPORTED for stdin, CF_EIO if
 * the file cannot seek. With the parse thread on and no point read since
 * the open or the last rewind, nothing moves: the thread's work is kept. */
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

/* Two halves for two threads: r from its first point up to the first line
 * start at or after the middle of the data (after a CSV header; raw: a
 * record boundary, half the whole records), *r2 from there to the end
 * (empty when the file has no second line start). r2 is a second reader
 * of the file, r's (cf_points_close(r) closes it; a later split rewinds and
 * returns it again). Both read on their callers' threads (no
 * cf_points_thread) and each keeps its own errors; r's lines and messages
 * are the file's, r2's count from the split until cf_points_rebase (raw:
 * its point numbers are the file's already). Regular ASCII and raw files
 * only: CF_EUNSUPPORTED otherwise (stdin, PLY, a middle inside a line
 * longer than CF_POINTS_MAX_LINE), CF_ENOMEM, CF_EIO: r unchanged. */
int cf_points_split(cf_points_t *r, cf_points_t **r2, char *msg, size_t msglen);

/* r reads the whole file again (after a split), from its first point. */
int cf_points_whole(cf_points_t *r);

/* Lines (raw: points) before the next point, counted from the file's
 * start: after a first half was read to its end, the second's base. */
long cf_points_lines(const cf_points_t *r);

/* A second half's lines (and the error it keeps) counted from the file's
 * start: lines before its first (cf_points_lines of the first half read to
 * its end). */
void cf_points_rebase(cf_points_t *r2, long lines);

void cf_points_close(cf_points_t *r);

#endif
