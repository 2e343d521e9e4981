/* SPDX-License-Identifier: MIT */
/* cf_plcrun.h: the job runner `cellfit serve` uses (cf_plcsrv.h's table):
 *   home     = reference the stage (a latched drive fault is reset first);
 *   scan     = the raster over SCAN_X0..SCAN_Y1 at SCAN_STEP measured into
 *              a new journal "<part>_<UTC>.jnl" in the journal folder (or
 *              the results folder RESULTS_FOLDER chooses) (cf_scanjob.h);
 *   fit      = FIT: the configured points file against the nominal RECIPE
 *              chooses (0: `nominal`, N: `nominal.N`)
 *              (cf_job); SCAN_FIT: the points just measured, streamed
 *              into a fit job opened before the scan (rr->live) and read
 *              from its memory after the last row, else from the journal
 *              (cf_scanjob_fit_live);
 *              both through the fit job with the PLC's weights, net,
 *              tolerance and fit settings (FIT_TOL > 0: the tolerance
 *              loop to FIT_WITHIN %, FIT_MAX_CP, FIT_REFINE; FIT_ROBUST,
 *              FIT_REPARAM; the config's are the registers' defaults,
 *              rr->fit the rest); results from the deviation statistics
 *              at TOLERANCE, FIT_STATUS from the loop;
 *   export   = the last fit's IGES and report JSON (the journal's path,
 *              its job's sequence, UTC time and PART_ID) into the results
 *              folder RESULTS_FOLDER chooses, in a new folder
 *              "<part>_<UTC>_<RESULT_SEQ>_<UUID>" made whole in a hidden
 *              temporary one and renamed (never overwritten).
 * The rig's lines belong to the job's thread while a phase runs (rig_mu);
 * an abort sets the server's stop flag, which the stage driver polls while
 * it waits for a move or homing (hal_stage_t.should_stop) and the scan
 * between points: the stage is stopped from the job's own line within one
 * poll. The stage's and the probe's transports see the same flag
 * (hal_set_stop): retries, late-reply waits and reconnects give up at once,
 * so an abort lands within one request timeout even on a hung device. With
 * no job running, an abort stops the stage at once (one attempt). A rig
 * lost for good (the simulator ended) stops the job with RIG_ELOST, which
 * the scan's journal ends with. */
#ifndef CF_PLCRUN_H
#define CF_PLCRUN_H

#include "cf_plcsrv.h"
#include "cf_scanfast.h"
#include "cf_simchild.h"
#include "hal_rig.h"
#include <pthread.h>
#include <stdatomic.h>

#define CF_PLCRUN_RECIPES 16                 /* RECIPE 0 (`nominal`) .. 15 (`nominal.15`) */
#define CF_PLCRUN_MIN_FREE (1024.0 * 1024.0) /* bytes free a job's folder keeps by default */

typedef struct cf_plcrun {
    const char *nominal, *points;             /* fit inputs (config) */
    const char *checks;                       /* check points/zones for EXPORT's DFQ (config) */
    const char *recipe[CF_PLCRUN_RECIPES];    /* nominal.N (config); [0] unused: nominal */
    cf_fitjob_opts_t fit;                     /* fit settings (config; PLC params override) */
    const char *results_dir[PLC_MAX_FOLDERS]; /* RESULTS_FOLDER choices */
    const char *journal_dir;                  /* scans' journals; NULL: the results folder */
    double z0, cal[3];                        /* kinematics of the probe (scan.h) */
    hal_rig_t *rig;                           /* NULL: no rig */
    cf_simchild_t *sim;                       /* --sim: the simulator, watched */
    pthread_mutex_t rig_mu;                   /* the rig's lines: one user at a time */
    const cf_job_ctl_t *ctl;                  /* the running phase's (under rig_mu) */
    cf_job_result_t last;                     /* the latched fit's result */
    int have_last, last_scan, sim_lost;
    unsigned long last_part;
    unsigned last_seq, last_program;        /* the latched fit's job: RESULT_SEQ */
    long long last_utc;                     /* its JOB_TIME */
    char last_part_id[PLC_PART_ID_LEN + 1]; /* its PART_ID */
    const char *last_nominal;               /* the nominal (recipe) it used */
    double job_t0;                          /* start of the running job (SCAN_FIT's duration) */
    char journal[4096];                     /* the last scan's journal */
    char last_journal[4096];                /* the journal of the latched fit ("" for FIT) */
    char last_export[4096];                 /* folder of the last export */
    /* issue 19: SCAN's method (cf_scanfast.h: 0 stop-and-go, 1 on the fly,
     * 2 the profiler)
     * and trigger period (config scan_method, scan_period_us) */
    int scan_method;
    double scan_period_us;
    int idle_stop; /* 1 while an ABORT with no job running sends STOP (under rig_mu) */
    /* The last scan's on-the-fly counts (SCAN_TRIGGERS .. SCAN_OVERRUNS;
     * 0 after a stop-and-go scan), written by the job, read by the server. */
    atomic_uint scan_counts[CF_PLC_SCAN_COUNTS];
    /* Bytes a job's folder must keep free beyond what the job writes
     * (config min_free_mb; 0: CF_PLCRUN_MIN_FREE, 1 MiB). */
    double min_free;
    /* SCAN_FIT streamed (issue 19): the fit job opened before the scan,
     * fed each point as it arrives, run and closed by the fit phase (NULL
     * otherwise); the clock time the scan's last row ended. */
    cf_fitjob_t *live;
    double t_last_row;
    /* scan_method profiler (issue 19): the line profiler's URI
     * (gev:ADDRESS[:SERIAL]) and its scan geometry (cf_scanfast.h). */
    const char *gev_uri;
    cf_scanfast_geom_t gev_geom;
} cf_plcrun_t;

/* The runner table over rr. rr->rig (and rr->sim) set before, or NULL. */
void cf_plcrun_init(cf_plcrun_t *rr, cf_runner_t *out);
void cf_plcrun_free(cf_plcrun_t *rr);

/* PLC error code (3xx, 2xx) for a rig_err_t that ended a job at where
 * (SCAN_AT_*); CF_PLC_ABORTED for RIG_EABORTED. */
int cf_plcrun_rig_code(int rc, int where);

#endif
