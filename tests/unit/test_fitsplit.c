/* SPDX-License-Identifier: MIT */
/* test_fitsplit.c: a points file read in two halves on two threads
 * (issue 20). The reader's halves (cf_points_split) against one reader of
 * the same file: the same rows in the same order, every row's line, and
 * the first error in file order with its true line and the very message
 * one reader gives (an error in the first half, in the second, in both;
 * a truncated raw record; a CSV header, comments, CRLF; one line, fewer
 * points than a batch, an empty second half). The fit job with two cores
 * (opts.cores) against one core and against the dense normal equations of
 * ref_dense.c, ASCII and raw: the net to 1e-12 (summation order), rms
 * and max; the residual pass alone in halves gives max exactly and rms to
 * 1e-12; the job's errors name the same line as one core. */
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include "ref_job.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define NU 7
#define NV 6
#define MPTS 3000

static char tmpdir[512];
static nf_surf_t g_s;
static double *g_pts;

static void path_of(char *b, size_t n, const char *name)
{
    snprintf(b, n, "%s/cf_fitsplit_%ld_%s", tmpdir, (long)getpid(), name);
}

static int setup(void **state)
{
    (void)state;
    const char *d = getenv("CF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", d && *d ? d : "/tmp");
    mkdir(tmpdir, 0777);
    ref_seed(2020);
    ref_surf_random(&g_s, 3, 2, NU, NV, 0.0, 2.0, -1.0, 1.0, 0.7, 1.4);
    g_pts = malloc(sizeof(double) * 5 * MPTS);
    if (!g_pts)
        return -1;
    for (long k = 0; k < MPTS; k++) {
        double *r = g_pts + 5 * k;
        r[0] = ref_rand(0.0, 2.0);
        r[1] = ref_rand(-1.0, 1.0);
        nf_surf_eval(&g_s, r[0], r[1], r + 2);
        for (int c = 2; c < 5; c++)
            r[c] += ref_rand(-0.01, 0.01);
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    ref_surf_free(&g_s);
    free(g_pts);
    return 0;
}

/* ------------------------------------------------------------ the reader */

/* Everything a read gives: rows, each row's line, the error. */
typedef struct got {
    double rows[5 * 4000];
    long lines[4000];
    long n;
    int rc;
    char msg[1024];
} got_t;

/* r to its end or error, batch rows at a time; lines as it reports them. */
static void drain(cf_points_t *r, int cols, long batch, got_t *g)
{
    for (;;) {
        long k = cf_points_read(r, g->rows + cols * g->n, batch, g->msg, sizeof g->msg);
        if (k < 0) {
            g->rc = (int)k;
            return;
        }
        if (k == 0)
            return;
        for (long i = 0; i < k; i++) /* the line of the last: exact with batch 1 */
            g->lines[g->n + i] = cf_points_line(r);
        g->n += k;
        assert_true(g->n + batch <= 4000);
    }
}

/* One reader of path, one point at a time. */
static void read_one(const char *path, int want, got_t *g)
{
    memset(g, 0, sizeof *g);
    cf_points_t *r;
    char m[1024];
    assert_int_equal(cf_points_open(&r, path, want, m, sizeof m), CF_OK);
    drain(r, cf_points_cols(r), 1, g);
    cf_points_close(r);
}

/* Two halves, the second read first (as on a thread that runs ahead), its
 * lines counted from the split until the first half has been read and
 * the second rebased: then its error repeats with the file's line. With
 * batch 1 every line is compared; larger batches, the rows. Returns the
 * points of the second half. */
static long read_split(const char *path, int want, long batch, got_t *g)
{
    static got_t h2;
    memset(g, 0, sizeof *g);
    memset(&h2, 0, sizeof h2);
    cf_points_t *r, *r2 = NULL;
    char m[1024];
    assert_int_equal(cf_points_open(&r, path, want, m, sizeof m), CF_OK);
    int cols = cf_points_cols(r);
    assert_int_equal(cf_points_split(r, &r2, m, sizeof m), CF_OK);
    assert_non_null(r2);
    drain(r2, cols, batch, &h2);
    drain(r, cols, batch, g);
    if (!g->rc) { /* the first half read to its end: the second's lines are the file's */
        long base = cf_points_lines(r);
        cf_points_rebase(r2, base);
        size_t pl = strlen(path);
        int raw =
            pl > 4 && !strcmp(path + pl - 4, ".bin"); /* raw: point numbers known at the split */
        for (long i = 0; i < h2.n; i++)
            h2.lines[i] += raw ? 0 : base;
        double row[5];
        if (h2.rc)
            assert_int_equal(cf_points_read(r2, row, 0, h2.msg, sizeof h2.msg), h2.rc);
        memcpy(g->rows + cols * g->n, h2.rows, sizeof(double) * (size_t)(cols * h2.n));
        memcpy(g->lines + g->n, h2.lines, sizeof(long) * (size_t)h2.n);
        g->n += h2.n;
        g->rc = h2.rc;
        memcpy(g->msg, h2.msg, sizeof g->msg);
    }
    /* A second split rewinds both halves and gives them again. */
    cf_points_t *again = NULL;
    assert_int_equal(cf_points_split(r, &again, m, sizeof m), CF_OK);
    assert_ptr_equal(again, r2);
    cf_points_close(r); /* closes r2 too */
    return h2.n;
}

/* The halves against one reader: rows, lines (batch 1), error. */
static long same_as_one(const char *path, int want)
{
    static got_t one, two;
    read_one(path, want, &one);
    long n2 = 0;
    long batches[3] = {1, 7, 1000};
    for (int b = 0; b < 3; b++) {
        n2 = read_split(path, want, batches[b], &two);
        assert_int_equal(two.rc, one.rc);
        assert_string_equal(two.msg, one.msg);
        if (!one.rc || batches[b] == 1) {
            assert_int_equal(two.n, one.n);
            assert_memory_equal(two.rows, one.rows, sizeof(double) * 5 * (size_t)one.n);
        }
        if (batches[b] == 1)
            for (long i = 0; i < one.n; i++)
                assert_int_equal(two.lines[i], one.lines[i]);
    }
    return n2;
}

/* n points of g_pts as text (style 1: comments, blank lines, CRLF;
 * style 2: a CSV header with an extra column), bad lines at bad1, bad2
 * (1-based points, 0: none). */
static void write_text(const char *path, long n, int style, long bad1, long bad2)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (style == 2)
        fprintf(f, "# scan\nid,u,v,x,y,z\n");
    for (long i = 1; i <= n; i++) {
        const double *r = g_pts + 5 * (i - 1);
        if (style == 1 && i % 37 == 0)
            fprintf(f, "\n# comment %ld\r\n", i);
        if (i == bad1 || i == bad2)
            fprintf(f, "1 2 x%ld 4 5\n", i);
        else if (style == 2)
            fprintf(f, "%ld,%.17g,%.17g,%.17g,%.17g,%.17g\n", i, r[0], r[1], r[2], r[3], r[4]);
        else
            fprintf(f, "%.17g %.17g %.17g %.17g %.17g%s", r[0], r[1], r[2], r[3], r[4],
                    style == 1 ? "\r\n" : "\n");
    }
    fclose(f);
}

