/* SPDX-License-Identifier: MIT */
/* test_points_el.c: the Eisel-Lemire fast path of the number parser
 * (lib/cf_points_el.c) against glibc's strtod, which is correctly rounded:
 * every value it decides has strtod's bits, on every input class (short
 * mantissas, 17-19 digits, the largest and smallest exponents, exact ties
 * and near-halfway decimals, subnormals, more than 19 digits through the
 * range form). Its power table against exact integer arithmetic. Then the
 * same classes through the reader (lib/cf_points.c), where the fast paths
 * and the strtod fallback meet. A fast path that never decides would pass
 * the exactness checks, so the share it decides is checked too. */
#include "cf_err.h"
#include "cf_points.h"
#include "cf_points_el.h"
#include "cf_test.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint64_t rng = 0x9E3779B97F4A7C15ULL;

static uint64_t next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static uint64_t pow10u(int n)
{
    uint64_t p = 1;
    while (n-- > 0)
        p *= 10;
    return p;
}

/* A random mantissa of exactly nd digits (1..19). */
static uint64_t rand_digits(int nd)
{
    uint64_t lo = pow10u(nd - 1), span = nd == 19 ? UINT64_C(9) * lo : pow10u(nd) - lo;
    return lo + next_u64() % span;
}

#if CF_PEL_HAVE
static double ref(uint64_t m, long q)
{
    char b[64];
    snprintf(b, sizeof b, "%llue%ld", (unsigned long long)m, q);
    return strtod(b, NULL);
}

/* Checks one (m, q); returns whether the fast path decided it. */
static int check(uint64_t m, long q)
{
    double got, want;
    if (!cf_pel_decide(m, q, &got))
        return 0;
    want = ref(m, q);
    if (memcmp(&got, &want, sizeof got))
        fail_msg("%llue%ld: fast path %a, strtod %a", (unsigned long long)m, q, got, want);
    return 1;
}

/* Short mantissas (1-8 digits), exponents where results are normal: nearly
 * all decided (Clinger's range included: the reader tries that first). */
static void test_short(void **state)
{
    (void)state;
    long n = 0, dec = 0;
    for (int i = 0; i < 200000; i++, n++) {
        int nd = 1 + (int)(next_u64() % 8);
        long q = (long)(next_u64() % 600) - 300;
        dec += check(rand_digits(nd), q);
    }
    printf("short: %ld of %ld decided\n", dec, n);
    assert_true(dec > n * 99 / 100);
}

/* 17-19 digits (%.17g output and longer), every exponent of the table. */
static void test_long_mantissa(void **state)
{
    (void)state;
    long n = 0, dec = 0;
    for (int i = 0; i < 300000; i++) {
        int nd = 17 + (int)(next_u64() % 3);
        long q = CF_PEL_QMIN + (long)(next_u64() % (CF_PEL_QMAX - CF_PEL_QMIN + 1));
        uint64_t m = rand_digits(nd);
        int d = check(m, q);
        double v = ref(m, q);
        if (isnormal(v) && fabs(v) < DBL_MAX) { /* the share only where it may decide */
            n++;
            dec += d;
        }
    }
    printf("17-19 digits: %ld of %ld normal results decided\n", dec, n);
    assert_true(n > 100000);
    assert_true(dec > n * 99 / 100);
}

/* The ends of the range: overflow and the normal/subnormal border are never
 * decided wrongly (the fast path declines both); subnormals entirely. */
