/* SPDX-License-Identifier: MIT */
/* test_fmt.c: cf_fmt17 against glibc's snprintf "%.17g", byte for byte,
 * and cf_fmt17_iges against that text with the IGES edits made here:
 * random doubles over every decimal scale of the fast range and past it,
 * exact ties (dyadic values with an 18th digit 5), powers of ten and their
 * neighbours, carries (9.99...), short digit strings (trailing zeros in
 * either group of eight), small integers, zeros, and the fallbacks. */
#include "cf_fmt.h"
#include "cf_test.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static uint64_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

/* snprintf's text as IGES writers want it: 'E', and a '.' in every real
 * (".0" before the exponent or at the end). */
static int iges_text(double x, char *b, size_t bl)
{
    char t[64];
    int n = snprintf(t, sizeof t, "%.17g", x), o = 0, dot = 0;
    for (int i = 0; i < n; i++)
        dot |= t[i] == '.';
    for (int i = 0; i < n; i++) {
        if (t[i] == 'e' && !dot)
            o += snprintf(b + o, bl - (size_t)o, ".0");
        b[o++] = t[i] == 'e' ? 'E' : t[i];
    }
    if (!dot && !strchr(t, 'e'))
        o += snprintf(b + o, bl - (size_t)o, ".0");
    b[o] = '\0';
    return o;
}

static void same(double x)
{
    char a[64], b[64];
    int na = cf_fmt17(x, a, sizeof a), nb = snprintf(b, sizeof b, "%.17g", x);
    if (na != nb || strcmp(a, b) != 0)
        fail_msg("%a: cf_fmt17 '%s' (%d), snprintf '%s' (%d)", x, a, na, b, nb);
    na = cf_fmt17_iges(x, a, sizeof a);
    nb = iges_text(x, b, sizeof b);
    if (na != nb || strcmp(a, b) != 0)
        fail_msg("%a: cf_fmt17_iges '%s' (%d), expected '%s' (%d)", x, a, na, b, nb);
    /* the smallest buffer allowed: the same text through the copy */
    char c[32];
    na = cf_fmt17(x, c, sizeof c);
    nb = snprintf(b, sizeof b, "%.17g", x);
    if (na != nb || strcmp(c, b) != 0)
        fail_msg("%a: cf_fmt17 in 32 bytes '%s', snprintf '%s'", x, c, b);
}

static void test_random(void **state)
{
    (void)state;
    for (long i = 0; i < 400000; i++) { /* random bits: every exponent */
        uint64_t u = next();
        double x;
        memcpy(&x, &u, sizeof x);
        same(x);
    }
    for (long i = 0; i < 400000; i++) { /* coordinates: 1e-20 .. 1e20 */
        double m = (double)(next() >> 11) / 9007199254740992.0;
        int e = (int)(next() % 41) - 20;
        same((next() & 1 ? -1 : 1) * m * pow(10.0, e));
    }
}

static void test_edges(void **state)
{
    (void)state;
    const double fixed[] = {0.0,
                            -0.0,
                            1.0,
                            -1.0,
                            0.1,
                            0.5,
                            1e-16,
                            1e17,
                            1e16,
                            1e-4,
                            1e-5,
                            123456.0,
                            1e15 + 0.25,
                            1234567890123456.75,
                            1234567890123456.25,
                            999999999999999.875,
                            0.30000000000000004,
                            9.9999999999999995e-5,
                            99999999999999.99,
                            1.7976931348623157e308,
                            4.9e-324,
                            INFINITY,
                            -INFINITY,
                            NAN,
                            2.2250738585072014e-308};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        same(fixed[i]);
    for (int e = -30; e <= 30; e++) { /* powers of ten and 16 neighbours each side */
        const double p = pow(10.0, e);
        double lo = p, hi = p;
        same(p);
        same(-p);
        for (int i = 0; i < 16; i++) {
            lo = nextafter(lo, 0.0);
            hi = nextafter(hi, INFINITY);
            same(lo);
            same(hi);
        }
    }
    for (int t = 1; t <= 60; t++) /* dyadic: long exact expansions */
        same(ldexp(1.0, -t) * 3.0);
    for (long j = 0; j < 100000; j++) { /* ties at the 18th digit: j + 1/4, 3/4 near 10^15 */
        const double base = 1e15 + (double)(next() % 1000000000000ULL);
        same(base + 0.25);
        same(base + 0.75);
        same((1e14 + (double)(next() % 100000000000ULL)) + 0.125);
    }
}

/* Fewer than 17 significant digits: trailing zeros in the last, the
 * middle and the first group of eight, integers with and without a '.',
 * and what a writer of machined parts meets (millimetres to 4 places). */
static void test_short(void **state)
{
    (void)state;
    for (int d = 1; d <= 17; d++) /* d significant digits at every scale */
        for (int e = -20; e <= 20; e++)
            for (int j = 0; j < 40; j++) {
                char t[64];
                snprintf(t, sizeof t, "%llue%d", (unsigned long long)(next() % 9 + 1), e);
                for (int i = 1; i < d; i++) /* append digits to the mantissa */
                    memmove(t + i + 1, t + i, strlen(t + i) + 1), t[i] = (char)('0' + next() % 10);
                same(strtod(t, NULL));
                same(-strtod(t, NULL));
            }
    for (long i = -100000; i <= 100000; i++) { /* integers, and 4-place decimals */
        same((double)i);
        same((double)i / 10000.0);
    }
    same(0.0);
    same(-0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random),
        cmocka_unit_test(test_edges),
        cmocka_unit_test(test_short),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
