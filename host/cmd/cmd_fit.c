/* SPDX-License-Identifier: MIT */
/* cmd_fit.c: `cellfit fit`: fit the control net of a base surface's space
 * to a points file through the fit job (cf_fitjob: Eq. 7, reprojection,
 * robust passes, the tolerance loop of Section 2.2), write the best fit
 * and print its summary as text or JSON. */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"
#include "cmd_fitopts.h"
#include "cmd_record.h"
#include "nf_err.h"
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

/* Peak resident set of this process (getrusage reports KiB on Linux). */
static long peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru))
        return -1;
    return ru.ru_maxrss * 1024L;
}

static int solver_arg(const char *v, void *dst)
{
    return cli_solver(v, dst);
}

typedef struct fit_args {
    const char *base, *points, *out;
    int uv, json;
    long entity, threads;
    cf_fitjob_opts_t o;
    cmd_fitopts_t fo;
    cmd_record_t rec;
} fit_args_t;

static int parse(int argc, char **argv, fit_args_t *a)
{
    memset(a, 0, sizeof *a);
    cf_fitjob_defaults(&a->o);
    a->threads = sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1;
    cf_fitjob_opts_t *o = &a->o;
    const cf_opt_t own[] = {
        {.name = "base",
         .kind = CF_OPT_STR,
         .dst = &a->base,
         .arg = "BASE.igs",
         .help = "the base surface: knots, weights and the nominal net P0",
         .req = 1},
        {.name = "points",
         .kind = CF_OPT_STR,
         .dst = &a->points,
         .arg = "FILE",
         .help = "points file: x y z (projected onto the base) or u v x y z with --uv",
         .req = 1},
        {.name = "out",
         .kind = CF_OPT_STR,
         .dst = &a->out,
         .arg = "OUT.igs",
         .help = "the fitted surface (the best round's)",
         .req = 1},
        {.name = "uv",
         .kind = CF_OPT_FLAG,
         .dst = &a->uv,
         .help = "the points carry their parameters: u v x y z"},
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &a->entity,
         .arg = "DE",
         .help = "the surface's directory entry in BASE (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "alpha",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->alpha,
         .arg = "A",
         .help = "pull of control points toward their Greville points (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "beta",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->beta,
         .arg = "B",
         .help = "pull of control points toward the nominal P0 (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "solver",
         .kind = CF_OPT_FUNC,
         .dst = &o->solver,
         .arg = "NAME",
         .help = "linear solver",
         .fn = solver_arg,
         .fn_what = "auto, gs, chol or pcg",
         .def = "auto"},
        {.name = "solve-tol",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->solve_tol,
         .arg = "R",
         .help = "relative residual the iterative solvers stop at",
         .lo = 1e-300,
         .hi = 0.999999},
        {.name = "max-iter",
         .kind = CF_OPT_LONG,
         .dst = &o->max_iter,
         .arg = "N",
         .help = "iterations of the iterative solvers at most",
         .lo = 1,
         .hi = 1e8},
        {.name = "far",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->far,
         .arg = "MM",
         .help = "projected points farther than this from the base are counted (0: 5 % of the "
                 "part)",
         .lo = 1e-300,
         .hi = 1e300,
         .def = "0"},
        {.name = "drop-far",
         .kind = CF_OPT_FLAG,
         .dst = &o->drop_far,
         .help = "leave the points beyond --far out of the fit"},
        {.name = "free-edges",
         .kind = CF_OPT_FLAG,
         .dst = &o->free_edges,
         .help = "leave control points with no point in their support to alpha and beta "
                 "(default: pinned to the nominal, so the fit does not extrapolate past the "
                 "data)"},
        {.name = "holdout",
         .kind = CF_OPT_LONG,
         .dst = &o->holdout,
         .arg = "K",
         .help = "leave every K-th scan row (a run of points of equal y, or v with --uv) out of "
                 "the fit and report their distances to it (docs/loop.md)",
         .lo = 2,
         .hi = 1000000},
        {.name = "threads",
         .kind = CF_OPT_LONG,
         .dst = &a->threads,
         .arg = "N",
         .help = "cores for a fit: 2 projects the points of each pass and accumulates each "
                 "fit pass in two halves (the same fit as 1), and with given parameters (--uv) "
                 "from a regular ASCII or raw file reads, accumulates and checks each half of "
                 "the file on its own (nets up to about 1.8e4 control points; the check pass at "
                 "any size); 1 one thread",
         .lo = 1,
         .hi = 2,
         .def = "2 with two cores online"},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &a->json, .help = "print the summary as JSON"},
        {0}};
    /* The job's shared options after own's first ten rows (--base to
     * --max-iter), --record and --db, then --far, --drop-far, --free-edges,
     * --holdout, --json. */
    cf_opt_t opts[CF_OPT_MAX];
    int n = 10, m = (int)(sizeof own / sizeof own[0]);
    memcpy(opts, own, sizeof(cf_opt_t) * (size_t)n);
    n += cmd_fitopts_table(opts + n, o, &a->fo,
                           "reprojection passes onto the fit, each refitted (x y z points)");
    n += cmd_record_table(opts + n, &a->rec);
    memcpy(opts + n, own + 10, sizeof(cf_opt_t) * (size_t)(m - 10));
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "fit",
                          .summary = "fit the base surface's net to points (Eq. 7), optionally "
                                     "robustly and to a tolerance",
                          .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return rc;
    if ((rc = cmd_fitopts_check("fit", o, &a->fo)))
        return rc;
    o->cores = (int)a->threads;
    if (a->uv && (o->far > 0 || o->drop_far))
        return cli_error("fit", CLI_USAGE,
                         "--far and --drop-far apply to projected points: not with --uv");
    if (a->uv && o->reparam)
        return cli_error("fit", CLI_USAGE, "--reparam projects x y z points: not with --uv");
    return CLI_OK;
}

