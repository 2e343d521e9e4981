/* SPDX-License-Identifier: MIT */
/* test_checks.c: check points and zones (cf_checks) on a 10 x 10 grid of
 * points (i, j, 0) with deviation i + 10 j, whose answers are worked out by
 * hand: the nearest point, a zone's mean with points on its edge, a tie
 * (the first point wins), an empty zone (no value), a second pass after a
 * reset; and the file's format: comments, blank lines, every malformed
 * line refused with its line number. */
#include "cf_checks.h"
#include "cf_err.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void tmp_file(char *path, size_t n, const char *text)
{
    const char *tmp = getenv("CF_TEST_TMP");
    snprintf(path, n, "%s/checks%ld.txt", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void grid(cf_checks_t *cs)
{
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 10; i++) {
            const double Q[3] = {i, j, 0};
            cf_checks_add(cs, Q, i + 10.0 * j);
        }
}

static void test_values(void **state)
{
    (void)state;
    char path[256], msg[256];
    tmp_file(path, sizeof path,
             "# name x y z [radius]\n"
             "\n"
             "near\t3.2 4.1 0.5   # nearest: (3, 4)\n"
             "zone 5 5 0 1.0\n"
             "empty 2.5 2.5 0 0.5\n"
             "tie 7.5 2 0\n");
    cf_checks_t cs;
    assert_int_equal(cf_checks_read(&cs, path, msg, sizeof msg), CF_OK);
    assert_int_equal(cs.n, 4);
    assert_string_equal(cs.c[0].name, "near");
    assert_true(isnan(cs.c[0].radius));
    assert_true(cs.c[1].radius == 1.0 && cs.c[1].p[0] == 5 && cs.c[1].p[2] == 0);
    for (int pass = 0; pass < 2; pass++) {
        cf_checks_reset(&cs);
        grid(&cs);
        assert_true(cf_checks_value(&cs, 0) == 43); /* (3, 4) */
        /* (5,5) and its four neighbours at distance exactly 1 (within). */
        assert_int_equal(cs.c[1].points, 5);
        assert_true(cf_checks_value(&cs, 1) == (55 + 54 + 56 + 45 + 65) / 5.0);
        assert_int_equal(cs.c[2].points, 0); /* the nearest at 0.707 > 0.5 */
        assert_true(isnan(cf_checks_value(&cs, 2)));
        assert_true(cf_checks_value(&cs, 3) == 27); /* (7, 2) before (8, 2) */
    }
    FILE *f = tmpfile();
    assert_non_null(f);
    assert_int_equal(cf_checks_warn(&cs, f, "t"), 1);
    char line[256] = "";
    rewind(f);
    assert_non_null(fgets(line, sizeof line, f));
    assert_non_null(strstr(line, "check empty"));
    fclose(f);
    /* No points at all: not even a nearest point has a value. */
    cf_checks_reset(&cs);
    char why[256];
    assert_true(isnan(cf_checks_value(&cs, 0)));
    assert_non_null(cf_checks_missing(&cs, 0, why, sizeof why));
    assert_string_equal(why, "check near: no points measured: no value");
    assert_non_null(cf_checks_missing(&cs, 2, why, sizeof why));
    assert_string_equal(why, "check empty: no point within 0.5 mm of (2.5, 2.5, 0): no value");
    cf_checks_free(&cs);
    assert_int_equal(cs.n, 0);
    remove(path);
}

static void test_malformed(void **state)
{
    (void)state;
    static const char *bad[] = {
        "ok 1 2 3\nA 1 2\n",       /* no Z */
        "ok 1 2 3\nA 1 2 3 0\n",   /* radius 0 */
        "ok 1 2 3\nA 1 2 3 -1\n",  /* negative radius */
        "ok 1 2 3\nA 1 2 3 4 5\n", /* a sixth token */
        "ok 1 2 3\nA 1 x 3\n",     /* not a number */
        "ok 1 2 3\nA 1 2 3mm\n",   /* trailing text */
        "ok 1 2 3\nok 4 5 6\n",    /* a name twice */
        "ok 1 2 3\nA 1 2 inf\n",   /* not finite */
    };
    char path[256], msg[256], want[300];
    cf_checks_t cs;
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        tmp_file(path, sizeof path, bad[i]);
        assert_int_equal(cf_checks_read(&cs, path, msg, sizeof msg), CF_EPARSE);
        snprintf(want, sizeof want, "%s:2:", path);
        if (!strstr(msg, want))
            fail_msg("case %zu: '%s' lacks '%s'", i, msg, want);
        assert_null(cs.c);
    }
    char name[100];
    memset(name, 'n', 81);
    name[81] = '\0';
    char text[200];
    snprintf(text, sizeof text, "%s 1 2 3\n", name);
    tmp_file(path, sizeof path, text);
    assert_int_equal(cf_checks_read(&cs, path, msg, sizeof msg), CF_EPARSE);
    snprintf(text, sizeof text, "%.80s 1 2 3\n", name); /* 80: the most K2002 holds */
    tmp_file(path, sizeof path, text);
    assert_int_equal(cf_checks_read(&cs, path, msg, sizeof msg), CF_OK);
    assert_int_equal((int)strlen(cs.c[0].name), 80);
    cf_checks_free(&cs);
    remove(path);
    assert_int_equal(cf_checks_read(&cs, path, msg, sizeof msg), CF_EIO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_values),
                                       cmocka_unit_test(test_malformed)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
