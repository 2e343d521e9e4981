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

/* Read to the end: the number of points, a checksum of their bits, the
 * refusal in msg (-1). */
static long pass_msg(cf_points_t *r, const char *path, uint64_t *sum, char *msg, size_t ml)
{
    double buf[FZ_CHUNK * CF_POINTS_MAX_COLS];
    long total = 0, k;
    int cols = cf_points_cols(r);
    *sum = 0;
    while ((k = cf_points_read(r, buf, FZ_CHUNK, msg, ml)) > 0) {
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

static long pass(cf_points_t *r, const char *path, uint64_t *sum)
{
    char msg[1024];
    return pass_msg(r, path, sum, msg, sizeof msg);
}

/* The checksum of a run of n values after one of sum a: a * P^n + b. */
static uint64_t chain(uint64_t a, uint64_t b, long n)
{
    uint64_t p = 1, q = 1099511628211u;
    for (; n > 0; n >>= 1, q *= q)
        if (n & 1)
            p *= q;
    return a * p + b;
}

/* Two halves (cf_points_split; ASCII and raw files only), the second read
 * first, rebased after the first: the whole's points and, in file order,
 * its refusal with the same line. */
static void halves(cf_points_t *r, const char *path, long nw, uint64_t sw, const char *mw)
{
    cf_points_t *r2;
    char m1[1024], m2[1024];
    if (cf_points_split(r, &r2, m1, sizeof m1) != CF_OK)
        return;
    uint64_t s1, s2;
    long b = pass_msg(r2, path, &s2, m2, sizeof m2), a = pass_msg(r, path, &s1, m1, sizeof m1);
    const char *m = m1;
    if (a >= 0) {
        cf_points_rebase(r2, cf_points_lines(r));
        double row[CF_POINTS_MAX_COLS];
        if (b < 0 && cf_points_read(r2, row, 0, m2, sizeof m2) >= 0) {
            fprintf(stderr, "fuzz_points: a second half forgot its error\n");
            abort();
        }
        m = m2;
    }
    long n = a < 0 || b < 0 ? -1 : a + b;
    if (n != nw || (n >= 0 && chain(s1, s2, b * cf_points_cols(r)) != sw) ||
        (n < 0 && strcmp(m, mw))) {
        fprintf(stderr, "fuzz_points: halves differ: %ld (%ld + %ld) vs %ld points; '%s' vs '%s'\n",
                n, a, b, nw, n < 0 ? m : "", nw < 0 ? mw : "");
        abort();
    }
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
        long n2 = pass_msg(r, path, &s2, msg, sizeof msg);
        if (n1 != n2 || (n1 >= 0 && s1 != s2)) {
            fprintf(stderr, "fuzz_points: second pass differs (%ld vs %ld points)\n", n1, n2);
            abort();
        }
        halves(r, path, n2, s2, msg);
    }
    cf_points_close(r);
    return 0;
}