static void print_json(const fit_args_t *a, const cf_fitjob_result_t *r, double secs)
{
    const cf_fitjob_opts_t *o = &a->o;
    const nf_surf_t *s = &r->surf;
    cf_json_t j;
    cf_json_begin(&j, stdout);
    cf_json_int(&j, "points", r->points);
    cf_json_int(&j, "control_points", (long)s->nu * s->nv);
    cf_json_int(&j, "nu", s->nu);
    cf_json_int(&j, "nv", s->nv);
    cf_json_int(&j, "p", s->p);
    cf_json_int(&j, "q", s->q);
    cf_json_num(&j, "alpha", o->alpha);
    cf_json_num(&j, "beta", o->beta);
    cf_json_str(&j, "parameters", a->uv ? "given" : "projected");
    cf_json_int(&j, "reparam", o->reparam);
    if (!a->uv) {
        cf_json_int(&j, "clamped", r->clamped);
        cf_json_num(&j, "far_limit", r->far_limit);
        cf_json_int(&j, "far", r->far);
        cf_json_int(&j, "dropped", r->dropped);
    }
    cf_json_str(&j, "solver", nf_solver_name(r->solve.solver));
    cf_json_int(&j, "iterations", r->solve.iterations);
    cf_json_num(&j, "rel_residual", r->solve.rel_residual);
    cf_json_num(&j, "rms", r->rms);
    cf_json_num(&j, "max_abs", r->max_abs);
    cf_json_int(&j, "pinned_cp", r->pinned);
    cf_json_str(&j, "fit_status", cf_fitjob_status_name(r->status));
    cmd_fitopts_json(&j, o, r);
    if (o->holdout >= 2) {
        cf_json_obj(&j, "holdout");
        cf_json_int(&j, "every", o->holdout);
        cf_json_int(&j, "points", r->ho_points);
        cf_json_num(&j, "rms", r->ho_rms);
        cf_json_num(&j, "p99", r->ho_p99);
        cf_json_num(&j, "max_abs", r->ho_max);
        cf_json_close(&j);
    }
    cf_json_arr(&j, "warnings");
    for (int i = 0; i < r->nwarn; i++)
        cf_json_str(&j, NULL, r->warn[i]);
    cf_json_close(&j);
    cf_json_num(&j, "seconds", secs);
    cf_json_num(&j, "accumulate_seconds", r->t_acc);
    cf_json_num(&j, "solve_seconds", r->t_solve);
    cf_json_int(&j, "bytes", r->bytes);
    cf_json_int(&j, "threads", r->threads);
    cf_json_int(&j, "peak_rss_bytes", peak_rss());
    cf_json_str(&j, "board", BOARD_NAME);
    cf_json_str(&j, "out", a->out);
    cf_json_end(&j);
}

