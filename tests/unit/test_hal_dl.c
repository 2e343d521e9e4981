/* SPDX-License-Identifier: MIT */
/* test_hal_dl.c: libraries loaded at first use (hal/hal_dl.h): a real one
 * (libm.so.6: every symbol resolved into its own typed slot and called,
 * against closed forms), one that does not exist and one that lacks a
 * symbol (the error names the soname, the package and the symbol; the
 * failure is sticky), no soname, and threads racing the first load. */
#include "cf_test.h"
#include "hal_dl.h"
#include <math.h>
#include <pthread.h>
#include <string.h>

/* Declared, defined nowhere: the symbol libm lacks. */
double hal_dl_test_absent(double x);

/* Four signatures, so a pointer filled into the wrong slot gives a wrong value. */
#define M_SYMS(X) X(hypot) X(pow) X(ldexp) X(fma)
HAL_DL_TABLE(mt, M_SYMS)
static hal_dl_t m_lib = HAL_DL_LIB(mt, "libm.so.6", "libc6", "the test");

#define RACE_SYMS(X) X(hypot) X(sqrt)
HAL_DL_TABLE(rt, RACE_SYMS)
static hal_dl_t race_lib = HAL_DL_LIB(rt, "libm.so.6", "libc6", "the race");

#define ABSENT_SYMS(X) X(hypot) X(hal_dl_test_absent)
HAL_DL_TABLE(at, ABSENT_SYMS)
static hal_dl_t absent_lib = HAL_DL_LIB(at, "libm.so.6", "libc6", "the absent test");

#define NOLIB_SYMS(X) X(hypot)
HAL_DL_TABLE(nt, NOLIB_SYMS)
static hal_dl_t nolib_lib =
    HAL_DL_LIB(nt, "libcellfit-no-such.so.7", "cellfit-no-such-pkg", "the missing test");

HAL_DL_TABLE(et, NOLIB_SYMS)
static hal_dl_t empty_lib = HAL_DL_LIB(et, "", "libnothing0", "a build without it");

static void test_real(void **state)
{
    (void)state;
    assert_null(mt.hypot); /* nothing before the first load */
    assert_int_equal(hal_dl_load(&m_lib), HAL_DL_OK);
    assert_string_equal(hal_dl_error(&m_lib), "");
    assert_non_null(m_lib.handle);
    assert_true(mt.hypot(3.0, 4.0) == 5.0);
    assert_true(mt.pow(2.0, 10.0) == 1024.0);
    assert_true(mt.ldexp(1.0, -3) == 0.125);
    assert_true(mt.fma(2.0, 3.0, 1.0) == 7.0);
    void *h = m_lib.handle;
    assert_int_equal(hal_dl_load(&m_lib), HAL_DL_OK); /* once: the same handle */
    assert_ptr_equal(m_lib.handle, h);
}

static void test_missing_library(void **state)
{
    (void)state;
    assert_int_equal(hal_dl_load(&nolib_lib), HAL_DL_ENOLIB);
    const char *e = hal_dl_error(&nolib_lib);
    assert_non_null(strstr(e, "libcellfit-no-such.so.7"));
    assert_non_null(strstr(e, "cellfit-no-such-pkg"));
    assert_non_null(strstr(e, "the missing test"));
    assert_null(nt.hypot);
    assert_null(nolib_lib.handle);
    assert_int_equal(hal_dl_load(&nolib_lib), HAL_DL_ENOLIB); /* sticky, same text */
    assert_string_equal(hal_dl_error(&nolib_lib), e);
}

static void test_missing_symbol(void **state)
{
    (void)state;
    assert_int_equal(hal_dl_load(&absent_lib), HAL_DL_ENOSYM);
    const char *e = hal_dl_error(&absent_lib);
    assert_non_null(strstr(e, "hal_dl_test_absent"));
    assert_non_null(strstr(e, "libm.so.6"));
    assert_non_null(strstr(e, "libc6"));
    assert_null(at.hypot); /* all or nothing: the table stays empty */
    assert_null(absent_lib.handle);
}

static void test_no_soname(void **state)
{
    (void)state;
    assert_int_equal(hal_dl_load(&empty_lib), HAL_DL_EARG);
    assert_non_null(strstr(hal_dl_error(&empty_lib), "a build without it"));
    assert_string_equal(hal_dl_strerror(HAL_DL_ENOLIB), "shared library not installed");
}

#define RACERS 8
static pthread_barrier_t gate;

static void *racer(void *arg)
{
    double *out = arg;
    pthread_barrier_wait(&gate);
    *out = hal_dl_load(&race_lib) ? -1.0 : rt.hypot(5.0, 12.0) + rt.sqrt(16.0);
    return NULL;
}

static void test_race(void **state)
{
    (void)state;
    pthread_t th[RACERS];
    double got[RACERS];
    assert_int_equal(pthread_barrier_init(&gate, NULL, RACERS), 0);
    for (int i = 0; i < RACERS; i++)
        assert_int_equal(pthread_create(&th[i], NULL, racer, &got[i]), 0);
    for (int i = 0; i < RACERS; i++)
        pthread_join(th[i], NULL);
    pthread_barrier_destroy(&gate);
    for (int i = 0; i < RACERS; i++)
        assert_true(got[i] == 17.0); /* 13 + 4: each saw the table filled */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real),           cmocka_unit_test(test_missing_library),
        cmocka_unit_test(test_missing_symbol), cmocka_unit_test(test_no_soname),
        cmocka_unit_test(test_race),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
