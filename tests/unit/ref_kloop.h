/* SPDX-License-Identifier: MIT */
/* ref_kloop.h: the fitting loop at the firmware level, for the knot tests
 * and the loop benchmark: fit (Eq. 7, nf_fit) -> check (distance of every
 * point at its parameters, nf_knotsel accumulation) -> insert (the chooser
 * and Boehm insertion, or uniform refinement) until nf_loopctl's verdict
 * stops it. Points carry their parameters (rows of u v x y z), so the loop
 * needs no projection. Heap use is fine here: tests and benchmarks only. */
#ifndef REF_KLOOP_H
#define REF_KLOOP_H

#include "nf_knotsel.h"
#include "nf_loopctl.h"
#include "nf_surf.h"

typedef struct ref_kloop_cfg {
    double tol, within;    /* tolerance and the share within it wanted (percent) */
    double alpha, beta;    /* Eq. 7 at the first level */
    int uniform;           /* 1: every span halved each round (nf_refine_uniform) */
    int scale_alpha;       /* 1: nf_loopctl_alpha at every level, exponent alpha_k */
    double alpha_k;        /* its k (NF_LOOPCTL_ALPHA_K is the default) */
    int progress;          /* 1: stop when a round gains less than min_gain */
    int budget;            /* 1: nf_loopctl_budget caps the control points a round adds */
    int reparam;           /* 1: the check pass projects each point onto the fit (nf_project
                              from its last parameters), d is the normal distance and the
                              next round fits at the new parameters; 0: parameters fixed */
    double min_gain;       /* points of the share (<= 0: NF_LOOPCTL_MIN_GAIN) */
    long max_cp;           /* <= 0: NF_MAX_CP */
    int max_rounds;        /* round limit */
    nf_knotsel_opts_t sel; /* chooser options (max_cp is set from max_cp) */
    int verbose;           /* 1: one line per round on stderr */
} ref_kloop_cfg_t;

typedef struct ref_kloop_out {
    nf_surf_t fit;     /* the best fit seen (most within, then lowest rms); ref_kloop_free */
    double within_pct; /* of the best fit */
    double rms, mx;    /* of the best fit's distances */
    long cp;           /* its control points */
    int rounds;        /* rounds run */
    int verdict;       /* nf_loopctl_stat_t */
} ref_kloop_out_t;

/* Run the loop from base on the M points. 0, or an nf_err_t of the fit or
 * of knot insertion. */
int ref_kloop_run(const nf_surf_t *base, const double *pts, long M, const ref_kloop_cfg_t *c,
                  ref_kloop_out_t *o);
void ref_kloop_free(ref_kloop_out_t *o);

/* A new surface of this shape on the heap (free with free(s->U)), and a
 * copy of src. */
void ref_kloop_surf(nf_surf_t *s, int p, int q, int nu, int nv);
void ref_kloop_copy(nf_surf_t *dst, const nf_surf_t *src);

/* Distance |S(u, v) - Q| of row r (u v x y z) to s. */
double ref_kloop_dist(const nf_surf_t *s, const double *r);

/* Distance of row r's point to s by projection from (u, v) of r (the
 * normal distance; ref_kloop_dist's when the projection fails). */
double ref_kloop_pdist(const nf_surf_t *s, const double *r);

#endif
