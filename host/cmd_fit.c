/* cmd_fit.c: `cellfit fit`: fit the control net of a base surface's space
 * to points with known parameters (Eq. 7), streaming the point file twice:
 * once into the stripes, once for the residual summary. Memory is the job's
 * byte formula plus fixed buffers, whatever the number of points. */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_project.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#define BATCH 4096
#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain */

/* Start points for projection: surface samples (8 per knot span and
 * direction) binned in a cell grid; host memory O(net), never O(points). */
typedef cf_seedgrid_t projector_t;

static int projector_init(projector_t *pj, const nf_surf_t *s)
{
    return cf_seedgrid_init(pj, s, 8);
}

/* rows of x y z in, rows of u v x y z out (distance in *dist if asked). */
static void project_rows(const projector_t *pj, const double *xyz, long n, double *uvxyz,
                         double *dist)
{
    for (long k = 0; k < n; k++) {
        const double *Q = xyz + 3 * k;
        double u0, v0;
        nf_proj_t pr;
        cf_seedgrid_start(pj, Q, &u0, &v0);
        nf_project(pj->seed.s, Q, u0, v0, PROJ_TOL, &pr); /* best point kept on ENOCONV */
        double *r = uvxyz + 5 * k;
        r[0] = pr.u;
        r[1] = pr.v;
        r[2] = Q[0];
        r[3] = Q[1];
        r[4] = Q[2];
        if (dist)
            dist[k] = pr.dist;
    }
}

typedef struct fit_opts {
    const char *base, *points, *out;
    int uv, json;
    long entity, reparam;
    double alpha, beta, tol;
    long max_iter;
    nf_solver_t solver;
} fit_opts_t;

static int parse(int argc, char **argv, fit_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->tol = 1e-12;
    o->max_iter = 20000;
    o->solver = NF_SOLVER_AUTO;
    for (int i = 1; i < argc;) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int takes = 1;
        if (!strcmp(a, "--uv"))
            o->uv = 1, takes = 0;
        else if (!strcmp(a, "--json"))
            o->json = 1, takes = 0;
        else if (!v)
            return cli_error("fit", CLI_USAGE, "option %s needs a value", a);
        else if (!strcmp(a, "--base"))
            o->base = v;
        else if (!strcmp(a, "--points"))
            o->points = v;
        else if (!strcmp(a, "--out"))
            o->out = v;
        else if (!strcmp(a, "--alpha")) {
            if (cli_double(v, &o->alpha) || o->alpha < 0)
                return cli_error("fit", CLI_USAGE, "--alpha '%s': need a number >= 0", v);
        } else if (!strcmp(a, "--beta")) {
            if (cli_double(v, &o->beta) || o->beta < 0)
                return cli_error("fit", CLI_USAGE, "--beta '%s': need a number >= 0", v);
        } else if (!strcmp(a, "--solve-tol")) {
            if (cli_double(v, &o->tol) || !(o->tol > 0) || o->tol >= 1)
                return cli_error("fit", CLI_USAGE, "--solve-tol '%s': need 0 < tol < 1", v);
        } else if (!strcmp(a, "--max-iter")) {
            if (cli_int(v, 1, 100000000, &o->max_iter))
                return cli_error("fit", CLI_USAGE, "--max-iter '%s': need 1..1e8", v);
        } else if (!strcmp(a, "--reparam")) {
            if (cli_int(v, 0, 100, &o->reparam))
                return cli_error("fit", CLI_USAGE, "--reparam '%s': need 0..100", v);
        } else if (!strcmp(a, "--entity")) {
            if (cli_int(v, 1, 9999999, &o->entity))
                return cli_error("fit", CLI_USAGE, "--entity '%s': need a DE number", v);
        } else if (!strcmp(a, "--solver")) {
            if (cli_solver(v, &o->solver))
                return cli_error("fit", CLI_USAGE, "--solver '%s': auto, gs, chol or pcg", v);
        } else
            return cli_error("fit", CLI_USAGE, "unknown option '%s'", a);
        i += 1 + takes;
    }
    if (!o->base || !o->points || !o->out)
        return cli_error("fit", CLI_USAGE, "need --base BASE.igs --points FILE --out OUT.igs");
    if (o->uv && o->reparam)
        return cli_error("fit", CLI_USAGE, "--reparam projects x y z points: not with --uv");
    return CLI_OK;
}

