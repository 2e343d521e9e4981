/* SPDX-License-Identifier: MIT */
/* test_accum.c: the accumulation paths of nf_accum.c (bicubic vector
 * kernels, factored runs of one v, raster row mode, short-run scatter, the
 * batched nf_fit_add_rows) and shards on two threads, each against the
 * dense R^T R of ref_dense.c and against the plain per-point path; the fast
 * span search against the binary one; the shard's budget. */
#include "cf_accum.h"
#include "cf_test.h"
#include "nf_basis.h"
#include "nf_budget.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "ref_dense.h"
#include <stdlib.h>

typedef struct job {
    nf_fit_t f, sh;
    nf_arena_t ar;
    void *mem;
} job_t;

/* A job (alpha = beta = 0, PCG) with room for one shard. plain: the
 * generic path (no vector kernels, no row mode). */
static void job_start(job_t *j, const nf_surf_t *s, int plain)
{
    nf_fit_params_t prm = {0.0, 0.0, NF_SOLVER_PCG};
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, NF_SOLVER_PCG) +
                nf_fit_shard_bytes(s->nu, s->nv, s->p, s->q);
    j->mem = malloc((size_t)need);
    nf_arena_init(&j->ar, j->mem, (size_t)need);
    assert_int_equal(nf_fit_init(&j->f, s, &prm, &j->ar), NF_OK);
    if (plain)
        j->f.acc.fast = 0;
}

static double max_abs(const double *a, long n)
{
    double m = 0.0;
    for (long i = 0; i < n; i++)
        m = fabs(a[i]) > m ? fabs(a[i]) : m;
    return m;
}

/* Point sets: 0 raster rows of one v (domain ends included), 1 raster with
 * v jittered per point (no two share v), 2 random, 3 random with each point
 * repeated 3 times (runs of one span and one v), 4 raster through the
 * interior knots exactly (span boundaries), 5 columns of one u (v varies
 * within each span: the block path), 6 a serpentine raster (rows run left
 * and right) with every third row cut to 2 points (the row kernel stops
 * and the general path takes over, then the kernel again). */
static double *points(const nf_surf_t *s, int kind, long *M)
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    const long cols = 61, rows = 19;
    long m = kind == 3 ? 3 * 400 : kind == 2 ? 1000 : cols * rows;
    if (kind == 4)
        m = (long)(s->nu - s->p + 1) * (s->nv - s->q + 1) * 8;
    double *pts = malloc(sizeof(double) * (size_t)(5 * m));
    for (long t = 0; t < m; t++) {
        double *r = pts + 5 * t, u, v;
        if (kind == 6) {
            const long row = t / cols, c = t % cols;
            const long cc = row % 3 == 2 ? c % 2 : c; /* a short row repeats 2 points */
            u = u0 + (u1 - u0) * (double)(row % 2 ? cols - 1 - cc : cc) / (cols - 1);
            v = v0 + (v1 - v0) * (double)row / (rows - 1);
            if (row % 3 == 2 && c >= 2) /* short row: its other points go to a row of their own */
                v = v0 + (v1 - v0) * ((double)row + 0.5) / (rows - 1);
            v = v < v0 ? v0 : v > v1 ? v1 : v;
        } else if (kind == 0 || kind == 1) {
            u = u0 + (u1 - u0) * (double)(t % cols) / (cols - 1);
            v = v0 + (v1 - v0) * (double)(t / cols) / (rows - 1);
            if (kind == 1 && t % cols && t % cols != cols - 1)
                v += ref_rand(-1e-3, 1e-3) * (v1 - v0) / rows;
            v = v < v0 ? v0 : v > v1 ? v1 : v;
        } else if (kind == 5) {
            u = u0 + (u1 - u0) * (double)(t / rows) / (cols - 1);
            v = v0 + (v1 - v0) * (double)(t % rows) / (rows - 1);
        } else if (kind == 4) { /* knots U[p..nu] x V[q..nv] in rows, each then a point near */
            long nk = s->nu - s->p + 1, e = t / 4;
            u = s->U[s->p + e % nk];
            v = s->V[s->q + (e / nk) % (s->nv - s->q + 1)];
            if (t % 4 >= 2) {
                u = u + ref_rand(-0.2, 0.2) * (u1 - u0) / nk;
                v = v + ref_rand(-0.2, 0.2) * (v1 - v0) / nk;
                u = u < u0 ? u0 : u > u1 ? u1 : u;
                v = v < v0 ? v0 : v > v1 ? v1 : v;
            }
        } else {
            long e = kind == 3 ? t / 3 : t;
            if (kind == 3 && t % 3) {
                u = pts[5 * (3 * e)];
                v = pts[5 * (3 * e) + 1];
            } else {
                u = ref_rand(u0, u1);
                v = ref_rand(v0, v1);
            }
        }
        r[0] = u;
        r[1] = v;
        nf_surf_eval(s, u, v, r + 2);
        r[4] += ref_rand(-0.1, 0.1);
    }
    *M = m;
    return pts;
}

