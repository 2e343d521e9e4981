/* cf_job.h: the cell's fit job on files, for `cellfit serve`: read the
 * nominal surface and a points file (x y z, projected onto the nominal, or
 * u v x y z), optionally refine the nominal's net to the size asked, fit
 * (Eq. 7, one pass), then the signed normal deviations of every point to the
 * fitted surface (cf_stats); and the export of a result into a folder
 * (fitted IGES + report JSON). Memory: the fit's byte formula, the fixed
 * statistics and batch buffers; never a function of the number of points.
 * Long loops report progress and stop between batches when asked. */
#ifndef CF_JOB_H
#define CF_JOB_H

#include "cf_stats.h"
#include "nf_fit.h"
#include <stddef.h>

/* Progress (0..100) and a cooperative stop check, both optional. */
typedef struct cf_job_ctl {
    void (*progress)(void *ctx, int pct);
    int (*should_stop)(void *ctx); /* non-zero: stop at the next batch */
    void *ctx;
} cf_job_ctl_t;

typedef struct cf_job_fit_opts {
    const char *nominal, *points;
    double alpha, beta, tol; /* tol: mm, for the within-tolerance count */
    int net_u, net_v;        /* 0: the nominal's net */
} cf_job_fit_opts_t;

typedef struct cf_job_result {
    nf_surf_t fitted; /* heap (cf_surf) */
    cf_stats_t *st;   /* heap: deviations of the points to the fit */
    long points;
    nf_solve_stats_t solve;
    double seconds;
    long bytes; /* fitter memory */
} cf_job_result_t;

/* Check that the nominal can be read and refined to net_u x net_v within
 * the board's budget, without fitting. 0, CF_EIO/CF_EPARSE (nominal),
 * NF_EBUDGET (too big), CF_EARG (net smaller than the nominal's). */
int cf_job_check(const cf_job_fit_opts_t *o, char *msg, size_t ml);

/* The nominal read and refined to the net asked (s: heap, cf_surf_free),
 * and the fit's byte count; the errors of cf_job_check. */
int cf_job_load_base(const cf_job_fit_opts_t *o, nf_surf_t *s, long *need, char *msg, size_t ml);

/* Run the fit. 0 with *out filled (free with cf_job_result_free);
 * RIG_EABORTED when ctl asked to stop; otherwise CF_E* / NF_E* with msg
 * naming file and line. On failure *out owns nothing. */
int cf_job_fit(const cf_job_fit_opts_t *o, const cf_job_ctl_t *ctl, cf_job_result_t *out, char *msg,
               size_t ml);
void cf_job_result_free(cf_job_result_t *r);

/* Identification of an exported result (goes into report.json). */
typedef struct cf_job_meta {
    unsigned long part;
    unsigned program, seq;
    const char *nominal, *points, *board;
    long long utc;       /* seconds since 1970 */
    const char *journal; /* the scan's journal (SCAN_FIT), or NULL */
} cf_job_meta_t;

/* Folder name for a result: "<part>_<YYYYMMDDTHHMMSSZ>" into buf. */
void cf_job_folder_name(unsigned long part, long long utc, char *buf, size_t n);

/* Create dir (one level; its parent must exist) and write dir/fitted.igs
 * and dir/report.json. CF_EIO with msg on failure. */
int cf_job_export(const cf_job_result_t *r, const cf_job_meta_t *meta, const char *dir, char *msg,
                  size_t ml);

#endif
