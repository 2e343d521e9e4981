/* SPDX-License-Identifier: MIT */
/* cf_scanfast.h: scanning at a sensor's pace (issue 19), the two fast
 * methods beside the stop-and-go raster of firmware/scan.c:
 *   on the fly  each raster row run at constant speed, the probe streaming
 *               one reading per trigger with the position latched at it
 *               (hal_probe_stream_*), paired by trigger number (scan_otf.h);
 *   profiler    a laser line profiler over GigE Vision (hal_gev.h): each
 *               profile one row, x from its number in the scan, y along it.
 * Both journal every point (jnl.h; one sync per row: docs/journal.md) and
 * hand it to the caller (the live fit, cf_fitjob_add) as it arrives; the
 * stop check (ABORT, watchdog, a signal) is asked between stream reads, so
 * it acts within one row. Every loss is counted (cf_scanfast_res_t) and
 * journalled as a gap record at its numbers (jnl_gap: a trigger's reading
 * or position lost, numbers lost on both sides, a lost profile at its own
 * number and x), never a shifted row.
 * Memory: scan_otf's struct and one frame, never a function of the points.
 * Prefix cf_scanfast_. Errors: rig_err_t codes, msg says where. */
#ifndef CF_SCANFAST_H
#define CF_SCANFAST_H

#include "hal_rig.h"
#include "jnl.h"
#include "scan.h"
#include <stddef.h>

typedef enum cf_scan_method {
    CF_SCAN_STOP = 0,    /* stop-and-go, firmware/scan.c */
    CF_SCAN_OTF = 1,     /* on the fly */
    CF_SCAN_PROFILER = 2 /* GigE Vision line profiler */
} cf_scan_method_t;

/* "stop", "otf", "profiler" -> the method (-1 unknown); the default of a
 * probe URI (gev: -> profiler, else stop); and the name. */
int cf_scanfast_method(const char *name);
cf_scan_method_t cf_scanfast_default_method(const char *probe_uri);
const char *cf_scanfast_method_name(cf_scan_method_t m);

typedef struct cf_scanfast_cb {
    int (*point)(void *ctx, const double xyz[3]); /* after journalling; non-zero ends the job */
    void (*progress)(void *ctx, long rows_done, long rows, long points);
    int (*should_stop)(void *ctx);
    void *ctx;
} cf_scanfast_cb_t;

/* The profiler's geometry: cellsim --gev's line "width W height H profiles
 * P x0 X dx DX y0 Y dy DY z0 Z lo LO scale S" (docs/rig-profiler.md):
 * profile n at x = x0 + (n mod P) dx, point i at y0 + i dy, distance
 * lo + raw scale, the point's z = z0 - distance. */
typedef struct cf_scanfast_geom {
    int width, height;
    long profiles;
    double x0, dx, y0, dy, z0, lo, scale;
} cf_scanfast_geom_t;

/* Parse the geometry line (the "cellsim: gev 127.0.0.1 SERIAL " prefix
 * may be there or not): 0, or -1. */
int cf_scanfast_geom_parse(const char *s, cf_scanfast_geom_t *g);

typedef struct cf_scanfast_res {
    long rows, rows_done; /* rows (profiles) planned, ended */
    long points;          /* journalled with a reading */
    long flagged;         /* journalled without a reading (losses are gap records) */
    /* on the fly (scan_otf_counts_t) */
    long triggers, nosurf, sensor_errors, lost_readings, lost_triggers, both_lost, dup, late,
        overrun, dropped_by_probe, rows_cut;
    long past_end;     /* events after a row's end trigger, dropped (scan_otf_row_end_at) */
    long before_start; /* events at a row's start before its last there (scan_otf_row_start_at) */
    double speed, period_us; /* the stage's speed and the trigger period used */
    /* profiler (hal_gev_stats_t) */
    long frames, frames_lost, profiles_lost, frames_bad, dropouts;
    long gap_records;           /* losses journalled as gap records (JNL_T_GAP, issue 19) */
    long fail_row;              /* the row the job ended in, -1 */
    int code;                   /* as returned */
    int where;                  /* SCAN_AT_* */
    double seconds, t_last_row; /* the scan's time; clock time of the last row's end */
} cf_scanfast_res_t;

/* On the fly over the plan's rows (serpentine, scan.h) on an open rig: the
 * stage's speed set so that period_us apart the triggers fall plan->dx
 * apart, each row: a move to its start, scan_otf_row_begin, the move to its
 * end started, the stream armed, read until the stage stops, stopped and
 * drained, the row ended (a stage fault: the row cut short, the job ends
 * with RIG_EFAULT), the journal synced. j open, empty of points. */
int cf_scanfast_otf(hal_rig_t *rig, const scan_plan_t *pl, const scan_kin_t *kin, double period_us,
                    jnl_t *j, const cf_scanfast_cb_t *cb, cf_scanfast_res_t *res, char *msg,
                    size_t ml);

/* The profiler at uri (gev:ADDRESS[:SERIAL]) for `profiles` profiles
 * (0: one pass, g->profiles) at frame_rate frames/s (0: the device's); a
 * lost frame is height gap records (JNL_GAP_PROFILE) at the numbers and x
 * of its profiles. ROWEND marks each profile's last record; one sync a frame. */
int cf_scanfast_profiler(const char *uri, const cf_scanfast_geom_t *g, long profiles,
                         double frame_rate, jnl_t *j, const cf_scanfast_cb_t *cb,
                         cf_scanfast_res_t *res, char *msg, size_t ml);

/* The journal header's planned count and kinematics for a method's plan. */
void cf_scanfast_header(const scan_kin_t *kin, long planned, jnl_header_t *h);

#endif