static void test_extremes(void **state)
{
    (void)state;
    long sub = 0;
    for (int i = 0; i < 200000; i++) {
        int nd = 1 + (int)(next_u64() % 19);
        uint64_t m = rand_digits(nd);
        long q = (next_u64() & 1) ? 308 - nd - 3 + (long)(next_u64() % 8)
                                  : -308 - nd - 20 + (long)(next_u64() % 40);
        if (q > CF_PEL_QMAX || q < CF_PEL_QMIN)
            continue;
        double v = ref(m, q);
        int d = check(m, q);
        if (!isnormal(v) || isinf(v)) {
            sub++;
            assert_false(d);
        }
    }
    assert_true(sub > 1000);
    /* The two ends of the table and DBL_MAX's and DBL_MIN's decimals. */
    check(UINT64_C(17976931348623157), 292);
    check(UINT64_C(17976931348623158), 292);
    check(UINT64_C(22250738585072014), -324);
    check(UINT64_C(22250738585072011), -324);
    check(UINT64_C(9999999999999999999), CF_PEL_QMIN);
    check(1, CF_PEL_QMAX);
    double x;
    assert_false(cf_pel_decide(2, CF_PEL_QMAX, &x)); /* 2e308 overflows */
    assert_false(cf_pel_decide(1, CF_PEL_QMAX + 1, &x));
    assert_false(cf_pel_decide(1, CF_PEL_QMIN - 1, &x));
    assert_false(cf_pel_decide(0, 0, &x));
}

/* Exact ties (X = P, 0 <= q <= 55): an odd 54-bit o * 5^q halfway between
 * two doubles, m = o with q > 0, or an integer below 2^64 with q = 0; ties
 * go to even. And one unit either side of each. */
static void test_ties(void **state)
{
    (void)state;
    long dec = 0, n = 0;
    for (int i = 0; i < 100000; i++) {
        int q = (int)(next_u64() % 23);
        uint64_t p5 = 1;
        for (int k = 0; k < q; k++)
            p5 *= 5;
        /* o * 5^q in [2^53, 2^54), o odd */
        uint64_t lo = ((UINT64_C(1) << 53) + p5 - 1) / p5, hi = ((UINT64_C(1) << 54) - 1) / p5;
        if (hi < lo)
            continue;
        uint64_t o = (lo + next_u64() % (hi - lo + 1)) | 1;
        if (o > hi || !((o * p5) & 1))
            continue;
        int shift = q ? 0 : (int)(next_u64() % 10); /* q = 0: any tie below 2^64 */
        uint64_t m = o << shift;
        for (int d = -1; d <= 1; d++, n++)
            dec += check(m + (uint64_t)(int64_t)d, q);
    }
    printf("ties: %ld of %ld decided\n", dec, n);
    assert_true(dec > n * 9 / 10);
}

/* On a rounding boundary with q < 0: m = r 5^n, q = -n, so that m 10^q =
 * r 2^-n exactly (the product P falls just below it): r of 53 bits (an
 * exact double), of 54 bits and odd (a tie, to even), or anything; and one
 * unit either side. All decided (exact integer comparison), all right. */
static void test_boundaries(void **state)
{
    (void)state;
    long n = 0, dec = 0;
    for (int i = 0; i < 200000; i++) {
        int e = 1 + (int)(next_u64() % 27);
        uint64_t p5 = 1;
        for (int k = 0; k < e; k++)
            p5 *= 5;
        uint64_t lim = UINT64_MAX / p5, r;
        int kind = (int)(next_u64() % 3);
        if (kind == 0)
            r = (UINT64_C(1) << 52) | (next_u64() >> 12);
        else if (kind == 1)
            r = (UINT64_C(1) << 53) | (next_u64() >> 11) | 1;
        else
            r = 1 + next_u64() % lim;
        if (r > lim) {
            r = 1 + next_u64() % lim;
            kind = 2;
        }
        uint64_t m = r * p5;
        for (int d = -1; d <= 1; d++, n++)
            dec += check(m + (uint64_t)(int64_t)d, -e);
    }
    printf("boundaries: %ld of %ld decided\n", dec, n);
    assert_true(dec > n * 999 / 1000);
}

/* Near halfway: the 19-digit truncation of the exact midpoint of two
 * doubles (and its neighbours): the product's error can matter here, so
 * these are where the fast path must decline or be right. */
