/* SPDX-License-Identifier: MIT */
/* test_dfq.c: the Q-DAS file read back line by line with sscanf (not with
 * the writer's code): K0100 count, part fields, every characteristic's
 * number, name, limits, unit, and its value, date/time and part ident. */
#include "cf_dfq.h"
#include "cf_err.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The value of "KXXXX/c" (or "KXXXX" when c = 0) in the file, or NULL. */
static const char *field(const char *text, const char *key, int c, char *out, size_t n)
{
    char want[32];
    if (c)
        snprintf(want, sizeof want, "\n%s/%d ", key, c);
    else
        snprintf(want, sizeof want, "\n%s ", key);
    const char *p = strstr(text, want);
    if (!p)
        return NULL;
    p += strlen(want);
    size_t k = 0;
    while (p[k] && p[k] != '\n' && k + 1 < n) {
        out[k] = p[k];
        k++;
    }
    out[k] = '\0';
    return out;
}

static void test_write_and_read(void **state)
{
    (void)state;
    char path[256], msg[256], v[128];
    const char *tmp = getenv("CF_TEST_TMP");
    snprintf(path, sizeof path, "%s/t%ld.dfq", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    cf_dfq_char_t c[3] = {
        {"RMS deviation", 0, NAN, 0.05, "mm", 0.0123, 4},
        {"Max deviation\nline", 0, -0.1, 0.1, "mm", -0.0456, 4},
        {"Within tolerance", 100, 99, NAN, "%", NAN, 2},
    };
    cf_dfq_part_t part = {"PN-1234", "Panel", "SN\x01 77", 1764646200LL}; /* 2025-12-02 03:30 */
    assert_int_equal(cf_dfq_write(path, &part, c, 3, msg, sizeof msg), CF_OK);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char text[8192] = "\n";
    size_t got = fread(text + 1, 1, sizeof text - 2, f);
    fclose(f);
    text[got + 1] = '\0';
    assert_string_equal(field(text, "K0100", 0, v, sizeof v), "3");
    assert_string_equal(field(text, "K1001", 1, v, sizeof v), "PN-1234");
    assert_string_equal(field(text, "K1002", 1, v, sizeof v), "Panel");
    for (int k = 1; k <= 3; k++) {
        int num;
        assert_non_null(field(text, "K2001", k, v, sizeof v));
        assert_int_equal(sscanf(v, "%d", &num), 1);
        assert_int_equal(num, k);
        assert_non_null(field(text, "K0004", k, v, sizeof v));
        int d, mo, y, h, mi, s;
        assert_int_equal(sscanf(v, "%d.%d.%d/%d:%d:%d", &d, &mo, &y, &h, &mi, &s), 6);
        assert_true(d == 2 && mo == 12 && y == 2025 && h == 3 && mi == 30 && s == 0);
        assert_string_equal(field(text, "K0014", k, v, sizeof v), "SN_ 77");
    }
    assert_string_equal(field(text, "K2002", 2, v, sizeof v), "Max deviation_line");
    double x;
    assert_null(field(text, "K2110", 1, v, sizeof v)); /* open lower limit */
    assert_int_equal(sscanf(field(text, "K2111", 1, v, sizeof v), "%lf", &x), 1);
    assert_true(x == 0.05);
    assert_int_equal(sscanf(field(text, "K2110", 2, v, sizeof v), "%lf", &x), 1);
    assert_true(x == -0.1);
    assert_int_equal(sscanf(field(text, "K0001", 1, v, sizeof v), "%lf", &x), 1);
    assert_true(x == 0.0123);
    assert_int_equal(sscanf(field(text, "K0001", 2, v, sizeof v), "%lf", &x), 1);
    assert_true(x == -0.0456);
    assert_string_equal(field(text, "K2142", 3, v, sizeof v), "%");
    assert_string_equal(field(text, "K0002", 3, v, sizeof v), "255"); /* not measured */
    assert_null(field(text, "K0002", 1, v, sizeof v));
    /* Every line is "Kdddd[/c] value". */
    for (char *l = strtok(text + 1, "\n"); l; l = strtok(NULL, "\n")) {
        int kf;
        assert_true(l[0] == 'K');
        assert_int_equal(sscanf(l + 1, "%4d", &kf), 1);
    }
    remove(path);
    assert_int_equal(cf_dfq_write(path, &part, c, 0, msg, sizeof msg), CF_EARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_write_and_read)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
