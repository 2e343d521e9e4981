/* SPDX-License-Identifier: MIT */
/* cmd_bench.c: `cellfit bench accumulate|solve|fit|export` (project:
 * bench_project.c): single measurements
 * on generated, seeded data streamed without files (issue 6). Prints
 * figures; asserts nothing. Nets are square, bicubic, uniform knots.
 * accumulate, solve and export time the fitter's raw kernels; fit runs
 * the fit job (cf_fitjob) on a source that generates the points. */
#include "bench_project.h"
#include "cf_accum.h"
#include "cf_cli.h"
#include "cf_fitjob.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_surf.h"
#include "cmd.h"
#include "nf_err.h"
#include "nf_fit.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#define CHUNK 65536

typedef struct bench_opts {
    long points, cp, threads, degree;
    int random, json;
    nf_solver_t solver;
    double alpha, beta, tol;
    const char *out;
} bench_opts_t;

#define B_RNG0 0x853C49E6748FEA9Bull
static unsigned long long b_rng = B_RNG0;

static double brand(void)
{
    b_rng ^= b_rng << 13;
    b_rng ^= b_rng >> 7;
    b_rng ^= b_rng << 17;
    return (double)(b_rng >> 11) / 9007199254740992.0;
}

/* The height field the points sample: smooth plus a bump, cheap to evaluate. */
static double height(double u, double v)
{
    return 10.0 * u * (1.0 - u) + 5.0 * v * v + 0.5 * sin(12.0 * u) * cos(9.0 * v);
}

/* Fill rows [k0, k0+n) of the point stream: raster (rows of constant v,
 * as a scanner delivers) or uniformly random parameters. */
static void gen_chunk(const bench_opts_t *o, long k0, long n, double *rows)
{
    long cols = (long)ceil(sqrt((double)o->points));
    for (long k = 0; k < n; k++) {
        double u, v, *r = rows + 5 * k;
        if (o->random) {
            u = brand();
            v = brand();
        } else {
            long kk = k0 + k;
            u = ((double)(kk % cols) + 0.5) / (double)cols;
            v = ((double)(kk / cols) + 0.5) / (double)cols;
        }
        r[0] = u;
        r[1] = v;
        r[2] = 100.0 * u;
        r[3] = 100.0 * v;
        r[4] = height(u, v);
    }
}

static int make_net(const bench_opts_t *o, nf_surf_t *s)
{
    return cf_surf_square(s, (int)o->degree, (int)lround(sqrt((double)o->cp))) ? -1 : 0;
}

/* The assembled Eq. 7 as a file other solvers read (bench/): "CFNE0001",
 * int64 n, int64 nnz, nnz x (int64 row, int64 col, double value) for the
 * upper triangle with row <= col, then n x 3 doubles of right-hand side
 * (x y z of control point i together). Little-endian, as the host writes. */
static int export_system(const nf_fit_t *f, const char *path)
{
    if (!path)
        return -1;
    FILE *fp = fopen(path, "wb");
    if (!fp)
        return -1;
    const nf_stripe_t *A = &f->A;
    int64_t n = A->n, nnz = 0;
    for (long i = 0; i < A->n; i++)
        for (int sl = 0; sl < A->K; sl++)
            nnz += A->S[i * A->K + sl] != 0.0 && i + A->delta[sl] < A->n;
    fwrite("CFNE0001", 1, 8, fp);
    fwrite(&n, sizeof n, 1, fp);
    fwrite(&nnz, sizeof nnz, 1, fp);
    for (long i = 0; i < A->n; i++)
        for (int sl = 0; sl < A->K; sl++) {
            double v = A->S[i * A->K + sl];
            int64_t r = i, c = i + A->delta[sl];
            if (v == 0.0 || c >= A->n)
                continue;
            fwrite(&r, sizeof r, 1, fp);
            fwrite(&c, sizeof c, 1, fp);
            fwrite(&v, sizeof v, 1, fp);
        }
    fwrite(f->rhs, sizeof(double), (size_t)(3 * A->n), fp);
    int bad = ferror(fp);
    bad |= fclose(fp);
    return bad ? -1 : 0;
}

static long peak_rss(void)
{
    struct rusage ru;
    return getrusage(RUSAGE_SELF, &ru) ? -1 : ru.ru_maxrss * 1024L;
}

/* bench fit's points as the fit job's source: generated per read, the
 * same points after every rewind; the first pass's generating time (the
 * fit's) kept apart from the rest (the job's check). */
