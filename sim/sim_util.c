/* SPDX-License-Identifier: MIT */
/* sim_util.c: the simulator's clock and seeded random numbers (xorshift64,
 * Box-Muller), one stream per purpose so that faults do not shift noise. */
#include "sim.h"
#include <math.h>
#include <time.h>

double sim_now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

void sim_rng_seed(sim_rng_t *r, uint64_t seed, uint64_t stream)
{
    r->s = 0x243F6A8885A308D3ull ^ (seed * 0x9E3779B97F4A7C15ull) ^ (stream << 32);
    if (!r->s)
        r->s = 1;
    for (int i = 0; i < 8; i++)
        (void)sim_urand(r);
}

double sim_urand(sim_rng_t *r)
{
    r->s ^= r->s << 13;
    r->s ^= r->s >> 7;
    r->s ^= r->s << 17;
    return ((double)(r->s >> 11) + 0.5) / 9007199254740992.0;
}

double sim_gauss(sim_rng_t *r)
{
    double a = sim_urand(r), b = sim_urand(r);
    return sqrt(-2.0 * log(a)) * cos(6.283185307179586 * b);
}
