/* cf_plcrun.h: the job runner `cellfit serve` uses (cf_plcsrv.h's table):
 *   fit    = fit the configured points file against the configured nominal
 *            (cf_job), results from the deviation statistics;
 *   export = the last fit's IGES and report JSON into the results folder
 *            chosen by RESULTS_FOLDER, in "<part>_<UTC timestamp>";
 *   home, scan = the rig. RIG WIRING: they wait for the stage and probe
 *            drivers (hal/, branch rig) and the scan job (firmware/scan.h,
 *            branch journal); until those are wired the runner has no rig,
 *            so the state machine refuses HOME / SCAN / SCAN_FIT with 106
 *            "rig not configured". */
#ifndef CF_PLCRUN_H
#define CF_PLCRUN_H

#include "cf_plcsrv.h"

typedef struct cf_plcrun {
    const char *nominal, *points;             /* fit inputs (config) */
    const char *results_dir[PLC_MAX_FOLDERS]; /* RESULTS_FOLDER choices */
    cf_job_result_t last;                     /* the latched fit's result */
    int have_last;
    unsigned long last_part;
    char last_export[4096]; /* folder of the last export */
} cf_plcrun_t;

/* The runner table over rr (rig: 0 until the rig is wired). */
void cf_plcrun_init(cf_plcrun_t *rr, cf_runner_t *out);
void cf_plcrun_free(cf_plcrun_t *rr);

#endif
