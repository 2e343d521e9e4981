/* SPDX-License-Identifier: MIT */
/* test_fitsrc.c: the points source's cache (cf_fitsrc_points_cache)
 * against the same file read without it: two sources over two readers,
 * the same passes with the same batch sizes (1, 7, larger than the file;
 * the parse thread's blocks are 8,192 rows), and every call must give the
 * same count, the same bits, the same error text and the same "FILE:LINE".
 * That the cache serves is shown by emptying the file under it; a bound
 * one row short keeps the file read, a bad line keeps its error. A fitting
 * loop (pruning too, given parameters on two cores too) gives the same
 * control points, bit for bit, with and without the cache. */
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_fitsrc.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "ref_job.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define NPTS 20000L /* across two of the parse thread's blocks */

static char f3[600], f5[600], fbad[600];
static char msg[1024];

static void tmp_path(char *buf, size_t n, const char *name)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(buf, n, "%s/cf_fitsrc_%ld_%s", d && *d ? d : "/tmp", (long)getpid(), name);
}

/* NPTS points of cols values (a comment first, blank lines between):
 * lines are not point numbers. bad > 0: that point's line unreadable. */
static int write_points(const char *path, int cols, long bad)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "# test points\n\n");
    for (long i = 0; i < NPTS; i++) {
        if (i % 997 == 0)
            fputc('\n', f);
        if (i == bad) {
            fprintf(f, "1 2 zz\n");
            continue;
        }
        for (int c = 0; c < cols; c++)
            fprintf(f, "%s%.17g", c ? " " : "", sin(0.37 * (double)i + c) * (c + 1) + 1e-3 * i);
        fputc('\n', f);
    }
    return fclose(f);
}

/* One pass (rewind, reads of max until 0 or an error): its rows, the
 * count of every call, and the last call's value (0 or the error). */
typedef struct pass {
    double *rows;  /* NPTS x 5 */
    long *counts;  /* NPTS + 2 */
    long n, calls; /* rows, calls */
    long last;
    char msg[1024];
} pass_t;

static void pass_init(pass_t *p)
{
    memset(p, 0, sizeof *p);
    p->rows = malloc(sizeof(double) * 5 * NPTS);
    p->counts = malloc(sizeof(long) * (NPTS + 2));
    assert_non_null(p->rows);
    assert_non_null(p->counts);
}

static void pass_free(pass_t *p)
{
    free(p->rows);
    free(p->counts);
}

static void one_pass(const cf_fitsrc_t *s, long max, pass_t *p)
{
    double *buf = malloc(sizeof(double) * 5 * (size_t)max);
    assert_non_null(buf);
    p->n = p->calls = 0;
    p->msg[0] = '\0';
    assert_int_equal(s->rewind(s->ctx, p->msg, sizeof p->msg), 0);
    long got;
    while ((got = s->read(s->ctx, buf, max, p->msg, sizeof p->msg)) > 0) {
        assert_true(got <= max && p->n + got <= NPTS);
        memcpy(p->rows + p->n * s->cols, buf, sizeof(double) * (size_t)(got * s->cols));
        p->n += got;
        p->counts[p->calls++] = got;
    }
    p->counts[p->calls++] = got;
    p->last = got;
    free(buf);
}

/* The same calls, counts, bits and end (error text too). */
static void same_pass(const pass_t *a, const pass_t *b, int cols)
{
    assert_int_equal(a->last, b->last);
    assert_int_equal(a->n, b->n);
    assert_int_equal(a->calls, b->calls);
    assert_memory_equal(a->counts, b->counts, sizeof(long) * (size_t)a->calls);
    if (a->n)
        assert_memory_equal(a->rows, b->rows, sizeof(double) * (size_t)(a->n * cols));
    assert_string_equal(a->msg, b->msg);
}

