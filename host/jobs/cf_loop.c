/* SPDX-License-Identifier: MIT */
/* cf_loop.c: next net of the fitting loop (uniform or residual-driven knot
 * insertion, within the limits) and the round records. */
#include "cf_loop.h"
#include "cf_err.h"
#include "cf_json.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_refine.h"
#include <stdlib.h>
#include <string.h>

int cf_loop_next(const nf_surf_t *fit, const nf_spanres_t *sr, cf_refine_t how, long max_cp,
                 nf_solver_t solver, nf_surf_t *nxt, int *stop, char *msg, size_t ml)
{
    int nu2, nv2, ru = 0, rv = 0, rc;
    double *Xu = NULL, *Xv = NULL;
    *stop = CF_LOOP_STOP_MAX_CP;
    if (how == CF_REFINE_UNIFORM) {
        rc = nf_refine_uniform_size(fit, &nu2, &nv2);
        if (rc == NF_EBUDGET)
            return cf_fail(msg, ml, CF_OK,
                           "the next net would exceed the board's %ld control points",
                           (long)NF_MAX_CP);
        if (rc)
            return cf_fail(msg, ml, rc, "refinement: %s", nf_strerror(rc));
    } else {
        if (!sr)
            return cf_fail(msg, ml, CF_EARG, "residual refinement without span counts");
        Xu = malloc(sizeof(double) * (size_t)fit->nu);
        Xv = malloc(sizeof(double) * (size_t)fit->nv);
        if (!Xu || !Xv) {
            free(Xu);
            free(Xv);
            return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        }
        nf_spanres_choose(sr, fit->nu - fit->p, Xu, &ru, fit->nv - fit->q, Xv, &rv);
        nu2 = fit->nu + ru;
        nv2 = fit->nv + rv;
    }
    long ncp = (long)nu2 * nv2, need = nf_fit_bytes(nu2, nv2, fit->p, fit->q, solver);
    rc = CF_OK;
    if (how == CF_REFINE_RESIDUAL && ru + rv == 0) {
        *stop = CF_LOOP_STOP_DATA;
        cf_fail(msg, ml, CF_OK, "no knot span left to split");
    } else if (ncp > max_cp || ncp > NF_MAX_CP)
        cf_fail(msg, ml, CF_OK, "the next net (%d x %d = %ld control points) would exceed %s %ld",
                nu2, nv2, ncp, ncp > max_cp ? "--max-cp" : "the board's",
                ncp > max_cp ? max_cp : (long)NF_MAX_CP);
    else if (need < 0 || need > NF_ARENA_BYTES)
        cf_fail(msg, ml, CF_OK, "the next net (%d x %d) would need %ld bytes, board %s allows %ld",
                nu2, nv2, need, BOARD_NAME, (long)NF_ARENA_BYTES);
    else {
        /* Refine: uniform in one go, else u into tmp and then v. */
        nf_surf_t tmp;
        memset(&tmp, 0, sizeof tmp);
        if (cf_surf_alloc(nxt, fit->p, fit->q, nu2, nv2) ||
            (how == CF_REFINE_RESIDUAL && cf_surf_alloc(&tmp, fit->p, fit->q, nu2, fit->nv)))
            rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        else if (how == CF_REFINE_UNIFORM)
            rc = nf_refine_uniform(fit, nxt);
        else if (!(rc = nf_refine_u(fit, Xu, ru, &tmp)))
            rc = nf_refine_v(&tmp, Xv, rv, nxt);
        cf_surf_free(&tmp);
        if (rc) {
            cf_surf_free(nxt);
            if (rc != CF_ENOMEM)
                cf_fail(msg, ml, rc, "knot insertion: %s", nf_strerror(rc));
        } else
            *stop = CF_LOOP_GO;
    }
    free(Xu);
    free(Xv);
    return rc;
}

const char *cf_refine_name(cf_refine_t how)
{
    return how == CF_REFINE_UNIFORM ? "uniform" : how == CF_REFINE_RESIDUAL ? "residual" : "auto";
}

