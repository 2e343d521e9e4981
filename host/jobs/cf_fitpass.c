/* SPDX-License-Identifier: MIT */
/* cf_fitpass.c: one pass of Eq. 7 over u v x y z [w] rows in a caller's
 * block (cf_fitpass.h): the fitter (and a second core's shard) set up in
 * the block, rows accumulated, the sums merged and solved, and the
 * fitter's refusals in words. */
#include "cf_fitpass.h"
#include "cf_accum.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "nf_err.h"
#include <stdint.h>
#include <string.h>

/* The second core's nf_fit_t at the start of the block, at its own
 * alignment (32 where the accumulator keeps vectors) in a block aligned to
 * 16: room for the padding too. */
#define SHARD_STATE ((sizeof(nf_fit_t) + _Alignof(nf_fit_t) - 1 + 15) / 16 * 16)

long cf_fitpass_bytes(const nf_surf_t *s, nf_solver_t solver, int threads)
{
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, solver);
    if (need < 0 || threads < 2)
        return need;
    long sh = nf_fit_shard_bytes(s->nu, s->nv, s->p, s->q);
    return sh < 0 ? sh : (long)SHARD_STATE + need + sh;
}

/* Eq. 7's refusals in words: the control point left free, the bytes. */
static int fit_error(int rc, const cf_fitpass_t *ps, const char *name, char *msg, size_t ml)
{
    long b = ps->f.bad_index;
    const nf_surf_t *s = ps->s;
    int i = b >= 0 ? (int)(b % s->nu) : -1, k = b >= 0 ? (int)(b / s->nu) : -1;
    switch (rc) {
    case NF_ENODATA:
        return cf_fail(msg, ml, rc,
                       "%s: control point (%d, %d) has no data under it and alpha = beta = 0: "
                       "the points do not determine the surface (measure there, or give --beta)",
                       name, i, k);
    case NF_ESINGULAR:
        return cf_fail(msg, ml, rc,
                       "%s: the points do not determine the surface: control point (%d, %d) is "
                       "left free (numerically rank-deficient normal equations; give "
                       "--alpha/--beta > 0 or more data there)",
                       name, i, k);
    case NF_ENOCONV:
        return cf_fail(msg, ml, rc, "%s; try --solver chol or more --max-iter", nf_strerror(rc));
    case NF_EBUDGET:
        return cf_fail(msg, ml, rc,
                       "job needs %ld bytes, board %s allows %ld: %s (use fewer control "
                       "points or another solver)",
                       ps->f.need_bytes, BOARD_NAME, (long)NF_ARENA_BYTES, nf_strerror(rc));
    default: return cf_fail(msg, ml, rc, "%s: %s", name, nf_strerror(rc));
    }
}

int cf_fitpass_begin(cf_fitpass_t *ps, void *block, size_t bytes, const nf_surf_t *s, double alpha,
                     double beta, nf_solver_t solver, int threads, const char *name, char *msg,
                     size_t ml)
{
    memset(ps, 0, sizeof *ps);
    ps->s = s;
    ps->threads = threads > 1 ? 2 : 1;
    ps->t0 = cli_now();
    if (ps->threads > 1) {
        if (bytes < SHARD_STATE)
            return fit_error(NF_EARENA, ps, name, msg, ml);
        uintptr_t a =
            ((uintptr_t)block + _Alignof(nf_fit_t) - 1) & ~(uintptr_t)(_Alignof(nf_fit_t) - 1);
        ps->sh = (nf_fit_t *)a;
        block = (char *)block + SHARD_STATE;
        bytes -= SHARD_STATE;
    }
    nf_arena_init(&ps->ar, block, bytes);
    nf_fit_params_t prm = {alpha, beta, solver};
    int rc = nf_fit_init(&ps->f, s, &prm, &ps->ar);
    if (!rc && ps->threads > 1)
        rc = nf_fit_shard_init(ps->sh, &ps->f, &ps->ar);
    return rc ? fit_error(rc, ps, name, msg, ml) : 0;
}

int cf_fitpass_rows(cf_fitpass_t *ps, const double *rows, long n, int cols, long *bad)
{
    double t = cli_now();
    int rc = 0;
    long b = -1;
    if (cols == 5)
        rc = cf_accum_rows_hook(&ps->f, ps->threads > 1 ? ps->sh : NULL, ps->serial, rows, n, &b,
                                ps->hook, ps->hook_ctx);
    else
        for (long k = 0; k < n && !rc; k++) {
            const double *q = rows + 6 * k;
            b = k;
            if (q[5] > 0)
                rc = nf_fit_add(&ps->f, q[0], q[1], q + 2, q[5]);
            else if (q[5] == 0)
                ps->rejected++;
            else
                rc = NF_EWEIGHT;
        }
    if (rc && bad)
        *bad = b;
    ps->t_rows += cli_now() - t;
    return rc;
}

int cf_fitpass_row_error(const cf_fitpass_t *ps, int rc, const double *row, const char *at,
                         char *msg, size_t ml)
{
    if (rc != NF_EDOMAIN)
        return cf_fail(msg, ml, rc, "%s: %s", at, nf_strerror(rc));
    double u0, u1, v0, v1;
    nf_surf_domain(ps->s, &u0, &u1, &v0, &v1);
    return cf_fail(msg, ml, rc,
                   "%s: parameters (%.17g, %.17g) outside the knot domain [%.17g, %.17g] x "
                   "[%.17g, %.17g] of the base",
                   at, row[0], row[1], u0, u1, v0, v1);
}

int cf_fitpass_solve(cf_fitpass_t *ps, const nf_solve_opts_t *so, nf_surf_t *out, const char *name,
                     char *msg, size_t ml)
{
    double t1 = cli_now();
    int rc = 0;
    if (ps->threads > 1) { /* Eq. 9: the sums over points, in any grouping */
        rc = nf_fit_shard_merge(&ps->f, ps->sh);
        ps->threads = 1;
        ps->t_merge = cli_now() - t1;
        ps->t_rows += ps->t_merge;
    }
    double t2 = cli_now();
    if (!rc)
        rc = nf_fit_finish(&ps->f);
    /* A control point no data determine follows its pin target (the
     * nominal): beta_i in Eq. 7's beta term, after finish, before the solve. */
    for (long i = 0; !rc && ps->pin && i < ps->f.n; i++)
        if (ps->pin[i])
            rc = ps->pin_to ? nf_fit_pin_to(&ps->f, i, ps->pin_beta, ps->pin_to + 3 * i)
                            : nf_fit_pin(&ps->f, i, ps->pin_beta);
    if (!rc)
        rc = nf_fit_solve(&ps->f, ps->f.prm.solver, so, &ps->st);
    if (rc)
        return fit_error(rc, ps, name, msg, ml);
    memcpy(out->cp, ps->f.P, sizeof(double) * (size_t)(3 * ps->f.n));
    ps->t_acc = t2 - ps->t0;
    ps->t_solve = cli_now() - t2;
    return 0;
}

long cf_fitpass_points(const cf_fitpass_t *ps)
{
    return ps->f.npoints + (ps->threads > 1 ? ps->sh->npoints : 0);
}

long cf_fitpass_store_bytes(const cf_fitpass_t *ps)
{
    return ps->f.n * (long)ps->f.A.K * (long)sizeof(double);
}
