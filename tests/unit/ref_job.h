/* SPDX-License-Identifier: MIT */
/* ref_job.h: what several fit-job tests share: one run of an open job over
 * a points file, and the largest distance between two surfaces on a grid
 * of parameters (the surfaces' own evaluation: a comparison, not a
 * reference result). */
#ifndef REF_JOB_H
#define REF_JOB_H

#include "cf_fitjob.h"
#include "nf_surf.h"
#include <stddef.h>

/* cf_fitjob_run of j over the points file path (cols values a point: 5
 * given parameters, 3 projected), the file closed after; j stays open.
 * 0 or the error (its text in m). */
int ref_job_file(cf_fitjob_t *j, const char *path, int cols, cf_fitjob_result_t *r, char *m,
                 size_t ml);

/* ref_job_file with the points source's cache of cache bytes (0: none,
 * cf_fitsrc_points_cache). */
int ref_job_file_cache(cf_fitjob_t *j, const char *path, int cols, size_t cache,
                       cf_fitjob_result_t *r, char *m, size_t ml);

/* The pruning loop's coarse spline S* (bicubic, u knot 0.5, none in v:
 * REF_JOB_SU x REF_JOB_SV control points, heights 2 sin(1.3 i + 0.4 j)) and
 * a 4 x 4 bicubic plane base over [0, 50] x [0, 40] (both cf_surf_alloc'd:
 * cf_surf_free them); S* sampled at 48 x 48 parameters into path5 (u v x y
 * z) and path3 (x y z). 0, or -1 when a file or the memory fails. */
#define REF_JOB_SU 5
#define REF_JOB_SV 4
int ref_job_star(nf_surf_t *star, nf_surf_t *base, const char *path5, const char *path3);

/* max |a(u, v) - b(u, v)| over a 21 x 21 grid of the unit square. */
double ref_job_gap(const nf_surf_t *a, const nf_surf_t *b);

#endif
