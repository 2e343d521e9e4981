/* SPDX-License-Identifier: MIT */
/* stream.c: the memory bounds cellfit's phases are quoted against, one core,
 * one JSON line:
 *   triad   a[i] = b[i] + s c[i] over 3 x 64 MB (STREAM's triad, 24 bytes
 *           counted per element; write-allocate traffic not counted)
 *   read    sum of a 128 MB array (8 bytes per element): the solvers'
 *           streaming reads of the stripe store
 *   scatter the memory pattern of accumulating random points into a stripe
 *           store of N control points (bicubic, 25 doubles each): per point,
 *           4 groups of 4 consecutive rows (800 bytes each, Nu apart) read,
 *           modified and written at a random place; points per second for
 *           N = 10^4, 10^5, 10^6. No arithmetic beyond one add per double.
 *   fma     the latency of one dependent FMA, and the core's peak FMA rate
 *           with 256-bit vectors (compiled with -ffp-contract=fast).
 * Each figure is the best of several repetitions. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define K 25

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned long long rng = 0x9E3779B97F4A7C15ull;

static unsigned long long xorshift(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static double triad(long n, int reps)
{
    double *a = malloc((size_t)n * sizeof *a), *b = malloc((size_t)n * sizeof *b),
           *c = malloc((size_t)n * sizeof *c);
    double best = INFINITY;
    if (!a || !b || !c)
        goto out;
    for (long i = 0; i < n; i++)
        a[i] = 0.0, b[i] = 1.0, c[i] = 2.0;
    for (int r = 0; r < reps; r++) {
        const double s = 0.5 + r, t0 = now();
        for (long i = 0; i < n; i++)
            a[i] = b[i] + s * c[i];
        const double t = now() - t0;
        best = t < best ? t : best;
    }
    if (a[n / 2] != 1.0 + 2.0 * (reps - 0.5)) /* keep the stores */
        best = INFINITY;
out:
    free(a);
    free(b);
    free(c);
    return 24.0 * (double)n / best / 1e9;
}

static double readsum(long n, int reps)
{
    double *a = malloc((size_t)n * sizeof *a), best = INFINITY;
    if (!a)
        return 0.0;
    for (long i = 0; i < n; i++)
        a[i] = (double)(i & 7);
    for (int r = 0; r < reps; r++) {
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        const double t0 = now();
        for (long i = 0; i + 3 < n; i += 4)
            s0 += a[i], s1 += a[i + 1], s2 += a[i + 2], s3 += a[i + 3];
        const double t = now() - t0;
        if (s0 + s1 + s2 + s3 != 3.5 * (double)(n & ~3L))
            return 0.0;
        best = t < best ? t : best;
    }
    free(a);
    return 8.0 * (double)n / best / 1e9;
}

/* Points per second of the random-order accumulation's memory traffic. */
static double scatter(long ncp, long points, int reps)
{
    const long side = lround(sqrt((double)ncp)), n = side * side;
    const long span = n - 3 * side - 4; /* first row of the 4x4 patch */
    double *S = calloc((size_t)(n * K), sizeof *S), best = INFINITY;
    if (!S)
        return 0.0;
    for (int r = 0; r < reps; r++) {
        const double t0 = now();
        for (long k = 0; k < points; k++) {
            const unsigned long long x = xorshift();
            const long i0 = (long)((x >> 11) % (unsigned long long)span);
            for (int g = 0; g < 4; g++) {
                double *row = S + (i0 + g * side) * K;
                for (int t = 0; t < 4 * K; t++)
                    row[t] += 1.0;
            }
        }
        const double t = now() - t0;
        best = t < best ? t : best;
    }
    double sum = 0.0;
    for (long i = 0; i < n * K; i++)
        sum += S[i];
    free(S);
    return sum == 16.0 * K * (double)points * reps ? (double)points / best : 0.0;
}

/* Nanoseconds per FMA in one dependent chain x = a x + b: the floor of a
 * row sum (Gauss-Seidel, the backward sweep) taken as one chain. */
static double fma_latency_ns(long n)
{
    volatile double seed = 1.0;
    double x = seed, best = INFINITY;
    for (int r = 0; r < 3; r++) {
        const double t0 = now();
        for (long i = 0; i < n; i++)
            x = x * 0.999999999 + 1e-9;
        const double t = now() - t0;
        best = t < best ? t : best;
    }
    return x > 0.0 ? 1e9 * best / (double)n : 0.0;
}

/* Peak double-precision GFLOP/s of one core with 256-bit FMAs (x86-64-v3):
 * 12 independent vector chains hide the latency. */
typedef double v4 __attribute__((vector_size(32)));
static double fma_peak_gflops(long n)
{
    volatile double seed = 1.0;
    v4 acc[12], m = {0.999999999, 0.999999999, 0.999999999, 0.999999999},
                c = {1e-9, 1e-9, 1e-9, 1e-9};
    double best = INFINITY, sum = 0.0;
    for (int k = 0; k < 12; k++)
        for (int l = 0; l < 4; l++)
            acc[k][l] = seed + k + l;
    for (int r = 0; r < 3; r++) {
        const double t0 = now();
        for (long i = 0; i < n; i++)
            for (int k = 0; k < 12; k++)
                acc[k] = acc[k] * m + c;
        const double t = now() - t0;
        best = t < best ? t : best;
    }
    for (int k = 0; k < 12; k++)
        for (int l = 0; l < 4; l++)
            sum += acc[k][l];
    return sum > 0.0 ? 2.0 * 4.0 * 12.0 * (double)n / best / 1e9 : 0.0;
}

int main(void)
{
    const double tri = triad(8L << 20, 5);
    const double rd = readsum(16L << 20, 5);
    const double s4 = scatter(10000, 2000000, 3);
    const double s5 = scatter(100000, 2000000, 3);
    const double s6 = scatter(1000000, 1000000, 3);
    const double lat = fma_latency_ns(100000000L);
    const double peak = fma_peak_gflops(20000000L);
    printf("{\"bench\": \"stream\", \"triad_GBps\": %.2f, \"read_GBps\": %.2f, "
           "\"scatter_1e4_points_per_s\": %.4g, \"scatter_1e5_points_per_s\": %.4g, "
           "\"scatter_1e6_points_per_s\": %.4g, \"scatter_bytes_per_point\": %d, "
           "\"fma_latency_ns\": %.3f, \"fma_peak_gflops\": %.1f}\n",
           tri, rd, s4, s5, s6, 16 * K * 8, lat, peak);
    return tri > 0 && rd > 0 && s4 > 0 && s5 > 0 && s6 > 0 && lat > 0 && peak > 0 ? 0 : 1;
}
