/* SPDX-License-Identifier: MIT */
/* nf_isa.c: the path of the hot kernels, chosen once, and the plain-named
 * entry points that forward to the baseline or the v3 copy (nf_isa.h). */
#include "nf_isa.h"
#include "nf_accum.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_quad.h"
#include "nf_solve.h"
#include "nf_stripe.h"
#include "nf_surf.h"

const char *nf_isa_name(nf_isa_t isa)
{
    switch (isa) {
    case NF_ISA_BASE: return "baseline";
    case NF_ISA_V3: return "x86-64-v3";
    default: return "auto";
    }
}

#if NF_ISA_DISPATCH
/* -1 until the first hot call or nf_isa_select settles it. Threads that
 * race on the first call compute the same answer; atomics keep that
 * defined behaviour. */
static int nf_isa_cur = -1;

int nf_isa_has_v3(void)
{
    /* libgcc's test includes the OS's support (XGETBV) for AVX state. */
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}

static int isa_settle(void)
{
    const int c = nf_isa_has_v3() ? NF_ISA_V3 : NF_ISA_BASE;
    __atomic_store_n(&nf_isa_cur, c, __ATOMIC_RELAXED);
    return c;
}

static inline int use_v3(void)
{
    int c = __atomic_load_n(&nf_isa_cur, __ATOMIC_RELAXED);
    if (__builtin_expect(c < 0, 0))
        c = isa_settle();
    return c == NF_ISA_V3;
}

nf_isa_t nf_isa_active(void)
{
    return use_v3() ? NF_ISA_V3 : NF_ISA_BASE;
}

int nf_isa_select(nf_isa_t isa)
{
    if (isa == NF_ISA_AUTO) {
        isa_settle();
        return NF_OK;
    }
    if (isa != NF_ISA_BASE && !(isa == NF_ISA_V3 && nf_isa_has_v3()))
        return NF_EARG;
    __atomic_store_n(&nf_isa_cur, (int)isa, __ATOMIC_RELAXED);
    return NF_OK;
}

/* Every hot entry point: R(ret, name, params, args) returns a value,
 * V(name, params, args) none. The same names as nf_isa_pass.h. */
