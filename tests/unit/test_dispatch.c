/* SPDX-License-Identifier: MIT */
/* test_dispatch.c: the two paths of the hot kernels (firmware/nf_isa.h),
 * forced in turn on the same fits: accumulation (raster rows, random order
 * in bins, weighted single points), finish, the three solvers, evaluation
 * and derivatives. Without fused multiply-adds in the v3 copy (gcc's C11
 * default) every value must be the same to the last bit; with them (clang,
 * -ffp-contract=fast) within 1e-12 of the array's largest value. The
 * baseline path itself is checked against a dense Gaussian elimination of
 * Eq. 7 (ref_dense.c). On a CPU without AVX2 (qemu -cpu Westmere) the v3
 * path is refused and its comparisons are skipped. */
#include "cf_test.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_isa.h"
#include "nf_solve.h"
#include "ref_dense.h"
#include <stdlib.h>
#include <string.h>

/* What one fit produces, every value a path computes. */
typedef struct outs {
    double *S, *rhs, *P, *ev; /* stripes and R^T Q after finish, solution, evaluations */
    long nS, n, nev;
    int iters;
} outs_t;

typedef struct fit_case {
    int p, q, nu, nv;
    double wlo;         /* weights in [wlo, 2] (1: polynomial) */
    nf_solver_t solver; /* the solver of the comparison */
    int weighted;       /* also single points of weight != 1 (nf_fit_add) */
    unsigned long long seed;
} fit_case_t;

#define RASTER_COLS 151
#define RASTER_ROWS 37
#define RANDOM_PTS 12000L
#define EVAL_SIDE 23

/* Points on s plus noise: a raster (rows of one v) then random order. */
static double *make_points(const nf_surf_t *s, long *m)
{
    const long mr = (long)RASTER_COLS * RASTER_ROWS, M = mr + RANDOM_PTS;
    double *pts = malloc(sizeof(double) * (size_t)(5 * M));
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (long k = 0; k < M; k++) {
        double *r = pts + 5 * k;
        if (k < mr) {
            r[0] = u0 + (u1 - u0) * (double)(k % RASTER_COLS) / (RASTER_COLS - 1);
            r[1] = v0 + (v1 - v0) * (double)(k / RASTER_COLS) / (RASTER_ROWS - 1);
        } else {
            r[0] = ref_rand(u0, u1);
            r[1] = ref_rand(v0, v1);
        }
        nf_surf_eval(s, r[0], r[1], r + 2);
        for (int c = 0; c < 3; c++)
            r[2 + c] += ref_rand(-0.05, 0.05);
    }
    *m = M;
    return pts;
}

static double *dup(const double *a, long n)
{
    double *b = malloc(sizeof(double) * (size_t)n);
    memcpy(b, a, sizeof(double) * (size_t)n);
    return b;
}

/* One whole fit of pts onto s on path isa. */
static void run_fit(nf_isa_t isa, const fit_case_t *c, const nf_surf_t *s, const double *pts,
                    long M, outs_t *o)
{
    assert_int_equal(nf_isa_select(isa), NF_OK);
    assert_int_equal(nf_isa_active(), isa);
    /* Sized for Cholesky, the largest: room for the bins of random order. */
    nf_fit_params_t prm = {NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, NF_SOLVER_CHOL};
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, NF_SOLVER_CHOL);
    long pcg = nf_fit_bytes(s->nu, s->nv, s->p, s->q, NF_SOLVER_PCG);
    need = pcg > need ? pcg : need;
    void *mem = malloc((size_t)need);
    nf_arena_t ar;
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_t f;
    assert_int_equal(nf_fit_init(&f, s, &prm, &ar), NF_OK);
    if (f.n >= 1024) /* NF_BIN_MIN: the random part goes through the bins */
        assert_true(f.bin_cap >= 1024);
    assert_int_equal(nf_fit_add_rows(&f, pts, M, NULL), NF_OK);
    if (c->weighted)
        for (long k = 0; k < 200; k++) {
            const double *r = pts + 5 * (k * 37 % M);
            assert_int_equal(nf_fit_add(&f, r[0], r[1], r + 2, 0.25 + 0.01 * (double)k), NF_OK);
        }
    assert_int_equal(nf_fit_finish(&f), NF_OK);
    o->n = f.n;
    o->nS = f.n * f.A.K;
    o->S = dup(f.A.S, o->nS);
    o->rhs = dup(f.rhs, 3 * f.n);
    nf_solve_opts_t opt = NF_SOLVE_OPTS_DEFAULT;
    opt.tol = 1e-14; /* both paths solved to rounding, whatever their iterates */
    nf_solve_stats_t st;
    assert_int_equal(nf_fit_solve(&f, c->solver, &opt, &st), NF_OK);
    o->iters = st.iterations;
    o->P = dup(f.P, 3 * f.n);
    /* The fitted surface evaluated and differentiated on a grid. */
    nf_surf_t fit = *s;
    fit.cp = o->P;
    o->nev = (long)EVAL_SIDE * EVAL_SIDE * 30;
    o->ev = malloc(sizeof(double) * (size_t)o->nev);
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (int i = 0; i < EVAL_SIDE; i++)
        for (int j = 0; j < EVAL_SIDE; j++) {
            double *e = o->ev + 30 * (i * EVAL_SIDE + j);
            const double u = u0 + (u1 - u0) * i / (EVAL_SIDE - 1),
                         v = v0 + (v1 - v0) * j / (EVAL_SIDE - 1);
            nf_surf_eval(&fit, u, v, e);
            nf_surf_derivs(&fit, u, v, 2, e + 3);
        }
    free(mem);
    assert_int_equal(nf_isa_select(NF_ISA_AUTO), NF_OK);
}

