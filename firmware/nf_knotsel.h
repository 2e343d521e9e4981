/* SPDX-License-Identifier: MIT */
/* nf_knotsel.h: knot lines where the residual lives, per control point added
 * (the knot step of the fitting loop, Brujic et al. 2010, Section 2.2: fit,
 * reparameterise, insert knots until the tolerance holds).
 *
 * The idea is FITPACK's (Dierckx 1993; surfit/fpsurf): sum the squared
 * residuals per knot interval and add a knot where that sum is largest, at
 * the residual-weighted centre of the interval, but only where data points
 * lie on both sides. Here, for a tensor-product NURBS with exact Boehm
 * insertion, a knot in u adds a whole line of Nv control points and one in
 * v adds Nu, so candidates of both directions are ranked by the misfit of
 * their span per control point added, and several are taken per round.
 *
 * 1. Accumulate (the check pass, streaming): per knot span in u and in v,
 *    NF_KNOTSEL_BINS sub-bins of equal width, each with its point count,
 *    the smallest and largest parameter seen (a lower bound on the distinct
 *    data rows it holds: 0, 1 or 2), and the squared distance of the points
 *    out of tolerance (plus its first moment for the centroid). Memory is
 *    per span, never per point: NF_KNOTSEL_DOUBLES(nu, nv, p, q) doubles,
 *    the caller's (a static array sized by the board's largest net, or
 *    the host's heap).
 * 2. Choose (nf_knotsel_choose): one candidate per span with misfit, at the
 *    sub-bin boundary nearest the misfit's centroid, no closer than a
 *    quarter span to the span's ends (and one on each side of it with
 *    misfit, at that side's centroid, no closer than a quarter side to
 *    the side's ends: NF_KNOTSEL_PER_SPAN, where the span's misfit is deep:
 *    NF_KNOTSEL_SIDE_DEPTH), and only where each new span
 *    holds at least min_pts points and min_rows data rows (a knot between
 *    two scan rows with no data between them would leave control points
 *    that no point determines: the ripple between rows of issue 14). Candidates are
 *    ranked by gain per control point, taken best first while they score at
 *    least NF_KNOTSEL_RATIO of the best and their direction has not yet
 *    been given NF_KNOTSEL_SHARE of its misfit, and while the net stays
 *    within the cap: half the points seen, max_cp, the board's NF_MAX_CP.
 * alpha per level and the loop's stop rules are in nf_loopctl.h. */
#ifndef NF_KNOTSEL_H
#define NF_KNOTSEL_H

#include "nf_surf.h"

/* Sub-bins per span (the resolution of the knot position and of the data
 * test), and doubles per sub-bin: count, lowest and highest parameter, sum
 * of d^2 of the points out of tolerance, and of d^2 t. */
#define NF_KNOTSEL_BINS 8
#define NF_KNOTSEL_BIN 5
/* Per span: the sub-bins, then the sum of d^2 over all its points (the
 * FITPACK interval sum, reported) and the points out of tolerance. */
#define NF_KNOTSEL_SPAN (NF_KNOTSEL_BINS * NF_KNOTSEL_BIN + 2)
#define NF_KNOTSEL_DOUBLES(nu, nv, p, q)                                                           \
    ((long)NF_KNOTSEL_SPAN * ((long)(nu) - (p) + (long)(nv) - (q)))

/* Candidates below this share of the best score wait for a later round: a
 * direction whose misfit is spread along it (a ridge across it) scores low
 * per control point and is not refined. */
#define NF_KNOTSEL_RATIO 0.25
/* A direction stops taking knots this round once its picks hold this share
 * of its misfit. */
#define NF_KNOTSEL_SHARE 0.5
/* Knots a span may get in one round (nf_knotsel_opts_t.per_span, at most
 * 3): the first near the misfit's centroid, then one on each side of it
 * with misfit, at that side's centroid (a quarter side or more from the
 * side's ends), the side holding more first (2: that side only); FITPACK's
 * several knots per interval. */
#define NF_KNOTSEL_PER_SPAN 3
/* Side knots only where the span's misfit is deep: the root mean square
 * distance of its points out of tolerance above this many tol
 * (nf_knotsel_opts_t.side_depth). One halving divides a resolved feature's
 * misfit by 4 or more (h^2; a cubic's h^4 once smooth), so shallower misfit
 * comes within tol by plain bisection, and side knots there only crowd it
 * (the holes field's hill from a 9 x 7 net on: 1.2 to 3.3 tol, four u knots
 * within 5 mm); a feature narrower than the span (the 1 mm ridge) leaves
 * 7 to 18 tol on a 7 x 7 net, 3 to 11 on 27 x 27 (docs/loop.md). */
#define NF_KNOTSEL_SIDE_DEPTH 4.0
/* Candidates nf_knotsel_choose may list: NF_KNOTSEL_PER_SPAN per span. */
#define NF_KNOTSEL_CANDS(nu, nv, p, q) (NF_KNOTSEL_PER_SPAN * ((nu) - (p) + (nv) - (q)))
/* Data rows each new span must hold by default (lower bound from the
 * sub-bins: a sub-bin with points counts 1, with two distinct values 2). */
#define NF_KNOTSEL_MIN_ROWS 1