int cf_loop_insert(const nf_surf_t *fit, const nf_knotsel_cand_t *c, int n, long max_cp,
                   nf_solver_t solver, nf_surf_t *nxt, int *stop, char *msg, size_t ml)
{
    int ru = 0, rv = 0, rc;
    *stop = CF_LOOP_STOP_DATA;
    if (n <= 0) {
        cf_fail(msg, ml, CF_OK, "no knot span with data enough to split");
        return CF_OK;
    }
    double *Xu = malloc(sizeof(double) * (size_t)n), *Xv = malloc(sizeof(double) * (size_t)n);
    if (!Xu || !Xv) {
        free(Xu);
        free(Xv);
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    }
    rc = nf_knotsel_split(c, n, Xu, n, &ru, Xv, n, &rv);
    int nu2 = fit->nu + ru, nv2 = fit->nv + rv;
    long ncp = (long)nu2 * nv2, need = nf_fit_bytes(nu2, nv2, fit->p, fit->q, solver);
    *stop = CF_LOOP_STOP_MAX_CP;
    if (rc)
        rc = cf_fail(msg, ml, rc, "knot selection: %s", nf_strerror(rc));
    else if (ncp > max_cp || ncp > NF_MAX_CP)
        cf_fail(msg, ml, CF_OK, "the next net (%d x %d = %ld control points) would exceed %s %ld",
                nu2, nv2, ncp, ncp > max_cp ? "--max-cp" : "the board's",
                ncp > max_cp ? max_cp : (long)NF_MAX_CP);
    else if (need < 0 || need > NF_ARENA_BYTES)
        cf_fail(msg, ml, CF_OK, "the next net (%d x %d) would need %ld bytes, board %s allows %ld",
                nu2, nv2, need, BOARD_NAME, (long)NF_ARENA_BYTES);
    else {
        nf_surf_t tmp;
        memset(&tmp, 0, sizeof tmp);
        if (cf_surf_alloc(nxt, fit->p, fit->q, nu2, nv2) ||
            cf_surf_alloc(&tmp, fit->p, fit->q, nu2, fit->nv))
            rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        else if (!(rc = nf_refine_u(fit, Xu, ru, &tmp)))
            rc = nf_refine_v(&tmp, Xv, rv, nxt);
        cf_surf_free(&tmp);
        if (rc) {
            cf_surf_free(nxt);
            if (rc != CF_ENOMEM)
                cf_fail(msg, ml, rc, "knot insertion: %s", nf_strerror(rc));
        } else
            *stop = CF_LOOP_GO;
    }
    free(Xu);
    free(Xv);
    return rc;
}

void cf_rounds_json(cf_json_t *j, const cf_round_t *r, int n, int robust)
{
    cf_json_arr(j, "rounds");
    for (int i = 0; i < n; i++) {
        cf_json_obj(j, NULL);
        cf_json_int(j, "round", i);
        cf_json_int(j, "nu", r[i].nu);
        cf_json_int(j, "nv", r[i].nv);
        cf_json_int(j, "control_points", (long)r[i].nu * r[i].nv);
        cf_json_num(j, "within_tol_pct", r[i].within_pct);
        cf_json_num(j, "rms", r[i].rms);
        cf_json_num(j, "max_abs", r[i].mx);
        if (robust) {
            cf_json_num(j, "sigma", r[i].sigma);
            cf_json_int(j, "rejected", r[i].rejected);
        }
        cf_json_num(j, "seconds", r[i].seconds);
        if (r[i].prune) {
            cf_json_bool(j, "pruned", r[i].prune > 0);
            cf_json_str(j, "removed_dir", r[i].prune_dir ? "v" : "u");
            cf_json_num(j, "removed_knot", r[i].prune_knot);
            cf_json_num(j, "removal_error", r[i].prune_err);
        }
        cf_json_close(j);
    }
    cf_json_close(j);
}

void cf_round_print(FILE *f, int i, const cf_round_t *r, double tol, int robust)
{
    if (r->prune)
        fprintf(f, "  prune %d: %s knot %g, %d x %d net (%ld control points)", i,
                r->prune_dir ? "v" : "u", r->prune_knot, r->nu, r->nv, (long)r->nu * r->nv);
    else
        fprintf(f, "  round %d: %d x %d net (%ld control points)", i, r->nu, r->nv,
                (long)r->nu * r->nv);
    if (tol > 0)
        fprintf(f, ", %.3f %% within %g mm", r->within_pct, tol);
    fprintf(f, ", rms %.6g, max %.6g", r->rms, r->mx);
    if (robust)
        fprintf(f, ", sigma %.3g, %ld rejected", r->sigma, r->rejected);
    fprintf(f, " (%.2f s)%s\n", r->seconds,
            r->prune > 0   ? ": kept"
            : r->prune < 0 ? ": undone (not met)"
                           : "");
    fflush(f);
}

int cf_loop_fold_auto(nf_knotsel_t *ks, const nf_knotsel_t *kr, const nf_spanres_t *sr)
{
    const nf_surf_t *s = ks->s;
    const int nsu = s->nu - s->p, nsv = s->nv - s->q;
    const double share = sr->all > 0 ? (double)sr->rej / (double)sr->all : 0.0;
    unsigned char *f = calloc((size_t)(nsu + nsv), 1); /* u spans, then v spans */
    if (!f)
        return CF_ENOMEM;
    for (int k = 0; k < nsv; k++)
        for (int l = 0; l < nsu; l++) {
            const double *c = sr->cell + NF_SPANRES_CELL * (l + (long)k * nsu);
            if (c[1] >= NF_KNOTS_MIN_REJ && c[1] >= NF_KNOTS_COHERENT * share * c[0])
                f[l] = f[nsu + k] = 1;
        }
    int merged = 0;
    for (int i = 0; i < nsu + nsv; i++)
        if (f[i] && nf_knotsel_merge_span(ks, kr, i >= nsu, i >= nsu ? i - nsu : i) == NF_OK)
            merged++;
    free(f);
    return merged;
}
