/* SPDX-License-Identifier: MIT */
/* scan.h: the scan job: a raster plan over a region of the part (serpentine
 * rows), and per grid point a stage move, a probe reading, the 3-D point by
 * the kinematic model below, a journal record (jnl.h) and a call into the
 * caller (the fitter). Nothing is kept per point.
 *
 * Kinematic model (docs/journal.md): the probe sits at height z0 above the
 * stage frame and looks along -z; with the stage at (x, y) and a reading d,
 *     point = (x + cx, y + cy, z0 - d + cz)
 * where (cx, cy, cz) is the calibration offset of the probe's beam.
 *
 * Faults: the HAL retries; the job decides what a fault means. A probe
 * seeing no surface (RIG_ENOSURF) is a flagged record and the scan goes on;
 * any other stage or probe error ends the job with that code; should_stop
 * stops the stage and ends it with RIG_EABORTED. Every ending writes the
 * end record (with the code) and syncs, so the journal is consistent. */
#ifndef SCAN_H
#define SCAN_H

#include "jnl.h"
#include "rig.h"

/* Grid points at x0 + i dx (0 <= i < nx), y0 + j dy (0 <= j < ny); row j
 * runs in +x when j is even and in -x when odd (serpentine). */
typedef struct scan_plan {
    double x0, y0, dx, dy;
    long nx, ny;
} scan_plan_t;

#define SCAN_MAX_POINTS 100000000L /* a plan beyond this is refused */

/* Plan over [x0, x1] x [y0, y1] with steps sx, sy > 0: as many points as
 * fit from x0 and y0 (the far edge is included when the step divides the
 * width, to 1e-9 relative). RIG_EARG for non-finite values, an empty
 * region or a plan over SCAN_MAX_POINTS. */
int scan_plan_init(scan_plan_t *p, double x0, double x1, double y0, double y1, double sx,
                   double sy);
long scan_plan_count(const scan_plan_t *p);
/* Stage target of the k-th point in scan order; *row_end 1 on a row's last. */
void scan_plan_point(const scan_plan_t *p, long k, double *x, double *y, int *row_end);

typedef struct scan_kin {
    double z0;     /* probe height above the stage frame (mm) */
    double cal[3]; /* calibration offset cx, cy, cz (mm) */
} scan_kin_t;

/* The measured point of a reading d with the stage at (x, y). */
void scan_kin_point(const scan_kin_t *k, double x, double y, double d, double out[3]);

typedef struct scan_cb {
    /* each point with a reading, after it is journalled; a non-zero return
     * ends the job with that code */
    int (*point)(void *ctx, const jnl_rec_t *r);
    /* after each grid point: visited, planned, acknowledged (synced) */
    void (*progress)(void *ctx, long done, long planned, uint64_t acked);
    void *ctx;
} scan_cb_t;

typedef struct scan_job {
    rig_stage_t stage;
    rig_probe_t probe;
    rig_clock_t clock;
    scan_plan_t plan;
    scan_kin_t kin;
    scan_cb_t cb; /* callbacks may be NULL */
    int home;     /* home the stage first when it is not homed (else RIG_ENOTHOMED) */
} scan_job_t;

typedef struct scan_result {
    long done;       /* grid points journalled */
    long points;     /* of which with a reading */
    long flagged;    /* of which without (RIG_ENOSURF) */
    long fail_index; /* grid point at which the job ended early, -1 */
    int code;        /* the job's result, as returned */
    int where;       /* SCAN_AT_*: what ended it early */
} scan_result_t;

enum {
    SCAN_AT_NONE = 0,
    SCAN_AT_STAGE = 1,   /* status, home, limits, move or position */
    SCAN_AT_PROBE = 2,   /* a reading */
    SCAN_AT_JOURNAL = 3, /* append or sync */
    SCAN_AT_CALLER = 4,  /* the point callback */
    SCAN_AT_STOP = 5     /* should_stop */
};

/* Header fields the job fixes: kinematics and the planned count (the caller
 * sets job id, nominal identity, start time, sync policy). */
void scan_header(const scan_job_t *job, jnl_header_t *h);

/* Run the job into j (open, empty of points or not). Returns RIG_OK or the
 * code the job ended with (also in res->code): a stage or probe error,
 * RIG_ELIMIT when the plan leaves the soft limits (before any move),
 * RIG_EABORTED, a journal error (RIG_EFULL, RIG_EIO) or the callback's. */
int scan_run(const scan_job_t *job, jnl_t *j, scan_result_t *res);

#endif
