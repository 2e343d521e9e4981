/* SPDX-License-Identifier: MIT */
/* bench_project.c: `cellfit bench project --count M [--cp N] [--degree P]
 * [--quad-tol REL] [--offset MM] [--order random|raster] [--json]`: projection of
 * points generated near a known surface (Piegl & Tiller 2001, Section 3:
 * quadrilateral decomposition, grid search, then Newton, nf_quad) with
 * their true parameters known: Q = S(u, v) + d n(u, v), |d| <= offset
 * (1 mm), on a curved bicubic 100 x 100 mm part. Prints the time, points
 * per second (generation excluded) and the largest parameter error
 * against the truth, relative to the domain. Measures, asserts nothing. */
#include "bench_project.h"
#include "cf_cli.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_surf.h"
#include "cmd.h"
#include "nf_err.h"
#include "nf_quad.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define CHUNK 65536
#define PROJ_TOL 1e-9

/* CPU seconds of this process: the figure per core, whatever else the
 * machine runs (wall time is printed beside it). */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static unsigned long long bp_rng = 0x9E3779B97F4A7C15ull;

static double bp_rand(void)
{
    bp_rng ^= bp_rng << 13;
    bp_rng ^= bp_rng >> 7;
    bp_rng ^= bp_rng << 17;
    return (double)(bp_rng >> 11) / 9007199254740992.0;
}

/* The part: a square bicubic net over 100 x 100 mm whose heights follow a
 * smooth field with a bump (radius of curvature >= ~30 mm). */
static int make_part(long cp, int p, nf_surf_t *s)
{
    if (cf_surf_square(s, p, (int)lround(sqrt((double)cp))))
        return -1;
    const int side = s->nu;
    for (int j = 0; j < side; j++)
        for (int i = 0; i < side; i++) {
            const double u = (double)i / (side - 1), v = (double)j / (side - 1);
            s->cp[3 * (i + (long)j * side) + 2] =
                10.0 * u * (1.0 - u) + 5.0 * v * v + 0.5 * sin(6.0 * u) * cos(4.5 * v);
        }
    return 0;
}

/* n points: rows u v x y z with Q = S + d n, d uniform in [-off, off]. */
static void gen(const nf_surf_t *s, long k0, long n, long total, int random, double off,
                double *rows)
{
    const long cols = (long)ceil(sqrt((double)total));
    for (long k = 0; k < n; k++) {
        double u, v, *r = rows + 5 * k;
        if (random) {
            u = bp_rand();
            v = bp_rand();
        } else {
            u = ((double)((k0 + k) % cols) + 0.5) / (double)cols;
            v = ((double)((k0 + k) / cols) + 0.5) / (double)cols;
        }
        double d[27];
        nf_surf_derivs(s, u, v, 1, d);
        const double *Su = d + 9, *Sv = d + 3;
        double nv[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                        Su[0] * Sv[1] - Su[1] * Sv[0]};
        const double l = sqrt(nv[0] * nv[0] + nv[1] * nv[1] + nv[2] * nv[2]);
        const double h = off * (2.0 * bp_rand() - 1.0);
        r[0] = u;
        r[1] = v;
        for (int c = 0; c < 3; c++)
            r[2 + c] = d[c] + h * nv[c] / l;
    }
}

static int rel_tol(const char *v, void *dst)
{
    double d;
    if (cli_double(v, &d) || !(d > 0 && d < 1))
        return -1;
    *(double *)dst = d;
    return 0;
}

