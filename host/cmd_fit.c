/* cmd_fit.c: `cellfit fit`: fit the control net of a base surface's space
 * to points with known parameters (Eq. 7), streaming the point file twice:
 * once into the stripes, once for the residual summary. Memory is the job's
 * byte formula plus fixed buffers, whatever the number of points. */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_fit.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#define BATCH 4096

typedef struct fit_opts {
    const char *base, *points, *out;
    int uv, json;
    long entity;
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
    if (!o->uv)
        return cli_error("fit", CLI_USAGE,
                         "points without parameters need projection onto the base, which this "
                         "build does not have yet: give 'u v x y z' points and --uv");
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

static int fit_error(int rc, const nf_fit_t *f, const nf_surf_t *s)
{
    long b = f->bad_index;
    int i = b >= 0 ? (int)(b % s->nu) : -1, j = b >= 0 ? (int)(b / s->nu) : -1;
    switch (rc) {
    case NF_ENODATA:
        return cli_error("fit", CLI_USAGE,
                         "control point (%d, %d) has no data under it and alpha = beta = 0: the "
                         "points do not determine the surface (measure there, or give --beta)",
                         i, j);
    case NF_ESINGULAR:
        return cli_error("fit", CLI_USAGE,
                         "the points do not determine the surface: control point (%d, %d) is "
                         "left free (numerically rank-deficient normal equations; give "
                         "--alpha/--beta > 0 or more data there)",
                         i, j);
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

static int residuals(cf_points_t *r, const nf_surf_t *s, double *buf, resid_t *out, char *msg,
                     size_t ml)
{
    memset(out, 0, sizeof *out);
    if (cf_points_rewind(r))
        return cli_error("fit", CLI_FAIL, "cannot re-read the points for the summary");
    long got;
    while ((got = cf_points_read(r, buf, BATCH, msg, ml)) > 0) {
        for (long k = 0; k < got; k++) {
            const double *q = buf + 5 * k;
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

int cmd_fit(int argc, char **argv)
{
    fit_opts_t o;
    int rc = parse(argc, argv, &o);
    if (rc)
        return rc;
    char msg[512];
    double t0 = cli_now();
    nf_surf_t base, out;
    memset(&out, 0, sizeof out);
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
    rc = cf_points_open(&pr, o.points, 5, msg, sizeof msg);
    if (rc) {
        cf_surf_free(&base);
        return cli_error("fit", CLI_USAGE, "%s", msg);
    }
    void *mem = malloc((size_t)need);
    double *buf = malloc(sizeof(double) * 5 * BATCH);
    nf_arena_t ar;
    nf_fit_t f;
    int ec = CLI_OK;
    if (!mem || !buf) {
        ec = cli_error("fit", CLI_FAIL, "cannot allocate %ld bytes", need);
        goto done;
    }
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_params_t prm = {o.alpha, o.beta, o.solver};
    rc = nf_fit_init(&f, &base, &prm, &ar);
    if (rc) {
        ec = fit_error(rc, &f, &base);
        goto done;
    }
    long got, total = 0;
    while ((got = cf_points_read(pr, buf, BATCH, msg, sizeof msg)) > 0) {
        long bad = -1;
        rc = nf_fit_add_rows(&f, buf, got, &bad);
        if (rc) {
            const double *q = buf + 5 * bad;
            long line = line_of_point(pr, total + bad);
            double u0, u1, v0, v1;
            nf_surf_domain(&base, &u0, &u1, &v0, &v1);
            if (rc == NF_EDOMAIN)
                ec = cli_error("fit", CLI_USAGE,
                               "%s:%ld: parameters (%.17g, %.17g) outside the knot domain "
                               "[%.17g, %.17g] x [%.17g, %.17g] of %s",
                               o.points, line, q[0], q[1], u0, u1, v0, v1, o.base);
            else
                ec = cli_error("fit", CLI_USAGE, "%s:%ld: %s", o.points, line, nf_strerror(rc));
            goto done;
        }
        total += got;
    }
    if (got < 0) {
        ec = cli_error("fit", CLI_USAGE, "%s", msg);
        goto done;
    }
    if (total == 0) {
        ec = cli_error("fit", CLI_USAGE, "%s: no points", o.points);
        goto done;
    }
    double t1 = cli_now();
    rc = nf_fit_finish(&f);
    nf_solve_stats_t st = {NF_SOLVER_AUTO, 0, 0.0};
    nf_solve_opts_t so = {o.tol, (int)o.max_iter, 1};
    if (!rc)
        rc = nf_fit_solve(&f, o.solver, &so, &st);
    if (rc) {
        ec = fit_error(rc, &f, &base);
        goto done;
    }
    double t2 = cli_now();
    if (cf_surf_copy(&out, &base)) {
        ec = cli_error("fit", CLI_FAIL, "out of memory");
        goto done;
    }
    memcpy(out.cp, f.P, sizeof(double) * (size_t)(3 * f.n));
    resid_t res;
    ec = residuals(pr, &out, buf, &res, msg, sizeof msg);
    if (ec)
        goto done;
    rc = cf_iges_write(o.out, &out, "cellfit fit", msg, sizeof msg);
    if (rc) {
        ec = cli_error("fit", CLI_FAIL, "%s", msg);
        goto done;
    }
    double t3 = cli_now();
    double rms = sqrt(res.ss / (double)res.n);
    if (o.json) {
        cli_json_t j;
        cli_json_begin(&j, stdout);
        cli_json_int(&j, "points", total);
        cli_json_int(&j, "control_points", f.n);
        cli_json_int(&j, "nu", base.nu);
        cli_json_int(&j, "nv", base.nv);
        cli_json_int(&j, "p", base.p);
        cli_json_int(&j, "q", base.q);
        cli_json_num(&j, "alpha", o.alpha);
        cli_json_num(&j, "beta", o.beta);
        cli_json_str(&j, "solver", nf_solver_name(st.solver));
        cli_json_int(&j, "iterations", st.iterations);
        cli_json_num(&j, "rel_residual", st.rel_residual);
        cli_json_num(&j, "rms", rms);
        cli_json_num(&j, "max_abs", res.mx);
        cli_json_num(&j, "seconds", t3 - t0);
        cli_json_num(&j, "accumulate_seconds", t1 - t0);
        cli_json_num(&j, "solve_seconds", t2 - t1);
        cli_json_int(&j, "bytes", need);
        cli_json_int(&j, "peak_rss_bytes", peak_rss());
        cli_json_str(&j, "board", BOARD_NAME);
        cli_json_str(&j, "out", o.out);
        cli_json_end(&j);
    } else {
        printf("cellfit fit: %ld points, %ld control points (%d x %d, degree %d x %d)\n", total,
               f.n, base.nu, base.nv, base.p, base.q);
        printf("  alpha %g  beta %g  solver %s  iterations %d  relative residual %.2e\n", o.alpha,
               o.beta, nf_solver_name(st.solver), st.iterations, st.rel_residual);
        printf("  rms %.6g  max |Q - S| %.6g\n", rms, res.mx);
        printf("  %.3f s (read + accumulate %.3f, solve %.3f, summary + write %.3f)\n", t3 - t0,
               t1 - t0, t2 - t1, t3 - t2);
        printf("  %ld bytes of fitter memory (board %s allows %ld)\n", need, BOARD_NAME,
               (long)NF_ARENA_BYTES);
        printf("  wrote %s\n", o.out);
    }
done:
    cf_points_close(pr);
    free(buf);
    free(mem);
    cf_surf_free(&out);
    cf_surf_free(&base);
    return ec;
}