static void same_where(const cf_fitsrc_t *a, const cf_fitsrc_t *b, long k)
{
    char wa[700], wb[700];
    a->where(a->ctx, k, wa, sizeof wa);
    b->where(b->ctx, k, wb, sizeof wb);
    assert_string_equal(wa, wb);
    assert_null(strstr(wa, ":-1"));
}

/* A source over a new reader of path (cache bytes, 0: none). */
typedef struct src {
    cf_points_t *r;
    cf_fitsrc_points_t pc;
    cf_fitsrc_t s;
} src_t;

static void src_open(src_t *s, const char *path, size_t cache)
{
    assert_int_equal(cf_points_open(&s->r, path, 0, msg, sizeof msg), 0);
    cf_fitsrc_points(&s->s, &s->pc, s->r, path);
    if (cache)
        cf_fitsrc_points_cache(&s->pc, cache);
}

static void src_close(src_t *s)
{
    cf_fitsrc_points_free(&s->pc);
    assert_null(s->pc.rows);
    cf_points_close(s->r);
}

/* (a) 3 passes alike at batches 1, 7 and more than the file; the rows in
 * memory after the first; then the file emptied: the cache still serves
 * (the uncached source sees no points). Where from the file. */
static void cached_like_file(const char *path, int cols)
{
    static const long maxes[] = {1, 7, 3 * NPTS};
    pass_t a, b;
    pass_init(&a), pass_init(&b);
    for (int m = 0; m < 3; m++) {
        assert_int_equal(write_points(path, cols, -1), 0);
        src_t u, c;
        src_open(&u, path, 0);
        src_open(&c, path, CF_FITSRC_CACHE_MAX);
        assert_int_equal(u.s.cols, cols);
        assert_int_equal(c.s.cols, cols);
        for (int k = 0; k < 3; k++) {
            one_pass(&u.s, maxes[m], &a);
            one_pass(&c.s, maxes[m], &b);
            assert_int_equal(a.n, NPTS);
            same_pass(&a, &b, cols);
            assert_non_null(c.pc.rows);
            assert_int_equal(c.pc.n, NPTS);
            assert_null(u.pc.rows);
        }
        same_where(&u.s, &c.s, 0);
        same_where(&u.s, &c.s, 4321);
        same_where(&u.s, &c.s, NPTS - 1);
        one_pass(&c.s, maxes[m], &b); /* from memory after where */
        same_pass(&a, &b, cols);
        if (cols == 5) {
            /* The halves read the file; the cache serves after them, and
             * where counts lines of the whole file again. */
            cf_fitsrc_t half[2];
            pass_t h;
            pass_init(&h);
            assert_int_equal(c.s.split(c.s.ctx, half, msg, sizeof msg), 0);
            one_pass(&half[0], maxes[m], &h);
            long n0 = h.n;
            assert_int_equal(h.last, 0);
            assert_true(n0 > 0 && n0 < NPTS);
            assert_memory_equal(h.rows, a.rows, sizeof(double) * 5 * (size_t)n0);
            c.s.join(c.s.ctx);
            one_pass(&half[1], maxes[m], &h);
            assert_int_equal(h.last, 0);
            assert_int_equal(n0 + h.n, NPTS);
            assert_memory_equal(h.rows, a.rows + 5 * n0, sizeof(double) * 5 * (size_t)h.n);
            pass_free(&h);
            one_pass(&c.s, maxes[m], &b);
            same_pass(&a, &b, cols);
            same_where(&u.s, &c.s, NPTS - 1);
        }
        FILE *f = fopen(path, "w"); /* empty now */
        assert_non_null(f);
        fclose(f);
        one_pass(&c.s, maxes[m], &b);
        same_pass(&a, &b, cols);
        one_pass(&u.s, maxes[m], &b);
        assert_int_equal(b.n, 0);
        src_close(&u);
        src_close(&c);
    }
    assert_int_equal(write_points(path, cols, -1), 0);
    pass_free(&a), pass_free(&b);
}

static void test_cached_3(void **state)
{
    (void)state;
    cached_like_file(f3, 3);
}