/* n points of g_pts as raw float64 (.uvxyz.bin), a NaN at point nan1
 * (1-based, 0: none), stray trailing bytes. */
static void write_raw(const char *path, long n, long nan1, int stray)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (long i = 1; i <= n; i++) {
        double r[5];
        memcpy(r, g_pts + 5 * (i - 1), sizeof r);
        if (i == nan1)
            r[3] = NAN;
        fwrite(r, sizeof r, 1, f);
    }
    for (int i = 0; i < stray; i++)
        fputc(0, f);
    fclose(f);
}

static void test_text_halves(void **state)
{
    (void)state;
    char p[700];
    path_of(p, sizeof p, "a.uvxyz");
    for (int style = 0; style < 3; style++) {
        write_text(p, 3000, style, 0, 0);
        assert_true(same_as_one(p, 5) > 1000); /* about half in each */
        assert_true(same_as_one(p, 0) > 1000); /* the columns from the first line */
    }
    /* Errors: in the first half, in the second, in both (the first wins). */
    long bad[3][2] = {{500, 0}, {2500, 0}, {2500, 500}};
    for (int i = 0; i < 3; i++)
        for (int style = 0; style < 3; style++) {
            write_text(p, 3000, style, bad[i][0], bad[i][1]);
            same_as_one(p, 5);
            got_t *g = malloc(sizeof *g);
            read_one(p, 5, g);
            assert_int_equal(g->rc, CF_EPARSE);
            char want[64];
            snprintf(want, sizeof want, "'x%ld'", bad[i][1] ? bad[i][1] : bad[i][0]);
            assert_non_null(strstr(g->msg, want));
            free(g);
        }
    unlink(p);
}

