/* SPDX-License-Identifier: MIT */
/* cf_ptsout.h: per-point deviations written as the points stream by, for a
 * spreadsheet (CSV with a header line) and for CloudCompare or MeshLab
 * (binary little-endian PLY, a colour per point on the map's scale). Memory
 * is fixed: nothing is kept per point; the PLY's vertex count is patched
 * into its header at the end. Both files appear atomically at close. */
#ifndef CF_PTSOUT_H
#define CF_PTSOUT_H

#include "cf_atomic.h"
#include <stddef.h>

typedef struct cf_ptsout_pt {
    double x, y, z, u, v;
    double dev;    /* signed normal deviation, mm */
    double weight; /* robust weight (written when the fit has weights) */
} cf_ptsout_pt_t;

/* The colour of a deviation (the map's scale). */
typedef void (*cf_ptsout_rgb_fn)(double dev, void *ctx, unsigned char rgb[3]);

typedef struct cf_ptsout {
    cf_atomic_t csv, ply;
    int has_csv, has_ply, weights;
    double tol;
    long long n;
    long count_at; /* offset of the PLY header's vertex count */
    cf_ptsout_rgb_fn rgb;
    void *rgb_ctx;
} cf_ptsout_t;

/* Either path may be NULL. tol: in/out of tolerance (|dev| <= tol);
 * weights: write the weight column. rgb is needed with a PLY path.
 * CF_OK, or CF_EIO with msg (nothing left behind). */
int cf_ptsout_open(cf_ptsout_t *o, const char *csv, const char *ply, double tol, int weights,
                   cf_ptsout_rgb_fn rgb, void *rgb_ctx, char *msg, size_t ml);
void cf_ptsout_add(cf_ptsout_t *o, const cf_ptsout_pt_t *p);
/* Finish both files (header count patched, synced, renamed). CF_OK or CF_EIO. */
int cf_ptsout_close(cf_ptsout_t *o, char *msg, size_t ml);
/* Give up: remove the temporaries. */
void cf_ptsout_abort(cf_ptsout_t *o);

#endif
