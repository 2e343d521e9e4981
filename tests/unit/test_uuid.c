/* SPDX-License-Identifier: MIT */
/* test_uuid.c: cf_uuid: the RFC 9562 form (version 4, variant 10), and no
 * repeat among many. */
#include "cf_err.h"
#include "cf_test.h"
#include "cf_uuid.h"
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

static int cmp(const void *a, const void *b)
{
    return strcmp(a, b);
}

static void test_form_and_uniqueness(void **state)
{
    (void)state;
    enum { N = 20000 };
    char(*u)[CF_UUID_LEN] = malloc(sizeof *u * N);
    assert_non_null(u);
    int ones[128] = {0};
    for (int i = 0; i < N; i++) {
        assert_int_equal(cf_uuid_new(u[i]), CF_OK);
        assert_true(cf_uuid_valid(u[i]));
        assert_int_equal(u[i][14], '4');           /* version */
        assert_non_null(strchr("89ab", u[i][19])); /* variant 10xx */
        for (int k = 0, bit = 0; k < 36; k++) {    /* random bits roughly balanced */
            if (k == 8 || k == 13 || k == 18 || k == 23 || k == 14 || k == 19)
                continue;
            int v = u[i][k] <= '9' ? u[i][k] - '0' : u[i][k] - 'a' + 10;
            for (int b = 0; b < 4; b++, bit++)
                ones[bit] += (v >> b) & 1;
        }
    }
    qsort(u, N, sizeof *u, cmp);
    for (int i = 1; i < N; i++)
        assert_true(strcmp(u[i - 1], u[i]) != 0);
    for (int b = 0; b < 120; b++) /* 122 random bits; mean N/2, sd ~71 */
        assert_true(ones[b] > N / 2 - 600 && ones[b] < N / 2 + 600);
    free(u);
}

static void test_valid(void **state)
{
    (void)state;
    assert_true(cf_uuid_valid("123e4567-e89b-12d3-a456-426614174000"));
    assert_false(cf_uuid_valid("123E4567-e89b-12d3-a456-426614174000")); /* lower case only */
    assert_false(cf_uuid_valid("123e4567e89b-12d3-a456-426614174000-"));
    assert_false(cf_uuid_valid("123e4567-e89b-12d3-a456-42661417400"));
    assert_false(cf_uuid_valid(NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_form_and_uniqueness),
        cmocka_unit_test(test_valid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