static void print_text(const fit_args_t *a, const cf_fitjob_result_t *r, double secs, double t_out)
{
    const cf_fitjob_opts_t *o = &a->o;
    const nf_surf_t *s = &r->surf;
    if (o->loop)
        for (int i = 0; i < r->nrounds; i++)
            cf_round_print(stdout, i, &r->rounds[i], o->tol, o->robust);
    printf("cellfit fit: %ld points, %ld control points (%d x %d, degree %d x %d)\n", r->points,
           (long)s->nu * s->nv, s->nu, s->nv, s->p, s->q);
    printf("  parameters %s", a->uv ? "given (--uv)" : "by projection onto the base");
    if (o->reparam)
        printf(", then %ld reparameterisation pass%s", o->reparam, o->reparam > 1 ? "es" : "");
    if (!a->uv)
        printf("\n  projection: %ld feet clamped to the boundary, %ld points farther than "
               "%g mm (%s)",
               r->clamped, r->far, r->far_limit,
               o->drop_far ? "dropped" : "kept; --drop-far drops them");
    printf("\n  alpha %g  beta %g  solver %s  iterations %d  relative residual %.2e\n", o->alpha,
           o->beta, nf_solver_name(r->solve.solver), r->solve.iterations, r->solve.rel_residual);
    int last = r->nrounds - 1; /* the result's round: not a pruning trial undone */
    while (last > 0 && r->rounds[last].prune < 0)
        last--;
    if (o->robust)
        printf("  robust: %ld Tukey passes, sigma %.3g mm, %ld points rejected as outliers\n",
               o->robust_iters, r->rounds[last].sigma, r->rounds[last].rejected);
    printf("  rms %.6g  max %.6g  (%s)\n", r->rms, r->max_abs,
           a->uv ? "|Q - S(u,v)| at the given parameters" : "normal distance to the fit");
    if (o->loop)
        printf("  tolerance %g mm: %.3f %% of the points within (need %g %%): %s\n"
               "  stopped (%s): %s\n",
               o->tol, r->within_pct, o->within, r->status == CF_FITJOB_MET ? "met" : "NOT met",
               cf_fitjob_status_name(r->status), r->why);
    if (r->pinned > 0)
        printf("  %ld control points without data under them follow the nominal\n", r->pinned);
    if (r->fp_cells > 0)
        printf("  footprint: %ld of %ld cells with points, %ld without, %ld on its edge\n",
               r->fp_filled, r->fp_cells, r->fp_empty, r->fp_outline);
    if (o->holdout >= 2)
        printf("  held out (every %ld-th row): %ld points, rms %.6g  p99 %.6g  max %.6g\n",
               o->holdout, r->ho_points, r->ho_rms, r->ho_p99, r->ho_max);
    printf("  %.3f s (read + accumulate %.3f, solve %.3f, summary + write %.3f)\n", secs, r->t_acc,
           r->t_solve, t_out);
    printf("  %ld bytes of fitter memory (board %s allows %ld), %d thread%s\n", r->bytes,
           BOARD_NAME, (long)NF_ARENA_BYTES, r->threads, r->threads > 1 ? "s" : "");
    printf("  wrote %s\n", a->out);
}

