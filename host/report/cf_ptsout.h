/* SPDX-License-Identifier: MIT */
/* cf_ptsout.h: per-point deviations written as the points stream by, for a
 * spreadsheet (CSV with a header line) and for CloudCompare or MeshLab
 * (binary little-endian PLY, a colour per point on the map's scale). Memory
 * is fixed: nothing is kept per point; the PLY's vertex count is patched
 * into its header at the end, and so are its colours when the scale is
 * known only after the last point. Both files appear atomically at close. */
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
    long data_at;  /* offset of the PLY's first vertex */
    int late_rgb;  /* the PLY's colours are written at close (cf_ptsout_set_rgb) */
    cf_ptsout_rgb_fn rgb;
    void *rgb_ctx;
} cf_ptsout_t;

/* Either path may be NULL. tol: in/out of tolerance (|dev| <= tol);
 * weights: write the weight column. rgb: the PLY's colours; NULL to give
 * them with cf_ptsout_set_rgb before close, when the scale depends on every
 * deviation (they are then written over the PLY from the deviations in it:
 * a pass over the file, none over the points). CF_OK, or CF_EIO with msg
 * (nothing left behind). */
int cf_ptsout_open(cf_ptsout_t *o, const char *csv, const char *ply, double tol, int weights,
                   cf_ptsout_rgb_fn rgb, void *rgb_ctx, char *msg, size_t ml);
void cf_ptsout_add(cf_ptsout_t *o, const cf_ptsout_pt_t *p);
/* The PLY's colours when open had none; any time before close. */
void cf_ptsout_set_rgb(cf_ptsout_t *o, cf_ptsout_rgb_fn rgb, void *rgb_ctx);
/* Finish both files (header count and late colours patched, synced,
 * renamed). CF_OK, CF_EARG (a PLY still without colours) or CF_EIO. */
int cf_ptsout_close(cf_ptsout_t *o, char *msg, size_t ml);
/* Give up: remove the temporaries. */
void cf_ptsout_abort(cf_ptsout_t *o);

#endif
