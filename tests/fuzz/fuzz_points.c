/* SPDX-License-Identifier: MIT */
/* fuzz_points.c: libFuzzer target for the point-file reader (cf_points.c,
 * ASCII and PLY): the input is a file, opened with 0 (the file decides), 3
 * or 5 columns (by its length mod 3: an open costs 1 MiB of fresh pages)
 * and read to the end twice (rewind between). A refusal is
 * one line naming the file; every accepted value is finite; the second pass
 * gives the same points as the first. Then a differential check of the
 * number parser against strtod: the input mapped onto the alphabet of
 * decimals is one token, written three times on a line; the reader accepts
 * it exactly when strtod takes all of it to a finite value, and then with
 * strtod's bits. */
#include "cf_err.h"
#include "cf_points.h"
#include "cf_points_el.h"
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

static void against_strtod(const uint8_t *data, size_t size)
{
    static const char abc[] = "0123456789012345678901234567890123456789.e+-E.";
    char tok[130], line[400], msg[1024];
    size_t n = size < sizeof tok - 1 ? size : sizeof tok - 1;
    for (size_t i = 0; i < n; i++)
        tok[i] = abc[data[i] % (sizeof abc - 1)];
    tok[n] = '\0';
    if (!n)
        return;
    char *end;
    double want = strtod(tok, &end);
    int ok = *end == '\0' && end != tok && isfinite(want);
    int len = snprintf(line, sizeof line, "%s %s %s\n", tok, tok, tok);
    const char *path = fz_file("tok.xyz", (const uint8_t *)line, (size_t)len);
    cf_points_t *r;
    double v[3];
    long k = -1;
    if (!cf_points_open(&r, path, 3, msg, sizeof msg)) {
        k = cf_points_read(r, v, 1, msg, sizeof msg);
        cf_points_close(r);
    }
    if (ok != (k == 1)) {
        fprintf(stderr, "fuzz_points: '%s': strtod %s, reader %s\n", tok,
                ok ? "accepts" : "refuses", k == 1 ? "accepts" : "refuses");
        abort();
    }
    for (int i = 0; ok && i < 3; i++)
        if (memcmp(&v[i], &want, sizeof want)) {
            fprintf(stderr, "fuzz_points: '%s': got %a, strtod %a\n", tok, v[i], want);
            abort();
        }
}

static void against_el(const uint8_t *data, size_t size)
{
    if (size < 10)
        return;
    uint64_t m = 0;
    for (int i = 0; i < 8; i++)
        m = m << 8 | data[i];
    m %= UINT64_C(10000000000000000000); /* at most 19 digits */
    long q = CF_PEL_QMIN + (long)((data[8] << 8 | data[9]) % (CF_PEL_QMAX - CF_PEL_QMIN + 1));
    char tok[96];
    int k = snprintf(tok, sizeof tok, "%llu", (unsigned long long)m), extra = 0;
    for (size_t i = 10; i < size && extra < 40; i++, extra++)
        tok[k++] = (char)('0' + data[i] % 10);
    snprintf(tok + k, sizeof tok - (size_t)k, "e%ld", q - extra);
    double got, want = strtod(tok, NULL);
    int dec = extra ? cf_pel_decide_range(m, q, &got) : cf_pel_decide(m, q, &got);
    if (dec && memcmp(&got, &want, sizeof got)) {
        fprintf(stderr, "fuzz_points: '%s': Eisel-Lemire %a, strtod %a\n", tok, got, want);
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    against_strtod(data, size);
    against_el(data, size);
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