int cmd_fit(int argc, char **argv)
{
    fit_args_t a;
    int rc = parse(argc, argv, &a);
    if (rc)
        return cf_opt_exit(rc);
    char msg[1024];
    double t0 = cli_now();
    /* The points first: their parse thread starts now and reads ahead
     * while the base is read and the job set up (the first pass's rewind
     * keeps that work). */
    cf_points_t *pr = NULL;
    if (cf_points_open(&pr, a.points, a.uv ? 5 : 3, msg, sizeof msg))
        return cli_error("fit", CLI_USAGE, "%s", msg);
    if (a.o.loop && !a.uv)
        (void)cf_points_thread(pr); /* without it, the points are read on this thread */
    nf_surf_t base;
    if (cf_surfio_read(a.base, (int)a.entity, &base, msg, sizeof msg)) {
        cf_points_close(pr);
        return cli_error("fit", CLI_USAGE, "%s", msg);
    }
    /* A trimmed nominal's trim goes to the output as it is: the fit keeps
     * the knot range, so the parameter-space curves stay valid. */
    cf_trim_t trim;
    if (cf_surfio_read_trim(a.base, a.entity, &trim, msg, sizeof msg)) {
        cf_surf_free(&base);
        cf_points_close(pr);
        return cli_error("fit", CLI_USAGE, "%s", msg);
    }
    cf_fitjob_t *j = NULL;
    rc = cf_fitjob_open(&j, &base, &a.o, msg, sizeof msg);
    cf_surf_free(&base);
    if (rc) {
        cf_trim_free(&trim);
        cf_points_close(pr);
        return cli_error("fit", rc == CF_ENOMEM ? CLI_FAIL : CLI_USAGE, "%s: %s", a.base, msg);
    }
    cf_fitsrc_t src;
    cf_fitsrc_points_t pc;
    cf_fitsrc_points(&src, &pc, pr, a.points);
    if (a.o.loop) /* two passes a round: the file parsed once */
        cf_fitsrc_points_cache(&pc, CF_FITSRC_CACHE_MAX);
    cf_fitjob_result_t r;
    rc = cf_fitjob_run(j, &src, NULL, 0, 100, &r, msg, sizeof msg);
    cf_fitsrc_points_free(&pc);
    cf_points_close(pr);
    cf_fitjob_close(j);
    if (rc) {
        cf_trim_free(&trim);
        return cli_error("fit", cf_fitjob_input_error(rc) ? CLI_USAGE : CLI_FAIL, "%s", msg);
    }
    double t2 = cli_now(), edge_err = 0.0;
    int ec = CLI_OK;
    if (cf_surfio_write_trimmed(a.out, &r.surf, &trim, "cellfit fit", cf_version_string(),
                                &edge_err, msg, sizeof msg)) {
        ec = cli_error("fit", CLI_FAIL, "%s", msg);
        goto done;
    }
    if (trim.nloops && !a.json)
        printf("  trimmed face: %d boundaries kept from %s; 3-D edges within %.3g mm\n",
               trim.nloops, a.base, edge_err);
    double t3 = cli_now();
    if (a.json)
        print_json(&a, &r, t3 - t0);
    else
        print_text(&a, &r, t3 - t0, t3 - t2);
    /* The best surface is written either way; a tolerance not met is a
     * failure of the work (exit 1), said in one line. Recorded first. */
    const cmd_record_job_t rj = {
        .command = "fit", .t0 = t0, .fit = &r, .fo = &a.o, .surface = a.out};
    if ((ec = cmd_record("fit", &a.rec, &rj)) == CLI_OK)
        ec = cmd_fitopts_verdict("fit", &a.o, &r, a.out);
done:
    cf_trim_free(&trim);
    cf_fitjob_result_free(&r);
    return ec;
}
