/* SPDX-License-Identifier: MIT */
/* test_stats.c: the streaming deviation statistics against independent
 * results: moments by a two-pass computation in long double, percentiles by
 * sorting a copy (nearest rank), the tolerance count and histogram by direct
 * comparison with the bin edges, and the empty input. */

#include "cf_err.h"
#include "cf_stats.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned long long rng = 0x9E3779B97F4A7C15ULL;

static double unif(void) /* [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1p-53;
}

static double gauss(void)
{
    double u = unif(), v = unif();
    return sqrt(-2.0 * log(1.0 - u)) * cos(6.283185307179586 * v);
}

static cf_stats_t st; /* 66 KB: static rather than on the test's stack */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The nearest-rank percentile of a sorted array, rank ceil(p n / 100) by
 * integer arithmetic. */
static double ref_pct(const double *sorted, long n, int p)
{
    long k = (p * n + 99) / 100;
    if (k < 1)
        k = 1;
    return sorted[k - 1];
}

static void check_moments(const double *d, long n, double tol, double reltol)
{
    assert_int_equal(cf_stats_init(&st, tol), CF_OK);
    for (long i = 0; i < n; i++)
        assert_int_equal(cf_stats_add(&st, d[i]), CF_OK);
    long double s = 0, sq = 0;
    long imin = 0, imax = 0;
    for (long i = 0; i < n; i++) {
        s += d[i];
        sq += (long double)d[i] * d[i];
        if (d[i] < d[imin])
            imin = i;
        if (d[i] > d[imax])
            imax = i;
    }
    long double mean = s / n, ss = 0;
    for (long i = 0; i < n; i++)
        ss += (d[i] - mean) * (d[i] - mean);
    double rms = (double)sqrtl(sq / n), sd = (double)sqrtl(ss / (n - 1));
    assert_int_equal(st.n, n);
    assert_near(cf_stats_mean(&st), (double)mean, reltol * fabs((double)mean) + 1e-300);
    assert_near(cf_stats_rms(&st), rms, reltol * rms);
    assert_near(cf_stats_std(&st), sd, reltol * sd);
    assert_true(st.min == d[imin] && st.imin == imin);
    assert_true(st.max == d[imax] && st.imax == imax);
    assert_true(st.max_abs == fmax(-d[imin], d[imax]));
}

static void test_moments(void **state)
{
    (void)state;
    long n = 200000;
    double *d = malloc((size_t)n * sizeof *d);
    assert_non_null(d);
    for (long i = 0; i < n; i++)
        d[i] = 0.003 + 0.02 * gauss();
    check_moments(d, n, 0.05, 1e-13);
    /* A large offset and a small spread: naive sums of squares would lose
     * the std entirely; Welford's update keeps it. */
    for (long i = 0; i < n; i++)
        d[i] = 1000.0 + 1e-3 * gauss();
    check_moments(d, n, 0.05, 1e-9);
    /* Alternating huge and tiny values: the compensated mean. */
    for (long i = 0; i < n; i++)
        d[i] = (i & 1 ? -1e8 : 1e8) + 1e-4 * unif();
    check_moments(d, n, 1.0, 1e-6);
    free(d);
    /* One and two points. */
    double one[2] = {-0.25, 0.75};
    check_moments(one, 2, 0.1, 1e-15);
    assert_int_equal(cf_stats_init(&st, 0.1), CF_OK);
    cf_stats_add(&st, 0.5);
    assert_near(cf_stats_mean(&st), 0.5, 0);
    assert_near(cf_stats_rms(&st), 0.5, 0);
    assert_true(isnan(cf_stats_std(&st)));
}

/* Percentiles of d and |d| within the stated bound of the sorted truth. */
static void check_percentiles(double *d, long n)
{
    assert_int_equal(cf_stats_init(&st, 0.05), CF_OK);
    for (long i = 0; i < n; i++)
        cf_stats_add(&st, d[i]);
    double *a = malloc((size_t)n * sizeof *a);
    assert_non_null(a);
    for (long i = 0; i < n; i++)
        a[i] = fabs(d[i]);
    qsort(d, (size_t)n, sizeof *d, cmp_double);
    qsort(a, (size_t)n, sizeof *a, cmp_double);
    static const int pcts[] = {0, 1, 5, 10, 25, 50, 75, 90, 95, 99, 100};
    for (size_t i = 0; i < sizeof pcts / sizeof pcts[0]; i++) {
        int p = pcts[i];
        double want = ref_pct(d, n, p), got = cf_stats_percentile(&st, p);
        assert_near(got, want, CF_STATS_PCT_RELERR * fabs(want) + 1e-9);
        want = ref_pct(a, n, p);
        got = cf_stats_percentile_abs(&st, p);
        assert_near(got, want, CF_STATS_PCT_RELERR * fabs(want) + 1e-9);
    }
    /* The extremes are exact. */
    assert_true(cf_stats_percentile(&st, 0) == d[0]);
    assert_true(cf_stats_percentile(&st, 100) == d[n - 1]);
    assert_true(cf_stats_percentile_abs(&st, 100) == a[n - 1]);
    assert_true(isnan(cf_stats_percentile(&st, -1)));
    assert_true(isnan(cf_stats_percentile(&st, 100.5)));
    free(a);
}