/* Line number of point index k (0-based) of a rewindable file, for messages. */
static long line_of_point(cf_points_t *r, long k)
{
    double row[5];
    char msg[16];
    if (cf_points_rewind(r))
        return -1;
    for (long i = 0; i <= k; i++)
        if (cf_points_read(r, row, 1, msg, sizeof msg) != 1)
            return -1;
    return cf_points_line(r);
}

/* points: the file the data came from, named by the refusals it causes. */
static int fit_error(int rc, const nf_fit_t *f, const nf_surf_t *s, const char *points)
{
    long b = f->bad_index;
    int i = b >= 0 ? (int)(b % s->nu) : -1, j = b >= 0 ? (int)(b / s->nu) : -1;
    switch (rc) {
    case NF_ENODATA:
        return cli_error("fit", CLI_USAGE,
                         "%s: control point (%d, %d) has no data under it and alpha = beta = 0: "
                         "the points do not determine the surface (measure there, or give --beta)",
                         points, i, j);
    case NF_ESINGULAR:
        return cli_error("fit", CLI_USAGE,
                         "%s: the points do not determine the surface: control point (%d, %d) is "
                         "left free (numerically rank-deficient normal equations; give "
                         "--alpha/--beta > 0 or more data there)",
                         points, i, j);
    case NF_ENOCONV:
        return cli_error("fit", CLI_FAIL, "%s; try --solver chol or more --max-iter",
                         nf_strerror(rc));
    case NF_EBUDGET:
        return cli_error("fit", CLI_USAGE,
                         "job needs %ld bytes, board %s allows %ld: %s (use fewer control "
                         "points or another solver)",
                         f->need_bytes, BOARD_NAME, (long)NF_ARENA_BYTES, nf_strerror(rc));
    default: return cli_error("fit", CLI_FAIL, "%s", nf_strerror(rc));
    }
}

typedef struct resid {
    double ss, mx;
    long n;
} resid_t;

/* Second pass for the summary: |Q - S(u, v)| at the given parameters with
 * --uv, else the normal distance to the fitted surface (projection). */
static int residuals(cf_points_t *r, const nf_surf_t *s, const projector_t *pj, double *buf,
                     double *rows, resid_t *out, char *msg, size_t ml)
{
    memset(out, 0, sizeof *out);
    if (cf_points_rewind(r))
        return cli_error("fit", CLI_FAIL, "cannot re-read the points for the summary");
    long got;
    while ((got = cf_points_read(r, buf, BATCH, msg, ml)) > 0) {
        const double *uv = buf;
        if (pj) {
            project_rows(pj, buf, got, rows, NULL);
            uv = rows;
        }
        for (long k = 0; k < got; k++) {
            const double *q = uv + 5 * k;
            double P[3];
            nf_surf_eval(s, q[0], q[1], P);
            double d2 = (q[2] - P[0]) * (q[2] - P[0]) + (q[3] - P[1]) * (q[3] - P[1]) +
                        (q[4] - P[2]) * (q[4] - P[2]);
            out->ss += d2;
            out->mx = d2 > out->mx ? d2 : out->mx;
            out->n++;
        }
    }
    if (got < 0)
        return cli_error("fit", CLI_USAGE, "%s", msg);
    out->mx = sqrt(out->mx);
    return CLI_OK;
}

/* Peak resident set of this process (getrusage reports KiB on Linux). */
static long peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru))
        return -1;
    return ru.ru_maxrss * 1024L;
}

typedef struct pass_out {
    long points;
    nf_solve_stats_t st;
    double t_acc, t_solve;
} pass_out_t;

/* One fit: stream the points (parameters given, or by projection onto
 * proj_onto) into a fresh job on base's space, solve, leave P in out->cp. */