typedef struct nf_knotsel {
    const nf_surf_t *s; /* the surface whose spans are counted (the fit) */
    double tol;         /* |d| above tol is out of tolerance */
    double *su, *sv;    /* spans l = p .. nu-1 (slot l - p), k = q .. nv-1 */
    long n, out;        /* points seen; out of tolerance */
    double rss, g;      /* sum of d^2 over all points; over those out of tolerance */
    double hu, hv;      /* spans per unit parameter: nf_find_span_from's first guess */
} nf_knotsel_t;

/* Clear the counts for s (after nf_surf_check) and tolerance tol > 0; mem
 * holds NF_KNOTSEL_DOUBLES(s->nu, s->nv, s->p, s->q) doubles. NF_EARG for a
 * null pointer or tol not > 0. */
int nf_knotsel_init(nf_knotsel_t *a, const nf_surf_t *s, double tol, double *mem);

/* One point of the check pass at parameters (u, v) (clamped to the domain)
 * at distance d from the fit. Non-finite u or v: ignored; non-finite d:
 * counted as data (rows, count) but not as misfit. */
void nf_knotsel_add(nf_knotsel_t *a, double u, double v, double d);

/* Points, and out of tolerance, of span slot i of direction dir (0: u). */
long nf_knotsel_span_points(const nf_knotsel_t *a, int dir, int i);
/* Sum of d^2 of all points of the span (FITPACK's interval sum). */
double nf_knotsel_span_rss(const nf_knotsel_t *a, int dir, int i);

/* Every count, bound and sum of b (the same surface and tolerance: a
 * check pass counted in parts) into a's: a then holds the points of both.
 * NF_EARG for null pointers or another surface or tolerance. */
int nf_knotsel_merge(nf_knotsel_t *a, const nf_knotsel_t *b);

/* Add the misfit of b's span slot i of direction dir (its points out of
 * tolerance: sums of d^2 and d^2 t per sub-bin, the count out) to a's, and
 * to a's totals. b counts, on the same surface, points a holds as data
 * without misfit (nf_knotsel_add with d NaN): a robust pass's rejected
 * points, whose misfit the caller found clustered in that span (a feature
 * the net cannot follow yet, not spikes: issue 14). NF_EARG for a
 * different surface or a slot outside the net. */
int nf_knotsel_merge_span(nf_knotsel_t *a, const nf_knotsel_t *b, int dir, int i);

typedef struct nf_knotsel_opts {
    long max_cp;       /* cap on Nu Nv after the round; <= 0: the board's NF_MAX_CP */
    int min_rows;      /* data rows each new span must hold; <= 0: NF_KNOTSEL_MIN_ROWS */
    int min_pts;       /* points each new span must hold; <= 0: the degree + 1 */
    double ratio;      /* <= 0: NF_KNOTSEL_RATIO */
    double share;      /* <= 0: NF_KNOTSEL_SHARE */
    int max_knots;     /* knots a round may insert in all; <= 0: no limit */
    long max_add;      /* control points a round may add (nf_loopctl_budget); <= 0: no limit;
                          the best candidate is always taken */
    int per_span;      /* knots a span may get in a round (1 .. 3); <= 0: NF_KNOTSEL_PER_SPAN */
    double side_depth; /* side knots only where the span's rms out of tolerance exceeds
                          side_depth tol; 0: NF_KNOTSEL_SIDE_DEPTH; < 0: wherever misfit */
} nf_knotsel_opts_t;

/* One knot line to insert. */
typedef struct nf_knotsel_cand {
    int dir;      /* 0: a knot in u (adds Nv control points), 1: in v (adds Nu) */
    int span;     /* its span slot (span index - degree) */
    double x;     /* the new knot */
    double score; /* misfit of the span (level 1: of its side) per control point added */
    int level;    /* 0: the span's first knot; 1: one on a side of it (same round) */
} nf_knotsel_cand_t;

/* Why a round inserts what it does. */
typedef enum nf_knotsel_status {
    NF_KNOTSEL_INSERT = 0,   /* knots chosen */
    NF_KNOTSEL_NONE_OUT = 1, /* no point out of tolerance: nothing to do */
    NF_KNOTSEL_DATA = 2,     /* no span with misfit holds data enough to split */
    NF_KNOTSEL_HALF_PTS = 3, /* a split would take the net past half the points */
    NF_KNOTSEL_MAX_CP = 4    /* a split would take the net past max_cp or NF_MAX_CP */
} nf_knotsel_status_t;

/* Static string for a status ("insert", "none_out", ...). */
const char *nf_knotsel_status_str(int status);

/* The knot lines of this round into out (room for cap entries: the spans
 * of both directions, (nu - p) + (nv - q), always suffice for the first
 * knot of each; NF_KNOTSEL_CANDS for the second ones too), best score
 * first; *n their count, *status why (NF_KNOTSEL_INSERT when *n > 0).
 * opts NULL: the defaults. Returns NF_OK, or NF_EARG for null pointers or
 * cap < 0. */
int nf_knotsel_choose(const nf_knotsel_t *a, const nf_knotsel_opts_t *opts, nf_knotsel_cand_t *out,
                      int cap, int *n, int *status);

/* The chosen knots as the ascending arrays nf_refine_u / nf_refine_v take:
 * Xu (room for maxu) and Xv (maxv); *ru, *rv their counts. NF_EARG when a
 * direction has more than its room. */
int nf_knotsel_split(const nf_knotsel_cand_t *c, int n, double *Xu, int maxu, int *ru, double *Xv,
                     int maxv, int *rv);

#endif