static void test_cached_5(void **state)
{
    (void)state;
    cached_like_file(f5, 5);
}

/* A pass rewound before its end is copied again from the start at the
 * next: the rows stay the file's. */
static void test_abandoned_pass(void **state)
{
    (void)state;
    for (int cols = 3; cols <= 5; cols += 2) {
        const char *path = cols == 3 ? f3 : f5;
        src_t u, c;
        src_open(&u, path, 0);
        src_open(&c, path, CF_FITSRC_CACHE_MAX);
        double buf[5 * 7];
        assert_int_equal(c.s.rewind(c.s.ctx, msg, sizeof msg), 0);
        for (int k = 0; k < 3; k++)
            assert_int_equal(c.s.read(c.s.ctx, buf, 7, msg, sizeof msg), 7);
        pass_t a, b;
        pass_init(&a), pass_init(&b);
        one_pass(&u.s, 7, &a);
        for (int k = 0; k < 3; k++) {
            one_pass(&c.s, 7, &b);
            same_pass(&a, &b, cols);
            assert_int_equal(c.pc.n, NPTS);
        }
        /* Abandoned when full: the next pass from the first row again. */
        assert_int_equal(c.s.rewind(c.s.ctx, msg, sizeof msg), 0);
        assert_int_equal(c.s.read(c.s.ctx, buf, 7, msg, sizeof msg), 7);
        one_pass(&c.s, 7, &b);
        same_pass(&a, &b, cols);
        pass_free(&a), pass_free(&b);
        src_close(&u);
        src_close(&c);
    }
}

/* (b) A bound one row short (or of 100 rows): no cache, the file read
 * every pass (still right); the bound exactly: cached. */
static void test_over_bound(void **state)
{
    (void)state;
    for (int cols = 3; cols <= 5; cols += 2) {
        const char *path = cols == 3 ? f3 : f5;
        const size_t all = sizeof(double) * (size_t)cols * NPTS;
        src_t u, c, e, t;
        src_open(&u, path, 0);
        src_open(&c, path, all - sizeof(double) * (size_t)cols);
        src_open(&e, path, all);
        src_open(&t, path, 100 * sizeof(double) * (size_t)cols); /* below the first block */
        pass_t a, b;
        pass_init(&a), pass_init(&b);
        for (int k = 0; k < 3; k++) {
            one_pass(&u.s, 7, &a);
            one_pass(&c.s, 7, &b);
            same_pass(&a, &b, cols);
            assert_null(c.pc.rows);
            one_pass(&t.s, 7, &b);
            same_pass(&a, &b, cols);
            assert_null(t.pc.rows);
            one_pass(&e.s, 7, &b);
            same_pass(&a, &b, cols);
            assert_int_equal(e.pc.n, NPTS);
        }
        pass_free(&a), pass_free(&b);
        src_close(&u);
        src_close(&c);
        src_close(&e);
        src_close(&t);
    }
}

/* (c) A bad line: the same rows, error and "FILE:LINE" on every pass. */
static void test_bad_line(void **state)
{
    (void)state;
    static const long maxes[] = {7, 3 * NPTS};
    const long bad = 12345;
    assert_int_equal(write_points(fbad, 3, bad), 0);
    for (int m = 0; m < 2; m++) {
        src_t u, c;
        src_open(&u, fbad, 0);
        src_open(&c, fbad, CF_FITSRC_CACHE_MAX);
        pass_t a, b;
        pass_init(&a), pass_init(&b);
        for (int k = 0; k < 3; k++) {
            one_pass(&u.s, maxes[m], &a);
            one_pass(&c.s, maxes[m], &b);
            assert_true(a.last < 0);
            assert_non_null(strstr(a.msg, fbad));
            same_pass(&a, &b, 3);
            assert_null(c.pc.rows);
            same_where(&u.s, &c.s, bad - 1);
            same_where(&u.s, &c.s, 17);
        }
        pass_free(&a), pass_free(&b);
        src_close(&u);
        src_close(&c);
    }
}

