/* SPDX-License-Identifier: MIT */
/* nf_robust.c: |residual| histogram, MAD scale with a floor, Tukey weights. */
#include "nf_robust.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

#define PER_DECADE ((double)NF_RHIST_BINS / NF_RHIST_DECADES)

void nf_rhist_init(nf_rhist_t *h)
{
    memset(h, 0, sizeof *h);
}

void nf_rhist_add(nf_rhist_t *h, double r)
{
    double a = fabs(r);
    if (!isfinite(a))
        return;
    h->n++;
    h->max = a > h->max ? a : h->max;
    if (a < NF_RHIST_LO) {
        h->zero++;
        return;
    }
    if (a >= NF_RHIST_HI) {
        h->over++;
        return;
    }
    long b = (long)floor(log10(a / NF_RHIST_LO) * PER_DECADE);
    b = b < 0 ? 0 : (b >= NF_RHIST_BINS ? NF_RHIST_BINS - 1 : b);
    h->bin[b]++;
}

double nf_rhist_quantile(const nf_rhist_t *h, double p)
{
    if (h->n <= 0 || !(p > 0.0))
        return 0.0;
    p = p > 1.0 ? 1.0 : p;
    long long rank = (long long)ceil(p * (double)h->n), seen = h->zero; /* 1-based */
    rank = rank < 1 ? 1 : rank;
    if (rank <= seen)
        return 0.0;
    for (int b = 0; b < NF_RHIST_BINS; b++) {
        seen += h->bin[b];
        if (rank <= seen) {
            double c = NF_RHIST_LO * pow(10.0, ((double)b + 0.5) / PER_DECADE);
            return c < h->max ? c : h->max;
        }
    }
    return h->max; /* in the overflow */
}

double nf_rhist_sigma(const nf_rhist_t *h)
{
    return NF_MAD_SIGMA * nf_rhist_quantile(h, 0.5);
}

double nf_tukey(double r, double c)
{
    double t = r / c;
    if (!(fabs(t) < 1.0))
        return 0.0;
    t = 1.0 - t * t;
    return t * t;
}

int nf_robust_init(nf_robust_t *rb, const nf_rhist_t *h, double floor)
{
    if (!rb || !h || !(floor >= 0.0) || !isfinite(floor))
        return NF_EARG;
    memset(rb, 0, sizeof *rb);
    rb->sigma = nf_rhist_sigma(h);
    rb->floor = floor;
    rb->scale = rb->sigma > floor ? rb->sigma : floor;
    rb->inner = NF_ROBUST_INNER * rb->scale;
    rb->cut = NF_ROBUST_CUT * rb->scale;
    return NF_OK;
}

double nf_robust_weight(nf_robust_t *rb, double r)
{
    rb->n++;
    if (!(rb->scale > 0.0)) /* an exact fit: nothing to reweight */
        return 1.0;
    const double a = fabs(r);
    if (a <= rb->inner)
        return 1.0;
    if (!(a < rb->cut)) { /* also NaN */
        rb->flagged++;
        return 0.0;
    }
    rb->partial++;
    double t = (a - rb->inner) / (rb->cut - rb->inner);
    t = 1.0 - t * t;
    return t * t;
}

double nf_robust_share(const nf_robust_t *rb)
{
    return rb->n > 0 ? (double)rb->flagged / (double)rb->n : 0.0;
}

int nf_robust_warn(const nf_robust_t *rb)
{
    return nf_robust_share(rb) > NF_ROBUST_WARN_SHARE;
}
