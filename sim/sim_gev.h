/* SPDX-License-Identifier: MIT */
/* sim_gev.h: the simulated laser line profiler: Aravis's fake GigE Vision
 * camera on 127.0.0.1, its frames filled with range profiles of the part
 * (docs/rig-profiler.md). The profiler rides on the stage along x at
 * constant speed: profile n of the scan (wire frame id * Height + row, the
 * id as GigE Vision 1.x sends it, 1..65535, wrapping) is taken
 * at x = x0 + (n mod profiles) * dx, its point i at y = y0 + i * dy; the
 * range value is round((d - offset) / scale) with d = z0 - z(part) + noise,
 * and 0 where there is no reading (off the part, outside the range, or a
 * flank steeper than the flank angle). Kept apart from sim.h so that only
 * this module sees GLib. */
#ifndef SIM_GEV_H
#define SIM_GEV_H

#include "sim.h"
#include <stddef.h>
#include <stdint.h>

typedef struct sim_gev_cfg {
    const sim_part_t *part;
    const char *serial; /* device serial number */
    double loss;        /* GVSP packet loss ratio, 0..1 */
    int width;          /* points per profile (the Width it starts with) */
    int height;         /* profiles per frame (the Height it starts with) */
    long profiles;      /* profiles per pass over the part */
    double z0, lo, hi;  /* beam origin height and measuring range, mm */
    double scale;       /* mm per count */
    double noise;       /* Gaussian sigma, mm */
    double flank_deg;   /* no reading where the slope is steeper */
    uint64_t seed;
    /* Filled by sim_gev_start: the scan geometry it uses. */
    double x0, dx, y0, dy;
} sim_gev_cfg_t;

typedef struct sim_gev sim_gev_t;

/* Build the range map and start the fake camera. -1 with the reason in msg
 * (e.g. the GigE Vision control port 3956 already taken on 127.0.0.1). */
int sim_gev_start(sim_gev_t **g, sim_gev_cfg_t *c, char *msg, size_t len);
void sim_gev_stop(sim_gev_t *g);

#endif
