/* SPDX-License-Identifier: MIT */
/* bd_selftest.c: the built-in fits. Points are sampled from a "true" bicubic
 * surface on the same knots as the base, so with alpha = beta = 0 the least-
 * squares fit has the true net as its unique answer: a property to check,
 * not a stored result. */
#include "bd_selftest.h"
#include "bd_text.h"
#include "nf_budget.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_surf.h"

#define BD_P 3               /* bicubic: the degree the budgets are designed for */
#define BD_SMALL 8           /* side of the small net */
#define BD_SAMPLES 3         /* points per knot span and direction */
#define BD_EXACT_RESID 1e-14 /* stop of the iterative solvers in exact cases */
#ifndef BOARD_SOLVER
#define BOARD_SOLVER NF_SOLVER_AUTO
#endif

/* Storage for every net built here: N <= NF_MAX_CP + 4 control points (the
 * "over" case), so NF_SURF_DOUBLES = 4N + nu + nv + 2(p + 1) with
 * nu + nv <= N + 1. */
#define BD_CP_CAP (NF_MAX_CP + 4L)
#define BD_SURF_CAP (5L * BD_CP_CAP + 1L + 2L * (BD_P + 1))

_Static_assert(NF_MAX_CP >= BD_SMALL * BD_SMALL, "the small net must fit the board");
_Static_assert(NF_MAX_DEGREE >= BD_P, "bicubic must fit the board");

static double surf_mem[BD_SURF_CAP];
static double true_cp[3 * BD_CP_CAP];
static nf_surf_t base, truth;
static nf_fit_t fit; /* holds the accumulation buffers: too big for the stack */

/* Clamped uniform knots for n control points of degree p on [0, 1]. */
static void uniform_knots(double *U, int n, int p)
{
    for (int i = 0; i <= n + p; i++)
        U[i] = i <= p ? 0.0 : (i >= n ? 1.0 : (double)(i - p) / (n - p));
}

/* Base (nominal) and true surfaces of an nu x nv bicubic net sharing knots:
 * the truth is a smooth sheet with a bounded ripple, the nominal the truth
 * moved by up to 1.2 in z and 0.3 in x, y. 0 when the net does not fit. */
static int build(int nu, int nv)
{
    if (NF_SURF_DOUBLES(nu, nv, BD_P, BD_P) > BD_SURF_CAP || (long)nu * nv > BD_CP_CAP)
        return 0;
    nf_surf_wire(&base, BD_P, BD_P, nu, nv, surf_mem);
    uniform_knots(base.U, nu, BD_P);
    uniform_knots(base.V, nv, BD_P);
    truth = base;
    truth.cp = true_cp;
    truth.w = NULL;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double u = nf_greville(i, BD_P, base.U), v = nf_greville(j, BD_P, base.V);
            double *t = true_cp + 3 * (i + (long)j * nu), *b = base.cp + 3 * (i + (long)j * nu);
            const int ripple = (7 * i + 3 * j) % 5 - 2;
            t[0] = 100.0 * u;
            t[1] = 80.0 * v;
            t[2] = 5.0 * u * (1.0 - u) * (1.0 + v) + 2.0 * v * v + 0.25 * ripple;
            b[0] = t[0] + 0.3 * v;
            b[1] = t[1] - 0.3 * u;
            b[2] = t[2] - 1.0 - 0.2 * u * v;
        }
    return 1;
}

static double max_diff(const double *a, const double *b, long n)
{
    double m = 0.0;
    for (long i = 0; i < n; i++) {
        const double d = a[i] > b[i] ? a[i] - b[i] : b[i] - a[i];
        if (d > m || d != d)
            m = d;
    }
    return m;
}

typedef struct bd_case {
    const char *name;
    int nu, nv;
    double alpha, beta;
    nf_solver_t solver;
    int exact; /* 1: must reproduce the truth; 0: must beat the nominal */
} bd_case_t;