static void test_near_halfway(void **state)
{
    (void)state;
    for (int i = 0; i < 100000; i++) {
        uint64_t bits = (next_u64() % (UINT64_C(2045) << 52)) + (UINT64_C(1) << 52);
        double y;
        memcpy(&y, &bits, sizeof y);
        long double mid = ((long double)y + (long double)nextafter(y, HUGE_VAL)) / 2;
        char b[80];
        snprintf(b, sizeof b, "%.18Le", mid); /* d.dddddddddddddddddde+XX: 19 digits */
        uint64_t m = 0;
        int k = 0;
        for (const char *p = b; *p && *p != 'e'; p++)
            if (*p >= '0' && *p <= '9')
                m = m * 10 + (uint64_t)(*p - '0'), k++;
        long q = strtol(strchr(b, 'e') + 1, NULL, 10) - (k - 1);
        for (int d = -1; d <= 1; d++)
            check(m + (uint64_t)(int64_t)d, q);
    }
}

/* More than 19 digits: the value lies in [m, m + 1] * 10^q; when both ends
 * round alike the range form decides it, and must equal strtod on the
 * whole string. */
static void test_many_digits(void **state)
{
    (void)state;
    long n = 0, dec = 0;
    for (int i = 0; i < 50000; i++) {
        char b[900];
        int extra = 1 + (int)(next_u64() % 700), k;
        uint64_t m = rand_digits(19);
        long q = (long)(next_u64() % 560) - 290;
        k = snprintf(b, sizeof b, "%llu", (unsigned long long)m);
        int zeros = (next_u64() & 3) == 0; /* trailing zeros: the exact value is m 10^q */
        for (int j = 0; j < extra; j++)
            b[k++] = zeros ? '0' : (char)('0' + next_u64() % 10);
        snprintf(b + k, sizeof b - (size_t)k, "e%ld", q - extra);
        double got, want = strtod(b, NULL);
        if (q < CF_PEL_QMIN || q > CF_PEL_QMAX)
            continue;
        n++;
        if (cf_pel_decide_range(m, q, &got)) {
            dec++;
            if (memcmp(&got, &want, sizeof got))
                fail_msg("%.40s...: fast path %a, strtod %a", b, got, want);
        }
    }
    printf("many digits: %ld of %ld decided\n", dec, n);
    assert_true(dec > n * 9 / 10);
}

/* The table: exact for 0 <= q <= 55 (5^q in unsigned 128-bit arithmetic);
 * for q = -1..-27, T = floor(2^-s / 5^n), i.e. T 5^n <= 2^-s < (T + 1) 5^n
 * (192-bit products); normalised everywhere. */
static void test_table(void **state)
{
    (void)state;
    unsigned __int128 p = 1;
    for (long q = 0; q <= 55; q++, p *= 5) {
        uint64_t hi, lo;
        int s;
        cf_pel_pow5(q, &hi, &lo, &s);
        unsigned __int128 t = ((unsigned __int128)hi << 64) | lo;
        assert_true(s <= 0);
        assert_true((t >> -s) == p && (p << -s) == t);
    }
    uint64_t p5 = 1;
    for (long n = 1; n <= 27; n++) {
        p5 *= 5;
        uint64_t hi, lo;
        int s;
        cf_pel_pow5(-n, &hi, &lo, &s);
        /* T * 5^n as three words */
        unsigned __int128 a = (unsigned __int128)lo * p5, b = (unsigned __int128)hi * p5;
        unsigned __int128 mid = b + (uint64_t)(a >> 64);
        uint64_t w[3] = {(uint64_t)a, (uint64_t)mid, (uint64_t)(mid >> 64)};
        int e = -s; /* 2^e: must lie in [T 5^n, T 5^n + 5^n) */
        assert_true(e >= 128 && e < 192);
        /* 2^e - T 5^n, as three words, must be in [0, 5^n) */
        uint64_t t[3] = {0, 0, 0};
        t[e / 64] = UINT64_C(1) << (e % 64);
        uint64_t brw = 0, d[3];
        for (int i = 0; i < 3; i++) {
            unsigned __int128 x = (unsigned __int128)t[i] - w[i] - brw;
            d[i] = (uint64_t)x;
            brw = (uint64_t)(x >> 64) ? 1 : 0;
        }
        assert_int_equal(brw, 0);
        assert_true(d[2] == 0 && d[1] == 0 && d[0] < p5);
    }
    for (long q = CF_PEL_QMIN; q <= CF_PEL_QMAX; q++) {
        uint64_t hi, lo;
        int s;
        cf_pel_pow5(q, &hi, &lo, &s);
        assert_true(hi >> 63);
    }
}

