/* SPDX-License-Identifier: MIT */
/* test_points_mt.c: the reader's parse thread (cf_points_thread,
 * lib/cf_points_mt.c) against the same file read on one thread: two
 * readers, one with the thread, read with the same random batch sizes
 * (0, 1, across the ring's 8,192-row blocks, larger than the ring), and
 * every call must give the same count, the same bits, the same line and
 * the same error text; rewinds in the middle, reads after the end and after
 * an error. Files: ASCII (3 and 5 columns, CRLF, comments, blank lines), a
 * CSV header, PLY ascii, bad lines on and around block boundaries, empty,
 * and the formats the thread leaves alone (raw float64, binary PLY). */
#include "cf_err.h"
#include "cf_points.h"
#include "cf_test.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static uint64_t rng = 0x2545F4914F6CDD1DULL;
static char dir[] = "/tmp/cf_test_points_mt_XXXXXX";

static uint64_t next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static void file_path(char *b, size_t n, const char *name)
{
    snprintf(b, n, "%s/%s", dir, name);
}

/* A batch size: mostly large, sometimes 0, 1 or just around a block. */
static long batch(void)
{
    switch (next_u64() % 6) {
    case 0: return (long)(next_u64() % 3);
    case 1: return 8191 + (long)(next_u64() % 3);
    case 2: return 40000 + (long)(next_u64() % 40000);
    default: return 1 + (long)(next_u64() % 5000);
    }
}

/* Read both to the end (or n_calls calls), comparing every call. */
static void compare(cf_points_t *a, cf_points_t *b, int cols, long n_calls, long *total)
{
    static double va[5 * 80000], vb[5 * 80000];
    char ma[1024], mb[1024];
    for (long c = 0; c < n_calls; c++) {
        long max = batch();
        ma[0] = mb[0] = '\0';
        long ka = cf_points_read(a, va, max, ma, sizeof ma);
        long kb = cf_points_read(b, vb, max, mb, sizeof mb);
        assert_int_equal(ka, kb);
        assert_string_equal(ma, mb);
        assert_int_equal(cf_points_line(a), cf_points_line(b));
        if (ka > 0) {
            assert_memory_equal(va, vb, (size_t)ka * (size_t)cols * sizeof(double));
            *total += ka;
        }
        if (ka < 0 || (ka == 0 && max > 0)) { /* the end, or an error: the next calls repeat it */
            for (int i = 0; i < 3; i++) {     /* 0 rows too: an error still comes back */
                long ra = cf_points_read(a, va, i, ma, sizeof ma);
                long rb = cf_points_read(b, vb, i, mb, sizeof mb);
                assert_int_equal(ra, ka);
                assert_int_equal(rb, kb);
                assert_string_equal(ma, mb);
            }
            return;
        }
    }
}

/* The file read both ways, to the end, then again after a rewind in the
 * middle of a pass. Returns the points of the first pass. */
static long check_file(const char *path, int want)
{
    cf_points_t *a, *b;
    char m1[1024], m2[1024];
    int ra = cf_points_open(&a, path, want, m1, sizeof m1);
    int rb = cf_points_open(&b, path, want, m2, sizeof m2);
    assert_int_equal(ra, rb);
    if (ra) {
        assert_string_equal(m1, m2);
        return -1;
    }
    assert_int_equal(cf_points_thread(b), CF_OK);
    int cols = cf_points_cols(a);
    assert_int_equal(cols, cf_points_cols(b));
    long total = 0, again = 0;
    compare(a, b, cols, 1000000, &total);
    for (int pass = 0; pass < 3; pass++) {
        ra = cf_points_rewind(a);
        assert_int_equal(ra, cf_points_rewind(b));
        if (ra)
            break;
        again = 0;
        compare(a, b, cols, pass == 2 ? 1000000 : 1 + (long)(next_u64() % 6), &again);
    }
    cf_points_close(a);
    cf_points_close(b); /* stops the thread, wherever it is */
    return total;
}

static void write_ascii(const char *path, long lines, int cols, long bad_at, int style)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (style == 2)
        fprintf(f, "# a comment\nu,v,x,y,z\n");
    for (long i = 1; i <= lines; i++) {
        if (i == bad_at) {
            fprintf(f, "1 2 oops\n");
            continue;
        }
        if (style == 1 && i % 97 == 0)
            fprintf(f, "\n# comment %ld\r\n", i);
        for (int c = 0; c < cols; c++) {
            double x = (double)(int64_t)next_u64() * 0x1p-60;
            fprintf(f, style == 2 ? "%s%.17g" : "%s%.9g", c ? (style == 2 ? "," : " ") : "", x);
        }
        fprintf(f, style == 1 ? "\r\n" : "\n");
    }
    assert_int_equal(fclose(f), 0);
}

static void test_ascii(void **state)
{
    (void)state;
    char path[600];
    file_path(path, sizeof path, "a.xyz");
    write_ascii(path, 100000, 3, 0, 0);
    assert_int_equal(check_file(path, 3), 100000);
    write_ascii(path, 50000, 5, 0, 1);
    assert_int_equal(check_file(path, 0), 50000);
    file_path(path, sizeof path, "h.csv");
    write_ascii(path, 30000, 5, 0, 2);
    assert_int_equal(check_file(path, 0), 30000);
}

