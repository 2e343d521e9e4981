/* SPDX-License-Identifier: MIT */
/* ref_kloop.c: the fit -> check -> insert loop on firmware calls alone. */
#include "ref_kloop.h"
#include "nf_budget.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_project.h"
#include "nf_refine.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void ref_kloop_surf(nf_surf_t *s, int p, int q, int nu, int nv)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, p, q), sizeof(double));
    nf_surf_wire(s, p, q, nu, nv, mem);
}

void ref_kloop_copy(nf_surf_t *dst, const nf_surf_t *src)
{
    ref_kloop_surf(dst, src->p, src->q, src->nu, src->nv);
    memcpy(dst->U, src->U, sizeof(double) * (size_t)(src->nu + src->p + 1));
    memcpy(dst->V, src->V, sizeof(double) * (size_t)(src->nv + src->q + 1));
    memcpy(dst->cp, src->cp, sizeof(double) * 3 * (size_t)src->nu * (size_t)src->nv);
    for (long i = 0; i < (long)src->nu * src->nv; i++)
        dst->w[i] = src->w ? src->w[i] : 1.0;
}

double ref_kloop_dist(const nf_surf_t *s, const double *r)
{
    double S[3];
    nf_surf_eval(s, r[0], r[1], S);
    return sqrt((S[0] - r[2]) * (S[0] - r[2]) + (S[1] - r[3]) * (S[1] - r[3]) +
                (S[2] - r[4]) * (S[2] - r[4]));
}

double ref_kloop_pdist(const nf_surf_t *s, const double *r)
{
    nf_proj_t pr;
    int rc = nf_project(s, r + 2, r[0], r[1], 1e-9, &pr);
    return rc == NF_OK || rc == NF_ENOCONV ? fabs(pr.dist) : ref_kloop_dist(s, r);
}

/* Eq. 7 on the net of cur (its control points are P0), solved into fit. */
static int fit_once(const nf_surf_t *cur, const double *pts, long M, double alpha, double beta,
                    nf_surf_t *fit)
{
    nf_fit_params_t prm = {alpha, beta, NF_SOLVER_AUTO};
    long need = nf_fit_bytes(cur->nu, cur->nv, cur->p, cur->q, NF_SOLVER_AUTO);
    if (need < 0)
        return NF_EBUDGET;
    void *mem = malloc((size_t)need);
    nf_arena_t ar;
    nf_fit_t f;
    nf_arena_init(&ar, mem, (size_t)need);
    int rc = nf_fit_init(&f, cur, &prm, &ar);
    long bad;
    if (!rc)
        rc = nf_fit_add_rows(&f, pts, M, &bad);
    if (!rc)
        rc = nf_fit_finish(&f);
    nf_solve_opts_t o = NF_SOLVE_OPTS_DEFAULT;
    o.probe = 0; /* alpha > 0 determines every control point */
    if (!rc)
        rc = nf_fit_solve(&f, NF_SOLVER_AUTO, &o, NULL);
    if (!rc) {
        ref_kloop_copy(fit, cur);
        memcpy(fit->cp, f.P, sizeof(double) * 3 * (size_t)f.n);
    }
    free(mem);
    return rc;
}

/* The next net: the chosen knots (or every span halved) inserted into fit. */
static int refine(const nf_surf_t *fit, const nf_knotsel_cand_t *c, int n, int uniform,
                  nf_surf_t *nxt)
{
    int rc, nu, nv;
    if (uniform) {
        if ((rc = nf_refine_uniform_size(fit, &nu, &nv)) != NF_OK)
            return rc;
        ref_kloop_surf(nxt, fit->p, fit->q, nu, nv);
        return nf_refine_uniform(fit, nxt);
    }
    double *Xu = malloc(sizeof(double) * (size_t)(n + 1)),
           *Xv = malloc(sizeof(double) * (size_t)(n + 1));
    int ru, rv;
    nf_surf_t tmp;
    rc = nf_knotsel_split(c, n, Xu, n, &ru, Xv, n, &rv);
    if (!rc) {
        ref_kloop_surf(&tmp, fit->p, fit->q, fit->nu + ru, fit->nv);
        ref_kloop_surf(nxt, fit->p, fit->q, fit->nu + ru, fit->nv + rv);
        rc = nf_refine_u(fit, Xu, ru, &tmp);
        if (!rc)
            rc = nf_refine_v(&tmp, Xv, rv, nxt);
        free(tmp.U);
    }
    free(Xu);
    free(Xv);
    return rc;
}