static int fit_pass(const fit_opts_t *o, const nf_surf_t *base, const nf_surf_t *proj_onto,
                    cf_points_t *pr, void *mem, long need, double *buf, double *rows,
                    nf_surf_t *out, pass_out_t *po)
{
    char msg[512];
    nf_arena_t ar;
    nf_fit_t f;
    projector_t pj;
    memset(&pj, 0, sizeof pj);
    int ec = CLI_OK;
    double t0 = cli_now();
    memset(po, 0, sizeof *po);
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_params_t prm = {o->alpha, o->beta, o->solver};
    int rc = nf_fit_init(&f, base, &prm, &ar);
    if (rc)
        return fit_error(rc, &f, base, o->points);
    if (proj_onto && projector_init(&pj, proj_onto))
        return cli_error("fit", CLI_FAIL, "out of memory");
    if (cf_points_rewind(pr)) {
        cf_seedgrid_free(&pj);
        return cli_error("fit", CLI_USAGE, "%s: cannot read the points again", o->points);
    }
    long got;
    while ((got = cf_points_read(pr, buf, BATCH, msg, sizeof msg)) > 0) {
        long bad = -1;
        const double *uv = buf;
        if (proj_onto) {
            project_rows(&pj, buf, got, rows, NULL);
            uv = rows;
        }
        rc = nf_fit_add_rows(&f, uv, got, &bad);
        if (rc) {
            const double *q = uv + 5 * bad;
            long line = line_of_point(pr, po->points + bad);
            double u0, u1, v0, v1;
            nf_surf_domain(base, &u0, &u1, &v0, &v1);
            if (rc == NF_EDOMAIN)
                ec = cli_error("fit", CLI_USAGE,
                               "%s:%ld: parameters (%.17g, %.17g) outside the knot domain "
                               "[%.17g, %.17g] x [%.17g, %.17g] of %s",
                               o->points, line, q[0], q[1], u0, u1, v0, v1, o->base);
            else
                ec = cli_error("fit", CLI_USAGE, "%s:%ld: %s", o->points, line, nf_strerror(rc));
            cf_seedgrid_free(&pj);
            return ec;
        }
        po->points += got;
    }
    cf_seedgrid_free(&pj);
    if (got < 0)
        return cli_error("fit", CLI_USAGE, "%s", msg);
    if (po->points == 0)
        return cli_error("fit", CLI_USAGE, "%s: no points", o->points);
    double t1 = cli_now();
    rc = nf_fit_finish(&f);
    nf_solve_opts_t so = {o->tol, (int)o->max_iter, 1};
    if (!rc)
        rc = nf_fit_solve(&f, o->solver, &so, &po->st);
    if (rc)
        return fit_error(rc, &f, base, o->points);
    memcpy(out->cp, f.P, sizeof(double) * (size_t)(3 * f.n));
    po->t_acc = t1 - t0;
    po->t_solve = cli_now() - t1;
    return CLI_OK;
}