static void test_percentiles(void **state)
{
    (void)state;
    long n = 100001;
    double *d = malloc((size_t)n * sizeof *d);
    assert_non_null(d);
    /* Gaussian, both signs. */
    for (long i = 0; i < n; i++)
        d[i] = 0.004 + 0.02 * gauss();
    check_percentiles(d, n);
    /* Scales over many decades (log-uniform magnitudes), random signs, and
     * some exact zeros and sub-1e-9 values. */
    for (long i = 0; i < n; i++) {
        double mag = pow(10.0, -11.0 + 16.0 * unif());
        d[i] = (i % 97 == 0) ? 0.0 : unif() < 0.3 ? -mag : mag;
    }
    check_percentiles(d, n);
    /* All positive and all negative, so some percentiles sit at one end. */
    for (long i = 0; i < n; i++)
        d[i] = 0.01 + 0.001 * unif();
    check_percentiles(d, n);
    for (long i = 0; i < n; i++)
        d[i] = -0.01 - 0.001 * unif();
    check_percentiles(d, n);
    /* Small counts, where the rank rule matters: 95 % of 20 is the 19th. */
    for (long m = 1; m <= 20; m++) {
        for (long i = 0; i < m; i++)
            d[i] = 0.001 * (double)(i + 1) * (i % 2 ? -1 : 1);
        check_percentiles(d, m);
    }
    for (long i = 0; i < 20; i++)
        d[i] = (double)(i + 1); /* 1 .. 20 */
    assert_int_equal(cf_stats_init(&st, 1.0), CF_OK);
    for (long i = 0; i < 20; i++)
        cf_stats_add(&st, d[i]);
    assert_near(cf_stats_percentile(&st, 95), 19.0, 19.0 * CF_STATS_PCT_RELERR);
    assert_near(cf_stats_percentile(&st, 50), 10.0, 10.0 * CF_STATS_PCT_RELERR);
    free(d);
}

/* Within-tolerance count and histogram against the edges computed here. */
static void test_tolerance_histogram(void **state)
{
    (void)state;
    const double tol = 0.05;
    long n = 50000;
    double *d = malloc((size_t)(n + 16) * sizeof *d);
    assert_non_null(d);
    for (long i = 0; i < n; i++)
        d[i] = 0.06 * gauss();
    /* Values on the edges: +/- tol are within, as are +/- 3 tol in the last bins. */
    double special[16] = {tol, -tol, 0.0,   -0.0,      3 * tol,    -3 * tol, -1e9,
                          1e9, 0.01, -0.01, 0.2 * tol, -0.2 * tol, 1e-12};
    int ns = 13;
    special[ns++] = nextafter(tol, 1); /* just outside the edges */
    special[ns++] = nextafter(-tol, -1);
    special[ns++] = nextafter(3 * tol, 1);
    for (int i = 0; i < ns; i++)
        d[n++] = special[i];
    assert_int_equal(cf_stats_init(&st, tol), CF_OK);
    long within = 0;
    for (long i = 0; i < n; i++) {
        assert_int_equal(cf_stats_add(&st, d[i]), CF_OK);
        within += fabs(d[i]) <= tol;
    }
    assert_int_equal(st.within, within);
    assert_near(cf_stats_within_pct(&st), 100.0 * (double)within / (double)n, 1e-12);
    /* Edges: 15 bins of 0.4 tol from -3 tol to 3 tol. */
    long long total = 0, mid = 0;
    for (int b = 0; b <= CF_STATS_HIST_BINS + 1; b++) {
        double lo, hi;
        long long c;
        cf_stats_hist_bin(&st, b, &lo, &hi, &c);
        if (b == 0)
            assert_true(isinf(lo) && lo < 0);
        else
            assert_near(lo, tol * (-3.0 + 0.4 * (b - 1)), 1e-15);
        if (b == CF_STATS_HIST_BINS + 1)
            assert_true(isinf(hi) && hi > 0);
        else
            assert_near(hi, tol * (-3.0 + 0.4 * b), 1e-15);
        long long want = 0;
        for (long i = 0; i < n; i++) {
            double x = d[i];
            int in = (hi <= 0)   ? (x >= lo && x < hi)
                     : (lo >= 0) ? (x > lo && x <= hi)
                                 : (x >= lo && x <= hi);
            want += in;
        }
        if (c != want)
            fail_msg("bin %d [%g, %g]: %lld points, want %lld", b, lo, hi, c, want);
        total += c;
        if (lo >= -tol - 1e-15 && hi <= tol + 1e-15)
            mid += c;
    }
    assert_int_equal(total, n);
    assert_int_equal(mid, within); /* +/- tol is a bin edge */
    /* The exact edge values themselves. */
    double lo, hi;
    long long c;
    cf_stats_hist_bin(&st, 1 + CF_STATS_HIST_HALF + 3, &lo, &hi, &c);
    assert_true(lo == tol);
    cf_stats_hist_bin(&st, 1 + CF_STATS_HIST_HALF - 3, &lo, &hi, &c);
    assert_true(hi == -tol);
    free(d);
}

