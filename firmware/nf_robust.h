/* nf_robust.h: robust reweighting for the fit (iteratively reweighted least
 * squares against laser spikes and other gross outliers). The scale of the
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

#endif