static void test_small_files(void **state)
{
    (void)state;
    char p[700];
    path_of(p, sizeof p, "s.uvxyz");
    FILE *f;
    /* One line: the second half is empty. */
    write_text(p, 1, 0, 0, 0);
    assert_int_equal(same_as_one(p, 5), 0);
    /* Fewer points than a batch, the last line without a newline. */
    write_text(p, 3, 0, 0, 0);
    f = fopen(p, "ab");
    fprintf(f, "0.5 0.5 1 2 3");
    fclose(f);
    assert_true(same_as_one(p, 5) >= 1);
    /* A bad last line without a newline, in the second half. */
    f = fopen(p, "ab");
    fprintf(f, "\n0.5 0.5 1 2");
    fclose(f);
    same_as_one(p, 5);
    /* Empty; a CSV header alone. */
    f = fopen(p, "wb");
    fclose(f);
    assert_int_equal(same_as_one(p, 5), 0);
    f = fopen(p, "wb");
    fprintf(f, "u,v,x,y,z\n");
    fclose(f);
    assert_int_equal(same_as_one(p, 5), 0);
    /* No line start near the middle: one reader only. */
    f = fopen(p, "wb");
    fprintf(f, "0.5 0.5 1 2 3\n");
    for (int i = 0; i < 3 * CF_POINTS_MAX_LINE; i++)
        fputc('7', f);
    fprintf(f, "\n0.5 0.5 1 2 3\n");
    fclose(f);
    cf_points_t *r, *r2 = NULL;
    char m[1024];
    assert_int_equal(cf_points_open(&r, p, 5, m, sizeof m), CF_OK);
    assert_int_equal(cf_points_split(r, &r2, m, sizeof m), CF_EUNSUPPORTED);
    assert_null(r2);
    cf_points_close(r);
    /* PLY is not split. */
    f = fopen(p, "wb");
    fprintf(f,
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty double u\nproperty double "
            "v\nproperty double x\nproperty double y\nproperty double z\nend_header\n1 2 3 4 5\n");
    fclose(f);
    assert_int_equal(cf_points_open(&r, p, 5, m, sizeof m), CF_OK);
    assert_int_equal(cf_points_split(r, &r2, m, sizeof m), CF_EUNSUPPORTED);
    cf_points_close(r);
    unlink(p);
}

static void test_raw_halves(void **state)
{
    (void)state;
    char p[700];
    path_of(p, sizeof p, "r.uvxyz.bin");
    write_raw(p, 1001, 0, 0);
    assert_int_equal(same_as_one(p, 5), 501); /* 500 whole records, then the rest */
    write_raw(p, 1001, 0, 13);                /* a truncated record: in the second half */
    same_as_one(p, 5);
    write_raw(p, 1001, 100, 0); /* NaN in the first half, the second, both */
    same_as_one(p, 5);
    write_raw(p, 1001, 900, 0);
    same_as_one(p, 5);
    write_raw(p, 1001, 100, 13);
    same_as_one(p, 5);
    write_raw(p, 1, 0, 0);
    assert_int_equal(same_as_one(p, 5), 1);
    write_raw(p, 0, 0, 5);
    same_as_one(p, 5);
    got_t *g = malloc(sizeof *g);
    write_raw(p, 1001, 0, 13);
    read_one(p, 5, g);
    assert_non_null(strstr(g->msg, "inside point 1002"));
    free(g);
    unlink(p);
}

/* ------------------------------------------------------------ the job */

static int job_r(const char *path, int cores, int threads, int robust, cf_fitjob_result_t *r,
                 char *m, size_t ml)
{
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.robust = robust;
    o.alpha = 0.1;
    o.beta = 0.001;
    o.solver = NF_SOLVER_CHOL;
    o.free_edges = 1; /* Eq. 7 alone: the dense reference has no pins */
    o.cores = cores;
    o.threads = threads;
    cf_fitjob_t *j;
    int rc = cf_fitjob_open(&j, &g_s, &o, m, ml);
    if (rc)
        return rc;
    rc = ref_job_file(j, path, 5, r, m, ml);
    cf_fitjob_close(j);
    return rc;
}