typedef struct gen_src {
    const bench_opts_t *o;
    long next;
    int passes;
    double t_gen;
} gen_src_t;

static int gen_rewind(void *ctx, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    gen_src_t *g = ctx;
    g->next = 0;
    g->passes++;
    b_rng = B_RNG0;
    return 0;
}

static long gen_read(void *ctx, double *rows, long max, char *msg, size_t ml)
{
    (void)msg, (void)ml;
    gen_src_t *g = ctx;
    long n = g->o->points - g->next < max ? g->o->points - g->next : max;
    double t0 = cli_now();
    gen_chunk(g->o, g->next, n, rows);
    if (g->passes == 1)
        g->t_gen += cli_now() - t0;
    g->next += n;
    return n;
}

static void gen_where(void *ctx, long k, char *buf, size_t n)
{
    (void)ctx;
    snprintf(buf, n, "generated point %ld", k);
}

/* `cellfit bench fit`: the fit job on the square net, its figures in the
 * raw benchmarks' words (accumulate: inside the fitter, merge included;
 * generating apart). */
static int bench_fit(const bench_opts_t *o)
{
    nf_surf_t s;
    if (make_net(o, &s))
        return cli_error("bench", CLI_FAIL, "out of memory");
    cf_fitjob_opts_t fo;
    cf_fitjob_defaults(&fo);
    fo.alpha = o->alpha;
    fo.beta = o->beta;
    fo.solver = o->solver;
    fo.solve_tol = o->tol;
    fo.max_iter = 100000;
    fo.probe = 0; /* the raw solve's figures: no homogeneous check solve */
    fo.threads = (int)o->threads;
    gen_src_t g = {o, 0, 0, 0.0};
    cf_fitsrc_t src = {
        5, o->points, "generated points", gen_rewind, gen_read, gen_where, &g, NULL, NULL, 0};
    char msg[1024];
    cf_fitjob_t *j = NULL;
    cf_fitjob_result_t r;
    memset(&r, 0, sizeof r);
    int rc = cf_fitjob_open(&j, &s, &fo, msg, sizeof msg);
    cf_surf_free(&s);
    if (!rc)
        rc = cf_fitjob_run(j, &src, NULL, 0, 100, &r, msg, sizeof msg);
    cf_fitjob_close(j);
    if (rc)
        return cli_error("bench", cf_fitjob_input_error(rc) ? CLI_USAGE : CLI_FAIL, "%s", msg);
    long ncp = (long)r.surf.nu * r.surf.nv;
    double t_acc = r.t_rows, t_solve = r.t_solve;
    if (o->json) {
        cf_json_t js;
        cf_json_begin(&js, stdout);
        cf_json_str(&js, "bench", "fit");
        cf_json_int(&js, "points", r.points);
        cf_json_int(&js, "control_points", ncp);
        cf_json_int(&js, "degree", o->degree);
        cf_json_str(&js, "order", o->random ? "random" : "raster");
        cf_json_int(&js, "threads", o->threads);
        cf_json_num(&js, "accumulate_seconds", t_acc);
        cf_json_num(&js, "merge_seconds", r.t_merge);
        cf_json_num(&js, "points_per_s", (double)r.points / t_acc);
        cf_json_str(&js, "solver", nf_solver_name(r.solve.solver));
        cf_json_num(&js, "solve_seconds", t_solve);
        cf_json_int(&js, "iterations", r.solve.iterations);
        cf_json_num(&js, "rel_residual", r.solve.rel_residual);
        cf_json_num(&js, "seconds", t_acc + t_solve);
        cf_json_num(&js, "generate_seconds", g.t_gen);
        cf_json_num(&js, "rms", r.rms);
        cf_json_int(&js, "store_bytes", r.store_bytes);
        cf_json_int(&js, "arena_bytes", r.bytes);
        cf_json_int(&js, "peak_rss_bytes", peak_rss());
        cf_json_end(&js);
    } else {
        printf("bench fit: %ld points, %ld control points, degree %ld, %s order, %ld thread%s\n",
               r.points, ncp, o->degree, o->random ? "random" : "raster", o->threads,
               o->threads > 1 ? "s" : "");
        printf("  accumulate %.4f s = %.3g points/s\n", t_acc, (double)r.points / t_acc);
        printf("  solve (%s) %.4f s, %d iterations, relative residual %.2e\n",
               nf_solver_name(r.solve.solver), t_solve, r.solve.iterations, r.solve.rel_residual);
        printf("  rms %.3g (the fit job's check of every point)\n", r.rms);
        printf("  stripe store %ld bytes, arena %ld bytes, peak RSS %ld bytes\n", r.store_bytes,
               r.bytes, peak_rss());
    }
    cf_fitjob_result_free(&r);
    return CLI_OK;
}

