/* SPDX-License-Identifier: MIT */
/* cf_jobfiles.h: the files an export writes beside fitted.igs and
 * report.json, the same set `make demo` writes: the fitted surface as STEP
 * AP242 (fitted.stp), the per-point deviations (deviations.csv: every point
 * of the job, from its points file or its scan's journal, projected on the
 * fitted surface) and the SPC figures as Q-DAS DFQ (report.dfq). Each file
 * is written atomically (PATH.tmp, renamed); memory is the surface's, never
 * a function of the number of points. */
#ifndef CF_JOBFILES_H
#define CF_JOBFILES_H

#include "cf_checks.h"
#include "cf_dfq.h"
#include "cf_job.h"
#include "cf_trim.h"
#include <stddef.h>

/* The names written into a folder, NULL-terminated (for clean-up). */
extern const char *const cf_jobfiles_names[];

/* Write dir/fitted.stp (trimmed by trim when it has loops),
 * dir/deviations.csv and dir/report.dfq for result r (r->stats must be
 * there). The points come from meta->points, or from
 * meta->journal when there is no points file; with neither, no CSV is
 * written. cs (NULL: none): the check points and zones, their deviations
 * gathered from the same points (reset first; without points, none has a
 * value: each logged as a warning) and written into the DFQ after the five
 * figures (cf_dfqset). CF_OK, or a CF_E* code with msg (files written so far are left
 * for the caller's clean-up). */
int cf_jobfiles_write(const cf_job_result_t *r, const cf_job_meta_t *meta, const cf_trim_t *trim,
                      cf_checks_t *cs, const char *dir, char *msg, size_t ml);

/* The trim of meta->nominal (cf_surfio_read_trim; none without a nominal),
 * checked to lie in r->surf's domain with closed loops. trim: cf_trim_free
 * it (empty on failure). CF_OK or the reader's error with msg. */
int cf_jobfiles_trim(const cf_job_result_t *r, const cf_job_meta_t *meta, cf_trim_t *trim,
                     char *msg, size_t ml);

#endif