/* Entry (i, k) of job g's stripes or of a dense n x n matrix. */
typedef struct ref {
    const nf_fit_t *g;
    const double *A, *b;
} ref_t;

static double ref_a(const ref_t *r, long n, long i, long k)
{
    return r->g ? nf_stripe_get(&r->g->A, i, k) : r->A[i * n + k];
}

static double ref_b(const ref_t *r, long i)
{
    return r->g ? r->g->rhs[i] : r->b[i];
}

/* Stripes and right-hand side of f equal the reference's, every entry
 * within the pattern's reach (i <= k <= i + q Nu + p). */
static void same_store(const nf_fit_t *f, ref_t r, double rtol)
{
    const long n = f->n, reach = (long)f->base->q * f->base->nu + f->base->p;
    double sc = max_abs(f->A.S, n * f->A.K), bs = max_abs(f->rhs, 3 * n);
    assert_true(sc > 0.0);
    for (long i = 0; i < n; i++) {
        for (long k = i; k < n && k <= i + reach + 1; k++)
            assert_near(nf_stripe_get(&f->A, i, k), ref_a(&r, n, i, k), rtol * sc);
        for (int c = 0; c < 3; c++)
            assert_near(f->rhs[3 * i + c], ref_b(&r, 3 * i + c), rtol * bs);
    }
}

/* Every path and order: fast = plain = dense, alone and split over a shard
 * on a second thread. */
static void check_paths(int p, int q, int nu, int nv, double wlo)
{
    nf_surf_t s;
    ref_surf_random(&s, p, q, nu, nv, 0, 1, 0, 2, wlo, wlo < 1 ? 2.0 : 1.0);
    for (int kind = 0; kind < 7; kind++) {
        long M;
        double *pts = points(&s, kind, &M), *A, *b;
        ref_eq7(&s, pts, M, 0.0, 0.0, &A, &b);
        job_t fast, plain, two, ser;
        job_start(&fast, &s, 0);
        job_start(&plain, &s, 1);
        job_start(&two, &s, 0);
        job_start(&ser, &s, 0);
        assert_int_equal(nf_fit_add_rows(&fast.f, pts, M, NULL), NF_OK);
        for (long t = 0; t < M; t++) /* the plain path, one point at a time */
            assert_int_equal(nf_fit_add(&plain.f, pts[5 * t], pts[5 * t + 1], pts + 5 * t + 2, 1.0),
                             NF_OK);
        assert_int_equal(nf_fit_shard_init(&two.sh, &two.f, &two.ar), NF_OK);
        assert_int_equal(nf_fit_shard_init(&ser.sh, &ser.f, &ser.ar), NF_OK);
        for (long t0 = 0; t0 < M; t0 += 100) { /* chunks of 100, halves on two threads */
            long n = M - t0 < 100 ? M - t0 : 100;
            assert_int_equal(cf_accum_rows(&two.f, &two.sh, 0, pts + 5 * t0, n, NULL), NF_OK);
            /* the same halves in turn on this thread */
            assert_int_equal(cf_accum_rows(&ser.f, &ser.sh, 1, pts + 5 * t0, n, NULL), NF_OK);
        }
        assert_int_equal(nf_fit_shard_merge(&two.f, &two.sh), NF_OK);
        assert_int_equal(nf_fit_shard_merge(&ser.f, &ser.sh), NF_OK);
        assert_int_equal(two.f.npoints, M);
        /* One core in turn sums as two cores do, bit for bit. */
        assert_int_equal(ser.f.npoints, M);
        assert_memory_equal(ser.f.A.S, two.f.A.S, sizeof(double) * (size_t)(two.f.n * two.f.A.K));
        assert_memory_equal(ser.f.rhs, two.f.rhs, sizeof(double) * (size_t)(3 * two.f.n));
        assert_int_equal(nf_fit_finish(&fast.f), NF_OK);
        assert_int_equal(nf_fit_finish(&plain.f), NF_OK);
        assert_int_equal(nf_fit_finish(&two.f), NF_OK);
        const ref_t dense = {NULL, A, b}, pl = {&plain.f, NULL, NULL};
        same_store(&fast.f, dense, 1e-12);
        same_store(&plain.f, dense, 1e-12);
        same_store(&two.f, dense, 1e-12);
        same_store(&fast.f, pl, 1e-13);
        /* The row buffers and the shard went back: the job holds its base only. */
        const long base = 8L * fast.f.n * (fast.f.A.K + 6);
        assert_true(two.ar.used == fast.ar.used && fast.ar.used == plain.ar.used);
        assert_true((long)fast.ar.used >= base && (long)fast.ar.used <= base + 3 * 64);
        free(A);
        free(b);
        free(pts);
        free(fast.mem);
        free(plain.mem);
        free(two.mem);
        free(ser.mem);
    }
    ref_surf_free(&s);
}