enum { B_ACCUMULATE, B_SOLVE, B_FIT, B_EXPORT, B_PROJECT, NBENCH };

static const struct {
    const char *name, *summary;
} benches[NBENCH] = {
    {"accumulate", "accumulate Eq. 7 from --count generated points: points per second"},
    {"solve", "solve Eq. 7 assembled from 10 random points per control point: seconds, "
              "iterations"},
    {"fit", "the fit job (accumulate and solve) on --count generated points"},
    {"export", "write the assembled Eq. 7 of the solve benchmark for other solvers (bench/)"},
    {"project", "projection of points generated near a known surface (Section 3)"},
};

static int solver_arg(const char *v, void *dst)
{
    return cli_solver(v, dst);
}

static int positive(const char *v, void *dst)
{
    double d;
    if (cli_double(v, &d) || !(d > 0))
        return -1;
    *(double *)dst = d;
    return 0;
}

/* The options of benchmark k (not project: bench_project.c), one table. */
static int parse(int k, int argc, char **argv, bench_opts_t *o)
{
    static const char *const orders[] = {"raster", "random", NULL};
    memset(o, 0, sizeof *o);
    o->points = 1000000;
    o->cp = 10000;
    o->threads = 1;
    o->degree = 3;
    o->solver = NF_SOLVER_AUTO;
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->tol = 1e-10;
    cf_opt_t opts[12];
    int n = 0;
    if (k == B_ACCUMULATE || k == B_FIT)
        opts[n++] = (cf_opt_t){.name = "count",
                               .kind = CF_OPT_LONG,
                               .dst = &o->points,
                               .arg = "M",
                               .help = "points to accumulate",
                               .lo = 1,
                               .hi = 4e9};
    opts[n++] = (cf_opt_t){.name = "cp",
                           .kind = CF_OPT_LONG,
                           .dst = &o->cp,
                           .arg = "N",
                           .help = "control points of the square net (rounded to a square)",
                           .lo = 4,
                           .hi = NF_MAX_CP};
    opts[n++] = (cf_opt_t){.name = "degree",
                           .kind = CF_OPT_LONG,
                           .dst = &o->degree,
                           .arg = "P",
                           .help = "degree in u and v",
                           .lo = 1,
                           .hi = NF_MAX_DEGREE};
    if (k == B_ACCUMULATE || k == B_FIT)
        opts[n++] = (cf_opt_t){.name = "order",
                               .kind = CF_OPT_CHOICE,
                               .dst = &o->random,
                               .arg = "ORDER",
                               .help = "the points' parameters: a raster (as a scanner delivers) "
                                       "or uniformly random",
                               .choices = orders};
    opts[n++] = (cf_opt_t){.name = "threads",
                           .kind = CF_OPT_LONG,
                           .dst = &o->threads,
                           .arg = "T",
                           .help = "accumulating cores (2: a second accumulator, merged)",
                           .lo = 1,
                           .hi = 2};
    opts[n++] = (cf_opt_t){.name = "solver",
                           .kind = CF_OPT_FUNC,
                           .dst = &o->solver,
                           .arg = "S",
                           .help = "the solver of Eq. 7 (and the storage it needs)",
                           .fn = solver_arg,
                           .fn_what = "one of auto, gs, chol, pcg",
                           .def = "auto"};
    if (k == B_SOLVE || k == B_FIT)
        opts[n++] = (cf_opt_t){.name = "solve-tol",
                               .kind = CF_OPT_FUNC,
                               .dst = &o->tol,
                               .arg = "REL",
                               .help = "the iterative solvers' relative residual",
                               .fn = positive,
                               .fn_what = "a number > 0",
                               .def = "1e-10"};
    if (k == B_EXPORT)
        opts[n++] = (cf_opt_t){.name = "out",
                               .kind = CF_OPT_STR,
                               .dst = &o->out,
                               .arg = "FILE",
                               .help = "the system: \"CFNE0001\", n, nnz, (row, col, value) of "
                                       "the upper triangle, n x 3 right-hand side",
                               .req = 1};
    else
        opts[n++] = (cf_opt_t){.name = "json",
                               .kind = CF_OPT_FLAG,
                               .dst = &o->json,
                               .help = "one JSON object on stdout"};
    opts[n] = (cf_opt_t){0};
    char name[24];
    snprintf(name, sizeof name, "bench %s", benches[k].name);
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = name,
                          .summary = benches[k].summary,
                          .descr = "Nets are square with uniform knots; the data are generated "
                                   "and seeded, streamed without files.",
                          .opts = opts};
    return cf_opt_parse(&cmd, argc - 1, argv + 1, NULL, NULL);
}

