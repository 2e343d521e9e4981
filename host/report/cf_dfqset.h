/* SPDX-License-Identifier: MIT */
/* cf_dfqset.h: the characteristics a report's DFQ carries, the one list
 * `cellfit report --dfq` and serve's EXPORT (report.dfq) both write: the
 * five figures of the deviations (RMS, max, min, max |d|, share within
 * tolerance, with their limits) and then one per named check point or zone
 * (cf_checks.h), nominal 0 and limits -tol, +tol (docs/formats.md). */
#ifndef CF_DFQSET_H
#define CF_DFQSET_H

#include "cf_checks.h"
#include "cf_dfq.h"
#include "cf_stats.h"

#define CF_DFQSET_FIGURES 5 /* the characteristics before the checks */

/* Fill c (CF_DFQSET_FIGURES + cs->n entries; cs may be NULL: none) for st,
 * within_pct the lower limit of the within-tolerance share; the checks'
 * names point into cs. The number of characteristics. */
int cf_dfqset_chars(const cf_stats_t *st, double within_pct, const cf_checks_t *cs,
                    cf_dfq_char_t *c);

#endif
