/* SPDX-License-Identifier: MIT */
/* nf_budget.c: the byte formula of nf_budget.h as a runtime function. */
#include "nf_budget.h"
#include <limits.h>

/* Above this many flops for the band factorisation, PCG wins in practice. */
#define NF_CHOL_AUTO_FLOPS 4.0e8

long nf_fit_bytes(int nu, int nv, int p, int q, nf_solver_t solver)
{
    if (nu < 1 || nv < 1 || p < 0 || q < 0)
        return -1;
    if (solver == NF_SOLVER_AUTO)
        solver = nf_solver_pick(nu, nv, p, q);
    /* The formula of nf_budget.h in double: a job whose bytes do not fit a
     * long (32 bits on the microcontrollers) is reported as -1, never
     * wrapped. Below 2^53 every value is exact. */
    const double n = (double)nu * nv, base = 8.0 * n * (NF_STRIPE_SLOTS(p, q) + 6.0);
    double b;
    switch (solver) {
    case NF_SOLVER_GS: b = base + 8.0 * 6.0 * n; break;
    case NF_SOLVER_CHOL: b = base + 8.0 * n * ((double)q * nu + p + 1 + 3); break;
    case NF_SOLVER_PCG:
    default: b = base + 8.0 * 17.0 * n; break;
    }
    b += (double)NF_ARENA_SLACK;
    if (b > (double)LONG_MAX)
        return -1;
    return (long)b;
}

long nf_fit_shard_bytes(int nu, int nv, int p, int q)
{
    if (nu < 1 || nv < 1 || p < 0 || q < 0)
        return -1;
    const double b = 8.0 * (double)nu * nv * (NF_STRIPE_SLOTS(p, q) + 3.0) + 4.0 * NF_ARENA_ALIGN;
    return b > (double)LONG_MAX ? -1 : (long)b;
}

long nf_footprint_bytes(int nu, int nv, int p, int q)
{
    if (p < 0 || q < 0 || nu <= p || nv <= q)
        return -1;
    const double b = 4.0 * NF_FP_SUB * NF_FP_SUB * ((double)nu - p) * ((double)nv - q) +
                     (double)nu * nv + NF_ARENA_ALIGN;
    return b > (double)LONG_MAX ? -1 : (long)b;
}

nf_solver_t nf_solver_pick(int nu, int nv, int p, int q)
{
    double n = (double)nu * nv, bw = (double)q * nu + p;
    double chol = 8.0 * n * (NF_STRIPE_SLOTS(p, q) + 6.0) + 8.0 * n * (bw + 4) + NF_ARENA_SLACK;
    if (chol <= (double)NF_ARENA_BYTES && n * bw * bw <= NF_CHOL_AUTO_FLOPS)
        return NF_SOLVER_CHOL;
    return NF_SOLVER_PCG;
}

long nf_budget_max_square(long arena_bytes, int p, nf_solver_t solver)
{
    long lo = p + 1, hi = 1L << 20; /* side length search */
    if (nf_fit_bytes(p + 1, p + 1, p, p, solver) > arena_bytes)
        return 0;
    while (hi - lo > 1) {
        long mid = (lo + hi) / 2;
        long b = (mid > NF_MAX_CP / mid) ? -1 : nf_fit_bytes((int)mid, (int)mid, p, p, solver);
        if (b >= 0 && b <= arena_bytes)
            lo = mid;
        else
            hi = mid;
    }
    return lo * lo;
}

const char *nf_solver_name(nf_solver_t s)
{
    switch (s) {
    case NF_SOLVER_AUTO: return "auto";
    case NF_SOLVER_GS: return "gs";
    case NF_SOLVER_CHOL: return "chol";
    case NF_SOLVER_PCG: return "pcg";
    default: return "unknown";
    }
}