/* `cellfit bench` without a benchmark: its own table (no options), whose
 * description lists the benchmarks; --help-man adds every benchmark's
 * section. */
static int bench_top(int argc, char **argv)
{
    char list[1024];
    size_t n = (size_t)snprintf(list, sizeof list,
                                "Single measurements on generated, seeded data; figures printed, "
                                "nothing asserted. Benchmarks (cellfit bench BENCHMARK --help "
                                "lists its options):");
    for (int k = 0; k < NBENCH && n < sizeof list; k++)
        n += (size_t)snprintf(list + n, sizeof list - n, "\n  %-10s %s", benches[k].name,
                              benches[k].summary);
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "bench",
                          .args = "BENCHMARK",
                          .summary = "benchmarks on generated data",
                          .descr = list,
                          .min_pos = 1};
    int rc = cf_opt_parse(&cmd, argc < 2 ? 1 : 2, argv, NULL, NULL);
    if (rc < 0 && !strcmp(argv[1], "--help-man")) {
        bench_opts_t o;
        char *av[] = {argv[0], argv[1], argv[1], NULL};
        for (int k = 0; k < B_PROJECT; k++)
            parse(k, 3, av, &o);
        bench_project(3, av);
    }
    return rc ? cf_opt_exit(rc) : CLI_USAGE;
}