#endif

/* ------------------------------------------ the same through the reader */

static char msg[1024];

static void rand_token(char *b, size_t n)
{
    int mode = (int)(next_u64() % 6);
    uint64_t u = next_u64();
    switch (mode) {
    case 0:
        snprintf(b, n, "%llue%d", (unsigned long long)rand_digits(1 + (int)(u % 19)),
                 (int)(next_u64() % 640) - 330);
        break;
    case 1: { /* any double, %.17g, or its 19-digit neighbour */
        double x;
        uint64_t bits = next_u64();
        memcpy(&x, &bits, sizeof x);
        if (!isfinite(x))
            x = 0.1;
        snprintf(b, n, (u & 1) ? "%.17g" : "%.18e", x);
        break;
    }
    case 2: { /* a midpoint, 18-21 digits */
        double y = ldexp(1.0 + (double)(next_u64() >> 12) * 0x1p-52, (int)(u % 2000) - 1000);
        long double mid = ((long double)y + (long double)nextafter(y, HUGE_VAL)) / 2;
        snprintf(b, n, "%.*Le", 17 + (int)(next_u64() % 4), mid);
        break;
    }
    case 3: /* subnormal */
        snprintf(b, n, "%.*e", 1 + (int)(u % 20), ldexp((double)(next_u64() >> 12), -1074));
        break;
    case 4: { /* 20-200 digits, a point inside */
        int nd = 20 + (int)(u % 180), k = 0, dot = (int)(next_u64() % (unsigned)nd);
        b[k++] = (char)('1' + next_u64() % 9);
        for (int i = 1; i < nd && k < (int)n - 12; i++) {
            if (i == dot)
                b[k++] = '.';
            b[k++] = (char)('0' + next_u64() % 10);
        }
        snprintf(b + k, n - (size_t)k, "e%d", (int)(next_u64() % 500) - 250);
        break;
    }
    default: /* exact ties below 2^64 */
        snprintf(b, n, "%llu",
                 (unsigned long long)((((UINT64_C(1) << 52) | (next_u64() >> 12)) << 10) + 512));
        break;
    }
}

static void test_reader_classes(void **state)
{
    (void)state;
    const long n = 150000;
    char(*tok)[256] = malloc(sizeof *tok * (size_t)n);
    assert_non_null(tok);
    char path[] = "/tmp/cf_test_points_el_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "wb");
    assert_non_null(f);
    for (long i = 0; i < n; i++) {
        do
            rand_token(tok[i], sizeof tok[i]);
        while (!isfinite(strtod(tok[i], NULL)));
        fprintf(f, "%s%s", tok[i], i % 3 == 2 ? "\n" : " ");
    }
    assert_int_equal(fclose(f), 0);
    cf_points_t *r;
    double v[3 * 512];
    long k = 0, got;
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    while ((got = cf_points_read(r, v, 512, msg, sizeof msg)) > 0)
        for (long j = 0; j < 3 * got; j++, k++) {
            double want = strtod(tok[k], NULL);
            if (memcmp(&v[j], &want, sizeof want))
                fail_msg("'%s': reader %a, strtod %a", tok[k], v[j], want);
        }
    assert_int_equal(got, 0);
    assert_int_equal(k, n);
    cf_points_close(r);
    remove(path);
    free(tok);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
#if CF_PEL_HAVE /* without 128-bit integers the fast path always declines */
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_short),
        cmocka_unit_test(test_long_mantissa),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_ties),
        cmocka_unit_test(test_near_halfway),
        cmocka_unit_test(test_many_digits),
        cmocka_unit_test(test_boundaries),
#endif
        cmocka_unit_test(test_reader_classes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
