/* SPDX-License-Identifier: MIT */
/* cf_scanjob.h: the cell's scan job for `cellfit serve`: the raster over
 * a region measured on the rig (firmware/scan.h) into a new journal file
 * (cf_store_file.h), with progress and a stop check; and the fit of such a
 * journal onto the nominal through the fit job (cf_fitjob, as cf_job: the
 * configured loop, robust passes and reprojection, the signed normal
 * deviations read back from the journal). The scan keeps nothing per
 * point; a SCAN_FIT's live fit job (opts.fit) holds them (cf_fitjob.h). */
#ifndef CF_SCANJOB_H
#define CF_SCANJOB_H

#include "cf_job.h"
#include "cf_scanfast.h"
#include "hal_rig.h"
#include "rig.h"
#include "scan.h"
#include <stddef.h>

typedef struct cf_scanjob_opts {
    rig_stage_t stage;
    rig_probe_t probe;
    double x0, y0, x1, y1, step; /* region (corners in any order) and grid step, mm */
    double z0, cal[3];           /* kinematics (scan.h) */
    const char *journal;         /* created; never overwritten */
    const char *nominal;         /* identity in the header, or NULL */
    unsigned long long job_id;
    int pct0, pct1; /* progress reported over this span */
    /* Appended (issue 19): the method (cf_scanfast.h; 0 stop-and-go) and,
     * on the fly, the rig's drivers (the stream and the non-blocking move
     * are theirs) and the trigger period (0: 50 us); the profiler is not a
     * cell method yet. */
    int method;
    hal_rig_t *rig;
    double period_us;
    /* Appended (map version 3): on the fly, the scan's counts (triggers,
     * losses) copied here when not NULL (struct cf_scanfast_res, cf_scanfast.h). */
    struct cf_scanfast_res *fast_out;
    const char *part_id; /* the PLC's PART_ID: a meta record in the journal, or NULL */
    /* Appended (issue 19, SCAN_FIT streamed): every point with a reading
     * goes into this open fit job (cf_fitjob_add) as it arrives, as the
     * shell's `scan --fit` does, so the first pass is done with the last
     * row; NULL: none. t_last_row gets the clock time (cli_now) the last
     * row ended (the scan's end when stop-and-go), when not NULL. */
    cf_fitjob_t *fit;
    double *t_last_row;
    /* Appended (issue 19): method CF_SCAN_PROFILER: the line profiler's URI
     * (gev:ADDRESS[:SERIAL]) and geometry; one pass of its profiles (the
     * region and step are not its plan: the geometry is). */
    const char *gev_uri;
    const cf_scanfast_geom_t *gev_geom;
} cf_scanjob_opts_t;

/* The plan of the region (RIG_EARG when it has no point or too many). */
int cf_scanjob_plan(const cf_scanjob_opts_t *o, scan_plan_t *pl);

/* Measure into o->journal. Returns RIG_OK or the job's rig_err_t (res->where
 * says which part failed), RIG_EOPEN / RIG_EIO when the journal cannot be
 * created (msg says why; nothing measured, no file left). The journal is
 * consistent whatever the ending (scan.h). */
int cf_scanjob_run(const cf_scanjob_opts_t *o, const cf_job_ctl_t *ctl, scan_result_t *res,
                   char *msg, size_t ml);

/* Fit the journal's points onto f->nominal (f->points unused) with f's
 * settings; progress over pct0..pct1. 0 with *out filled
 * (free with cf_job_result_free), RIG_EABORTED, CF_EEMPTY (no point), or
 * CF_E* / NF_E* / RIG_E* with msg. */
int cf_scanjob_fit(const char *journal, const cf_job_fit_opts_t *f, const cf_job_ctl_t *ctl,
                   int pct0, int pct1, cf_job_result_t *out, char *msg, size_t ml);

/* The fit of a SCAN_FIT whose points went into fj during the scan
 * (cf_scanjob_opts_t.fit): the later passes read the points fj holds when
 * cf_fitjob_held, else the journal (as cf_scanjob_fit). *from gets
 * "memory" or "journal" when not NULL. Returns as cf_scanjob_fit; fj stays
 * the caller's (cf_fitjob_close). */
int cf_scanjob_fit_live(cf_fitjob_t *fj, const char *journal, const cf_job_ctl_t *ctl, int pct0,
                        int pct1, cf_job_result_t *out, const char **from, char *msg, size_t ml);

#endif