static int job(const char *path, int cores, int threads, cf_fitjob_result_t *r, char *m, size_t ml)
{
    return job_r(path, cores, threads, 0, r, m, ml);
}

static double max_cp(const nf_surf_t *s)
{
    double m = 0;
    for (long i = 0; i < 3L * s->nu * s->nv; i++)
        m = fmax(m, fabs(s->cp[i]));
    return m;
}

static void test_job_two_cores(void **state)
{
    (void)state;
    double *A, *b, x[3 * NU * NV];
    ref_eq7(&g_s, g_pts, MPTS, 0.1, 0.001, &A, &b);
    assert_int_equal(ref_solve(A, b, (long)NU * NV, x), 0);
    free(A);
    free(b);
    char p[2][700], m[1024];
    path_of(p[0], sizeof p[0], "j.uvxyz");
    path_of(p[1], sizeof p[1], "j.uvxyz.bin");
    write_text(p[0], MPTS, 1, 0, 0);
    write_raw(p[1], MPTS, 0, 0);
    for (int f = 0; f < 2; f++) {
        cf_fitjob_result_t r1, r2;
        if (job(p[f], 1, 1, &r1, m, sizeof m) || job(p[f], 2, 1, &r2, m, sizeof m))
            fail_msg("%s", m);
        assert_int_equal(r1.threads, 1);
        assert_int_equal(r2.threads, 2);
        assert_int_equal(r2.points, MPTS);
        assert_true(r2.bytes > r1.bytes); /* the second accumulator counts */
        double s = max_cp(&r1.surf);
        for (long i = 0; i < 3L * NU * NV; i++) {
            assert_near(r2.surf.cp[i], r1.surf.cp[i], 1e-12 * s);
            assert_near(r1.surf.cp[i], x[i], 1e-9 * s);
        }
        /* Distances to nets 1e-12 apart (of the part's size) */
        assert_near(r2.rms, r1.rms, 1e-12 * s);
        assert_near(r2.max_abs, r1.max_abs, 1e-12 * s);
        assert_true(r1.rms > 1e-3 && r1.rms < 0.02); /* the noise, not a misfit */
        cf_fitjob_result_free(&r1);
        cf_fitjob_result_free(&r2);
        /* The fit on bench's two accumulators (the same net on both): the
         * residual pass alone in halves, max exactly, rms to 1e-12. */
        if (job(p[f], 1, 2, &r1, m, sizeof m) || job(p[f], 2, 2, &r2, m, sizeof m))
            fail_msg("%s", m);
        assert_memory_equal(r1.surf.cp, r2.surf.cp, sizeof(double) * 3 * NU * NV);
        assert_int_equal(r2.threads, 2);
        assert_true(r2.max_abs == r1.max_abs);
        assert_near(r2.rms, r1.rms, 1e-12 * r1.rms);
        cf_fitjob_result_free(&r1);
        cf_fitjob_result_free(&r2);
        /* Robust: the scale from the |d| histogram of the halves, merged by
         * its bins, is one thread's exactly, and so are the weights and the
         * reweighted net. */
        if (job_r(p[f], 1, 2, 1, &r1, m, sizeof m) || job_r(p[f], 2, 2, 1, &r2, m, sizeof m))
            fail_msg("%s", m);
        assert_true(r1.sigma > 0);
        assert_true(r2.sigma == r1.sigma);
        assert_int_equal(r2.outliers, r1.outliers);
        assert_memory_equal(r1.surf.cp, r2.surf.cp, sizeof(double) * 3 * NU * NV);
        assert_int_equal(r2.threads, 2);
        cf_fitjob_result_free(&r1);
        cf_fitjob_result_free(&r2);
    }
    unlink(p[0]);
    unlink(p[1]);
}

/* The tolerance loop on projected points (x y z) with two cores: each
 * check pass's feet on two threads (the search grid shared, the warm
 * starts from the last check's feet), summed in the points' order: one
 * core's fit bit for bit, round by round, pruning trials included; with
 * statistics (the signed distances) too. A flat plane base, a wavy part:
 * the loop must insert knots. */
