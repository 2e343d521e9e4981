/* nf_fit.c: streaming assembly of the generalised normal equations (Eq. 7). */
#include "nf_fit.h"
#include "nf_basis.h"
#include "nf_err.h"
#include "nf_solve.h"

static int finite3(const double *x)
{
    return x[0] - x[0] == 0.0 && x[1] - x[1] == 0.0 && x[2] - x[2] == 0.0;
}

int nf_fit_init(nf_fit_t *f, const nf_surf_t *base, const nf_fit_params_t *prm, nf_arena_t *a)
{
    if (!f || !base || !prm || !a)
        return NF_EARG;
    f->need_bytes = -1;
    f->bad_index = -1;
    int rc = nf_surf_check(base);
    if (rc == NF_EBUDGET)
        f->need_bytes = nf_fit_bytes(base->nu, base->nv, base->p, base->q, prm->solver);
    if (rc)
        return rc;
    if (!(prm->alpha >= 0.0) || !(prm->beta >= 0.0) || prm->alpha - prm->alpha != 0.0 ||
        prm->beta - prm->beta != 0.0)
        return NF_EARG;
    f->need_bytes = nf_fit_bytes(base->nu, base->nv, base->p, base->q, prm->solver);
    if (f->need_bytes < 0 || f->need_bytes > NF_ARENA_BYTES)
        return NF_EBUDGET;
    if ((size_t)f->need_bytes > nf_arena_room(a))
        return NF_EARENA;

    const long n = (long)base->nu * base->nv;
    const int K = NF_STRIPE_SLOTS(base->p, base->q);
    double *S = nf_arena_doubles(a, (size_t)(n * K));
    f->rhs = nf_arena_doubles(a, (size_t)(3 * n));
    f->P = nf_arena_doubles(a, (size_t)(3 * n));
    if (!S || !f->rhs || !f->P)
        return NF_EARENA; /* unreachable when the formula is right */
    nf_stripe_init(&f->A, base->nu, base->nv, base->p, base->q, S);
    nf_accum_init(&f->acc, base, &f->A, f->rhs);
    for (long i = 0; i < 3 * n; i++)
        f->P[i] = base->cp[i]; /* P0: the nominal net is the start and the beta target */
    f->base = base;
    f->prm = *prm;
    f->arena = a;
    f->n = n;
    f->npoints = 0;
    f->sumw = 0.0;
    f->finished = 0;
    /* A store that fits in cache gains nothing from prefetching. */
    f->prefetch = (double)n * K * sizeof(double) > 8.0 * 1024 * 1024;
    f->pf_l = f->pf_k = -1;
    nf_surf_domain(base, &f->dom[0], &f->dom[1], &f->dom[2], &f->dom[3]);
    f->dtol[0] = 1e-12 * (f->dom[1] - f->dom[0]);
    f->dtol[1] = 1e-12 * (f->dom[3] - f->dom[2]);
    return NF_OK;
}

int nf_fit_add(nf_fit_t *f, double u, double v, const double xyz[3], double wgt)
{
    if (f->finished)
        return NF_ESTATE;
    if (!finite3(xyz) || u - u != 0.0 || v - v != 0.0 || !(wgt > 0.0) || wgt - wgt != 0.0)
        return NF_ENONFINITE;
    if (u < f->dom[0] - f->dtol[0] || u > f->dom[1] + f->dtol[0] || v < f->dom[2] - f->dtol[1] ||
        v > f->dom[3] + f->dtol[1])
        return NF_EDOMAIN;
    u = u < f->dom[0] ? f->dom[0] : (u > f->dom[1] ? f->dom[1] : u);
    v = v < f->dom[2] ? f->dom[2] : (v > f->dom[3] ? f->dom[3] : v);
    nf_accum_point(&f->acc, u, v, xyz, wgt);
    f->npoints++;
    f->sumw += wgt;
    return NF_OK;
}

/* Points this far ahead have their stripe rows prefetched: in random order
 * every point's 16 rows are cache misses, and the loads of later points can
 * overlap the arithmetic of this one. */
#define NF_PREFETCH_AHEAD 6

static void prefetch_point(nf_fit_t *f, double u, double v)
{
#if defined(__GNUC__)
    const nf_surf_t *s = f->base;
    if (!(u >= f->dom[0] && u <= f->dom[1] && v >= f->dom[2] && v <= f->dom[3]))
        return; /* nf_fit_add reports it */
    /* Raster scans stay in one span for many points, then step to the next
     * span in u, whose rows follow in memory: the hardware prefetcher has
     * them. Only a jump elsewhere is worth two searches and the prefetches. */
    if (f->pf_l >= 0 && v >= s->V[f->pf_k] && v < s->V[f->pf_k + 1] && u >= s->U[f->pf_l] &&
        u < s->U[f->pf_l + 2 < s->nu + 1 ? f->pf_l + 2 : s->nu]) {
        if (u >= s->U[f->pf_l + 1])
            f->pf_l++;
        return;
    }
    const int l = nf_find_span(s->nu - 1, s->p, u, s->U),
              k = nf_find_span(s->nv - 1, s->q, v, s->V);
    f->pf_l = l;
    f->pf_k = k;
    const long base = (l - s->p) + (long)(k - s->q) * s->nu, K = f->A.K;
    for (int b = 0; b <= s->q; b++) {
        const char *a = (const char *)(f->A.S + (base + (long)b * s->nu) * K);
        const long bytes = (long)(s->p + 1) * K * (long)sizeof(double);
        for (long o = 0; o < bytes; o += 64)
            __builtin_prefetch(a + o, 1, 3);
    }
#else
    (void)f;
    (void)u;
    (void)v;
#endif
}