static int run_case(const bd_case_t *c, unsigned char *mem, size_t bytes, bd_emit_fn emit)
{
    char line[256];
    bd_text_t t;
    nf_arena_t ar;
    nf_solve_stats_t st = {c->solver, 0, 0.0};
    const nf_fit_params_t prm = {c->alpha, c->beta, c->solver};
    nf_solve_opts_t opt = NF_SOLVE_OPTS_DEFAULT;
    long points = 0;
    int rc = build(c->nu, c->nv) ? NF_OK : NF_ESIZE;

    /* The error in P is about cond(A) times the relative residual: exact
     * reproduction to BD_EXACT_TOL asks the iterative solvers for more
     * digits than the default stop. */
    if (c->exact)
        opt.tol = BD_EXACT_RESID;
    nf_arena_init(&ar, mem, bytes);
    if (rc == NF_OK)
        rc = nf_fit_init(&fit, &base, &prm, &ar);
    /* Samples on a uniform grid, BD_SAMPLES per span, ends included. */
    const int gu = BD_SAMPLES * (c->nu - BD_P) + 1, gv = BD_SAMPLES * (c->nv - BD_P) + 1;
    for (int b = 0; b < gv && rc == NF_OK; b++)
        for (int a = 0; a < gu && rc == NF_OK; a++) {
            const double u = (double)a / (gu - 1), v = (double)b / (gv - 1);
            double q[3];
            nf_surf_eval(&truth, u, v, q);
            rc = nf_fit_add(&fit, u, v, q, 1.0);
            points++;
        }
    if (rc == NF_OK)
        rc = nf_fit_finish(&fit);
    if (rc == NF_OK)
        rc = nf_fit_solve(&fit, c->solver, &opt, &st);

    const long n = (long)c->nu * c->nv;
    const double err = rc == NF_OK ? max_diff(fit.P, true_cp, 3 * n) : -1.0;
    const double dev0 = rc == NF_OK ? max_diff(base.cp, true_cp, 3 * n) : -1.0;
    const long used = (long)(ar.high + ar.skip);
    int ok = rc == NF_OK && st.rel_residual <= opt.tol && used <= fit.need_bytes &&
             (c->exact ? err <= BD_EXACT_TOL : err < dev0);

    bd_text_init(&t, line, sizeof line);
    bd_text_str(&t, "case=");
    bd_text_str(&t, c->name);
    bd_text_str(&t, " net=");
    bd_text_long(&t, c->nu);
    bd_text_str(&t, "x");
    bd_text_long(&t, c->nv);
    bd_text_str(&t, " points=");
    bd_text_long(&t, points);
    bd_text_str(&t, " rc=");
    bd_text_long(&t, rc);
    bd_text_str(&t, " solver=");
    bd_text_str(&t, nf_solver_name(st.solver));
    bd_text_str(&t, " iters=");
    bd_text_long(&t, st.iterations);
    bd_text_str(&t, " resid=");
    bd_text_sci(&t, st.rel_residual);
    bd_text_str(&t, " maxerr=");
    bd_text_sci(&t, err);
    bd_text_str(&t, " dev0=");
    bd_text_sci(&t, dev0);
    bd_text_str(&t, " need=");
    bd_text_long(&t, fit.need_bytes);
    bd_text_str(&t, " used=");
    bd_text_long(&t, used);
    bd_text_str(&t, ok ? " ok=1" : " ok=0");
    emit(line);
    return ok;
}

/* A net over NF_MAX_CP must be refused before any storage is taken, with
 * the bytes it would have needed. */
static int run_over(unsigned char *mem, size_t bytes, bd_emit_fn emit)
{
    char line[160];
    bd_text_t t;
    nf_arena_t ar;
    const nf_fit_params_t prm = {NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, NF_SOLVER_PCG};
    const int nv = BD_P + 1, nu = (int)(NF_MAX_CP / nv) + 1;
    int rc = build(nu, nv) ? NF_OK : NF_ESIZE;
    nf_arena_init(&ar, mem, bytes);
    if (rc == NF_OK)
        rc = nf_fit_init(&fit, &base, &prm, &ar);
    const long need = NF_BYTES_PCG((long)nu * nv, BD_P, BD_P);
    const int ok = rc == NF_EBUDGET && fit.need_bytes == need && ar.high == 0;
    bd_text_init(&t, line, sizeof line);
    bd_text_str(&t, "case=over net=");
    bd_text_long(&t, nu);
    bd_text_str(&t, "x");
    bd_text_long(&t, nv);
    bd_text_str(&t, " rc=");
    bd_text_long(&t, rc);
    bd_text_str(&t, " need=");
    bd_text_long(&t, fit.need_bytes);
    bd_text_str(&t, ok ? " ok=1" : " ok=0");
    emit(line);
    return ok;
}

/* Side of the largest square bicubic net within NF_MAX_CP and the arena,
 * found here from the macros, independently of nf_budget_max_square. */
static int largest_side(void)
{
    int s = BD_P + 1;
    while ((long)(s + 1) * (s + 1) <= NF_MAX_CP &&
           NF_BYTES_PCG((long)(s + 1) * (s + 1), BD_P, BD_P) <= NF_ARENA_BYTES)
        s++;
    return s;
}

int bd_selftest_run(unsigned char *arena, size_t bytes, bd_emit_fn emit)
{
    char line[200];
    bd_text_t t;
    const int big = largest_side();
    const bd_case_t cases[] = {
        {"exact-gs", BD_SMALL, BD_SMALL, 0.0, 0.0, NF_SOLVER_GS, 1},
        {"exact-chol", BD_SMALL, BD_SMALL, 0.0, 0.0, NF_SOLVER_CHOL, 1},
        {"exact-pcg", BD_SMALL, BD_SMALL, 0.0, 0.0, NF_SOLVER_PCG, 1},
        {"default", BD_SMALL, BD_SMALL, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, BOARD_SOLVER, 0},
        {"default-pcg", BD_SMALL, BD_SMALL, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, NF_SOLVER_PCG, 0},
        {"largest", big, big, 0.0, 0.0, NF_SOLVER_PCG, 1},
    };

    bd_text_init(&t, line, sizeof line);
    bd_text_str(&t, "board=" BOARD_NAME " arena=");
    bd_text_long(&t, (long)bytes);
    bd_text_str(&t, " max_cp=");
    bd_text_long(&t, NF_MAX_CP);
    bd_text_str(&t, " max_degree=");
    bd_text_long(&t, NF_MAX_DEGREE);
    bd_text_str(&t, " max_square_gs=");
    bd_text_long(&t, nf_budget_max_square(NF_ARENA_BYTES, BD_P, NF_SOLVER_GS));
    bd_text_str(&t, " max_square_chol=");
    bd_text_long(&t, nf_budget_max_square(NF_ARENA_BYTES, BD_P, NF_SOLVER_CHOL));
    bd_text_str(&t, " max_square_pcg=");
    bd_text_long(&t, nf_budget_max_square(NF_ARENA_BYTES, BD_P, NF_SOLVER_PCG));
    emit(line);

    int ok = 1;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        ok &= run_case(&cases[i], arena, bytes, emit);
    ok &= run_over(arena, bytes, emit);
    return ok;
}