int ref_kloop_run(const nf_surf_t *base, const double *pts, long M, const ref_kloop_cfg_t *c,
                  ref_kloop_out_t *o)
{
    nf_surf_t cur, fit;
    int rc = NF_OK;
    double *w = NULL; /* the points at their current parameters (reparam) */
    if (c->reparam) {
        w = malloc(sizeof(double) * 5 * (size_t)M);
        memcpy(w, pts, sizeof(double) * 5 * (size_t)M);
        pts = w;
    }
    nf_loopctl_t lc;
    nf_loopctl_init(&lc);
    memset(o, 0, sizeof *o);
    o->within_pct = -1.0;
    ref_kloop_copy(&cur, base);
    for (int round = 0;; round++) {
        const double alpha =
            c->scale_alpha ? nf_loopctl_alpha(c->alpha, base, &cur, c->alpha_k) : c->alpha;
        if ((rc = fit_once(&cur, pts, M, alpha, c->beta, &fit)) != NF_OK) {
            free(cur.U);
            free(w);
            return rc;
        }
        free(cur.U);
        cur.U = NULL;
        /* Check pass: distances at the points' parameters, per span. */
        const int ncand = NF_KNOTSEL_CANDS(fit.nu, fit.nv, fit.p, fit.q);
        double *mem =
            malloc(sizeof(double) * (size_t)NF_KNOTSEL_DOUBLES(fit.nu, fit.nv, fit.p, fit.q));
        nf_knotsel_cand_t *cand = malloc(sizeof *cand * (size_t)ncand);
        nf_knotsel_t a;
        nf_knotsel_init(&a, &fit, c->tol, mem);
        long within = 0;
        double ss = 0.0, mx = 0.0;
        for (long k = 0; k < M; k++) {
            double d;
            if (w) {
                nf_proj_t pr;
                double *r = w + 5 * k;
                int prc = nf_project(&fit, r + 2, r[0], r[1], 1e-9, &pr);
                if (prc == NF_OK || prc == NF_ENOCONV) {
                    r[0] = pr.u;
                    r[1] = pr.v;
                }
                d = ref_kloop_dist(&fit, r);
            } else {
                d = ref_kloop_dist(&fit, pts + 5 * k);
            }
            nf_knotsel_add(&a, pts[5 * k], pts[5 * k + 1], d);
            within += d <= c->tol;
            ss += d * d;
            mx = d > mx ? d : mx;
        }
        const double pct = 100.0 * (double)within / (double)M, rms = sqrt(ss / (double)M);
        int n = 0, st = NF_KNOTSEL_INSERT;
        if (c->uniform) {
            int nu, nv;
            long cap = c->max_cp > 0 && c->max_cp < NF_MAX_CP ? c->max_cp : NF_MAX_CP;
            if (nf_refine_uniform_size(&fit, &nu, &nv) != NF_OK || (long)nu * nv > cap)
                st = NF_KNOTSEL_MAX_CP;
            else if ((long)nu * nv > M / 2)
                st = NF_KNOTSEL_HALF_PTS;
        } else {
            nf_knotsel_opts_t so = c->sel;
            so.max_cp = c->max_cp;
            if (c->budget) {
                nf_loopctl_record(&lc, pct, (long)fit.nu * fit.nv);
                so.max_add = nf_loopctl_budget(&lc, c->within, fit.nu < fit.nv ? fit.nu : fit.nv);
                so.per_span = so.per_span > 0 ? so.per_span : nf_loopctl_per_span(pct, c->within);
            }
            nf_knotsel_choose(&a, &so, cand, ncand, &n, &st);
        }
        nf_loopctl_t fresh; /* without the progress test: never a previous round */
        nf_loopctl_init(&fresh);
        const int v = nf_loopctl_verdict(c->progress ? &lc : &fresh, pct, c->within, c->min_gain,
                                         round, c->max_rounds, st);
        if (c->verbose)
            fprintf(stderr,
                    "  round %d: %d x %d, alpha %.3g, %.3f %% within, rms %.4g, max %.4g; %s, %d "
                    "knots -> %s\n",
                    round, fit.nu, fit.nv, alpha, pct, rms, mx, nf_knotsel_status_str(st), n,
                    nf_loopctl_str(v));
        o->rounds = round + 1;
        if (pct > o->within_pct || (pct == o->within_pct && rms < o->rms)) {
            if (o->fit.U)
                free(o->fit.U);
            ref_kloop_copy(&o->fit, &fit);
            o->within_pct = pct;
            o->rms = rms;
            o->mx = mx;
            o->cp = (long)fit.nu * fit.nv;
        }
        if (v == NF_LOOPCTL_CONTINUE)
            rc = refine(&fit, cand, n, c->uniform, &cur);
        free(mem);
        free(cand);
        free(fit.U);
        if (v != NF_LOOPCTL_CONTINUE) {
            o->verdict = v;
            free(w);
            return NF_OK;
        }
        if (rc) {
            free(cur.U);
            free(w);
            return rc;
        }
    }
}

void ref_kloop_free(ref_kloop_out_t *o)
{
    free(o->fit.U);
    o->fit.U = NULL;
}