int cmd_fit(int argc, char **argv)
{
    fit_opts_t o;
    int rc = parse(argc, argv, &o);
    if (rc)
        return rc;
    char msg[512];
    double t0 = cli_now();
    nf_surf_t base, out, prev;
    memset(&out, 0, sizeof out);
    memset(&prev, 0, sizeof prev);
    rc = cf_iges_read(o.base, (int)o.entity, &base, msg, sizeof msg);
    if (rc)
        return cli_error("fit", CLI_USAGE, "%s", msg);

    long need = nf_fit_bytes(base.nu, base.nv, base.p, base.q, o.solver);
    nf_solver_t used =
        o.solver == NF_SOLVER_AUTO ? nf_solver_pick(base.nu, base.nv, base.p, base.q) : o.solver;
    if (need < 0 || need > NF_ARENA_BYTES) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE,
                         "%s: a %d x %d net of degree %d x %d with solver %s needs %ld bytes; "
                         "board %s allows %ld: job refused",
                         o.base, base.nu, base.nv, base.p, base.q, nf_solver_name(used), need,
                         BOARD_NAME, (long)NF_ARENA_BYTES);
    }
    cf_points_t *pr = NULL;
    rc = cf_points_open(&pr, o.points, o.uv ? 5 : 3, msg, sizeof msg);
    if (rc) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE, "%s", msg);
    }
    void *mem = malloc((size_t)need);
    double *buf = malloc(sizeof(double) * 5 * BATCH), *rows = malloc(sizeof(double) * 5 * BATCH);
    int ec = CLI_OK;
    pass_out_t po = {0, {NF_SOLVER_AUTO, 0, 0.0}, 0.0, 0.0};
    double t_acc = 0.0, t_solve = 0.0;
    if (!mem || !buf || !rows || cf_surf_copy(&out, &base) || cf_surf_copy(&prev, &base)) {
        ec = cli_error("fit", CLI_FAIL, "cannot allocate %ld bytes", need);
        goto done;
    }
    /* Pass 0 takes parameters from the file or from projection onto the
     * base; each --reparam pass projects onto the previous fit and refits
     * in the same space with the same nominal P0 (Section 2.2). */
    for (long pass = 0; pass <= o.reparam; pass++) {
        ec = fit_pass(&o, &base, o.uv ? NULL : &prev, pr, mem, need, buf, rows, &out, &po);
        if (ec)
            goto done;
        t_acc += po.t_acc;
        t_solve += po.t_solve;
        memcpy(prev.cp, out.cp, sizeof(double) * 3 * (size_t)base.nu * (size_t)base.nv);
    }
    double t2 = cli_now();
    resid_t res;
    projector_t pj;
    memset(&pj, 0, sizeof pj);
    if (!o.uv && projector_init(&pj, &out)) {
        ec = cli_error("fit", CLI_FAIL, "out of memory");
        goto done;
    }
    ec = residuals(pr, &out, o.uv ? NULL : &pj, buf, rows, &res, msg, sizeof msg);
    cf_seedgrid_free(&pj);
    if (ec)
        goto done;
    rc = cf_iges_write(o.out, &out, "cellfit fit", msg, sizeof msg);
    if (rc) {
        ec = cli_error("fit", CLI_FAIL, "%s", msg);
        goto done;
    }
    double t3 = cli_now();
    double rms = sqrt(res.ss / (double)res.n);
    long ncp = (long)base.nu * base.nv;
    if (o.json) {
        cli_json_t j;
        cli_json_begin(&j, stdout);
        cli_json_int(&j, "points", po.points);
        cli_json_int(&j, "control_points", ncp);
        cli_json_int(&j, "nu", base.nu);
        cli_json_int(&j, "nv", base.nv);
        cli_json_int(&j, "p", base.p);
        cli_json_int(&j, "q", base.q);
        cli_json_num(&j, "alpha", o.alpha);
        cli_json_num(&j, "beta", o.beta);
        cli_json_str(&j, "parameters", o.uv ? "given" : "projected");
        cli_json_int(&j, "reparam", o.reparam);
        cli_json_str(&j, "solver", nf_solver_name(po.st.solver));
        cli_json_int(&j, "iterations", po.st.iterations);
        cli_json_num(&j, "rel_residual", po.st.rel_residual);
        cli_json_num(&j, "rms", rms);
        cli_json_num(&j, "max_abs", res.mx);
        cli_json_num(&j, "seconds", t3 - t0);
        cli_json_num(&j, "accumulate_seconds", t_acc);
        cli_json_num(&j, "solve_seconds", t_solve);
        cli_json_int(&j, "bytes", need);
        cli_json_int(&j, "peak_rss_bytes", peak_rss());
        cli_json_str(&j, "board", BOARD_NAME);
        cli_json_str(&j, "out", o.out);
        cli_json_end(&j);
    } else {
        printf("cellfit fit: %ld points, %ld control points (%d x %d, degree %d x %d)\n", po.points,
               ncp, base.nu, base.nv, base.p, base.q);
        printf("  parameters %s", o.uv ? "given (--uv)" : "by projection onto the base");
        if (o.reparam)
            printf(", then %ld reparameterisation pass%s", o.reparam, o.reparam > 1 ? "es" : "");
        printf("\n  alpha %g  beta %g  solver %s  iterations %d  relative residual %.2e\n", o.alpha,
               o.beta, nf_solver_name(po.st.solver), po.st.iterations, po.st.rel_residual);
        printf("  rms %.6g  max %.6g  (%s)\n", rms, res.mx,
               o.uv ? "|Q - S(u,v)| at the given parameters" : "normal distance to the fit");
        printf("  %.3f s (read + accumulate %.3f, solve %.3f, summary + write %.3f)\n", t3 - t0,
               t_acc, t_solve, t3 - t2);
        printf("  %ld bytes of fitter memory (board %s allows %ld)\n", need, BOARD_NAME,
               (long)NF_ARENA_BYTES);
        printf("  wrote %s\n", o.out);
    }
done:
    cf_points_close(pr);
    free(buf);
    free(rows);
    free(mem);
    cf_surf_free(&prev);
    cf_surf_free(&out);
    cf_surf_free(&base);
    return ec;
}
