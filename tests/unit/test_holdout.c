/* SPDX-License-Identifier: MIT */
/* test_holdout.c: every K-th scan row held out of a point source
 * (cf_holdout) against a brute-force split: an in-memory source of rows of
 * equal y (some a single point, one across a batch boundary, y jittering
 * below CF_HOLDOUT_EPS inside a row), read in small batches through the
 * kept and the held-out filters: together they give every point exactly
 * once, in order, each on the side its row number says; a rewind starts
 * the row count again. */
#include "cf_holdout.h"
#include "cf_test.h"
#include <stdio.h>
#include <string.h>

#define NPTS 64

typedef struct mem {
    double p[NPTS][3];
    long n, at;
} mem_t;

static int m_rewind(void *ctx, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    ((mem_t *)ctx)->at = 0;
    return 0;
}

static long m_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    mem_t *m = ctx;
    long k = 0;
    for (; k < max && m->at < m->n; k++, m->at++)
        memcpy(rows + 3 * k, m->p[m->at], sizeof m->p[0]);
    return k;
}

static void m_where(void *ctx, long k, char *buf, size_t n)
{
    (void)ctx;
    snprintf(buf, n, "point %ld", k);
}

/* The rows: row r has len[r] points at y = r (plus jitter inside a row). */
static const int len[] = {5, 1, 7, 3, 1, 9, 4, 2, 6, 8, 1, 5, 3, 9};
#define NROWS ((int)(sizeof len / sizeof len[0]))

static void test_split(void **state)
{
    (void)state;
    static mem_t m;
    static long rowof[NPTS];
    memset(&m, 0, sizeof m);
    for (int r = 0; r < NROWS; r++)
        for (int i = 0; i < len[r]; i++) {
            assert_true(m.n < NPTS);
            m.p[m.n][0] = (double)m.n; /* identity of the point */
            m.p[m.n][1] = r + (i % 2 ? 0.5 * CF_HOLDOUT_EPS : 0.0);
            m.p[m.n][2] = -1.0;
            rowof[m.n++] = r;
        }
    cf_fitsrc_t in = {3, m.n, "mem", m_rewind, m_read, m_where, &m, NULL, NULL, 0};
    char msg[128];
    for (long k = 2; k <= 5; k++) {
        long seen[NPTS] = {0}, last[2] = {-1, -1};
        for (int side = 0; side < 2; side++) {
            cf_holdout_t h;
            cf_fitsrc_t s;
            cf_holdout_src(&s, &h, &in, k, side);
            for (int pass = 0; pass < 2; pass++) { /* the second after a rewind */
                assert_int_equal(s.rewind(s.ctx, msg, sizeof msg), 0);
                double buf[4 * 3];
                long got, count = 0;
                while ((got = s.read(s.ctx, buf, 4, msg, sizeof msg)) > 0) {
                    for (long i = 0; i < got; i++) {
                        long id = (long)buf[3 * i];
                        int held = rowof[id] % k == k - 1; /* brute force: the row's number */
                        assert_int_equal(held, side);
                        assert_true(id > last[side]); /* file order kept */
                        last[side] = id;
                        if (pass == 0)
                            seen[id]++;
                        count++;
                    }
                }
                assert_int_equal(got, 0);
                last[side] = -1;
                long want = 0;
                for (long i = 0; i < m.n; i++)
                    want += (rowof[i] % k == k - 1) == side;
                assert_int_equal(count, want);
            }
        }
        for (long i = 0; i < m.n; i++)
            assert_int_equal(seen[i], 1); /* every point on exactly one side */
    }
    assert_true(cf_holdout_is_held(4, 5) && !cf_holdout_is_held(5, 5) && !cf_holdout_is_held(0, 1));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_split),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
