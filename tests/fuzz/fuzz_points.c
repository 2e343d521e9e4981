/* fuzz_points.c: libFuzzer target for the point-file reader (cf_points.c,
 * ASCII and PLY): the input is a file, opened with 0 (the file decides), 3
 * or 5 columns (by its length mod 3: an open costs 1 MiB of fresh pages)
 * and read to the end twice (rewind between). A refusal is
 * one line naming the file; every accepted value is finite; the second pass
 * gives the same points as the first. */
#include "cf_err.h"
#include "cf_points.h"
#include "fuzz.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FZ_CHUNK 64

/* Read to the end: the number of points, a checksum of their bits. */
static long pass(cf_points_t *r, const char *path, uint64_t *sum)
{
    double buf[FZ_CHUNK * CF_POINTS_MAX_COLS];
    char msg[1024];
    long total = 0, k;
    int cols = cf_points_cols(r);
    *sum = 0;
    while ((k = cf_points_read(r, buf, FZ_CHUNK, msg, sizeof msg)) > 0) {
        for (long i = 0; i < k * cols; i++) {
            uint64_t b;
            if (!isfinite(buf[i])) {
                fprintf(stderr, "fuzz_points: accepted a non-finite value\n");
                abort();
            }
            memcpy(&b, &buf[i], sizeof b);
            *sum = *sum * 1099511628211u + b;
        }
        total += k;
    }
    if (k < 0) {
        fz_one_line(msg);
        fz_names(msg, path);
        return -1;
    }
    return total;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fz_file("in.xyz", data, size);
    static const int want[3] = {0, 3, 5};
    cf_points_t *r;
    char msg[1024];
    if (cf_points_open(&r, path, want[size % 3], msg, sizeof msg)) {
        fz_one_line(msg);
        fz_names(msg, path);
        return 0;
    }
    uint64_t s1, s2;
    long n1 = pass(r, path, &s1);
    if (cf_points_rewind(r) == CF_OK) {
        long n2 = pass(r, path, &s2);
        if (n1 != n2 || (n1 >= 0 && s1 != s2)) {
            fprintf(stderr, "fuzz_points: second pass differs (%ld vs %ld points)\n", n1, n2);
            abort();
        }
    }
    cf_points_close(r);
    return 0;
}