#define NF_ISA_LIST(R, V)                                                                          \
    V(nf_accum_point, (nf_accum_t * ac, double u, double v, const double xyz[3], double wgt),      \
      (ac, u, v, xyz, wgt))                                                                        \
    V(nf_accum_point_at,                                                                           \
      (nf_accum_t * ac, double u, double v, int l, int k, const double xyz[3], double wgt),        \
      (ac, u, v, l, k, xyz, wgt))                                                                  \
    V(nf_accum_lone33, (nf_accum_t * ac, double u, double v, int l, int k, const double xyz[3]),   \
      (ac, u, v, l, k, xyz))                                                                       \
    R(long, nf_accum_rows33,                                                                       \
      (nf_accum_t * ac, const double *rows, long n, const double lim[4], const double dom[4]),     \
      (ac, rows, n, lim, dom))                                                                     \
    V(nf_accum_flush, (nf_accum_t * ac), (ac))                                                     \
    R(int, nf_chol_solve,                                                                          \
      (const nf_stripe_t *A, const double *b, double *x, nf_arena_t *ar, nf_solve_stats_t *st,     \
       long *bad),                                                                                 \
      (A, b, x, ar, st, bad))                                                                      \
    R(int, nf_fit_add, (nf_fit_t * f, double u, double v, const double xyz[3], double wgt),        \
      (f, u, v, xyz, wgt))                                                                         \
    R(int, nf_fit_add_rows, (nf_fit_t * f, const double *rows, long n, long *bad),                 \
      (f, rows, n, bad))                                                                           \
    R(int, nf_fit_shard_merge, (nf_fit_t * f, nf_fit_t * sh), (f, sh))                             \
    R(int, nf_fit_finish, (nf_fit_t * f), (f))                                                     \
    R(int, nf_fit_solve,                                                                           \
      (nf_fit_t * f, nf_solver_t solver, const nf_solve_opts_t *opt, nf_solve_stats_t *st),        \
      (f, solver, opt, st))                                                                        \
    R(int, nf_pcg_solve,                                                                           \
      (const nf_stripe_t *A, const double *b, double *x, const nf_solve_opts_t *o, nf_arena_t *ar, \
       nf_solve_stats_t *st, long *bad),                                                           \
      (A, b, x, o, ar, st, bad))                                                                   \
    R(int, nf_pcg_apply,                                                                           \
      (const nf_stripe_t *A, const double *d, double *t, double *q, double dq[3], int generic,     \
       nf_arena_t *ar),                                                                            \
      (A, d, t, q, dq, generic, ar))                                                               \
    V(nf_stripe_add_outer, (nf_stripe_t * st, long base, const double *R, double wgt),             \
      (st, base, R, wgt))                                                                          \
    V(nf_stripe_matvec, (const nf_stripe_t *st, const double *x, double *y), (st, x, y))           \
    R(int, nf_quad_init,                                                                           \
      (nf_quad_t * q, const nf_surf_t *s, const nf_quad_params_t *prm, long maxq, void *mem,       \
       size_t bytes),                                                                              \
      (q, s, prm, maxq, mem, bytes))                                                               \
    V(nf_quad_start, (const nf_quad_t *q, const double Q[3], double *u0, double *v0),              \
      (q, Q, u0, v0))                                                                              \
    R(int, nf_quad_newton,                                                                         \
      (const nf_quad_t *q, const double Q[3], double tol, double *u, double *v, nf_proj_t *out),   \
      (q, Q, tol, u, v, out))                                                                      \
    R(int, nf_quad_project, (nf_quad_t * q, const double Q[3], double tol, nf_proj_t *out),        \
      (q, Q, tol, out))                                                                            \
    V(nf_surf_eval, (const nf_surf_t *s, double u, double v, double out[3]), (s, u, v, out))       \
    R(int, nf_surf_rbasis, (const nf_surf_t *s, double u, double v, int *l, int *k, double *R),    \
      (s, u, v, l, k, R))                                                                          \
    V(nf_surf_derivs, (const nf_surf_t *s, double u, double v, int d, double skl[27]),             \
      (s, u, v, d, skl))

/* The two copies' names, declared here only (their modules define them
 * under the header's declaration, renamed). */
#define NF_ISA_DECL_R(ret, f, params, args)                                                        \
    ret f##_base params;                                                                           \
    ret f##_v3 params;
#define NF_ISA_DECL_V(f, params, args)                                                             \
    void f##_base params;                                                                          \
    void f##_v3 params;
NF_ISA_LIST(NF_ISA_DECL_R, NF_ISA_DECL_V)

/* The plain names, declared by the modules' headers: one predictable
 * branch on a value read once per call. */
#define NF_ISA_FWD_R(ret, f, params, args)                                                         \
    ret f params                                                                                   \
    {                                                                                              \
        return use_v3() ? f##_v3 args : f##_base args;                                             \
    }
#define NF_ISA_FWD_V(f, params, args)                                                              \
    void f params                                                                                  \
    {                                                                                              \
        if (use_v3())                                                                              \
            f##_v3 args;                                                                           \
        else                                                                                       \
            f##_base args;                                                                         \
    }
NF_ISA_LIST(NF_ISA_FWD_R, NF_ISA_FWD_V)

#else /* one copy: nothing to choose */
int nf_isa_has_v3(void)
{
    return 0;
}

nf_isa_t nf_isa_active(void)
{
    return NF_ISA_BASE;
}

int nf_isa_select(nf_isa_t isa)
{
    return isa == NF_ISA_BASE || isa == NF_ISA_AUTO ? NF_OK : NF_EARG;
}

double nf_isa_v3_fma_probe(double a, double b, double c)
{
    (void)a;
    (void)b;
    (void)c;
    return 0.0;
}
#endif