/* Points within tol of s and their sum of squared distances, each foot
 * from the nearest of a 121 x 121 sample of s, finished by nf_project. */
static void brute_check(const nf_surf_t *s, const double *xyz, long n, double tol, long *within,
                        double *ss)
{
    enum { G = 121 };
    double *smp = malloc(sizeof(double) * 3 * G * G), u0, u1, v0, v1;
    assert_non_null(smp);
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (int b = 0; b < G; b++)
        for (int a = 0; a < G; a++)
            nf_surf_eval(s, u0 + (u1 - u0) * a / (G - 1), v0 + (v1 - v0) * b / (G - 1),
                         smp + 3 * (a + G * b));
    *within = 0;
    *ss = 0.0;
    for (long k = 0; k < n; k++) {
        const double *q = xyz + 3 * k;
        long best = 0;
        double bd = HUGE_VAL;
        for (long t = 0; t < G * G; t++) {
            const double *P = smp + 3 * t;
            const double d = (P[0] - q[0]) * (P[0] - q[0]) + (P[1] - q[1]) * (P[1] - q[1]) +
                             (P[2] - q[2]) * (P[2] - q[2]);
            if (d < bd)
                bd = d, best = t;
        }
        nf_proj_t pr;
        assert_int_equal(nf_project(s, q, u0 + (u1 - u0) * (double)(best % G) / (G - 1),
                                    v0 + (v1 - v0) * (double)(best / G) / (G - 1), 1e-12, &pr),
                         NF_OK);
        *within += fabs(pr.dist) <= tol;
        *ss += pr.dist * pr.dist;
    }
    free(smp);
}

static void test_job_projected_loop(void **state)
{
    (void)state;
    char p[700], m[1024];
    path_of(p, sizeof p, "l.xyz");
    FILE *f = fopen(p, "w");
    assert_non_null(f);
    double *xyz = malloc(sizeof(double) * 3 * MPTS);
    assert_non_null(xyz);
    for (long k = 0; k < MPTS; k++) {
        double *q = xyz + 3 * k;
        q[0] = ref_rand(0.0, 100.0), q[1] = ref_rand(0.0, 80.0);
        q[2] = 3.0 * sin(q[0] / 11.0) * cos(q[1] / 13.0) + ref_rand(-0.005, 0.005);
        fprintf(f, "%.17g %.17g %.17g\n", q[0], q[1], q[2]);
    }
    fclose(f);
    double mem[4 * 8 + 3 * 16 + 16];
    nf_surf_t base;
    nf_surf_wire(&base, 3, 3, 4, 4, mem);
    for (int i = 0; i < 8; i++) {
        base.U[i] = i < 4 ? 0.0 : 1.0;
        base.V[i] = i < 4 ? 0.0 : 1.0;
    }
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *P = base.cp + 3 * (i + 4 * j);
            P[0] = -5.0 + 110.0 * i / 3.0, P[1] = -5.0 + 90.0 * j / 3.0, P[2] = 0.0;
        }
    const double o_tol = 0.05;
    for (int stats = 0; stats < 2; stats++) {
        cf_fitjob_result_t r[2];
        for (int c = 0; c < 2; c++) {
            cf_fitjob_opts_t o;
            cf_fitjob_defaults(&o);
            o.tol = o_tol;
            o.loop = 1;
            o.within = 99;
            o.stats = stats;
            o.cores = c + 1;
            cf_fitjob_t *j;
            if (cf_fitjob_open(&j, &base, &o, m, sizeof m) ||
                ref_job_file(j, p, 3, &r[c], m, sizeof m))
                fail_msg("%s", m);
            cf_fitjob_close(j);
        }
        assert_true(r[0].nrounds >= 3); /* knots were inserted */
        assert_int_equal(r[1].nrounds, r[0].nrounds);
        for (int k = 0; k < r[0].nrounds; k++) {
            assert_int_equal(r[1].rounds[k].nu, r[0].rounds[k].nu);
            assert_int_equal(r[1].rounds[k].nv, r[0].rounds[k].nv);
            assert_int_equal(r[1].rounds[k].prune, r[0].rounds[k].prune);
            assert_true(r[1].rounds[k].within_pct == r[0].rounds[k].within_pct);
            assert_true(r[1].rounds[k].rms == r[0].rounds[k].rms);
            assert_true(r[1].rounds[k].mx == r[0].rounds[k].mx);
        }
        assert_int_equal(r[1].surf.nu, r[0].surf.nu);
        assert_int_equal(r[1].surf.nv, r[0].surf.nv);
        assert_memory_equal(r[1].surf.cp, r[0].surf.cp,
                            sizeof(double) * 3 * r[0].surf.nu * r[0].surf.nv);
        assert_true(r[1].max_abs == r[0].max_abs);
        assert_int_equal(r[1].status, r[0].status);
        /* The check pass's sums (in two parts, merged) against feet found
         * here without it: the nearest of a dense sample, then nf_project. */
        long within = 0;
        double ss = 0.0;
        brute_check(&r[0].surf, xyz, MPTS, o_tol, &within, &ss);
        assert_true(fabs(r[0].within_pct - 100.0 * (double)within / MPTS) <= 100.0 / MPTS);
        assert_near(r[0].rms, sqrt(ss / MPTS), 1e-6 * r[0].rms);
        cf_fitjob_result_free(&r[0]);
        cf_fitjob_result_free(&r[1]);
    }
    free(xyz);
    unlink(p);
}