static char *capture_json(void)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    cf_stats_json(&st, f);
    fclose(f);
    return buf;
}

static char *capture_print(void)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    cf_stats_print(&st, f);
    fclose(f);
    return buf;
}

/* Empty input: counts 0, the rest undefined (NAN, JSON null), no crash. */
static void test_empty(void **state)
{
    (void)state;
    assert_int_equal(cf_stats_init(&st, 0.02), CF_OK);
    assert_int_equal(st.n, 0);
    assert_true(isnan(cf_stats_mean(&st)));
    assert_true(isnan(cf_stats_rms(&st)));
    assert_true(isnan(cf_stats_std(&st)));
    assert_true(isnan(cf_stats_within_pct(&st)));
    assert_true(isnan(cf_stats_percentile(&st, 50)));
    assert_true(isnan(cf_stats_percentile_abs(&st, 95)));
    char *j = capture_json();
    assert_non_null(strstr(j, "\"points\": 0,"));
    assert_non_null(strstr(j, "\"rms\": null"));
    assert_non_null(strstr(j, "\"max\": null"));
    assert_non_null(strstr(j, "\"p95_abs\": null"));
    assert_non_null(strstr(j, "\"within_tol_pct\": null"));
    assert_non_null(strstr(j, "[{\"lo\": null, \"hi\": -0.0"));
    assert_non_null(strstr(j, "\"hi\": null, \"count\": 0}]}"));
    free(j);
    char *p = capture_print();
    assert_non_null(strstr(p, "no points"));
    free(p);
}

static void test_bad_input(void **state)
{
    (void)state;
    assert_int_equal(cf_stats_init(&st, 0.0), CF_EARG);
    assert_int_equal(cf_stats_init(&st, -1.0), CF_EARG);
    assert_int_equal(cf_stats_init(&st, NAN), CF_EARG);
    assert_int_equal(cf_stats_init(&st, INFINITY), CF_EARG);
    assert_int_equal(cf_stats_init(&st, 0.1), CF_OK);
    assert_int_equal(cf_stats_add(&st, NAN), CF_EARG);
    assert_int_equal(cf_stats_add(&st, -INFINITY), CF_EARG);
    assert_int_equal(st.n, 0);
    assert_int_equal(cf_stats_add(&st, 0.1), CF_OK);
    assert_int_equal(st.n, 1);
}

/* The JSON object: every field, histogram counts adding up to n; the table:
 * figures and the tolerance lines. */
static void test_reports(void **state)
{
    (void)state;
    assert_int_equal(cf_stats_init(&st, 0.05), CF_OK);
    for (int i = 0; i < 1000; i++)
        cf_stats_add(&st, 0.03 * gauss() - 0.005);
    cf_stats_add(&st, 0.5); /* the max, index 1000 */
    char *j = capture_json();
    static const char keys[] = "points tol rms mean std min max max_abs min_index max_index "
                               "max_abs_index within_tol within_tol_pct p5 p50 p95 p99 p5_abs "
                               "p50_abs p95_abs p99_abs pct_rel_err histogram";
    char key[32];
    int used;
    for (const char *k = keys; sscanf(k, "%31s%n", key, &used) == 1; k += used) {
        char want[64];
        snprintf(want, sizeof want, "\"%s\": ", key);
        if (!strstr(j, want))
            fail_msg("JSON lacks %s: %s", key, j);
    }
    assert_non_null(strstr(j, "\"points\": 1001,"));
    assert_non_null(strstr(j, "\"max\": 0.5,"));
    assert_non_null(strstr(j, "\"max_index\": 1000,"));
    assert_true(j[0] == '{' && j[strlen(j) - 2] == '}' && j[strlen(j) - 1] == '\n');
    long long sum = 0, c;
    int bins = 0;
    for (const char *p = strstr(j, "\"count\": "); p; p = strstr(p + 1, "\"count\": ")) {
        assert_int_equal(sscanf(p, "\"count\": %lld", &c), 1);
        sum += c;
        bins++;
    }
    assert_int_equal(bins, CF_STATS_HIST_BINS + 2);
    assert_int_equal(sum, 1001);
    free(j);
    char *p = capture_print();
    assert_non_null(strstr(p, "points            1001"));
    assert_non_null(strstr(p, "+0.5000  (point 1000)"));
    assert_non_null(strstr(p, "lower tolerance -0.0500"));
    assert_non_null(strstr(p, "upper tolerance +0.0500"));
    assert_non_null(strstr(p, "above +0.1500"));
    assert_true(strstr(p, "lower tolerance") < strstr(p, "-0.0100 .. +0.0100"));
    assert_true(strstr(p, "-0.0100 .. +0.0100") < strstr(p, "upper tolerance"));
    if (getenv("CF_TEST_VERBOSE"))
        fputs(p, stdout);
    free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_moments),
        cmocka_unit_test(test_percentiles),
        cmocka_unit_test(test_tolerance_histogram),
        cmocka_unit_test(test_empty),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_reports),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