static void test_bicubic_polynomial(void **state)
{
    (void)state;
    ref_seed(11);
    check_paths(3, 3, 9, 7, 1.0);
    check_paths(3, 3, 4, 4, 1.0); /* one span each way */
}

static void test_bicubic_rational(void **state)
{
    (void)state;
    ref_seed(12);
    check_paths(3, 3, 8, 6, 0.5);
}

static void test_mixed_degrees(void **state)
{
    (void)state;
    ref_seed(13);
    check_paths(2, 3, 7, 6, 0.5);
    check_paths(3, 2, 6, 5, 1.0);
    check_paths(2, 2, 6, 6, 1.0);
}

/* Weighted points: the vector kernels (factored runs, row mode, rational)
 * equal the plain path; a weight w equals w repetitions. */
static void test_weights_all_paths(void **state)
{
    (void)state;
    ref_seed(14);
    for (int r = 0; r < 2; r++) {
        nf_surf_t s;
        ref_surf_random(&s, 3, 3, 8, 7, 0, 1, 0, 1, r ? 0.5 : 1.0, r ? 2.0 : 1.0);
        for (int kind = 0; kind < 6; kind++) {
            long M;
            double *pts = points(&s, kind, &M);
            job_t fast, plain, rep;
            job_start(&fast, &s, 0);
            job_start(&plain, &s, 1);
            job_start(&rep, &s, 0);
            for (long t = 0; t < M; t++) {
                const double *q5 = pts + 5 * t;
                int w = 1 + (int)(t % 3);
                assert_int_equal(nf_fit_add(&fast.f, q5[0], q5[1], q5 + 2, w), NF_OK);
                assert_int_equal(nf_fit_add(&plain.f, q5[0], q5[1], q5 + 2, w), NF_OK);
                for (int k = 0; k < w; k++)
                    assert_int_equal(nf_fit_add(&rep.f, q5[0], q5[1], q5 + 2, 1.0), NF_OK);
            }
            assert_int_equal(nf_fit_finish(&fast.f), NF_OK);
            assert_int_equal(nf_fit_finish(&plain.f), NF_OK);
            assert_int_equal(nf_fit_finish(&rep.f), NF_OK);
            const ref_t pl = {&plain.f, NULL, NULL};
            same_store(&fast.f, pl, 1e-13);
            same_store(&rep.f, pl, 1e-13);
            free(pts);
            free(fast.mem);
            free(plain.mem);
            free(rep.mem);
        }
        ref_surf_free(&s);
    }
}

/* nf_find_span_from gives nf_find_span's span from any hint, on uniform,
 * non-uniform and repeated knots, at every knot and at both ends. */
static void test_span_search(void **state)
{
    (void)state;
    ref_seed(15);
    double U[40];
    for (int kind = 0; kind < 3; kind++) {
        const int p = 3, n = 20; /* n + 1 control points, knots U[0..n+p+1] */
        for (int i = 0; i <= p; i++) {
            U[i] = 0.0;
            U[n + 1 + i] = 1.0;
        }
        for (int i = p + 1; i <= n; i++)
            U[i] = kind == 0 ? (double)(i - p) / (n + 1 - p)
                             : ((double)(i - p) / (n + 1 - p)) * ((double)(i - p) / (n + 1 - p));
        if (kind == 2) { /* a double and a triple knot */
            U[8] = U[7];
            U[14] = U[13] = U[12];
        }
        assert_int_equal(nf_knots_check(n, p, U), NF_OK);
        const double h = (n + 1 - p) / (U[n + 1] - U[p]);
        for (int t = 0; t < 2000; t++) {
            double u = t < n + 2 ? U[p + (t < n + 1 - p ? t : n + 1 - p)] : ref_rand(0.0, 1.0);
            int last = (t % 5 == 0) ? -1 : p + (int)ref_rand(0, n + 1 - p);
            assert_int_equal(nf_find_span_from(last, n, p, u, U, h), nf_find_span(n, p, u, U));
        }
    }
}