static void outs_free(outs_t *o)
{
    free(o->S);
    free(o->rhs);
    free(o->P);
    free(o->ev);
}

/* a and b: the same bits (exact), or within 1e-12 of a's largest value. */
static void agree(const char *what, const double *a, const double *b, long n, int exact)
{
    double m = 0.0, d = 0.0;
    long differ = 0;
    for (long i = 0; i < n; i++) {
        m = fabs(a[i]) > m ? fabs(a[i]) : m;
        d = fabs(a[i] - b[i]) > d ? fabs(a[i] - b[i]) : d;
        differ += memcmp(a + i, b + i, sizeof(double)) != 0;
    }
    print_message("  %-10s %7ld values, %6ld differ in some bit, max |diff| %.3g (%.3g of max)\n",
                  what, n, differ, d, m > 0.0 ? d / m : 0.0);
    if (exact && differ)
        fail_msg("%s: %ld values differ between the paths without FMA", what, differ);
    if (!(d <= 1e-12 * m))
        fail_msg("%s: paths differ by %.3g, more than 1e-12 of %.3g", what, d, m);
}

/* Does the v3 copy fuse a * b + c? 1 + 2^-30 times 1 - 2^-30 is 1 - 2^-60,
 * which rounds to 1: plain arithmetic gives 0, a fused one -2^-60. */
static int v3_fuses(void)
{
    const double e = 1.0 / 1073741824.0;
    return nf_isa_v3_fma_probe(1.0 + e, 1.0 - e, -1.0) != 0.0;
}

static void compare_paths(const fit_case_t *c)
{
    if (!nf_isa_has_v3()) {
        assert_int_equal(nf_isa_select(NF_ISA_V3), NF_EARG);
        skip(); /* no second path on this CPU (or build) */
    }
    ref_seed(c->seed);
    nf_surf_t s;
    ref_surf_random(&s, c->p, c->q, c->nu, c->nv, 0, 1, 0, 1, c->wlo, c->wlo < 1.0 ? 2.0 : 1.0);
    long M;
    double *pts = make_points(&s, &M);
    outs_t base, v3;
    run_fit(NF_ISA_BASE, c, &s, pts, M, &base);
    run_fit(NF_ISA_V3, c, &s, pts, M, &v3);
    const int exact = !v3_fuses();
    print_message("  %dx%d net %dx%d, %s, %ld points, %d iterations; v3 copy %s\n", c->p, c->q,
                  c->nu, c->nv, c->wlo < 1.0 ? "rational" : "polynomial", M, base.iters,
                  exact ? "without FMA: bit for bit" : "with FMA: within 1e-12");
    agree("stripes", base.S, v3.S, base.nS, exact);
    agree("R^T Q", base.rhs, v3.rhs, 3 * base.n, exact);
    agree("solution", base.P, v3.P, 3 * base.n, exact);
    agree("surface", base.ev, v3.ev, base.nev, exact);
    if (exact)
        assert_int_equal(base.iters, v3.iters);
    outs_free(&base);
    outs_free(&v3);
    free(pts);
    ref_surf_free(&s);
}