/* A bad line at, before and after the block boundaries, and at the start. */
static void test_errors(void **state)
{
    (void)state;
    static const long at[] = {1, 2, 8192, 8193, 8194, 16384, 16385, 32769, 40000};
    char path[600];
    file_path(path, sizeof path, "bad.xyz");
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        write_ascii(path, 45000, 3, at[i], 0);
        check_file(path, 3);
    }
    /* a file ending without a newline, and one whose last line is short */
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (int i = 0; i < 9000; i++)
        fprintf(f, "%d 2 3\n", i);
    fprintf(f, "1 2");
    assert_int_equal(fclose(f), 0);
    check_file(path, 3);
}

static void test_empty_and_comments(void **state)
{
    (void)state;
    char path[600];
    file_path(path, sizeof path, "e.xyz");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fclose(f), 0);
    assert_int_equal(check_file(path, 0), 0);
    assert_int_equal(check_file(path, 3), 0);
    f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "# only\n\n# comments\n");
    assert_int_equal(fclose(f), 0);
    assert_int_equal(check_file(path, 3), 0);
}

static void test_ply(void **state)
{
    (void)state;
    char path[600];
    file_path(path, sizeof path, "p.ply");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex 20000\nproperty float x\nproperty float "
               "y\nproperty float z\nproperty uchar red\nend_header\n");
    for (int i = 0; i < 20000; i++)
        fprintf(f, "%d.5 %d %g 7\n", i, -i, i * 0.25);
    assert_int_equal(fclose(f), 0);
    assert_int_equal(check_file(path, 3), 20000);
    /* binary PLY: the thread stays off, the readings the same */
    f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty double "
               "x\nproperty double y\nproperty double z\nend_header\n");
    for (int i = 0; i < 3000; i++) {
        double d = i * 0.5;
        fwrite(&d, sizeof d, 1, f);
    }
    assert_int_equal(fclose(f), 0);
    assert_int_equal(check_file(path, 3), 1000);
    file_path(path, sizeof path, "r.uvxyz.bin");
    f = fopen(path, "wb");
    assert_non_null(f);
    for (int i = 0; i < 50000; i++) {
        double d = i * 0.125;
        fwrite(&d, sizeof d, 1, f);
    }
    assert_int_equal(fclose(f), 0);
    assert_int_equal(check_file(path, 5), 10000);
}

/* The thread is asked for before the first read (or after a rewind). */
static void test_only_at_the_start(void **state)
{
    (void)state;
    char path[600], m[256];
    double v[3];
    file_path(path, sizeof path, "s.xyz");
    write_ascii(path, 10, 3, 0, 0);
    cf_points_t *r;
    assert_int_equal(cf_points_open(&r, path, 3, m, sizeof m), CF_OK);
    assert_int_equal(cf_points_read(r, v, 1, m, sizeof m), 1);
    assert_int_equal(cf_points_thread(r), CF_EARG);
    assert_int_equal(cf_points_rewind(r), CF_OK);
    assert_int_equal(cf_points_thread(r), CF_OK);
    assert_int_equal(cf_points_thread(r), CF_OK); /* on already */
    long n = 0, k;
    while ((k = cf_points_read(r, v, 1, m, sizeof m)) > 0)
        n += k;
    assert_int_equal(k, 0);
    assert_int_equal(n, 10);
    assert_int_equal(cf_points_line(r), 10);
    cf_points_close(r);
    assert_int_equal(cf_points_thread(NULL), CF_EARG);
}

/* A rewind before any read keeps the thread's work (cf_points_rewind: the
 * fit starts the thread at the open and rewinds at its first pass): the
 * same points, lines and errors as a reader on one thread, also for a
 * file whose first line is bad, and after the thread has parsed ahead. */
static void test_rewind_untouched(void **state)
{
    (void)state;
    static const long at[] = {0, 1, 5000, 44999};
    char path[600];
    file_path(path, sizeof path, "u.xyz");
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        write_ascii(path, 45000, 3, at[i], i % 2);
        cf_points_t *a, *b;
        char m[1024];
        assert_int_equal(cf_points_open(&a, path, 3, m, sizeof m), CF_OK);
        assert_int_equal(cf_points_open(&b, path, 3, m, sizeof m), CF_OK);
        assert_int_equal(cf_points_thread(b), CF_OK);
        if (i >= 2) { /* let it parse ahead first */
            struct timespec t = {0, 20000000L};
            nanosleep(&t, NULL);
        }
        assert_int_equal(cf_points_rewind(a), CF_OK);
        assert_int_equal(cf_points_rewind(b), CF_OK);
        assert_int_equal(cf_points_rewind(b), CF_OK); /* twice: still untouched */
        long ta = 0, tb = 0;
        compare(a, b, 3, 1000000, &ta);
        /* and a real rewind after reads starts again as before */
        assert_int_equal(cf_points_rewind(a), CF_OK);
        assert_int_equal(cf_points_rewind(b), CF_OK);
        compare(a, b, 3, 1000000, &tb);
        /* (with a bad line, how many come before the error depends on the
         * batches: compare checked each call against the one thread) */
        assert_true(at[i] == 0 ? ta == 45000 && tb == 45000 : ta < 45000 && tb < 45000);
        cf_points_close(a);
        cf_points_close(b);
    }
}

static int teardown(void **state)
{
    (void)state;
    char cmd[700];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) ? -1 : 0;
}

int main(void)
{
    if (!mkdtemp(dir))
        return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ascii),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_empty_and_comments),
        cmocka_unit_test(test_ply),
        cmocka_unit_test(test_only_at_the_start),
        cmocka_unit_test(test_rewind_untouched),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