int bench_project(int argc, char **argv)
{
    long points = 1000000, cp = 10000, degree = 3, maxq = 200000;
    double rel = NF_QUAD_SEED_TOL, off = 1.0; /* as cf_seedgrid's projections */
    int json = 0, random = 1;
    char quad_tol_def[32]; /* a FUNC option's default is shown as text */
    snprintf(quad_tol_def, sizeof quad_tol_def, "%g", rel);
    static const char *const orders[] = {"raster", "random", NULL};
    const cf_opt_t opts[] = {
        {.name = "count",
         .kind = CF_OPT_LONG,
         .dst = &points,
         .arg = "M",
         .help = "points to project",
         .lo = 1,
         .hi = 4e9},
        {.name = "cp",
         .kind = CF_OPT_LONG,
         .dst = &cp,
         .arg = "N",
         .help = "control points of the square net (rounded to a square)",
         .lo = 4,
         .hi = NF_MAX_CP},
        {.name = "degree",
         .kind = CF_OPT_LONG,
         .dst = &degree,
         .arg = "P",
         .help = "degree in u and v",
         .lo = 1,
         .hi = NF_MAX_DEGREE},
        {.name = "maxq",
         .kind = CF_OPT_LONG,
         .dst = &maxq,
         .arg = "Q",
         .help = "quadrilaterals at most",
         .lo = 1,
         .hi = 100000000},
        {.name = "quad-tol",
         .kind = CF_OPT_FUNC,
         .dst = &rel,
         .arg = "REL",
         .help = "the decomposition's relative tolerance (Section 3)",
         .fn = rel_tol,
         .fn_what = "a number in (0, 1)",
         .def = quad_tol_def},
        {.name = "offset",
         .kind = CF_OPT_DOUBLE,
         .dst = &off,
         .arg = "MM",
         .help = "largest distance of a point from the surface, along its normal",
         .lo = 0,
         .hi = 1e308},
        {.name = "order",
         .kind = CF_OPT_CHOICE,
         .dst = &random,
         .arg = "ORDER",
         .help = "the points' parameters: a raster or uniformly random",
         .choices = orders},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "one JSON object on stdout"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "bench project",
                          .summary = "projection of points generated near a known surface "
                                     "(Section 3): time and largest parameter error",
                          .opts = opts};
    int prc = cf_opt_parse(&cmd, argc - 1, argv + 1, NULL, NULL);
    if (prc)
        return cf_opt_exit(prc);
    nf_surf_t s;
    if (make_part(cp, (int)degree, &s))
        return cli_error("bench", CLI_FAIL, "out of memory");
    const size_t bytes = NF_QUAD_BYTES(maxq, s.nu, s.nv);
    void *mem = malloc(bytes);
    double *rows = malloc(sizeof(double) * 5 * CHUNK);
    int ec = CLI_OK;
    if (!mem || !rows) {
        ec = cli_error("bench", CLI_FAIL, "out of memory");
        goto done;
    }
    nf_quad_t q;
    nf_quad_params_t prm = {rel, 0.0, 0};
    double t0 = cli_now();
    int rc = nf_quad_init(&q, &s, &prm, maxq, mem, bytes);
    const double t_init = cli_now() - t0;
    if (rc) {
        ec = cli_error("bench", CLI_FAIL, "decomposition: %s", nf_strerror(rc));
        goto done;
    }
    double t_proj = 0.0, c_proj = 0.0, err = 0.0, dmax = 0.0;
    long iters = 0, lost = 0;
    for (long k = 0; k < points; k += CHUNK) {
        const long n = points - k < CHUNK ? points - k : CHUNK;
        gen(&s, k, n, points, random, off, rows);
        double e = 0.0, dm = 0.0;
        long it = 0, ls = 0;
        t0 = cli_now();
        const double c0 = cpu_now();
        for (long m = 0; m < n; m++) {
            const double *r = rows + 5 * m;
            nf_proj_t pr;
            ls += nf_quad_project(&q, r + 2, PROJ_TOL, &pr) != NF_OK;
            e = fmax(e, fmax(fabs(pr.u - r[0]), fabs(pr.v - r[1])));
            dm = fmax(dm, fabs(pr.dist));
            it += pr.iters;
        }
        c_proj += cpu_now() - c0;
        t_proj += cli_now() - t0;
        err = fmax(err, e);
        dmax = fmax(dmax, dm);
        iters += it;
        lost += ls;
    }
    const long store = (long)bytes;
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "bench", "project");
        cf_json_int(&j, "points", points);
        cf_json_int(&j, "control_points", (long)s.nu * s.nv);
        cf_json_int(&j, "degree", degree);
        cf_json_str(&j, "order", random ? "random" : "raster");
        cf_json_num(&j, "rel_tol", rel);
        cf_json_int(&j, "quads", nf_quad_count(&q));
        cf_json_int(&j, "grid_cells", (long)q.gx * q.gy);
        cf_json_int(&j, "folded", q.folded);
        cf_json_num(&j, "init_seconds", t_init);
        cf_json_num(&j, "seconds", c_proj);
        cf_json_num(&j, "wall_seconds", t_proj);
        cf_json_num(&j, "points_per_s", (double)points / c_proj);
        cf_json_num(&j, "max_param_error", err);
        cf_json_num(&j, "max_distance", dmax);
        cf_json_num(&j, "mean_newton_iters", (double)iters / (double)points);
        cf_json_int(&j, "slow_points", q.n_slow);
        cf_json_int(&j, "clamped", q.n_clamped);
        cf_json_int(&j, "far", q.n_far);
        cf_json_int(&j, "not_converged", lost);
        cf_json_int(&j, "quad_bytes", store);
        cf_json_end(&j);
    } else {
        printf("bench project: %ld points, %ld control points, degree %ld, %s order\n", points,
               (long)s.nu * s.nv, degree, random ? "random" : "raster");
        printf("  %ld quadrilaterals (tol %.3g), %d x %d grid, init %.4f s, %ld bytes\n",
               nf_quad_count(&q), rel, q.gx, q.gy, t_init, store);
        printf("  project %.4f s CPU (%.4f s wall) = %.3g points/s, max parameter error %.3g, %.2f "
               "Newton steps, "
               "%ld slow, %ld clamped, %ld far, %ld not converged\n",
               c_proj, t_proj, (double)points / c_proj, err, (double)iters / (double)points,
               q.n_slow, q.n_clamped, q.n_far, lost);
    }
done:
    free(mem);
    free(rows);
    cf_surf_free(&s);
    return ec;
}
