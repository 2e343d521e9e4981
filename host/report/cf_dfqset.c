/* SPDX-License-Identifier: MIT */
/* cf_dfqset.c: a report's DFQ characteristics (cf_dfqset.h). */
#include "cf_dfqset.h"
#include <math.h>
#include <string.h>

int cf_dfqset_chars(const cf_stats_t *st, double within_pct, const cf_checks_t *cs,
                    cf_dfq_char_t *c)
{
    const double t = st->tol;
    const cf_dfq_char_t v[CF_DFQSET_FIGURES] = {
        {"RMS deviation", 0, NAN, t, "mm", cf_stats_rms(st), 4},
        {"Max deviation", 0, -t, t, "mm", st->max, 4},
        {"Min deviation", 0, -t, t, "mm", st->min, 4},
        {"Max absolute deviation", 0, NAN, t, "mm", st->max_abs, 4},
        {"Points within tolerance", 100, within_pct, NAN, "%", cf_stats_within_pct(st), 2},
    };
    memcpy(c, v, sizeof v);
    int n = CF_DFQSET_FIGURES;
    for (int i = 0; cs && i < cs->n; i++) /* NaN: written as not measured */
        c[n++] = (cf_dfq_char_t){cs->c[i].name, 0, -t, t, "mm", cf_checks_value(cs, i), 4};
    return n;
}
