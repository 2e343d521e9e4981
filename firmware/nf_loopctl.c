/* SPDX-License-Identifier: MIT */
/* nf_loopctl.c: alpha per refinement level and the verdict of each round of
 * the fitting loop. */
#include "nf_loopctl.h"
#include <math.h>

/* Mean width of the non-empty spans of T (n + 1 control points). */
static double spacing(const double *T, int n, int deg)
{
    int c = 0;
    for (int i = deg; i <= n; i++)
        c += T[i] < T[i + 1];
    return c > 0 ? (T[n + 1] - T[deg]) / c : 0.0;
}

double nf_loopctl_alpha(double alpha, const nf_surf_t *first, const nf_surf_t *cur, double k)
{
    if (!first || !cur || !(alpha >= 0.0) || !isfinite(alpha) || !isfinite(k))
        return alpha;
    double a0, a1, b0, b1, c0, c1, d0, d1;
    nf_surf_domain(first, &a0, &a1, &b0, &b1);
    nf_surf_domain(cur, &c0, &c1, &d0, &d1);
    if (a0 != c0 || a1 != c1 || b0 != d0 || b1 != d1)
        return alpha;
    const double h0u = spacing(first->U, first->nu - 1, first->p),
                 h0v = spacing(first->V, first->nv - 1, first->q),
                 hu = spacing(cur->U, cur->nu - 1, cur->p),
                 hv = spacing(cur->V, cur->nv - 1, cur->q);
    if (!(hu > 0.0) || !(hv > 0.0) || !(h0u > 0.0) || !(h0v > 0.0))
        return alpha;
    return alpha * pow((h0u * h0v) / (hu * hv), 0.5 * k);
}

const char *nf_loopctl_str(int st)
{
    switch (st) {
    case NF_LOOPCTL_CONTINUE: return "continue";
    case NF_LOOPCTL_MET: return "met";
    case NF_LOOPCTL_DATA_LIMIT: return "not_met_data_limit";
    case NF_LOOPCTL_MAX_CP: return "not_met_max_cp";
    case NF_LOOPCTL_NO_PROGRESS: return "not_met_no_progress";
    case NF_LOOPCTL_MAX_ROUNDS: return "not_met_max_rounds";
    default: return "unknown verdict";
    }
}

void nf_loopctl_init(nf_loopctl_t *c)
{
    c->best = -1.0;
    c->stall = 0;
    c->last_pct = -1.0;
    c->last_cp = 0;
    c->last_add = 0;
    c->gain = 0.0;
    c->ref_add = 0;
    c->fine = 0;
    c->was_fine = 0;
}

void nf_loopctl_record(nf_loopctl_t *c, double within_pct, long cp)
{
    /* The gain of this round is (within_pct - last_pct) for (cp - last_cp)
     * control points: keep the pair of the last two rounds. */
    c->last_add = c->last_pct >= 0.0 ? cp - c->last_cp : 0;
    c->gain = c->last_pct >= 0.0 ? within_pct - c->last_pct : 0.0;
    c->last_pct = within_pct;
    c->last_cp = cp;
    /* A fine step (see nf_loopctl_budget) is a trial, not the step size
     * the rounds go on from. */
    c->was_fine = c->fine;
    c->fine = 0;
    if (!c->was_fine)
        c->ref_add = c->last_add;
}

long nf_loopctl_budget(nf_loopctl_t *c, double need_pct, long min_line)
{
    c->fine = 0;
    if (c->last_add <= 0)
        return 0;
    const double added = (double)c->last_add, missing = need_pct - c->last_pct;
    /* After a fine step that did not meet the goal, the step before it
     * caps the round (a fine step's gain says little about a larger one). */
    const double ref = c->was_fine && c->ref_add > added ? (double)c->ref_add : added;
    double b = 2.0 * ref;
    if (c->gain > 0.0) {
        const double est = added * missing / c->gain;
        b = est < b ? est : b;
        /* FITPACK's floor of half the last step keeps early rounds from
         * crawling; near the goal it makes the last round overshoot. */
        if (missing > NF_LOOPCTL_FINE_GAP)
            b = b < 0.5 * added ? 0.5 * added : b;
    }
    b = b < (double)min_line ? (double)min_line : b;
    c->fine = b < 0.5 * added;
    return (long)ceil(b);
}

int nf_loopctl_per_span(double within_pct, double need_pct)
{
    return need_pct - within_pct > NF_LOOPCTL_SIDES_GAP ? NF_KNOTSEL_PER_SPAN : 1;
}

int nf_loopctl_verdict(nf_loopctl_t *c, double within_pct, double need_pct, double min_gain,
                       int round, int max_rounds, int chooser_status)
{
    if (within_pct >= need_pct)
        return NF_LOOPCTL_MET;
    if (!(min_gain > 0.0))
        min_gain = NF_LOOPCTL_MIN_GAIN;
    /* Rounds that help less than min_gain points of the share will not
     * reach the target within reason (issue 14: 95.56 -> 95.58 -> 95.63 %
     * at 767,849 control points). */
    if (c->best >= 0.0)
        c->stall = within_pct - c->best < min_gain ? c->stall + 1 : 0;
    c->best = within_pct > c->best ? within_pct : c->best;
    if (c->stall >= NF_LOOPCTL_PATIENCE)
        return NF_LOOPCTL_NO_PROGRESS;
    switch (chooser_status) {
    case NF_KNOTSEL_INSERT: break;
    case NF_KNOTSEL_MAX_CP: return NF_LOOPCTL_MAX_CP;
    default: return NF_LOOPCTL_DATA_LIMIT; /* no split the data support, or half the points */
    }
    if (round + 1 >= max_rounds)
        return NF_LOOPCTL_MAX_ROUNDS;
    return NF_LOOPCTL_CONTINUE;
}

int nf_loopctl_supported(double ss0, long cp0, double ss1, long cp1, long n)
{
    if (cp1 <= cp0 || n <= cp1 || !(ss0 >= 0.0 && ss0 < INFINITY) ||
        !(ss1 >= 0.0 && ss1 < INFINITY))
        return 1;
    const double var = ss1 / (double)(n - cp1);
    return ss0 - ss1 >= NF_LOOPCTL_NOISE_K * var * (double)(cp1 - cp0);
}
