/* SPDX-License-Identifier: MIT */
/* rig.h: what a scan job needs from the world, declared by the firmware and
 * implemented outside it (hal/ on the cell controller, a board port on a
 * microcontroller): a motion stage, a displacement probe, append-only
 * storage for the journal, and a clock. firmware/ sees only these tables;
 * it never knows whether the rig is real or simulated, nor the wire.
 *
 * Every operation returns RIG_OK (0) or a negative rig_err_t (rig_err.h).
 * Each table starts with `version`; operations are appended, never
 * reordered, so an older implementation stays valid (SQLite's io_methods). */
#ifndef RIG_H
#define RIG_H

#include "rig_err.h"
#include <stddef.h>
#include <stdint.h>

#define RIG_OPS_VERSION 1

/* Stage status bits (rig_stage_ops.status). */
enum {
    RIG_ST_HOMED = 1u << 0, /* reference found since power-up */
    RIG_ST_BUSY = 1u << 1,  /* a move or homing is in progress */
    RIG_ST_INPOS = 1u << 2, /* at the commanded target, settled */
    RIG_ST_FAULT = 1u << 3, /* drive fault latched (reset needed) */
    RIG_ST_ESTOP = 1u << 4, /* emergency stop active */
    RIG_ST_LIMIT = 1u << 5  /* a soft or hard limit was hit */
};

/* A motion stage: x, y in millimetres in the machine frame. move_to blocks
 * until in position, a fault, or its own timeout; it refuses a target
 * outside the soft limits with RIG_ELIMIT before moving. */
typedef struct rig_stage_ops {
    int version;
    int (*home)(void *ctx);
    int (*move_to)(void *ctx, double x, double y);
    int (*position)(void *ctx, double *x, double *y);
    int (*status)(void *ctx, uint32_t *bits);
    int (*stop)(void *ctx);        /* abort any motion now (abort, watchdog) */
    int (*reset_fault)(void *ctx); /* clear a latched fault */
    int (*limits)(void *ctx, double lo[2], double hi[2]); /* soft limits, mm */
} rig_stage_ops_t;

typedef struct rig_stage {
    const rig_stage_ops_t *ops;
    void *ctx;
} rig_stage_t;

/* A displacement probe: one reading, the distance in mm along its beam
 * (rig_kin.h says how it becomes a point). RIG_ENOSURF when no surface is
 * within the measuring range (a reading, not a failure of the line). */
typedef struct rig_probe_ops {
    int version;
    int (*read)(void *ctx, double *dist_mm);
    int (*range)(void *ctx, double *lo_mm, double *hi_mm); /* measuring range */
} rig_probe_ops_t;

typedef struct rig_probe {
    const rig_probe_ops_t *ops;
    void *ctx;
} rig_probe_t;

/* Append-only storage for the journal: a file on the cell controller, a
 * flash region on a board. append writes all n bytes or fails (RIG_EFULL
 * when there is no room); sync makes everything appended durable (fsync);
 * read returns fewer bytes than asked only at the end; truncate cuts a
 * torn tail found at recovery. */
typedef struct rig_store_ops {
    int version;
    int (*append)(void *ctx, const void *buf, size_t n);
    int (*sync)(void *ctx);
    int (*read)(void *ctx, uint64_t off, void *buf, size_t n, size_t *got);
    int (*size)(void *ctx, uint64_t *bytes);
    int (*truncate)(void *ctx, uint64_t bytes);
} rig_store_ops_t;

typedef struct rig_store {
    const rig_store_ops_t *ops;
    void *ctx;
} rig_store_t;

/* Monotonic time in seconds, and a cooperative check the long loops call
 * between points: non-zero asks the job to stop (abort, watchdog). */
typedef struct rig_clock_ops {
    int version;
    double (*now)(void *ctx);
    int (*should_stop)(void *ctx);
} rig_clock_ops_t;

typedef struct rig_clock {
    const rig_clock_ops_t *ops;
    void *ctx;
} rig_clock_t;

/* On-the-fly scanning (scan_otf.h): the stage keeps moving, a trigger box
 * latches both encoder counts at every trigger, and the probe streams one
 * reading per trigger. Both number their events from 0 at arming, 16 bits
 * on the wire (wrapping), so a reading is paired with the position of the
 * same trigger number, never by arrival order. */
enum {
    RIG_TRIG_F_OVERRUN = 1u << 0 /* the box's queue overflowed before this event */
};

typedef struct rig_trig_event {
    uint16_t seq;   /* trigger number since arming, wraps */
    uint8_t flags;  /* RIG_TRIG_F_* */
    uint32_t t_us;  /* box time, us, wraps */
    int32_t enc[2]; /* encoder counts of x and y latched at the trigger */
} rig_trig_event_t;

/* A trigger/encoder box: fires every period_us (0 keeps it) and queues one
 * event per trigger; read returns the events queued so far (up to max,
 * *n of them, 0 after its own short timeout). */
typedef struct rig_trig_ops {
    int version;
    int (*set_period)(void *ctx, uint32_t period_us);
    int (*arm)(void *ctx, int on); /* on: numbering restarts at 0 */
    int (*read)(void *ctx, rig_trig_event_t *ev, size_t max, size_t *n);
} rig_trig_ops_t;

typedef struct rig_trig {
    const rig_trig_ops_t *ops;
    void *ctx;
} rig_trig_t;

/* Status of one streamed reading. */
enum { RIG_RD_VALID = 0, RIG_RD_NOSURF = 1, RIG_RD_ERROR = 2 };

typedef struct rig_reading {
    uint16_t seq;   /* trigger number the probe saw, wraps */
    uint8_t status; /* RIG_RD_* */
    double d;       /* mm, when status is RIG_RD_VALID */
} rig_reading_t;

/* A probe in streaming mode: start arms it (one reading per trigger input,
 * numbered from 0), read returns the readings queued so far, stop ends the
 * stream (readings still in flight are delivered by the next reads). */
typedef struct rig_probe_stream_ops {
    int version;
    int (*start)(void *ctx);
    int (*stop)(void *ctx);
    int (*read)(void *ctx, rig_reading_t *r, size_t max, size_t *n);
} rig_probe_stream_ops_t;

typedef struct rig_probe_stream {
    const rig_probe_stream_ops_t *ops;
    void *ctx;
} rig_probe_stream_t;

#endif
