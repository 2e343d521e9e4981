/* SPDX-License-Identifier: MIT */
/* test_ptsout.c: per-point CSV and binary PLY read back by the point
 * reader (cf_points: a separate parser) and byte by byte: every point's
 * coordinates bit for bit, the header's count patched, the colour and the
 * in/out column as the scale and the tolerance say, whether the colours
 * are given at open or only before close (written over the finished PLY). */
#include "cf_err.h"
#include "cf_points.h"
#include "cf_ptsout.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void rgb(double dev, void *ctx, unsigned char c[3])
{
    (void)ctx;
    c[0] = dev > 0 ? 255 : 0;
    c[1] = 7;
    c[2] = dev > 0 ? 0 : 255;
}

static void csv_and_ply(int late)
{
    char csv[256], ply[256], msg[256];
    const char *tmp = getenv("CF_TEST_TMP");
    snprintf(csv, sizeof csv, "%s/p%ld.csv", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    snprintf(ply, sizeof ply, "%s/p%ld.ply", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    enum { N = 1000 };
    cf_ptsout_t o;
    assert_int_equal(
        cf_ptsout_open(&o, csv, ply, 0.05, 1, late ? NULL : rgb, NULL, msg, sizeof msg), CF_OK);
    assert_int_equal(access(csv, F_OK), -1); /* nothing visible before close */
    for (int i = 0; i < N; i++) {
        cf_ptsout_pt_t p = {i * 0.1, 1.0 / (i + 1),      -i * 1e-7,         i / 1000.0,
                            0.5,     (i % 7 - 3) * 0.02, i % 2 ? 1.0 : 0.25};
        cf_ptsout_add(&o, &p);
    }
    if (late)
        cf_ptsout_set_rgb(&o, rgb, NULL);
    assert_int_equal(cf_ptsout_close(&o, msg, sizeof msg), CF_OK);
    /* The CSV through the header-aware reader: u v x y z by name. */
    cf_points_t *r;
    double row[5];
    assert_int_equal(cf_points_open(&r, csv, 5, msg, sizeof msg), CF_OK);
    for (int i = 0; i < N; i++) {
        assert_int_equal(cf_points_read(r, row, 1, msg, sizeof msg), 1);
        assert_true(row[0] == i / 1000.0 && row[1] == 0.5);
        assert_true(row[2] == i * 0.1 && row[3] == 1.0 / (i + 1) && row[4] == -i * 1e-7);
    }
    assert_int_equal(cf_points_read(r, row, 1, msg, sizeof msg), 0);
    cf_points_close(r);
    /* In/out and weight columns as text. */
    FILE *f = fopen(csv, "r");
    char line[512];
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "x,y,z,u,v,deviation,in_tolerance,weight\n");
    for (int i = 0; i < N; i++) {
        assert_non_null(fgets(line, sizeof line, f));
        char *c = strrchr(line, ',');
        int in = c[-1] - '0';
        assert_int_equal(in, abs(i % 7 - 3) * 0.02 <= 0.05);
        assert_string_equal(c + 1, i % 2 ? "1\n" : "0.25\n");
    }
    fclose(f);
    /* The PLY: x y z by the PLY reader, colours from the bytes. */
    assert_int_equal(cf_points_open(&r, ply, 3, msg, sizeof msg), CF_OK);
    for (int i = 0; i < N; i++) {
        assert_int_equal(cf_points_read(r, row, 1, msg, sizeof msg), 1);
        assert_true(row[0] == i * 0.1 && row[1] == 1.0 / (i + 1) && row[2] == -i * 1e-7);
    }
    assert_int_equal(cf_points_read(r, row, 1, msg, sizeof msg), 0);
    cf_points_close(r);
    f = fopen(ply, "rb");
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    char *end = strstr(buf, "end_header\n");
    assert_non_null(end);
    assert_non_null(strstr(buf, "element vertex 000000000001000\n"));
    const unsigned char *v = (const unsigned char *)end + 11;
    assert_int_equal((size_t)(v - (const unsigned char *)buf) + (size_t)N * 35, n);
    for (int i = 0; i < N; i++) {
        const unsigned char *c = v + 35 * i + 24;
        int pos = (i % 7 - 3) > 0;
        assert_int_equal(c[0], pos ? 255 : 0);
        assert_int_equal(c[1], 7);
        assert_int_equal(c[2], pos ? 0 : 255);
    }
    remove(csv);
    remove(ply);
}

static void test_csv_and_ply(void **state)
{
    (void)state;
    csv_and_ply(0);
}

static void test_late_colours(void **state)
{
    (void)state;
    csv_and_ply(1);
}

/* A PLY whose colours never came: refused at close, nothing left behind. */
static void test_no_colours(void **state)
{
    (void)state;
    char ply[256], msg[256];
    const char *tmp = getenv("CF_TEST_TMP");
    snprintf(ply, sizeof ply, "%s/q%ld.ply", tmp && *tmp ? tmp : "/tmp", (long)getpid());
    cf_ptsout_t o;
    assert_int_equal(cf_ptsout_open(&o, NULL, ply, 0.05, 0, NULL, NULL, msg, sizeof msg), CF_OK);
    cf_ptsout_pt_t p = {1, 2, 3, 0, 0, 0.01, 1};
    cf_ptsout_add(&o, &p);
    assert_int_equal(cf_ptsout_close(&o, msg, sizeof msg), CF_EARG);
    assert_int_equal(access(ply, F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_csv_and_ply),
                                       cmocka_unit_test(test_late_colours),
                                       cmocka_unit_test(test_no_colours)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
