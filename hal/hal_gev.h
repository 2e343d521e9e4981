/* SPDX-License-Identifier: MIT */
/* hal_gev.h: a laser line profiler over GigE Vision (Aravis), opened by
 * gev:ADDRESS[:SERIAL] (hal_uri): its GenICam features set (PixelFormat
 * Mono16, Width points per profile, Height profiles per frame, frame rate,
 * exposure), and its frames received in order, each Height profiles of
 * Width 16-bit range values with its frame id and timestamp.
 *
 * Loss: packet resend is on; a frame that still arrives incomplete is not
 * delivered (its profiles would be wrong, not merely noisy) and counts as
 * lost, as does a frame id that never arrives; the ids of incomplete frames
 * are not trusted, so a loss is counted by the gap in the ids of the frames
 * delivered around it (frames_gap); losses after the last delivered frame
 * show only in frames_bad, and incomplete frames before the first
 * delivered one (the numbering starts there) are no losses at all
 * (frames_bad_before). Each delivered frame says
 * how many frames were lost just before it (gap_before), so a lost profile
 * is a gap in the numbering, never a shifted row: profile r of frame f is
 * profile f * Height + r of the scan. Frame ids are 16 bits on the wire
 * (GigE Vision 1.x); they are unwrapped here, which holds while fewer than
 * 32768 frames are lost in a row.
 *
 * Range values: 0 means no reading (dropout); otherwise the distance is
 * offset + raw * scale, in mm, with scale and offset from the profiler's
 * configuration (the fake camera has no such features: docs/rig-profiler.md).
 * Host code only (GLib underneath); errors are rig_err_t codes. */
#ifndef HAL_GEV_H
#define HAL_GEV_H

#include "rig.h"
#include <stddef.h>
#include <stdint.h>

typedef struct hal_gev hal_gev_t;

typedef struct hal_gev_opts {
    int width, height;  /* points per profile, profiles per frame (0: the device's) */
    double frame_rate;  /* frames/s (0: the device's) */
    double exposure_us; /* (0: the device's) */
    int buffers;        /* frames queued for the stream (0: 16) */
    int timeout_ms;     /* control channel timeout (0: 1000) */
} hal_gev_opts_t;

typedef struct hal_gev_frame {
    uint64_t id;           /* unwrapped frame id */
    uint64_t timestamp_ns; /* the device's */
    uint64_t gap_before;   /* frames lost between the previous delivered frame and this */
    int width, height;
    const uint16_t *range; /* height rows of width values; valid until the next call */
} hal_gev_frame_t;

typedef struct hal_gev_stats {
    uint64_t frames;            /* delivered */
    uint64_t frames_bad;        /* arrived incomplete (missing packets, timeout), not delivered,
                          * after the first delivered frame: lost frames (<= frames_gap
                          * but for those after the last delivered one) */
    uint64_t frames_bad_before; /* the same before the first delivered frame: not losses */
    uint64_t frames_gap;        /* ids skipped between delivered frames: every lost frame (bad or
                          * never seen) that a later frame revealed */
    uint64_t packets_missing, packets_resent; /* Aravis's counts */
    uint64_t underruns;                       /* frames dropped for want of a buffer */
} hal_gev_stats_t;

/* Open and configure (nothing streams yet). RIG_EARG for a bad URI,
 * RIG_EOPEN when no device answers at the address or the serial differs,
 * RIG_EUNSUPPORTED when it refuses a feature; the reason in err. */
int hal_gev_open(hal_gev_t **g, const char *uri, const hal_gev_opts_t *o, char *err, size_t len);
int hal_gev_start(hal_gev_t *g);
/* The next complete frame within timeout_ms: RIG_OK, RIG_ETIMEOUT. */
int hal_gev_next(hal_gev_t *g, hal_gev_frame_t *f, int timeout_ms);
int hal_gev_stop(hal_gev_t *g);
void hal_gev_stats(const hal_gev_t *g, hal_gev_stats_t *s);
/* Width and height in force (after open). */
void hal_gev_size(const hal_gev_t *g, int *width, int *height);
const char *hal_gev_error(const hal_gev_t *g);
void hal_gev_close(hal_gev_t *g);

#endif