/* (d) The fitting loop with and without the cache: the coarse spline S*
 * (bicubic 5 x 4, u knot 0.5) at 48 x 48 parameters from a 4 x 4 plane,
 * auto refinement, pruning; x y z (projected, the trials' feet) and
 * u v x y z (given; on two cores too, the halves from the file). */
static nf_surf_t star, bez;
static char loop3[600], loop5[600];

static int loop_setup(void)
{
    tmp_path(loop3, sizeof loop3, "loop.xyz");
    tmp_path(loop5, sizeof loop5, "loop.uvxyz");
    return ref_job_star(&star, &bez, loop5, loop3);
}

static int run_loop(const char *file, int cols, int cores, size_t cache, cf_fitjob_result_t *r)
{
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.alpha = o.beta = 0.0;
    o.solver = NF_SOLVER_CHOL;
    o.tol = cols == 5 ? 1e-6 : 1e-4;
    o.loop = 1;
    o.refine = CF_REFINE_AUTO;
    o.prune = 40;
    o.cores = cores;
    cf_fitjob_t *j;
    int rc = cf_fitjob_open(&j, &bez, &o, msg, sizeof msg);
    if (rc)
        return rc;
    rc = ref_job_file_cache(j, file, cols, cache, r, msg, sizeof msg);
    cf_fitjob_close(j);
    return rc;
}

static void test_loop_same(void **state)
{
    (void)state;
    assert_int_equal(loop_setup(), 0);
    for (int t = 0; t < 3; t++) {
        const int cols = t ? 5 : 3, cores = t == 2 ? 2 : 1;
        const char *file = cols == 5 ? loop5 : loop3;
        cf_fitjob_result_t a, b;
        if (run_loop(file, cols, cores, 0, &a) ||
            run_loop(file, cols, cores, CF_FITSRC_CACHE_MAX, &b))
            fail_msg("%s", msg);
        assert_int_equal(a.status, CF_FITJOB_MET);
        assert_true(a.nrounds > 2);
        assert_true(a.pruned > 0);
        assert_int_equal(a.points, 48 * 48);
        assert_int_equal(a.status, b.status);
        assert_int_equal(a.nrounds, b.nrounds);
        assert_int_equal(a.pruned, b.pruned);
        assert_int_equal(a.surf.nu, b.surf.nu);
        assert_int_equal(a.surf.nv, b.surf.nv);
        const nf_surf_t *s = &a.surf;
        assert_memory_equal(s->U, b.surf.U, sizeof(double) * (size_t)(s->nu + s->p + 1));
        assert_memory_equal(s->V, b.surf.V, sizeof(double) * (size_t)(s->nv + s->q + 1));
        assert_memory_equal(s->cp, b.surf.cp, sizeof(double) * 3 * (size_t)(s->nu * s->nv));
        assert_memory_equal(&a.within_pct, &b.within_pct, sizeof a.within_pct);
        assert_memory_equal(&a.max_abs, &b.max_abs, sizeof a.max_abs);
        if (cores == 2)
            assert_int_equal(a.threads, b.threads);
        cf_fitjob_result_free(&a);
        cf_fitjob_result_free(&b);
    }
    remove(loop3);
    remove(loop5);
    cf_surf_free(&star);
    cf_surf_free(&bez);
}

static int setup(void **state)
{
    (void)state;
    tmp_path(f3, sizeof f3, "p.xyz");
    tmp_path(f5, sizeof f5, "p.uvxyz");
    tmp_path(fbad, sizeof fbad, "bad.xyz");
    return write_points(f3, 3, -1) | write_points(f5, 5, -1);
}

static int teardown(void **state)
{
    (void)state;
    remove(f3), remove(f5), remove(fbad);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cached_3),       cmocka_unit_test(test_cached_5),
        cmocka_unit_test(test_abandoned_pass), cmocka_unit_test(test_over_bound),
        cmocka_unit_test(test_bad_line),       cmocka_unit_test(test_loop_same),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
