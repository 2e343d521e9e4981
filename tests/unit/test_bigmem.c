/* SPDX-License-Identifier: MIT */
/* test_bigmem.c: cf_bigmem: small sizes from malloc, large ones a mapping
 * on a huge-page boundary advised for huge pages (where the kernel has
 * them: its VmFlags then carry "hg"), every byte writable, 64-byte aligned. */
#include "cf_bigmem.h"
#include "cf_test.h"
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* 1 if the kernel offers transparent huge pages at all. */
static int thp_offered(void)
{
    char line[128] = "";
    FILE *f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
    if (!f)
        return 0;
    int ok = fgets(line, sizeof line, f) && !strstr(line, "[never]");
    fclose(f);
    return ok;
}

/* 1 if the mapping holding p is advised for huge pages (smaps' VmFlags);
 * its length to *len (if len). */
static int advised_huge_len(const void *p, size_t *len)
{
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f)
        return -1;
    char line[512];
    int in = 0, hg = 0;
    uintptr_t a = (uintptr_t)p;
    while (fgets(line, sizeof line, f)) {
        unsigned long lo, hi;
        if (sscanf(line, "%lx-%lx ", &lo, &hi) == 2 && strchr(line, '-') < strchr(line, ' ')) {
            in = a >= lo && a < hi;
            if (in && len)
                *len = hi - lo;
        } else if (in && !strncmp(line, "VmFlags:", 8))
            hg = strstr(line, " hg") != NULL;
    }
    fclose(f);
    return hg;
}

static int advised_huge(const void *p)
{
    return advised_huge_len(p, NULL);
}

static void fill_check(unsigned char *p, size_t n)
{
    assert_int_equal((uintptr_t)p % 64, 0);
    for (size_t i = 0; i < n; i++)
        p[i] = (unsigned char)(i * 7);
    for (size_t i = 0; i < n; i += 4093)
        assert_int_equal(p[i], (unsigned char)(i * 7));
    assert_int_equal(p[n - 1], (unsigned char)((n - 1) * 7));
}

static void test_small(void **state)
{
    (void)state;
    size_t n = 1000;
    unsigned char *p = cf_bigmem_alloc(n);
    assert_non_null(p);
    assert_false(cf_bigmem_huge(p));
    fill_check(p, n);
    cf_bigmem_free(p);
    cf_bigmem_free(NULL);
}

static void test_large(void **state)
{
    (void)state;
    size_t n = CF_BIGMEM_MIN * 3 + 12345; /* not a multiple of any page */
    unsigned char *p = cf_bigmem_alloc(n);
    assert_non_null(p);
    fill_check(p, n);
#if defined(__linux__)
    assert_true(cf_bigmem_huge(p));
    assert_int_equal(((uintptr_t)p - 64) % CF_BIGMEM_MIN, 0); /* the mapping's start */
    if (thp_offered())
        assert_int_equal(advised_huge(p + n / 2), 1);
#endif
    cf_bigmem_free(p);
    /* Many in turn: nothing kept between them (the mapping goes back). */
    for (int k = 0; k < 64; k++) {
        unsigned char *q = cf_bigmem_alloc(n);
        assert_non_null(q);
        q[0] = q[n - 1] = 1;
        cf_bigmem_free(q);
    }
}

/* From half a huge page up: whole huge pages, no 4 KiB tail (each of its
 * pages would be a fault of its own). */
static void test_whole_pages(void **state)
{
    (void)state;
    const size_t H = (size_t)2 << 20;
    const size_t sizes[] = {CF_BIGMEM_MIN, H - 4096, H + 12345, 3 * H - 64};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        size_t n = sizes[k];
        unsigned char *p = cf_bigmem_alloc(n);
        assert_non_null(p);
        fill_check(p, n);
#if defined(__linux__)
        assert_true(cf_bigmem_huge(p));
        size_t len = 0;
        if (thp_offered()) {
            assert_int_equal(advised_huge_len(p, &len), 1);
            assert_int_equal(len % H, 0);
            assert_true(len >= n + 64);
            assert_true(len < n + 64 + H);
        }
#endif
        cf_bigmem_free(p);
    }
    unsigned char *q = cf_bigmem_alloc(CF_BIGMEM_MIN - 1); /* below: malloc's */
    assert_non_null(q);
    assert_false(cf_bigmem_huge(q));
    cf_bigmem_free(q);
}

static void test_too_large(void **state)
{
    (void)state;
    assert_null(cf_bigmem_alloc(SIZE_MAX - 10));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_small),
        cmocka_unit_test(test_large),
        cmocka_unit_test(test_whole_pages),
        cmocka_unit_test(test_too_large),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
