/* SPDX-License-Identifier: MIT */
/* cf_part.h: a synthetic part for demos and the simulated rig: a nominal
 * bicubic panel (the CAD surface) and the "as manufactured" part, which
 * deviates from it by a dent and a warp along z. Both are functions of the
 * nominal's parameters (u, v), so the truth is known exactly everywhere. */
#ifndef CF_PART_H
#define CF_PART_H

#include "nf_surf.h"

typedef struct cf_part {
    double len_x, len_y;           /* panel size, mm */
    double crown;                  /* height of the nominal's crown, mm */
    double dent_depth;             /* depth of the dent (negative z), mm */
    double dent_x, dent_y, dent_r; /* dent centre and radius (1/e^2), mm */
    double warp;                   /* twist: z += warp * (x/Lx - 1/2)(y/Ly - 1/2) */
    /* Narrow features for the refinement tests (0 height: none, the default). */
    double bump_h, bump_x, bump_y, bump_r; /* Gaussian bump: height, centre, radius (1/e^2) */
    double ridge_h, ridge_x, ridge_w;      /* ridge along y at x = ridge_x, half-width (1/e^2) */
} cf_part_t;

/* The default part: a 200 x 150 mm panel with a 12 mm crown, a 0.4 mm deep
 * dent of radius 15 mm and a 0.3 mm warp; no bump, no ridge. */
void cf_part_default(cf_part_t *pt);

/* The nominal surface: degree p x p, nu x nv net on [0,1]^2 with uniform
 * interior knots, control points at the Greville points of the panel shape
 * (the nominal is this spline exactly). s must be allocated for the shape. */
void cf_part_nominal(const cf_part_t *pt, nf_surf_t *s);

/* Deviation along z of the real part from the nominal at (x, y): dent,
 * warp, bump and ridge. */
double cf_part_deviation(const cf_part_t *pt, double x, double y);

/* The real part's point at nominal parameters (u, v). */
void cf_part_true_point(const cf_part_t *pt, const nf_surf_t *nominal, double u, double v,
                        double out[3]);

#endif
