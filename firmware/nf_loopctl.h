/* nf_loopctl.h: the rules of the fitting loop around the knot chooser
 * (nf_knotsel.h): alpha scaled with the knot spacing at each refinement
 * level (Eq. 7's Greville term), and the verdict after each round: met, or
 * why the loop stops (issue 14: no progress, data limit, max_cp, rounds). */
#ifndef NF_LOOPCTL_H
#define NF_LOOPCTL_H

#include "nf_knotsel.h"
#include "nf_surf.h"

/* alpha_level = alpha ((h0u h0v) / (hu hv))^NF_LOOPCTL_ALPHA_POW; see
 * nf_loopctl_alpha. */
#define NF_LOOPCTL_ALPHA_POW 1.0
/* Default least gain of a round, in points of the percentage within. */
#define NF_LOOPCTL_MIN_GAIN 0.1

/* alpha for a net of knot spacing (hu, hv) when alpha was set for the
 * first net (h0u, h0v): alpha (h0u h0v / (hu hv))^NF_LOOPCTL_ALPHA_POW,
 * h = the domain's width over its non-empty spans in that direction.
 * Why: alpha |(B - I) P|^2 (Eq. 7) is, per control point, a second
 * difference of the net, about h^2 times the surface's second derivative;
 * summed over the (area / (hu hv)) control points it is an energy
 * alpha h^2 |S''|^2 area that halving the spans would cut by 4: empty and
 * sparse spans would lose the smoothing they had at the first level. The
 * scale keeps that energy per area. A non-finite or negative alpha, or
 * nets with another domain, return alpha unchanged. */
double nf_loopctl_alpha(double alpha, const nf_surf_t *first, const nf_surf_t *cur);

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

/* Verdict of round `round` (0-based) with within_pct of the points within
 * tolerance (need_pct wanted), prev_pct the previous round's (< 0 on the
 * first round), min_gain the least gain a round must bring (<= 0:
 * NF_LOOPCTL_MIN_GAIN), max_rounds the limit, and the chooser's status for
 * the next round. Checked in this order: met; no progress; data limit or
 * half the points; max_cp; max rounds; else continue. */
int nf_loopctl_verdict(double within_pct, double need_pct, double prev_pct, double min_gain,
                       int round, int max_rounds, int chooser_status);

#endif
