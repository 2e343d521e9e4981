/* SPDX-License-Identifier: MIT */
/* nf_probe.c: does the data determine the net? A homogeneous solve A e = 0
 * from a random start converges to the part of the start lying in the null
 * space of A; a survivor means some control points are free (no data, data
 * on a line within a span, ...). Krylov and Gauss-Seidel iterates for A P = b
 * never show this: b = R^T Q lies in the range of A. */
#include "nf_err.h"
#include "nf_solve.h"
#include <math.h>
#include <stdint.h>

#define NF_PROBE_SURVIVOR 1e-4

void nf_probe_fill(double *e, long n)
{
    uint64_t s = 0x9E3779B97F4A7C15ull; /* fixed seed: the probe is repeatable */
    for (long i = 0; i < 3 * n; i++) {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        uint64_t r = s * 0x2545F4914F6CDD1Dull;
        e[i] = (double)(r >> 11) * (2.0 / 9007199254740992.0) - 1.0;
    }
}

int nf_probe_judge(const double *e, long n, double e0, long *bad)
{
    double worst = 0.0;
    long at = -1;
    for (long i = 0; i < 3 * n; i++) {
        double a = fabs(e[i]);
        if (a > worst || a != a) {
            worst = a;
            at = i / 3;
            if (a != a)
                break;
        }
    }
    if (worst != worst || worst > NF_PROBE_SURVIVOR * e0) {
        *bad = at;
        return NF_ESINGULAR;
    }
    return NF_OK;
}

double nf_probe_max(const double *e, long n)
{
    double m = 0.0;
    for (long i = 0; i < 3 * n; i++)
        m = fabs(e[i]) > m ? fabs(e[i]) : m;
    return m;
}