int cmd_bench(int argc, char **argv)
{
    if (argc < 2 || argv[1][0] == '-')
        return bench_top(argc, argv);
    const char *what = argv[1];
    int b = 0;
    while (b < NBENCH && strcmp(what, benches[b].name))
        b++;
    if (b == NBENCH)
        return cli_error("bench", CLI_USAGE,
                         "unknown benchmark '%s' (accumulate, solve, fit, export, project; "
                         "cellfit bench --help)",
                         what);
    if (b == B_PROJECT) /* bench_project.c */
        return bench_project(argc, argv);
    int acc = b == B_ACCUMULATE, sol = b == B_SOLVE || b == B_EXPORT;
    int exp = b == B_EXPORT; /* export writes the system the solve benchmark solves */
    bench_opts_t o;
    int rc = parse(b, argc, argv, &o);
    if (rc)
        return cf_opt_exit(rc);
    if (b == B_FIT)
        return bench_fit(&o);
    if (sol) {
        o.points = 10 * o.cp; /* enough data to determine every control point */
        o.random = 1;
    }
    nf_surf_t s;
    if (make_net(&o, &s))
        return cli_error("bench", CLI_FAIL, "out of memory");
    long need = nf_fit_bytes(s.nu, s.nv, s.p, s.q, o.solver);
    /* --threads 2: a second accumulator (nf_fit_shard_init), in the formula. */
    long shard = o.threads > 1 ? nf_fit_shard_bytes(s.nu, s.nv, s.p, s.q) : 0;
    if (need >= 0 && shard >= 0 && need <= NF_ARENA_BYTES && shard > NF_ARENA_BYTES - need) {
        cf_surf_free(&s);
        return cli_error("bench", CLI_USAGE, "net on %ld threads needs %ld bytes, board allows %ld",
                         o.threads, need + shard, (long)NF_ARENA_BYTES);
    }
    need += shard;
    if (need < 0 || need > NF_ARENA_BYTES) {
        cf_surf_free(&s);
        return cli_error("bench", CLI_USAGE, "net needs %ld bytes, board allows %ld", need,
                         (long)NF_ARENA_BYTES);
    }
    void *mem = malloc((size_t)need);
    if (!mem) {
        cf_surf_free(&s);
        return cli_error("bench", CLI_FAIL, "out of memory");
    }
    nf_arena_t ar;
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_t f;
    nf_fit_params_t prm = {o.alpha, o.beta, o.solver};
    rc = nf_fit_init(&f, &s, &prm, &ar);
    nf_fit_t sh;
    if (!rc && o.threads > 1)
        rc = nf_fit_shard_init(&sh, &f, &ar);
    /* Chunks as large as the job bins at once (up to N points, its lent
     * window), on T cores T windows: random order sorts whole windows. */
    long chunk = rc ? CHUNK : f.bin_cap * (o.threads > 1 ? 2 : 1);
    chunk = chunk < CHUNK ? CHUNK : chunk;
    double *rows = malloc(sizeof(double) * 5 * (size_t)chunk);
    if (!rows) {
        free(mem);
        cf_surf_free(&s);
        return cli_error("bench", CLI_FAIL, "out of memory");
    }
    double t_acc = 0.0, t_gen = 0.0, t_solve = 0.0, t_merge = 0.0;
    nf_solve_stats_t st = {o.solver, 0, 0.0};
    for (long k = 0; !rc && k < o.points; k += chunk) {
        long n = o.points - k < chunk ? o.points - k : chunk;
        double t0 = cli_now();
        gen_chunk(&o, k, n, rows);
        double t1 = cli_now();
        rc = cf_accum_rows(&f, o.threads > 1 ? &sh : NULL, 0, rows, n, NULL);
        t_acc += cli_now() - t1;
        t_gen += t1 - t0;
    }
    if (!rc && o.threads > 1) { /* the second core's sums join the job's: part of the time */
        double t0 = cli_now();
        rc = nf_fit_shard_merge(&f, &sh);
        t_merge = cli_now() - t0;
        t_acc += t_merge;
    }
    if (!rc && exp) {
        rc = nf_fit_finish(&f);
        if (!rc)
            rc = export_system(&f, o.out);
        free(mem);
        free(rows);
        cf_surf_free(&s);
        return rc ? cli_error("bench", CLI_FAIL, "%s: cannot write", o.out) : CLI_OK;
    }
    if (!rc && (sol)) {
        rc = nf_fit_finish(&f);
        nf_solve_opts_t so = {o.tol, 100000, 0};
        double t0 = cli_now();
        if (!rc)
            rc = nf_fit_solve(&f, o.solver, &so, &st);
        t_solve = cli_now() - t0;
    }
    if (rc) {
        free(mem);
        free(rows);
        cf_surf_free(&s);
        return cli_error("bench", CLI_FAIL, "%s", nf_strerror(rc));
    }
    long store = (long)f.n * f.A.K * (long)sizeof(double);
    cf_json_t j;
    if (o.json) {
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "bench", what);
        cf_json_int(&j, "points", o.points);
        cf_json_int(&j, "control_points", f.n);
        cf_json_int(&j, "degree", o.degree);
        cf_json_str(&j, "order", o.random ? "random" : "raster");
        cf_json_int(&j, "threads", o.threads);
        if (acc) {
            cf_json_num(&j, "accumulate_seconds", t_acc);
            cf_json_num(&j, "merge_seconds", t_merge);
            cf_json_num(&j, "points_per_s", (double)o.points / t_acc);
        }
        if (sol) {
            cf_json_str(&j, "solver", nf_solver_name(st.solver));
            cf_json_num(&j, "solve_seconds", t_solve);
            cf_json_int(&j, "iterations", st.iterations);
            cf_json_num(&j, "rel_residual", st.rel_residual);
        }
        cf_json_num(&j, "seconds", acc ? t_acc : t_solve);
        cf_json_num(&j, "generate_seconds", t_gen);
        cf_json_int(&j, "store_bytes", store);
        cf_json_int(&j, "arena_bytes", need);
        cf_json_int(&j, "peak_rss_bytes", peak_rss());
        cf_json_end(&j);
    } else {
        printf("bench %s: %ld points, %ld control points, degree %ld, %s order, %ld thread%s\n",
               what, o.points, f.n, o.degree, o.random ? "random" : "raster", o.threads,
               o.threads > 1 ? "s" : "");
        if (acc)
            printf("  accumulate %.4f s = %.3g points/s\n", t_acc, (double)o.points / t_acc);
        if (sol)
            printf("  solve (%s) %.4f s, %d iterations, relative residual %.2e\n",
                   nf_solver_name(st.solver), t_solve, st.iterations, st.rel_residual);
        printf("  stripe store %ld bytes, arena %ld bytes, peak RSS %ld bytes\n", store, need,
               peak_rss());
    }
    free(mem);
    free(rows);
    cf_surf_free(&s);
    return CLI_OK;
}
