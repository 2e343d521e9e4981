/* SPDX-License-Identifier: MIT */
/* test_fmt.c: cf_fmt17 against glibc's snprintf "%.17g", byte for byte:
 * random doubles over every decimal scale of the fast range and past it,
 * exact ties (dyadic values with an 18th digit 5), powers of ten and their
 * neighbours, carries (9.99...), and the fallbacks. */
#include "cf_fmt.h"
#include "cf_test.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static uint64_t rng = 0x9E3779B97F4A7C15ULL;
static uint64_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static void same(double x)
{
    char a[64], b[64];
    const int na = cf_fmt17(x, a, sizeof a), nb = snprintf(b, sizeof b, "%.17g", x);
    if (na != nb || strcmp(a, b) != 0)
        fail_msg("%a: cf_fmt17 '%s' (%d), snprintf '%s' (%d)", x, a, na, b, nb);
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
    for (int e = -30; e <= 30; e++) { /* powers of ten and their neighbours */
        const double p = pow(10.0, e);
        same(p);
        same(nextafter(p, 0.0));
        same(nextafter(p, INFINITY));
        same(-p);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random),
        cmocka_unit_test(test_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
