/* SPDX-License-Identifier: MIT */
/* cf_trim.h: the trim of a trimmed face, kept beside its surface: loops of
 * 2-D B-spline curves in the surface's parameter space (u, v), the outer
 * loop first, then the holes (IGES 144/142, STEP ADVANCED_FACE bounds).
 * A curve is an nf_curve_t whose points are (u, v, 0); the curves of a
 * loop follow one another head to tail. The fitted surface keeps the
 * nominal's knot range, so a nominal's trim is valid on the fit as it is;
 * only the 3-D edges are made again (cf_trim_edge3d). Host memory. */
#ifndef CF_TRIM_H
#define CF_TRIM_H

#include "nf_curve.h"
#include "nf_surf.h"
#include <stddef.h>

#define CF_TRIM_MAX_LOOPS 1024  /* outer and holes */
#define CF_TRIM_MAX_CURVES 4096 /* per loop */
#define CF_TRIM_EDGE_MAXS 257   /* points a 3-D edge interpolates per knot span, at most */
/* The 3-D edges' target, mm: half the 1e-7 mm distance accuracy the STEP
 * writer declares, so a CAD reader finds edge and surface in agreement. */
#define CF_TRIM_EDGE_TOL 5e-8

typedef struct cf_trim_loop {
    int n;         /* curves */
    nf_curve_t *c; /* n curves, (u, v, 0) points */
} cf_trim_loop_t;

typedef struct cf_trim {
    int nloops;           /* 0: no trim (the whole surface) */
    cf_trim_loop_t *loop; /* loop[0] the outer boundary */
} cf_trim_t;

/* Free every curve and loop; t becomes empty. */
void cf_trim_free(cf_trim_t *t);
/* Append a loop of n curves taken over (their storage belongs to t then,
 * also on failure). CF_ENOMEM, CF_EARG (too many). */
int cf_trim_add_loop(cf_trim_t *t, nf_curve_t *c, int n);
/* The outer loop as the domain's four sides (IGES 144 with N1 = 0):
 * degree-1 curves, counter-clockwise in (u, v). */
int cf_trim_add_domain(cf_trim_t *t, const nf_surf_t *s);
/* Deep copy. CF_ENOMEM. */
int cf_trim_copy(cf_trim_t *dst, const cf_trim_t *src);
/* 1 when a and b hold the same curves bit for bit. */
int cf_trim_equal(const cf_trim_t *a, const cf_trim_t *b);
/* CF_OK when every curve lies in s's domain (its control points within it,
 * so the curve does too) and every loop is closed (each curve's end within
 * tol of the next one's start); CF_EARG with msg otherwise. */
int cf_trim_check(const cf_trim_t *t, const nf_surf_t *s, double tol, char *msg, size_t ml);

/* The 3-D edge over a 2-D trim curve c on s: per knot span of c, the cubic
 * B-spline that interpolates S(c(t)) at m parameters t uniform over the
 * span, with those t as its parameters (NURBS Book A9.1, knots by
 * averaging, Eq. 9.8), the spans joined at triple knots (C0), so edge(t) ~
 * S(c(t)) on c's whole domain; m = 9, 17, 33, ... doubled until the error
 * is within tol (or m reaches CF_TRIM_EDGE_MAXS). *err: the largest
 * distance |edge(t) - S(c(t))| at the midpoints between samples (mm). out
 * is allocated (cf_curve_free). CF_ENOMEM, CF_EARG (no span, singular). */
int cf_trim_edge3d(const nf_surf_t *s, const nf_curve_t *c, double tol, nf_curve_t *out,
                   double *err);

#endif
