/* SPDX-License-Identifier: MIT */
/* nf_loopctl.h: the rules of the fitting loop around the knot chooser
 * (nf_knotsel.h): alpha scaled with the knot spacing at each refinement
 * level (Eq. 7's Greville term), and the verdict after each round: met, or
 * why the loop stops (issue 14: no progress, data limit, max_cp, rounds). */
#ifndef NF_LOOPCTL_H
#define NF_LOOPCTL_H

#include "nf_knotsel.h"
#include "nf_surf.h"

/* Default exponent k of nf_loopctl_alpha: alpha follows the area of a
 * control point's support, as the data term does (see there). */
#define NF_LOOPCTL_ALPHA_K (-2.0)
/* Default least gain of a round, in points of the percentage within. */
#define NF_LOOPCTL_MIN_GAIN 0.1

/* alpha for the current net when alpha was set for the first one:
 *   alpha_level = alpha (h0 / h)^k,  (h0 / h)^2 = (h0u h0v) / (hu hv),
 * h = the domain's width over its non-empty spans in that direction.
 * alpha |(B - I) P|^2 (Eq. 7) is, per control point, a second difference
 * of the net, about h^2 times the surface's second derivative, against a
 * data term (R^T R)_ii that, for points spread evenly, falls with the area
 * hu hv of the control point's support. k = -2 keeps the two in the same
 * balance at every level: where data are, the Greville term stays as weak
 * relative to them as at the first level (it does not flatten a feature the
 * finer net was made for); where they are not (holes, gaps between rows),
 * the control points are held by alpha and beta alone and follow the
 * previous level's surface (P0 is the refined previous fit), which is
 * smooth. k = 2 would keep the Greville energy alpha h^2 |S''|^2 per area
 * instead; measured on the test fields (docs/loop.md) it smooths features
 * away and needs more control points for the same share, so it is not the
 * default. k = 0: alpha unchanged. A non-finite or negative alpha, or nets
 * over different domains, return alpha unchanged. */
double nf_loopctl_alpha(double alpha, const nf_surf_t *first, const nf_surf_t *cur, double k);

/* The loop's verdict after a round's check pass. */
typedef enum nf_loopctl_stat {
    NF_LOOPCTL_CONTINUE = 0,    /* insert the chosen knots and fit again */
    NF_LOOPCTL_MET = 1,         /* the share within tolerance reached */
    NF_LOOPCTL_DATA_LIMIT = 2,  /* no split the data support (or half the points) */
    NF_LOOPCTL_MAX_CP = 3,      /* the next net would exceed max_cp / the board */
    NF_LOOPCTL_NO_PROGRESS = 4, /* the round gained less than min_gain points */
    NF_LOOPCTL_MAX_ROUNDS = 5   /* the round limit */
} nf_loopctl_stat_t;

/* "continue", "met", "not_met_data_limit", "not_met_max_cp",
 * "not_met_no_progress", "not_met_max_rounds". */
const char *nf_loopctl_str(int st);

/* Rounds in a row that may gain less than min_gain before the loop stops:
 * one round on a coarse net can lose share (a knot line moves the misfit
 * before it removes it), two in a row say the rounds stopped helping. */
#define NF_LOOPCTL_PATIENCE 2

/* The loop's memory between rounds. */
typedef struct nf_loopctl {
    double best;     /* best share within so far (percent), < 0 before the first round */
    int stall;       /* rounds in a row that gained less than min_gain over best */
    double last_pct; /* share of the last round (< 0: none) */
    long last_cp;    /* its control points */
    long last_add;   /* control points the last round had more than the one before (0: none) */
    double gain;     /* points of share it gained over the one before */
    long ref_add;    /* the last step that was not a fine one (nf_loopctl_budget) */
    int fine;        /* the budget last given is a fine step: under half the last step */
    int was_fine;    /* the round last recorded was a fine step */
} nf_loopctl_t;

/* Before the first round. */
void nf_loopctl_init(nf_loopctl_t *c);

/* Verdict after the check pass of round `round` (0-based) with within_pct
 * of the points within tolerance (need_pct wanted), min_gain the least gain
 * over the best earlier round that counts as progress (<= 0:
 * NF_LOOPCTL_MIN_GAIN), max_rounds the limit, and the chooser's status for
 * the next round. Checked in this order: met; no progress
 * (NF_LOOPCTL_PATIENCE rounds in a row); data limit or half the points;
 * max_cp; max rounds; else continue. Updates c. */
int nf_loopctl_verdict(nf_loopctl_t *c, double within_pct, double need_pct, double min_gain,
                       int round, int max_rounds, int chooser_status);

/* Control points the next round may add (nf_knotsel_opts_t.max_add), from
 * the last round's gain, after nf_loopctl_record of a round: FITPACK's way
 * of sizing the next step (fpcurf/fpsurf extrapolate how many knots will
 * bring the residual to s from what the last ones brought; Dierckx 1993,
 * 5.2.2): est = added (need - within) / gained, at most twice the step
 * (twice when it gained nothing), at least half of it, and never less than
 * min_line (one knot line: min(Nu, Nv)). 0 (no limit) before two rounds
 * have been seen. Near the target this keeps the last round from adding
 * several times the control points the missing share needs.
 * Once at most NF_LOOPCTL_FINE_GAP points are missing the half-step floor
 * is dropped (a fine step: a step that gained over twice what is missing
 * says a step under half its size may do; cliffs at 4,047 points took 2
 * lines, 216 control points and 99.41 %, where 1 line, 204, gives
 * 99.33 %). After a fine step the cap is twice the last step that was not
 * one: a fine step's gain says little about a larger step, and a robust
 * fit whose last rounds gain 0.01 points each otherwise crawled a line or
 * two a round into the no-progress stop. Sets c->fine. */
#define NF_LOOPCTL_FINE_GAP 5.0
long nf_loopctl_budget(nf_loopctl_t *c, double need_pct, long min_line);

/* Knots a span may get in the next round (nf_knotsel_opts_t.per_span):
 * while more than NF_LOOPCTL_SIDES_GAP points of the share are missing,
 * NF_KNOTSEL_PER_SPAN (a span's first knot and its sides: a narrow feature
 * bracketed in one round, issue 14's narrow ridge met within 12 rounds);
 * nearer the target one per span, FITPACK's step, so that the last rounds
 * do not add lines the missing share does not need. */
#define NF_LOOPCTL_SIDES_GAP 5.0
int nf_loopctl_per_span(double within_pct, double need_pct);

/* Whether the data support the control points a round added (issue 14:
 * never more control points than the data support): 0 when the sum of
 * squared distances fell from ss0 (cp0 control points) to ss1 (cp1) by
 * less than NF_LOOPCTL_NOISE_K residual variances, ss1 / (n - cp1), per
 * control point added, else 1. A control point fitted to noise removes
 * about one variance from the sum, one that brings shape many (Akaike's
 * criterion, K = 2). On the loop's noise-free fields no round comes near
 * it; with noise of half the tolerance (99 % within it out of reach, 95 %
 * at best) the loop otherwise adds lines to fit the noise until its round
 * limit (docs/loop.md, "Noise: the rounds the data do not support").
 * 1 too when cp1 <= cp0, n <= cp1 or a sum is not finite. */
#define NF_LOOPCTL_NOISE_K 2.0
int nf_loopctl_supported(double ss0, long cp0, double ss1, long cp1, long n);

/* Record a round for nf_loopctl_budget: its share within and its control
 * points (once per round, before nf_loopctl_budget). */
void nf_loopctl_record(nf_loopctl_t *c, double within_pct, long cp);

#endif