/* A shard is in the byte formula: refused when the job plus the shard
 * exceed the board, and when the arena lacks the room; the job's arena
 * high-water mark stays within nf_fit_bytes + nf_fit_shard_bytes. */
static void test_shard_budget(void **state)
{
    (void)state;
    ref_seed(16);
    nf_surf_t s;
    int side = 0;
    /* Cholesky fits the board, with a shard not (sim: 134 a side;
     * linux-cell, 1.5 GiB: 400). */
    for (int t = 20; (long)t * t <= NF_MAX_CP && !side; t++) {
        long need = nf_fit_bytes(t, t, 3, 3, NF_SOLVER_CHOL);
        if (need <= NF_ARENA_BYTES && need + nf_fit_shard_bytes(t, t, 3, 3) > NF_ARENA_BYTES)
            side = t;
    }
    assert_true(side > 0);
    ref_surf_random(&s, 3, 3, side, side, 0, 1, 0, 1, 1, 1);
    long need = nf_fit_bytes(side, side, 3, 3, NF_SOLVER_CHOL);
    void *mem = malloc((size_t)need); /* linux-cell: 1.5 GiB, 48 MB of it touched */
    assert_non_null(mem);
    nf_arena_t ar;
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_t f, sh;
    nf_fit_params_t prm = {0.1, 0.001, NF_SOLVER_CHOL};
    assert_int_equal(nf_fit_init(&f, &s, &prm, &ar), NF_OK);
    assert_int_equal(nf_fit_shard_init(&sh, &f, &ar), NF_EBUDGET);
    free(mem);
    ref_surf_free(&s);

    ref_surf_random(&s, 3, 3, 12, 10, 0, 1, 0, 1, 1, 1);
    need = nf_fit_bytes(12, 10, 3, 3, NF_SOLVER_GS);
    long more = nf_fit_shard_bytes(12, 10, 3, 3);
    assert_int_equal(more, NF_BYTES_SHARD(120, 3, 3));
    mem = malloc((size_t)(need + more));
    nf_arena_init(&ar, mem, (size_t)need);
    prm.solver = NF_SOLVER_GS;
    assert_int_equal(nf_fit_init(&f, &s, &prm, &ar), NF_OK);
    assert_int_equal(nf_fit_shard_init(&sh, &f, &ar), NF_EARENA); /* the job's bytes only */
    nf_arena_init(&ar, mem, (size_t)(need + more));
    assert_int_equal(nf_fit_init(&f, &s, &prm, &ar), NF_OK);
    assert_int_equal(nf_fit_shard_init(&sh, &f, &ar), NF_OK);
    long M;
    double *pts = points(&s, 0, &M);
    assert_int_equal(cf_accum_rows(&f, &sh, 0, pts, M, NULL), NF_OK);
    assert_int_equal(nf_fit_finish(&sh), NF_ESTATE); /* a shard is merged, never finished */
    assert_int_equal(nf_fit_shard_merge(&f, &sh), NF_OK);
    assert_int_equal(nf_fit_add(&sh, pts[0], pts[1], pts + 2, 1.0), NF_ESTATE);
    assert_int_equal(nf_fit_finish(&f), NF_OK);
    assert_int_equal(nf_fit_solve(&f, NF_SOLVER_GS, NULL, NULL), NF_OK);
    assert_true(ar.high <= (size_t)(need + more));
    free(pts);
    free(mem);
    ref_surf_free(&s);
}

/* The row kernel alone: it takes a raster whole (sums as the dense R^T R),
 * stops after a row of one v shorter than NF_ROW_MIN and at a bad row. */
/* cf_accum_rows_hook: each row reaches the hook once, after it is
 * accumulated, on its half (0: the job's, 1: the shard's), whether the
 * halves run on two threads or in turn. */
