/* cmd_report.c: `cellfit report SURF.igs POINTS --tol T [--png MAP.png]
 * [--json]`: signed normal distances of measured points to a surface
 * (projection, positive along Su x Sv), their statistics and histogram,
 * and a colour deviation map viewed on the points' best-fit plane. The
 * points are streamed (three passes with --png: plane, extent, deviations);
 * memory is fixed by the surface, the map raster and the histogram. */
#include "cf_cli.h"
#include "cf_devmap.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_stats.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cmd.h"
#include <stdlib.h>
#include <string.h>

#define RBATCH 4096

typedef struct report_opts {
    const char *surf, *points, *png;
    double tol;
    int json;
    long entity;
} report_opts_t;

/* --tol: a deviation tolerance, strictly positive. */
static int positive(const char *v, void *dst)
{
    double d;
    if (cli_double(v, &d) || !(d > 0))
        return -1;
    *(double *)dst = d;
    return 0;
}

/* 0 to go on; otherwise cf_opt_parse's result (-1: --help answered). */
static int parse(int argc, char **argv, report_opts_t *o)
{
    memset(o, 0, sizeof *o);
    const char *pos[2];
    const cf_opt_t opts[] = {
        {.name = "tol",
         .kind = CF_OPT_FUNC,
         .dst = &o->tol,
         .arg = "MM",
         .help = "the deviation tolerance: the histogram's and the map's scale",
         .fn = positive,
         .fn_what = "a number > 0 (mm)",
         .req = 1},
        {.name = "png",
         .kind = CF_OPT_STR,
         .dst = &o->png,
         .arg = "MAP.png",
         .help = "write a colour deviation map on the points' best-fit plane"},
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &o->entity,
         .arg = "DE",
         .help = "the surface's directory entry in SURF (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &o->json, .help = "one JSON object on stdout"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "report",
                          .args = "SURF.igs POINTS",
                          .summary = "signed normal distances of POINTS to SURF (+ along Su x Sv): "
                                     "statistics, histogram, deviation map",
                          .descr = "POINTS is a file of x y z or u v x y z rows (the last three "
                                   "columns are used); with --png it is read three times, so it "
                                   "must be a file, not standard input.",
                          .opts = opts,
                          .min_pos = 2,
                          .max_pos = 2};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return rc;
    o->surf = pos[0];
    o->points = pos[1];
    return 0;
}

/* The x y z of a point row: the last three columns (x y z or u v x y z). */
static const double *xyz_of(const double *buf, int cols, long k)
{
    return buf + (long)cols * k + (cols - 3);
}

int cmd_report(int argc, char **argv)
{
    report_opts_t o;
    int rc = parse(argc, argv, &o);
    if (rc)
        return cf_opt_exit(rc);
    char msg[512];
    double t0 = cli_now();
    nf_surf_t s;
    if (cf_surfio_read(o.surf, (int)o.entity, &s, msg, sizeof msg))
        return cli_error("report", CLI_USAGE, "%s", msg);
    cf_points_t *pr = NULL;
    cf_seedgrid_t sg;
    memset(&sg, 0, sizeof sg);
    cf_devmap_t *map = NULL;
    cf_stats_t *st = malloc(sizeof *st);
    double *buf = malloc(sizeof(double) * 5 * RBATCH);
    int ec = CLI_OK;
    long got, clamped = 0;
    if (!st || !buf || cf_seedgrid_init(&sg, &s, 8)) {
        ec = cli_error("report", CLI_FAIL, "out of memory");
        goto done;
    }
    cf_stats_init(st, o.tol);
    if (cf_points_open(&pr, o.points, 0, msg, sizeof msg)) {
        ec = cli_error("report", CLI_USAGE, "%s", msg);
        goto done;
    }
    if (o.png) {
        /* Pass 1: the view plane; pass 2: the map's extent on it. */
        cf_planefit_t pf;
        cf_plane_t pl;
        double sd[3];
        cf_devmap_plane_init(&pf);
        while ((got = cf_points_read(pr, buf, RBATCH, msg, sizeof msg)) > 0)
            for (long k = 0; k < got; k++)
                cf_devmap_plane_add(&pf, xyz_of(buf, cf_points_cols(pr), k));
        if (got < 0) {
            ec = cli_error("report", CLI_USAGE, "%s", msg);
            goto done;
        }
        char title[256];
        snprintf(title, sizeof title, "%s vs %s", o.surf, o.points);
        cf_devmap_opts_t mo = {o.tol, 0, CF_DEVMAP_MEAN, title};
        if (cf_devmap_plane_fit(&pf, &pl, sd, msg, sizeof msg) ||
            cf_devmap_create(&map, &pl, &mo, msg, sizeof msg)) {
            ec = cli_error("report", CLI_USAGE, "%s: %s", o.points, msg);
            goto done;
        }
        if (cf_points_rewind(pr)) {
            ec = cli_error("report", CLI_USAGE,
                           "%s: --png reads the points three times: give a "
                           "file, not standard input",
                           o.points);
            goto done;
        }
        while ((got = cf_points_read(pr, buf, RBATCH, msg, sizeof msg)) > 0)
            for (long k = 0; k < got; k++)
                cf_devmap_extent(map, xyz_of(buf, cf_points_cols(pr), k));
        if (got < 0 || cf_devmap_begin(map, msg, sizeof msg) || cf_points_rewind(pr)) {
            ec = cli_error("report", CLI_USAGE, "%s: %s", o.points, msg);
            goto done;
        }
    }
    /* The deviations: project each point, add its signed distance. */
    while ((got = cf_points_read(pr, buf, RBATCH, msg, sizeof msg)) > 0) {
        const int cols = cf_points_cols(pr);
        for (long k = 0; k < got; k++) {
            const double *Q = xyz_of(buf, cols, k);
            nf_proj_t pj;
            cf_seedgrid_project(&sg, Q, 1e-9, &pj); /* best point kept on ENOCONV */
            clamped += pj.clamped;
            cf_stats_add(st, pj.dist);
            if (map)
                cf_devmap_add(map, Q, pj.dist);
        }
    }
    if (got < 0) {
        ec = cli_error("report", CLI_USAGE, "%s", msg);
        goto done;
    }
    if (st->n == 0) {
        ec = cli_error("report", CLI_USAGE, "%s: no points", o.points);
        goto done;
    }
    if (map && cf_devmap_write_png(map, st, o.png, msg, sizeof msg)) {
        ec = cli_error("report", CLI_FAIL, "%s", msg);
        goto done;
    }
    if (o.json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "surface", o.surf);
        cf_json_str(&j, "points_file", o.points);
        cf_stats_json_fields(st, &j);
        cf_json_int(&j, "boundary_feet", clamped);
        if (o.png)
            cf_json_str(&j, "png", o.png);
        cf_json_num(&j, "seconds", cli_now() - t0);
        cf_json_end(&j);
    } else {
        printf("cellfit report: %s against %s (signed normal distance, + along Su x Sv)\n",
               o.points, o.surf);
        cf_stats_print(st, stdout);
        if (clamped)
            printf("  %ld points project onto the surface boundary\n", clamped);
        if (o.png)
            printf("  deviation map: %s\n", o.png);
    }
done:
    cf_devmap_free(map);
    cf_points_close(pr);
    cf_seedgrid_free(&sg);
    free(buf);
    free(st);
    cf_surf_free(&s);
    return ec;
}
