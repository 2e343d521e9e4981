/* SPDX-License-Identifier: MIT */
/* nf_project.h: parameters of measured points by projection onto a surface
 * (Piegl & Tiller 2001, Section 3; NURBS Book 6.1; Brujic et al. 2010,
 * Section 2.2): the closest point S(u, v) to Q, found by Newton iteration
 * on (S - Q) . Su = 0, (S - Q) . Sv = 0 (Eqs. 6.6-6.8) from a start point,
 * the parameters kept in the domain. Start points come from a sampling of
 * the surface held in caller storage of fixed size (the paper's
 * quadrilateral decomposition, Section 3.1, can replace it later). */
#ifndef NF_PROJECT_H
#define NF_PROJECT_H

#include "nf_surf.h"

typedef struct nf_proj {
    double u, v;    /* foot point parameters */
    double foot[3]; /* S(u, v) */
    double dist;    /* signed distance: |Q - S| with the sign of (Q - S) . n,
                     * n = Su x Sv / |Su x Sv| (equal to (Q - S) . n at an interior
                     * foot); unsigned where the normal is degenerate */
    int clamped;    /* 1 when the foot lies on the domain boundary and the
                     * distance would decrease outside it (gradient outward) */
    int iters;      /* Newton steps taken */
} nf_proj_t;

/* Newton steps nf_project takes at most before NF_ENOCONV. */
#define NF_PROJ_MAX_ITERS 50

/* Newton from (u0, v0) until the parameter step is below tol times the
 * domain size (1e-9 in cellfit) or the point is a stationary point of the
 * distance within the domain (boundary: projected step). NF_ENOCONV if not
 * converged within NF_PROJ_MAX_ITERS steps (out still holds the best point
 * found). Every accepted step brings Q nearer (step halving), so the
 * result is never further than the start. Handles: bounds (a parameter
 * held on its bound continues as 1-D Newton in the other), creases (C0
 * knot lines: steps stop on them, and a minimum on one is found exactly),
 * collapsed edges (poles: left by the steepest way out), and directions
 * where |S - Q|^2 is lost in rounding (thin surfaces: the tangential
 * residual decides), and feet held on a bound (the true foot: nf_project_edge
 * compares them with the edge's other minima and the valleys beside it, at
 * the cost of a few hundred evaluations for such a point only; the result
 * may then lie in another valley than the start's). s must have passed
 * nf_surf_check (not repeated here:
 * it costs O(N) per point). NF_EARG for a null pointer, tol not in (0, 1)
 * or a non-finite start; NF_ENONFINITE for a non-finite Q. A start outside
 * the domain is clamped to it. */
int nf_project(const nf_surf_t *s, const double Q[3], double u0, double v0, double tol,
               nf_proj_t *out);

/* A sampling grid for start points: nsu x nsv surface points at uniform
 * parameters, stored in caller storage pts (NF_SEED_DOUBLES(nsu, nsv)
 * doubles: all x, then all y, then all z, so that the search streams). */
typedef struct nf_seed {
    const nf_surf_t *s;
    int ns;       /* nsu when the grid is square (nf_seed_init), else 0 */
    int nsu, nsv; /* samples in u and in v */
    double *pts;
    double reach; /* twice the longest chord between neighbouring samples:
                   * about how far a surface point can be from its nearest
                   * sample (unless a grid cell is strongly curved) */
} nf_seed_t;

#define NF_SEED_DOUBLES(nsu, nsv) (3L * (long)(nsu) * (long)(nsv))

/* Largest sample count per direction (a larger request is reduced to it,
 * which needs less storage); keeps nsu nsv within a 32-bit long. */
#define NF_SEED_MAX_NS 4096

/* Samples at the parameters u0 + (u1 - u0) i / (nsu - 1), likewise in v
 * (a count of 1: the middle of the domain; counts below 1 are taken as 1).
 * nf_seed_init is the square grid ns x ns (3 ns^2 doubles). */
void nf_seed_init(nf_seed_t *g, const nf_surf_t *s, int ns, double *pts);
void nf_seed_init_uv(nf_seed_t *g, const nf_surf_t *s, int nsu, int nsv, double *pts);

/* Sample counts for s: at most 8 per knot span and direction and at most cap
 * in all, spread so that the samples are about evenly spaced on the surface
 * (nsu / nsv follows the lengths of the control polygons in u and in v),
 * keeping at least 4 per span (2 in all) in each direction within the cap.
 * A long thin surface gets its samples along its length: with a square grid
 * the nearest sample could be a whole sample spacing away along it, more
 * than its width, and the start would land in the wrong valley. */
void nf_seed_size(const nf_surf_t *s, long cap, int *nsu, int *nsv);

/* Parameters of the sample nearest Q: exact, the samples read tile by tile
 * and a tile skipped when the chord bound proves it further. */
void nf_seed_start(const nf_seed_t *g, const double Q[3], double *u0, double *v0);

/* Up to k (<= NF_SEED_MAX_STARTS) starts: the nearest samples that are local
 * minima of the distance over the grid (no 4-neighbour nearer), nearest
 * first, in u0[], v0[]; returns how many (>= 1). The first is
 * nf_seed_start's. The others are the starts of other valleys of the
 * distance: with the samples a spacing apart, the nearest sample is not
 * always in the valley of the nearest foot (a point over a fold or a
 * crease of the surface has one local minimum per side). */
#define NF_SEED_MAX_STARTS 4
int nf_seed_starts(const nf_seed_t *g, const double Q[3], int k, double *u0, double *v0);

/* The true foot at the boundary (nf_project runs it on every foot it
 * holds on a bound; public for callers with a Newton of their own): when
 * out's foot is held on a bound (out->clamped), Newton restarts from every
 * local minimum of the distance over samples (4 per knot span, at most 256)
 * of two curves: the boundary curve the foot lies on (its other minima:
 * 1-D Newton along it, or into the interior where the distance falls
 * inward), and the iso-parameter curve across the edge through the foot
 * (interior valleys beside the edge, and those a fold brings near in space
 * though far in parameter: a hem's plate under its free edge). A converged
 * foot nearer than out's replaces it. Nothing is done for an interior
 * foot. NF_EARG for null pointers or tol not in (0, 1), NF_ENONFINITE for
 * a non-finite Q. */
int nf_project_edge(const nf_surf_t *s, const double Q[3], double tol, nf_proj_t *out);

/* The projection cellfit uses: nf_project from each of NF_PROJ_STARTS
 * starts of nf_seed_starts (only those within reach of the nearest
 * sample's distance), and once more across a crease within a sample
 * spacing of the foot (over a valley crease there is a minimum on each
 * side); the nearest converged foot is kept. Errors as nf_project
 * (NF_ENOCONV only if no start converged; out then holds the nearest point
 * found). */
#define NF_PROJ_STARTS 3
int nf_project_seeded(const nf_seed_t *g, const double Q[3], double tol, nf_proj_t *out);

/* nf_project_seeded's second half, for callers that find the starts their
 * own way (host/jobs/cf_seedgrid.c's cell grid): nf_project from each of
 * the n >= 1 starts (u0[t], v0[t]), nearest first, and across a crease
 * within a sample spacing of g's grid; the nearest converged foot kept. */
int nf_project_starts(const nf_seed_t *g, const double Q[3], const double *u0, const double *v0,
                      int n, double tol, nf_proj_t *out);

/* Sample k of g is a local minimum of the distance to Q over the grid (no
 * 4-neighbour strictly nearer): nf_seed_starts's rule for a valley's start. */
int nf_seed_local_min(const nf_seed_t *g, long k, const double Q[3]);

#endif
