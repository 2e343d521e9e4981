/* cf_sfit.c: streaming fit of measured points onto a nominal (cf_sfit.h). */
#include "cf_sfit.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "nf_err.h"
#include "nf_project.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain (as cmd_fit) */

int cf_sfit_init(cf_sfit_t *s, const nf_surf_t *nominal, const nf_surf_t *proj, double alpha,
                 double beta, const char *cmd)
{
    memset(s, 0, sizeof *s);
    s->nominal = nominal;
    s->proj = proj ? proj : nominal;
    s->need = nf_fit_bytes(nominal->nu, nominal->nv, nominal->p, nominal->q, NF_SOLVER_AUTO);
    if (s->need < 0 || s->need > NF_ARENA_BYTES)
        return cli_error(cmd, CLI_USAGE,
                         "a %d x %d net of degree %d x %d needs %ld bytes; board %s allows %ld: "
                         "job refused",
                         nominal->nu, nominal->nv, nominal->p, nominal->q, s->need, BOARD_NAME,
                         (long)NF_ARENA_BYTES);
    s->mem = malloc((size_t)s->need);
    if (!s->mem || cf_seedgrid_init(&s->pj, s->proj, 8)) {
        cf_sfit_free(s);
        return cli_error(cmd, CLI_FAIL, "cannot allocate %ld bytes", s->need);
    }
    nf_arena_init(&s->ar, s->mem, (size_t)s->need);
    nf_fit_params_t prm = {alpha, beta, NF_SOLVER_AUTO};
    int rc = nf_fit_init(&s->f, nominal, &prm, &s->ar);
    if (rc) {
        cf_sfit_free(s);
        return cli_error(cmd, CLI_USAGE, "%s", nf_strerror(rc));
    }
    return 0;
}

int cf_sfit_add(cf_sfit_t *s, const double xyz[3])
{
    nf_proj_t pr;
    int rc = cf_seedgrid_project(&s->pj, xyz, PROJ_TOL, &pr);
    if (rc && rc != NF_ENOCONV) /* the best point is kept on ENOCONV, as cmd_fit does */
        return rc;
    rc = nf_fit_add(&s->f, pr.u, pr.v, xyz, 1.0);
    if (rc)
        return rc;
    double d = fabs(pr.dist);
    s->dev_ss += d * d;
    s->dev_max = d > s->dev_max ? d : s->dev_max;
    s->points++;
    return 0;
}

int cf_sfit_solve(cf_sfit_t *s, nf_surf_t *out, nf_solve_stats_t *st, const char *cmd)
{
    if (s->points == 0)
        return cli_error(cmd, CLI_USAGE, "no measured points to fit");
    int rc = nf_fit_finish(&s->f);
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    if (!rc)
        rc = nf_fit_solve(&s->f, NF_SOLVER_AUTO, &so, st);
    if (rc) {
        long b = s->f.bad_index;
        int nu = s->nominal->nu;
        if (rc == NF_ENODATA || rc == NF_ESINGULAR)
            return cli_error(cmd, CLI_USAGE,
                             "the points do not determine the surface: control point (%ld, %ld) "
                             "is left free (%s; give --alpha/--beta > 0 or measure there)",
                             b >= 0 ? b % nu : -1L, b >= 0 ? b / nu : -1L, nf_strerror(rc));
        return cli_error(cmd, CLI_FAIL, "%s", nf_strerror(rc));
    }
    memcpy(out->cp, s->f.P, sizeof(double) * 3 * (size_t)s->f.n);
    return 0;
}

void cf_sfit_free(cf_sfit_t *s)
{
    cf_seedgrid_free(&s->pj);
    free(s->mem);
    s->mem = NULL;
}

int cf_sfit_residuals(const nf_surf_t *s, jnl_reader_t *rd, cf_sfit_resid_t *out)
{
    memset(out, 0, sizeof *out);
    cf_seedgrid_t pj;
    if (cf_seedgrid_init(&pj, s, 8))
        return CF_ENOMEM;
    jnl_reader_rewind(rd);
    jnl_rec_t r;
    int rc;
    double ss = 0;
    while ((rc = jnl_reader_next(rd, &r)) == 1) {
        if (r.type != JNL_T_POINT || (r.flags & JNL_F_NOSURF))
            continue;
        nf_proj_t pr;
        cf_seedgrid_project(&pj, r.xyz, PROJ_TOL, &pr); /* best point kept on ENOCONV */
        double d = fabs(pr.dist);
        ss += d * d;
        out->max = d > out->max ? d : out->max;
        out->n++;
    }
    cf_seedgrid_free(&pj);
    out->rms = out->n ? sqrt(ss / (double)out->n) : 0.0;
    return rc < 0 ? rc : 0;
}

int cf_sfit_nominal_id(const char *path, uint64_t *hash, char name[JNL_NAME_LEN])
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return CF_EIO;
    uint64_t h = 0xcbf29ce484222325ULL;
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0)
        for (size_t i = 0; i < n; i++)
            h = (h ^ buf[i]) * 0x100000001b3ULL;
    int bad = ferror(f);
    fclose(f);
    if (bad)
        return CF_EIO;
    *hash = h;
    const char *b = strrchr(path, '/');
    memset(name, 0, JNL_NAME_LEN);
    snprintf(name, JNL_NAME_LEN, "%s", b ? b + 1 : path);
    return CF_OK;
}