static void test_paths_bicubic_pcg(void **state)
{
    (void)state;
    const fit_case_t c = {3, 3, 36, 34, 1.0, NF_SOLVER_PCG, 1, 11};
    compare_paths(&c);
}

static void test_paths_bicubic_chol_gs(void **state)
{
    (void)state;
    fit_case_t c = {3, 3, 33, 35, 1.0, NF_SOLVER_CHOL, 0, 12};
    compare_paths(&c);
    c.solver = NF_SOLVER_GS;
    c.seed = 13;
    compare_paths(&c);
}

static void test_paths_rational_and_other_degrees(void **state)
{
    (void)state;
    fit_case_t c = {3, 3, 18, 17, 0.5, NF_SOLVER_PCG, 1, 14};
    compare_paths(&c);
    c = (fit_case_t){2, 3, 19, 14, 1.0, NF_SOLVER_PCG, 1, 15};
    compare_paths(&c);
    c = (fit_case_t){4, 2, 15, 16, 0.5, NF_SOLVER_CHOL, 1, 16};
    compare_paths(&c);
}

/* The baseline path (which a CPU without AVX2 runs) against the dense,
 * independently built Eq. 7: raster rows and random order as above (a net
 * below NF_BIN_MIN control points, so no bins: test_accum.c has them). */
static void test_baseline_against_dense(void **state)
{
    (void)state;
    ref_seed(21);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 15, 13, 0, 1, 0, 1, 1.0, 1.0);
    long M;
    double *pts = make_points(&s, &M);
    const fit_case_t c = {3, 3, 15, 13, 1.0, NF_SOLVER_PCG, 0, 21};
    outs_t o;
    run_fit(NF_ISA_BASE, &c, &s, pts, M, &o);
    double *A, *b, *x = malloc(sizeof(double) * (size_t)(3 * o.n));
    ref_eq7(&s, pts, M, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, &A, &b);
    assert_int_equal(ref_solve(A, b, o.n, x), 0);
    double m = 0.0;
    for (long i = 0; i < 3 * o.n; i++)
        m = fabs(x[i]) > m ? fabs(x[i]) : m;
    for (long i = 0; i < 3 * o.n; i++)
        assert_near(o.P[i], x[i], 1e-9 * m);
    free(A);
    free(b);
    free(x);
    outs_free(&o);
    free(pts);
    ref_surf_free(&s);
}

/* Selection: baseline always; v3 exactly when the CPU has it; AUTO takes
 * the best; a refused request leaves the path as it was. */
static void test_select(void **state)
{
    (void)state;
    assert_int_equal(nf_isa_select(NF_ISA_BASE), NF_OK);
    assert_int_equal(nf_isa_active(), NF_ISA_BASE);
    const int has = nf_isa_has_v3();
    assert_int_equal(nf_isa_select(NF_ISA_V3), has ? NF_OK : NF_EARG);
    assert_int_equal(nf_isa_active(), has ? NF_ISA_V3 : NF_ISA_BASE);
    assert_int_equal(nf_isa_select((nf_isa_t)7), NF_EARG);
    assert_int_equal(nf_isa_active(), has ? NF_ISA_V3 : NF_ISA_BASE);
    assert_int_equal(nf_isa_select(NF_ISA_AUTO), NF_OK);
    assert_int_equal(nf_isa_active(), has ? NF_ISA_V3 : NF_ISA_BASE);
    assert_string_equal(nf_isa_name(NF_ISA_BASE), "baseline");
    assert_string_equal(nf_isa_name(NF_ISA_V3), "x86-64-v3");
    print_message("  this CPU and build: %s path\n", nf_isa_name(nf_isa_active()));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_select),
        cmocka_unit_test(test_baseline_against_dense),
        cmocka_unit_test(test_paths_bicubic_pcg),
        cmocka_unit_test(test_paths_bicubic_chol_gs),
        cmocka_unit_test(test_paths_rational_and_other_degrees),
    };
    return cmocka_run_group_tests_name("dispatch", tests, NULL, NULL);
}