typedef struct marks {
    const double *pts;
    unsigned char *seen;
    long per[2];
} marks_t;

static void mark_rows(void *ctx, int half, const double *rows, long n)
{
    marks_t *m = ctx;
    const long i0 = (rows - m->pts) / 5;
    for (long k = 0; k < n; k++)
        m->seen[i0 + k] += (unsigned char)(1 + half);
    m->per[half] += n;
}

static void test_hook(void **state)
{
    (void)state;
    ref_seed(31);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 9, 7, 0, 1, 0, 2, 1.0, 1.0);
    long M;
    double *pts = points(&s, 0, &M);
    for (int serial = 0; serial < 2; serial++) {
        job_t t;
        job_start(&t, &s, 0);
        assert_int_equal(nf_fit_shard_init(&t.sh, &t.f, &t.ar), NF_OK);
        marks_t m = {pts, calloc((size_t)M, 1), {0, 0}};
        assert_non_null(m.seen);
        for (long t0 = 0; t0 < M; t0 += 101) {
            long n = M - t0 < 101 ? M - t0 : 101;
            assert_int_equal(
                cf_accum_rows_hook(&t.f, &t.sh, serial, pts + 5 * t0, n, NULL, mark_rows, &m),
                NF_OK);
        }
        assert_int_equal(m.per[0] + m.per[1], M);
        for (long k = 0; k < M; k++) { /* once each; a chunk's second half on the shard */
            const long c0 = k - k % 101, n = M - c0 < 101 ? M - c0 : 101;
            assert_int_equal(m.seen[k], n >= 2 && k - c0 >= n / 2 ? 2 : 1);
        }
        assert_int_equal(nf_fit_shard_merge(&t.f, &t.sh), NF_OK);
        assert_int_equal(t.f.npoints, M);
        free(m.seen);
        free(t.mem);
    }
    free(pts);
    ref_surf_free(&s);
}

static void test_row_kernel(void **state)
{
    (void)state;
    ref_seed(19);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 9, 7, 0, 1, 0, 2, 1.0, 1.0);
    double dom[4];
    nf_surf_domain(&s, &dom[0], &dom[1], &dom[2], &dom[3]);
    long M;
    double *pts = points(&s, 0, &M), *A, *b;
    ref_eq7(&s, pts, M, 0.0, 0.0, &A, &b);
    job_t j;
    job_start(&j, &s, 0);
    assert_int_equal(nf_accum_rows33(&j.f.acc, pts, M, dom, dom), M);
    j.f.npoints = M;
    j.f.sumw = (double)M;
    assert_int_equal(nf_fit_finish(&j.f), NF_OK);
    same_store(&j.f, (ref_t){NULL, A, b}, 1e-12);
    free(j.mem);
    free(A);
    free(b);
    free(pts);
    /* rows 0 and 1 (61 points each), then row 2 of 2 points ends short */
    pts = points(&s, 6, &M);
    job_start(&j, &s, 0);
    assert_int_equal(nf_accum_rows33(&j.f.acc, pts, M, dom, dom), 2 * 61 + 2);
    free(j.mem);
    pts[5 * 70 + 3] = NAN; /* a bad row inside row 1 */
    job_start(&j, &s, 0);
    assert_int_equal(nf_accum_rows33(&j.f.acc, pts, M, dom, dom), 70);
    j.f.acc.fast = 0; /* not the bicubic kernels: it does not apply */
    assert_int_equal(nf_accum_rows33(&j.f.acc, pts, M, dom, dom), 0);
    free(j.mem);
    free(pts);
    ref_surf_free(&s);
}

/* A bad row is reported by its index in the chunk, from either half. */
static void test_bad_row_index(void **state)
{
    (void)state;
    ref_seed(17);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 6, 6, 0, 1, 0, 1, 1, 1);
    long M;
    double *pts = points(&s, 2, &M);
    for (int w = 0; w < 3; w++) {
        const long at = w == 0 ? 5 : w == 1 ? 13 : M - 3; /* in a batch, after one, 2nd half */
        pts[5 * at] = 7.0;                                /* outside [0, 1] */
        job_t j;
        job_start(&j, &s, 0);
        long bad = -1;
        assert_int_equal(nf_fit_add_rows(&j.f, pts, M, &bad), NF_EDOMAIN);
        assert_int_equal(bad, at);
        assert_int_equal(j.f.npoints, at); /* the rows before it, none after */
        free(j.mem);
        job_start(&j, &s, 0);
        assert_int_equal(nf_fit_shard_init(&j.sh, &j.f, &j.ar), NF_OK);
        bad = -1;
        assert_int_equal(cf_accum_rows(&j.f, &j.sh, 0, pts, M, &bad), NF_EDOMAIN);
        assert_int_equal(bad, at);
        free(j.mem);
        pts[5 * at] = 0.5;
    }
    free(pts);
    ref_surf_free(&s);
}