int nf_fit_add_rows(nf_fit_t *f, const double *rows, long n, long *bad)
{
    for (long i = 0; i < n; i++) {
        const double *r = rows + 5 * i;
        if (i + NF_PREFETCH_AHEAD < n && f->prefetch)
            prefetch_point(f, r[5 * NF_PREFETCH_AHEAD], r[5 * NF_PREFETCH_AHEAD + 1]);
        int rc = nf_fit_add(f, r[0], r[1], r + 2, 1.0);
        if (rc) {
            if (bad)
                *bad = i;
            return rc;
        }
    }
    return NF_OK;
}

/* The alpha criterion: row r of (B - I) is the rational basis at control
 * point r's Greville point minus 1 at column r. Greville point r lies in
 * [U[i+1], U[i+p]], inside the support of basis function i, so column r is
 * one of the row's (p+1)(q+1) non-zeros and the row has exactly the pattern
 * of a measured point's row of R (Eq. 9): (B - I)^T (B - I) fills the same
 * stripes as R^T R and adds nothing to the right-hand side. */
static void add_alpha(nf_fit_t *f)
{
    const nf_surf_t *s = f->base;
    const int p = s->p, q = s->q, o = p + 1;
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER], R[NF_MAX_LOCAL];
    for (int j = 0; j < s->nv; j++) {
        double vg = nf_greville(j, q, s->V);
        int k = nf_find_span(s->nv - 1, q, vg, s->V);
        k = k < j ? j : (k > j + q ? j + q : k); /* keep column j in the span */
        k = k < q ? q : (k > s->nv - 1 ? s->nv - 1 : k);
        nf_basis_funs(k, vg, q, s->V, Nv);
        for (int i = 0; i < s->nu; i++) {
            double ug = nf_greville(i, p, s->U);
            int l = nf_find_span(s->nu - 1, p, ug, s->U);
            l = l < i ? i : (l > i + p ? i + p : l);
            l = l < p ? p : (l > s->nu - 1 ? s->nu - 1 : l);
            nf_basis_funs(l, ug, p, s->U, Nu);
            double W = 0.0;
            for (int b = 0; b <= q; b++)
                for (int a = 0; a <= p; a++) {
                    double w = s->w ? s->w[(l - p + a) + (long)(k - q + b) * s->nu] : 1.0;
                    R[a + b * o] = Nu[a] * Nv[b] * w;
                    W += R[a + b * o];
                }
            for (int t = 0; t < o * (q + 1); t++)
                R[t] /= W;
            R[(i - (l - p)) + (j - (k - q)) * o] -= 1.0;
            nf_stripe_add_outer(&f->A, (l - p) + (long)(k - q) * s->nu, R, f->prm.alpha);
        }
    }
}

int nf_fit_finish(nf_fit_t *f)
{
    if (f->finished)
        return NF_ESTATE;
    nf_accum_flush(&f->acc);
    const int K = f->A.K;
    if (f->prm.alpha == 0.0 && f->prm.beta == 0.0) {
        for (long i = 0; i < f->n; i++)
            if (f->A.S[i * K] == 0.0) { /* (R^T R)_ii = sum of R_ki^2 = 0: no data */
                f->bad_index = i;
                return NF_ENODATA;
            }
    }
    if (f->prm.alpha > 0.0)
        add_alpha(f);
    if (f->prm.beta > 0.0) {
        const double *P0 = f->base->cp;
        for (long i = 0; i < f->n; i++) {
            f->A.S[i * K] += f->prm.beta;
            f->rhs[3 * i] += f->prm.beta * P0[3 * i];
            f->rhs[3 * i + 1] += f->prm.beta * P0[3 * i + 1];
            f->rhs[3 * i + 2] += f->prm.beta * P0[3 * i + 2];
        }
    }
    f->finished = 1;
    return NF_OK;
}

int nf_fit_solve(nf_fit_t *f, nf_solver_t solver, const nf_solve_opts_t *opt, nf_solve_stats_t *st)
{
    if (!f->finished)
        return NF_ESTATE;
    const nf_surf_t *s = f->base;
    if (solver == NF_SOLVER_AUTO)
        solver = nf_solver_pick(s->nu, s->nv, s->p, s->q);
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, solver);
    if (need < 0 || need > NF_ARENA_BYTES) {
        f->need_bytes = need;
        return NF_EBUDGET;
    }
    nf_solve_opts_t o = NF_SOLVE_OPTS_DEFAULT;
    if (opt)
        o = *opt;
    nf_solve_stats_t tmp;
    if (!st)
        st = &tmp;
    st->solver = solver;
    st->iterations = 0;
    st->rel_residual = 0.0;
    size_t mark = nf_arena_mark(f->arena);
    int rc;
    switch (solver) {
    case NF_SOLVER_GS:
        rc = nf_gs_solve(&f->A, f->rhs, f->P, &o, f->arena, st, &f->bad_index);
        break;
    case NF_SOLVER_CHOL:
        rc = nf_chol_solve(&f->A, f->rhs, f->P, f->arena, st, &f->bad_index);
        break;
    case NF_SOLVER_PCG:
        rc = nf_pcg_solve(&f->A, f->rhs, f->P, &o, f->arena, st, &f->bad_index);
        break;
    default: rc = NF_ESOLVER; break;
    }
    nf_arena_release(f->arena, mark);
    return rc;
}
