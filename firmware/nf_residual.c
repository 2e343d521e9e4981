/* SPDX-License-Identifier: MIT */
/* nf_residual.c: r = b - A x and its relative norm, per coordinate. */
#include "nf_solve.h"
#include <math.h>

double nf_residual(const nf_stripe_t *A, const double *b, const double *x, double *r)
{
    nf_stripe_matvec(A, x, r);
    double rr[3] = {0, 0, 0}, bb[3] = {0, 0, 0};
    for (long i = 0; i < A->n; i++)
        for (int c = 0; c < 3; c++) {
            double d = b[3 * i + c] - r[3 * i + c];
            r[3 * i + c] = d;
            rr[c] += d * d;
            bb[c] += b[3 * i + c] * b[3 * i + c];
        }
    double worst = 0.0;
    for (int c = 0; c < 3; c++) {
        double rel = bb[c] > 0.0 ? sqrt(rr[c] / bb[c]) : sqrt(rr[c]);
        if (rel > worst || rel != rel)
            worst = rel;
    }
    return worst;
}