/* Windows of at least 1,024 points go through the bins (tiles of 16 x 16
 * spans; a raster window keeps its order, its spans from the bins): the same stripes as the dense R^T R (built here from the
 * reference basis rows, only where they are non-zero) and as the plain
 * path; a bad row inside a binned window is reported by its index, with
 * exactly the rows before it accumulated. */
static void test_binned_random(void **state)
{
    (void)state;
    ref_seed(18);
    for (int r = 0; r < 3; r++) { /* random polynomial, random rational, raster */
        nf_surf_t s;
        ref_surf_random(&s, 3, 3, 36, 36, 0, 1, 0, 1, r == 1 ? 0.5 : 1.0, r == 1 ? 2.0 : 1.0);
        const long n = 36L * 36, M = 3000;
        double *pts = malloc(sizeof(double) * 5 * M), *row = malloc(sizeof(double) * n);
        for (long t = 0; t < M; t++) {
            double *q5 = pts + 5 * t;
            q5[0] = r == 2 ? (double)(t % 60) / 59 : ref_rand(0, 1);
            q5[1] = r == 2 ? (double)(t / 60) / 49 : ref_rand(0, 1);
            nf_surf_eval(&s, q5[0], q5[1], q5 + 2);
        }
        job_t fast, plain;
        job_start(&fast, &s, 0);
        job_start(&plain, &s, 1);
        assert_true(fast.f.bin_cap >= 1024 && fast.f.bin_cap < M);
        assert_int_equal(nf_fit_add_rows(&fast.f, pts, M, NULL), NF_OK);
        for (long t = 0; t < M; t++)
            assert_int_equal(nf_fit_add(&plain.f, pts[5 * t], pts[5 * t + 1], pts + 5 * t + 2, 1.0),
                             NF_OK);
        nf_accum_flush(&fast.f.acc); /* a corner may lack data: no finish */
        nf_accum_flush(&plain.f.acc);
        const ref_t pl = {&plain.f, NULL, NULL};
        same_store(&fast.f, pl, 1e-13);
        /* Dense reference: A = sum r r^T, b = sum r q over the non-zeros of r. */
        double *A = calloc((size_t)(n * n), sizeof(double)), *b = calloc((size_t)(3 * n), 8);
        for (long t = 0; t < M; t++) {
            ref_rbasis_row(&s, pts[5 * t], pts[5 * t + 1], row);
            for (long i = 0; i < n; i++) {
                if (row[i] == 0.0)
                    continue;
                for (long k = 0; k < n; k++)
                    if (row[k] != 0.0)
                        A[i * n + k] += row[i] * row[k];
                for (int c = 0; c < 3; c++)
                    b[3 * i + c] += row[i] * pts[5 * t + 2 + c];
            }
        }
        const ref_t dense = {NULL, A, b};
        same_store(&fast.f, dense, 1e-12);
        free(A);
        free(b);
        /* A bad row in the second window. */
        free(fast.mem);
        job_start(&fast, &s, 0);
        const long at = fast.f.bin_cap + 100;
        pts[5 * at + 3] = NAN;
        long bad = -1;
        assert_int_equal(nf_fit_add_rows(&fast.f, pts, M, &bad), NF_ENONFINITE);
        assert_int_equal(bad, at);
        assert_int_equal(fast.f.npoints, at);
        free(fast.mem);
        free(plain.mem);
        free(pts);
        free(row);
        ref_surf_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bicubic_polynomial), cmocka_unit_test(test_bicubic_rational),
        cmocka_unit_test(test_mixed_degrees),      cmocka_unit_test(test_weights_all_paths),
        cmocka_unit_test(test_span_search),        cmocka_unit_test(test_shard_budget),
        cmocka_unit_test(test_bad_row_index),      cmocka_unit_test(test_row_kernel),
        cmocka_unit_test(test_binned_random),      cmocka_unit_test(test_hook),
    };
    return cmocka_run_group_tests_name("accum", tests, NULL, NULL);
}
