/* SPDX-License-Identifier: MIT */
/* nf_robust.h: robust reweighting for the fit (iteratively reweighted least
 * squares against laser spikes and other gross outliers), with a floor
 * under the scale so that clean data keep weight 1 (nf_robust_t). The scale of the
 * residuals comes from their median absolute value, estimated from a
 * fixed-size histogram of |r| filled while the points stream by (no array
 * of residuals: memory does not grow with the points); the weights of the
 * next fit (nf_fit_add's wgt) are Tukey's biweight of r / (c sigma).
 *
 * Histogram: NF_RHIST_BINS log-spaced bins of |r| over [NF_RHIST_LO,
 * NF_RHIST_HI) mm. A quantile estimate is the geometric centre of the bin
 * holding the exact nearest-rank order statistic (the ceil(p n)-th
 * smallest), clamped to the largest value seen, so
 *     |estimate - exact| <= NF_RHIST_RELERR |exact|
 * for NF_RHIST_LO <= |exact| < NF_RHIST_HI; below NF_RHIST_LO it gives 0. */
#ifndef NF_ROBUST_H
#define NF_ROBUST_H

#define NF_RHIST_BINS 512
#define NF_RHIST_LO 1e-9
#define NF_RHIST_HI 1e3
#define NF_RHIST_DECADES 12
/* Half a bin in ratio: 10^(12 / 1024) - 1 = 0.02735, rounded up. */
#define NF_RHIST_RELERR 0.0274

/* Consistency factor of the median absolute deviation for Gaussian noise
 * (sigma = 1.4826 median |r|) and Tukey's tuning constant (95 % efficiency
 * at the Gaussian). */
#define NF_MAD_SIGMA 1.482602218505602
#define NF_TUKEY_C 4.685

typedef struct nf_rhist {
    long long n;    /* values added */
    long long zero; /* |r| < NF_RHIST_LO */
    long long over; /* |r| >= NF_RHIST_HI */
    double max;     /* largest |r| seen */
    long long bin[NF_RHIST_BINS];
} nf_rhist_t;

void nf_rhist_init(nf_rhist_t *h);
/* One residual (its absolute value is counted); non-finite r is ignored. */
void nf_rhist_add(nf_rhist_t *h, double r);
/* Estimate of the nearest-rank p-quantile (0 < p <= 1) of |r|; 0 when empty. */
double nf_rhist_quantile(const nf_rhist_t *h, double p);
/* sigma = NF_MAD_SIGMA * median |r| (0 when empty). */
double nf_rhist_sigma(const nf_rhist_t *h);

/* Tukey's biweight (1 - (r/c)^2)^2 for |r| < c, else 0 (c > 0). */
double nf_tukey(double r, double c);

/* Robust weights that do no harm (issue 14). The MAD scale alone collapses
 * where the residuals are the fit's own approximation error (a clean part:
 * sigma 1e-4 mm, and Tukey at 4.685 sigma then cuts off a fifth of good
 * points). So the scale has a floor the caller chooses (the probe's stated
 * noise, or a fraction of the tolerance), scale = max(sigma, floor), and
 * the weight is 1 up to NF_ROBUST_INNER scales, then falls as a biweight to
 * 0 at NF_ROBUST_CUT scales: points within the noise keep weight 1, and an
 * outlier is a point far beyond the scale. Gaussian data (|r| the 3-D
 * distance, sigma = 1.4826 median |r| = 2.28 per-coordinate sigma) lose
 * weight beyond 6.8 per-coordinate sigmas only: no point in 10^9. The
 * share of points flagged (weight 0) is counted so that the caller can warn
 * when it exceeds NF_ROBUST_WARN_SHARE. */
#define NF_ROBUST_INNER 3.0
#define NF_ROBUST_CUT 6.0
#define NF_ROBUST_WARN_SHARE 0.03

typedef struct nf_robust {
    double sigma;      /* NF_MAD_SIGMA * median |r| of the histogram */
    double floor;      /* the caller's floor (mm) */
    double scale;      /* max(sigma, floor); 0: nothing to reweight */
    double inner, cut; /* weight 1 up to inner, 0 from cut on (mm) */
    long long n;       /* residuals weighed */
    long long partial; /* of them: weight in (0, 1) */
    long long flagged; /* of them: weight 0 (outliers) */
} nf_robust_t;

/* Scale from the residual histogram h of the last fit and the floor (>= 0,
 * finite); counts cleared. NF_EARG for null pointers or a bad floor. */
int nf_robust_init(nf_robust_t *rb, const nf_rhist_t *h, double floor);

/* Weight of a point with residual r (distance to the last fit), counted:
 * 1 for |r| <= inner, (1 - ((|r| - inner) / (cut - inner))^2)^2 up to cut,
 * 0 beyond (and for a non-finite r); always 1 when scale is 0. */
double nf_robust_weight(nf_robust_t *rb, double r);

/* Share of the weighed points flagged (weight 0), 0 when none weighed. */
double nf_robust_share(const nf_robust_t *rb);

/* 1 when the flagged share exceeds NF_ROBUST_WARN_SHARE: the caller warns
 * (too many "outliers" means the scale or the part is wrong, not spikes). */
int nf_robust_warn(const nf_robust_t *rb);

#endif
