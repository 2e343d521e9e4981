/* SPDX-License-Identifier: MIT */
/* genbin.c: the benchmark's binary point files (docs/formats.md, raw
 * little-endian float64): `genbin IN.uvxyz OUT.uvxyz.bin [TIMES]` reads the
 * ASCII points `cellfit gen` wrote (strtod, '#' lines skipped) and writes
 * them TIMES times (1) in a row, each copy in the file's raster order: the
 * 10^8-point file is the 10^6-point raster 100 times (the same sums as 100
 * scans of the part). Prints one JSON line: points written, bytes, seconds. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* x as 8 little-endian bytes, whatever the host's order. */
static void le64(unsigned char *b, double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    for (int i = 0; i < 8; i++)
        b[i] = (unsigned char)(u >> (8 * i));
}

int main(int argc, char **argv)
{
    if (argc < 3 || argc > 4) {
        fprintf(stderr, "usage: genbin IN.uvxyz OUT.uvxyz.bin [TIMES]\n");
        return 2;
    }
    long times = argc == 4 ? atol(argv[3]) : 1;
    FILE *in = fopen(argv[1], "r");
    if (!in || times < 1) {
        fprintf(stderr, "genbin: %s: cannot read\n", argv[1]);
        return 1;
    }
    size_t cap = 1 << 20, n = 0;
    unsigned char *pts = malloc(cap * 40);
    char line[512];
    while (pts && fgets(line, sizeof line, in)) {
        double v[5];
        if (line[0] == '#' ||
            sscanf(line, "%lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4]) != 5)
            continue;
        if (n == cap) {
            unsigned char *p = realloc(pts, 2 * cap * 40);
            if (!p)
                break;
            pts = p, cap *= 2;
        }
        for (int c = 0; c < 5; c++)
            le64(pts + 40 * n + 8 * c, v[c]);
        n++;
    }
    fclose(in);
    double t0 = now();
    FILE *out = fopen(argv[2], "wb");
    int bad = !pts || !out;
    for (long k = 0; !bad && k < times; k++)
        bad = fwrite(pts, 40, n, out) != n;
    bad |= !out || fclose(out) != 0;
    free(pts);
    if (bad) {
        fprintf(stderr, "genbin: %s: cannot write\n", argv[2]);
        return 1;
    }
    printf("{\"bench\": \"genbin\", \"points\": %ld, \"bytes\": %.0f, \"seconds\": %.3f}\n",
           (long)n * times, 40.0 * (double)n * (double)times, now() - t0);
    return 0;
}
