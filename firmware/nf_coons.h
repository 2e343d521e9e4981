/* SPDX-License-Identifier: MIT */
/* nf_coons.h: Coons base surfaces from four boundary curves (Piegl & Tiller
 * 2001, Sections 2.1-2.2; The NURBS Book 10.5). The curves are
 *   C0(u) on v = 0, C1(u) on v = 1, D0(v) on u = 0, D1(v) on u = 1,
 * on the domain [0, 1] x [0, 1] (their knots are mapped there). They may come
 * in any order and direction: nf_coons_prepare pairs them by their corners,
 * reverses what runs the wrong way, makes each pair compatible (degree
 * elevation, knot merging) and scales rational weights so the four agree at
 * the corners. Then
 *   - nf_coons_bilinear: S = R_u + R_v - T (ruled surfaces in u and in v
 *     minus the bilinear corner patch), an exact NURBS surface;
 *   - nf_coons3_*: the bicubically blended patch, whose unknown
 *     cross-boundary derivative curves are fitted to points (least squares,
 *     twist compatibility built in), with the paper's derivative scaling.
 * No heap: all storage is the caller's, sized from the curves' control
 * counts by nf_coons_doubles and NF_COONS3_DOUBLES. */
#ifndef NF_COONS_H
#define NF_COONS_H

#include "nf_curve.h"
#include "nf_surf.h"

/* Errors of this module (beyond nf_err_t, which it also returns). */
enum {
    NF_COONS_ECORNER = -40,   /* boundary curves do not meet at a corner */
    NF_COONS_EWEIGHTS = -41,  /* rational curves' end weights cannot agree at the corners */
    NF_COONS_ERATIONAL = -42, /* bicubic Coons needs polynomial (non-rational) curves */
    NF_COONS_EWORK = -43      /* storage given is smaller than nf_coons_doubles */
};

/* A string for the codes above and for every nf_err_t. */
const char *nf_coons_strerror(int err);

typedef struct nf_coons {
    nf_curve_t c[4]; /* C0, C1, D0, D1: compatible pairs, domains [0, 1] */
    int from[4];     /* input index each came from */
    int rev[4];      /* 1 when it was reversed */
    double gap;      /* largest corner gap (distance) among the four corners */
    int corner;      /* NF_COONS_ECORNER: corner that failed, 0..3 = (u,v) 00 10 01 11 */
} nf_coons_t;

/* Doubles of storage nf_coons_prepare needs for these curves when the pairs
 * are raised to degree >= pmin (an upper bound from control counts and
 * degrees alone), or a negative error for invalid curves. */
long nf_coons_doubles(const nf_curve_t in[4], int pmin);

/* Orient, pair and make compatible (see above). Corners must meet within
 * tol (distance); they are then snapped together exactly. in is not
 * changed. Errors: nf_curve_check's for a bad curve, NF_COONS_ECORNER
 * (cs->corner, cs->gap say where), NF_COONS_EWEIGHTS, NF_COONS_EWORK,
 * NF_EDEGREE when pmin exceeds NF_MAX_DEGREE. */
int nf_coons_prepare(nf_coons_t *cs, const nf_curve_t in[4], int pmin, double tol, double *mem,
                     long len);

/* Shape of the Coons surfaces: degrees and net of the compatible pairs. */
void nf_coons_size(const nf_coons_t *cs, int *p, int *q, int *nu, int *nv);

/* Bilinearly blended Coons patch (Section 2.1) into out, wired with
 * nf_coons_size's shape (weights present). Reproduces the four curves
 * exactly (to rounding). NF_EARG for a wrong out, NF_EWEIGHT when a net
 * weight comes out non-positive (extreme rational input). */
int nf_coons_bilinear(const nf_coons_t *cs, nf_surf_t *out);

/* ---------------------------------------------------- bicubic Coons */

/* Unknowns per coordinate: the four corner twists and the inner control
 * vectors of the cross-derivative curves, 4 + 2 (nu - 4) + 2 (nv - 4). */
int nf_coons3_unknowns(const nf_coons_t *cs);
#define NF_COONS3_DOUBLES(K, nu, nv) ((long)(K) * (K) + 3L * (K) + 6L * ((nu) + (nv)) + 12L)

typedef struct nf_coons3 {
    const nf_coons_t *cs; /* prepared with pmin = 3 */
    int K;                /* unknowns per coordinate */
    double *A;            /* K x K normal matrix */
    double *rhs;          /* 3K */
    double *e0, *e1;      /* 3 nu each: dS/dv along C0 (v = 0) and C1 (v = 1) */
    double *f0, *f1;      /* 3 nv each: dS/du along D0 (u = 0) and D1 (u = 1) */
    double *tw;           /* 12: twists d2S/dudv at corners 00 10 01 11 */
    double s[4];          /* derivative scale of e0 e1 f0 f1 (1: as fitted) */
    long npoints;
    int solved;
} nf_coons3_t;

/* Start a fit: mem holds NF_COONS3_DOUBLES(K, nu, nv). The cross
 * derivatives' end vectors are the curves' tangents at the corners (the
 * compatibility conditions); twist compatibility is built in by tying the
 * second and second-to-last control vectors of each curve to the corner
 * twists (the paper's constraint equations, solved for those vectors).
 * NF_COONS_ERATIONAL for rational curves, NF_EDEGREE when a pair has
 * degree < 3, NF_COONS_EWORK for too little storage. */
int nf_coons3_init(nf_coons3_t *b, const nf_coons_t *cs, double *mem, long len);

/* One point Q with parameters (u, v) in [0, 1]^2 (from projection onto the
 * bilinear patch): a row of the overdetermined system Q = S(u, v).
 * NF_EDOMAIN outside, NF_ENONFINITE for NaN, NF_ESTATE after solve. */
int nf_coons3_add(nf_coons3_t *b, double u, double v, const double Q[3]);

/* Least squares for the unknowns (Cholesky of the normal equations).
 * NF_ESINGULAR when the points do not determine them. */
int nf_coons3_solve(nf_coons3_t *b);

/* The paper's derivative scaling: each cross-derivative curve D becomes
 * (L / (Lu + Lv)) (L / mag) D, L the mean arc length of the pair of
 * boundary curves it points along (Lv for dS/dv, Lu for dS/du), mag its
 * mean magnitude. Boundary curves stay exact; derivatives no longer match. */
void nf_coons3_scale(nf_coons3_t *b);

/* The bicubic Coons patch S = L_u + L_v - T (Hermite lofts of the curves and
 * their cross derivatives minus the bicubic Hermite corner patch) as an
 * exact NURBS surface, out wired with nf_coons_size's shape. */
int nf_coons3_surface(const nf_coons3_t *b, nf_surf_t *out);

/* The same surface evaluated from its definition (curves and Hermite
 * blends), independent of the NURBS net. */
void nf_coons3_eval(const nf_coons3_t *b, double u, double v, double out[3]);

#endif