/* One line (an empty second half) and a few points, through the job:
 * two cores give one core's net. */
static void test_job_small(void **state)
{
    (void)state;
    char p[700], m[1024];
    path_of(p, sizeof p, "one.uvxyz");
    for (long n = 1; n <= 3; n += 2) {
        write_text(p, n, 0, 0, 0);
        cf_fitjob_result_t r1, r2;
        if (job(p, 1, 1, &r1, m, sizeof m) || job(p, 2, 1, &r2, m, sizeof m))
            fail_msg("%s", m);
        assert_int_equal(r2.points, n);
        assert_int_equal(r2.threads, 2);
        double s = max_cp(&r1.surf);
        for (long i = 0; i < 3L * NU * NV; i++)
            assert_near(r2.surf.cp[i], r1.surf.cp[i], 1e-12 * s);
        assert_near(r2.max_abs, r1.max_abs, 1e-12 * s);
        cf_fitjob_result_free(&r1);
        cf_fitjob_result_free(&r2);
    }
    unlink(p);
}

/* The job's error on two cores is one core's: the same code and text. */
static void same_error(const char *path)
{
    char m1[1024], m2[1024];
    cf_fitjob_result_t r1, r2;
    int a = job(path, 1, 1, &r1, m1, sizeof m1), b = job(path, 2, 1, &r2, m2, sizeof m2);
    assert_true(a != 0);
    assert_int_equal(b, a);
    assert_string_equal(m2, m1);
}

static void test_job_errors(void **state)
{
    (void)state;
    char p[700];
    path_of(p, sizeof p, "e.uvxyz");
    /* Parse errors: first half, second half, both. */
    write_text(p, MPTS, 1, 600, 0);
    same_error(p);
    write_text(p, MPTS, 1, 2600, 0);
    same_error(p);
    write_text(p, MPTS, 1, 2600, 600);
    same_error(p);
    /* A row outside the domain in the second half: its line (where). */
    write_text(p, MPTS, 0, 0, 0);
    FILE *f = fopen(p, "ab");
    fprintf(f, "5 0 1 2 3\n");
    fclose(f);
    same_error(p);
    char m[1024];
    cf_fitjob_result_t r;
    assert_int_equal(job(p, 2, 1, &r, m, sizeof m), NF_EDOMAIN);
    char want[64];
    snprintf(want, sizeof want, ":%d: parameters", MPTS + 1);
    assert_non_null(strstr(m, want));
    /* Raw: a truncated record, and a NaN in either half. */
    path_of(p, sizeof p, "e.uvxyz.bin");
    write_raw(p, MPTS, 0, 11);
    same_error(p);
    write_raw(p, MPTS, 2900, 0);
    same_error(p);
    write_raw(p, MPTS, 10, 11);
    same_error(p);
    unlink(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_text_halves),        cmocka_unit_test(test_small_files),
        cmocka_unit_test(test_raw_halves),         cmocka_unit_test(test_job_two_cores),
        cmocka_unit_test(test_job_errors),         cmocka_unit_test(test_job_small),
        cmocka_unit_test(test_job_projected_loop),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
