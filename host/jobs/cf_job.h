/* SPDX-License-Identifier: MIT */
/* cf_job.h: the cell's fit job on files, for `cellfit serve`: the nominal
 * (refined to the net asked) and a points file (x y z, projected, or
 * u v x y z) through the fit job (cf_fitjob: plain, robust, reprojected or
 * to a tolerance, as configured), with the signed normal deviations of
 * every point to the fit (cf_stats); and the export of a result into a
 * folder (fitted IGES and STEP, report JSON, per-point CSV, Q-DAS DFQ). Memory: the fit job's; never a
 * function of the number of points. */
#ifndef CF_JOB_H
#define CF_JOB_H

#include "cf_fitjob.h"
#include "cf_stats.h"
#include <stddef.h>

typedef struct cf_job_fit_opts {
    const char *nominal, *points;
    cf_fitjob_opts_t fit; /* tol: the part's tolerance, mm; net_u, net_v: 0 the nominal's */
} cf_job_fit_opts_t;

/* The result: the fit job's, with its statistics (stats) always there. */
typedef cf_fitjob_result_t cf_job_result_t;

/* The nominal read and the job opened on it (refined, budget checked):
 * 0, CF_EIO/CF_EPARSE (nominal), NF_EBUDGET (too big), CF_EARG (net
 * smaller than the nominal's, bad settings). *j: cf_fitjob_close. */
int cf_job_open(const cf_job_fit_opts_t *o, cf_fitjob_t **j, char *msg, size_t ml);

/* cf_job_open's checks without fitting. */
int cf_job_check(const cf_job_fit_opts_t *o, char *msg, size_t ml);

/* Run the fit on o->points. 0 with *out filled (free with
 * cf_job_result_free); RIG_EABORTED when ctl asked to stop; otherwise
 * CF_E* / NF_E* with msg naming file and line. On failure *out owns
 * nothing. */
int cf_job_fit(const cf_job_fit_opts_t *o, const cf_job_ctl_t *ctl, cf_job_result_t *out, char *msg,
               size_t ml);
void cf_job_result_free(cf_job_result_t *r);

/* Identification of an exported result (goes into report.json). */
typedef struct cf_job_meta {
    unsigned long part;
    unsigned program, seq; /* seq: the job's sequence (RESULT_SEQ) */
    const char *nominal, *points, *board;
    long long utc;        /* the job's time (JOB_TIME), seconds since 1970 */
    const char *journal;  /* the scan's journal (SCAN_FIT), or NULL */
    const char *part_id;  /* PART_ID, or NULL */
    unsigned export_seq;  /* the EXPORT command's sequence (0: none) */
    long long export_utc; /* when it was exported (0: none) */
    const char *checks;   /* check points and zones (config `checks`, cf_checks.h), or NULL */
} cf_job_meta_t;

/* Folder name for a result: "<part>_<YYYYMMDDTHHMMSSZ>" into buf. */
void cf_job_folder_name(unsigned long part, long long utc, char *buf, size_t n);

/* A folder name that no other export takes: "<part>_<UTC>_<seq>_<UUID>"
 * (UUID: cf_uuid_new). CF_OK, or CF_EIO when no random UUID is to be had. */
int cf_job_unique_name(unsigned long part, long long utc, unsigned seq, char *buf, size_t n);

/* Write dir/fitted.igs, dir/report.json and cf_jobfiles' fitted.stp,
 * deviations.csv and report.dfq as one (the surfaces as the trimmed face
 * meta->nominal is, when it is one): both into a hidden
 * temporary sibling ".DIR.tmp.PID" (dir's parent must exist), then renamed
 * to dir, which must not exist: an export never overwrites one, and a
 * reader never sees a folder half written. CF_EIO with msg on failure
 * (the temporary removed), also when dir exists. */
int cf_job_export(const cf_job_result_t *r, const cf_job_meta_t *meta, const char *dir, char *msg,
                  size_t ml);

#endif
