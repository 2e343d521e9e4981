/* SPDX-License-Identifier: MIT */
/* cf_resfmt.h: a results row (cf_resdb.h) as one JSON object on one line
 * (the MQTT payload, `cellfit results --json`) or as CSV (`--csv`). */
#ifndef CF_RESFMT_H
#define CF_RESFMT_H

#include "cf_resdb.h"
#include <stdio.h>

void cf_resfmt_json(FILE *f, const cf_resdb_job_t *j);
void cf_resfmt_csv_header(FILE *f);
void cf_resfmt_csv(FILE *f, const cf_resdb_job_t *j);

/* The JSON object in buf (NUL-terminated): its length, or -1 when it does
 * not fit. */
int cf_resfmt_json_buf(const cf_resdb_job_t *j, char *buf, size_t n);

#endif
