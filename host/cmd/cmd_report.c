/* SPDX-License-Identifier: MIT */
/* cmd_report.c: `cellfit report SURF POINTS --tol T [--png MAP.png]
 * [--csv FILE] [--ply FILE] [--dfq FILE] [--checks FILE] [--json]`: signed normal distances
 * of measured points to a surface (projection, positive along Su x Sv),
 * their statistics and histogram, a colour deviation map viewed on the
 * points' best-fit plane, the per-point deviations for a spreadsheet (CSV)
 * and for CloudCompare (PLY coloured on the map's scale), and the figures
 * for an SPC system (Q-DAS DFQ), with the deviation at named check points
 * or zones (--checks, cf_checks.h) after the five figures. The points are
 * streamed (three passes with --png or --ply: plane, extent, deviations;
 * each point projected once, the PLY's colours written over it at the end,
 * when the scale is known); memory is fixed by the surface, the map raster
 * and the histogram. The data footprint (cf_fpmap: the feet per cell of the
 * surface's knot spans) is counted (no_data_cells, footprint_share) and
 * marked on the map: "no data" cells hatched, the outline drawn. */
#include "cf_checks.h"
#include "cf_cli.h"
#include "cf_devmap.h"
#include "cf_dfqset.h"
#include "cf_fpmap.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_ptsout.h"
#include "cf_seedgrid.h"
#include "cf_stats.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cmd.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RBATCH 4096

typedef struct report_opts {
    const char *surf, *points, *png, *csv, *ply, *dfq, *checks;
    const char *part_number, *part_name, *part_id;
    double tol, scale, within;
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
    o->within = 99;
    o->part_number = "";
    o->part_name = "";
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
        {.name = "scale",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->scale,
         .arg = "MM",
         .help = "fix the colour scale's ends at +/- MM (the map's and the PLY's)",
         .lo = 1e-9,
         .hi = 1e6,
         .def = "from the data: symmetric, covering 99 % of |deviation|"},
        {.name = "csv",
         .kind = CF_OPT_STR,
         .dst = &o->csv,
         .arg = "FILE",
         .help = "per-point deviations: x,y,z,u,v,deviation,in_tolerance with a header line"},
        {.name = "ply",
         .kind = CF_OPT_STR,
         .dst = &o->ply,
         .arg = "FILE",
         .help = "the points as binary PLY, coloured on the map's scale (CloudCompare, MeshLab)"},
        {.name = "dfq",
         .kind = CF_OPT_STR,
         .dst = &o->dfq,
         .arg = "FILE",
         .help = "the figures as a Q-DAS DFQ file (RMS, max, min, max |d|, share within "
                 "tolerance, with limits: docs/formats.md)"},
        {.name = "checks",
         .kind = CF_OPT_STR,
         .dst = &o->checks,
         .arg = "FILE",
         .help = "named check points and zones, NAME X Y Z [RADIUS] a line: their deviations "
                 "in the DFQ after the five and in --json (docs/formats.md)"},
        {.name = "within",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->within,
         .arg = "PCT",
         .help = "the share of points that must lie within --tol (the DFQ's lower limit)",
         .lo = 0,
         .hi = 100},
        {.name = "part-number",
         .kind = CF_OPT_STR,
         .dst = &o->part_number,
         .arg = "TEXT",
         .help = "the part number in the DFQ (K1001)"},
        {.name = "part-name",
         .kind = CF_OPT_STR,
         .dst = &o->part_name,
         .arg = "TEXT",
         .help = "the part's name in the DFQ (K1002)"},
        {.name = "part-id",
         .kind = CF_OPT_STR,
         .dst = &o->part_id,
         .arg = "TEXT",
         .help = "the part's serial or ident in the DFQ (K0014)"},
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
                                   "columns are used), CSV with a header, or PLY; with --png or "
                                   "--ply it is read more than once, so it must be a file, not "
                                   "standard input. SURF is IGES or STEP (by extension).",
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

/* The PLY's colours: the map's scale. */
static void map_rgb(double d, void *ctx, unsigned char rgb[3])
{
    uint32_t c = cf_devmap_colour(ctx, d);
    rgb[0] = (unsigned char)(c >> 16);
    rgb[1] = (unsigned char)(c >> 8);
    rgb[2] = (unsigned char)c;
}

/* The PLY's colours, once the scale is known: a scale chosen from the data
 * needs every deviation (cf_devmap_render; the PNG's render fixed it already). */
static int ply_colours(const report_opts_t *o, cf_devmap_t *map, const cf_stats_t *st,
                       cf_ptsout_t *out)
{
    char msg[512];
    cf_image_t im;
    if (!o->png) {
        if (cf_devmap_render(map, st, &im, msg, sizeof msg))
            return cli_error("report", CLI_FAIL, "%s", msg);
        cf_image_free(&im);
    }
    cf_ptsout_set_rgb(out, map_rgb, map);
    return CLI_OK;
}

/* The DFQ's characteristics: the report's figures with their limits, then
 * the checks (cf_dfqset, as serve's EXPORT writes them). */
static int write_dfq(const report_opts_t *o, const cf_stats_t *st, const cf_checks_t *cs)
{
    char msg[512];
    cf_dfq_char_t *c = malloc(sizeof *c * (size_t)(CF_DFQSET_FIGURES + cs->n));
    if (!c)
        return cli_error("report", CLI_FAIL, "out of memory");
    int n = cf_dfqset_chars(st, o->within, cs, c);
    cf_dfq_part_t part = {o->part_number, o->part_name, o->part_id, (long long)time(NULL)};
    if (!part.name[0])
        part.name = o->surf;
    int rc = cf_dfq_write(o->dfq, &part, c, n, msg, sizeof msg);
    free(c);
    if (rc)
        return cli_error("report", CLI_FAIL, "%s", msg);
    return CLI_OK;
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
    cf_ptsout_t out; /* the CSV and the PLY */
    memset(&out, 0, sizeof out);
    cf_fpmap_t fpm;
    memset(&fpm, 0, sizeof fpm);
    nf_footprint_stats_t fs;
    cf_checks_t cs;
    memset(&cs, 0, sizeof cs);
    cf_stats_t *st = malloc(sizeof *st);
    double *buf = malloc(sizeof(double) * 5 * RBATCH);
    int ec = CLI_OK;
    long got, clamped = 0;
    if (!st || !buf || cf_seedgrid_init(&sg, &s, 8) || cf_fpmap_init(&fpm, &s)) {
        ec = cli_error("report", CLI_FAIL, "out of memory");
        goto done;
    }
    cf_stats_init(st, o.tol);
    if (o.checks && cf_checks_read(&cs, o.checks, msg, sizeof msg)) {
        ec = cli_error("report", CLI_USAGE, "%s", msg);
        goto done;
    }
    if (cf_points_open(&pr, o.points, 0, msg, sizeof msg)) {
        ec = cli_error("report", CLI_USAGE, "%s", msg);
        goto done;
    }
    if (o.png || o.ply) {
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
            cf_devmap_create(&map, &pl, &mo, msg, sizeof msg) ||
            (o.scale > 0 && cf_devmap_set_scale(map, o.scale, msg, sizeof msg))) {
            ec = cli_error("report", CLI_USAGE, "%s: %s", o.points, msg);
            goto done;
        }
        if (cf_points_rewind(pr)) {
            ec = cli_error("report", CLI_USAGE,
                           "%s: --png and --ply read the points more than once: give a "
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
    if ((o.csv || o.ply) &&
        cf_ptsout_open(&out, o.csv, o.ply, o.tol, 0, NULL, NULL, msg, sizeof msg)) {
        ec = cli_error("report", CLI_FAIL, "%s", msg);
        goto done;
    }
    while ((got = cf_points_read(pr, buf, RBATCH, msg, sizeof msg)) > 0) {
        const int cols = cf_points_cols(pr);
        for (long k = 0; k < got; k++) {
            const double *Q = xyz_of(buf, cols, k);
            nf_proj_t pj;
            cf_seedgrid_project(&sg, Q, 1e-9, &pj); /* best point kept on ENOCONV */
            clamped += pj.clamped;
            cf_fpmap_add(&fpm, pj.u, pj.v, pj.clamped);
            cf_stats_add(st, pj.dist);
            cf_checks_add(&cs, Q, pj.dist);
            if (map)
                cf_devmap_add(map, Q, pj.dist);
            if (o.csv || o.ply) {
                cf_ptsout_pt_t p = {Q[0], Q[1], Q[2], pj.u, pj.v, pj.dist, NAN};
                cf_ptsout_add(&out, &p);
            }
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
    cf_fpmap_stats(&fpm, &fs);
    if (map)
        cf_fpmap_mark(&fpm, map);
    if (o.png && cf_devmap_write_png(map, st, o.png, msg, sizeof msg)) {
        ec = cli_error("report", CLI_FAIL, "%s", msg);
        goto done;
    }
    if (o.ply && (ec = ply_colours(&o, map, st, &out)) != CLI_OK)
        goto done;
    if ((o.csv || o.ply) && cf_ptsout_close(&out, msg, sizeof msg)) {
        ec = cli_error("report", CLI_FAIL, "%s", msg);
        goto done;
    }
    cf_checks_warn(&cs, stderr, "cellfit report");
    if (o.dfq && (ec = write_dfq(&o, st, &cs)) != CLI_OK)
        goto done;
    if (o.json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "surface", o.surf);
        cf_json_str(&j, "points_file", o.points);
        cf_stats_json_fields(st, &j);
        cf_json_int(&j, "boundary_feet", clamped);
        cf_json_int(&j, "footprint_cells", fs.cells);
        cf_json_int(&j, "footprint_filled", fs.filled);
        cf_json_int(&j, "no_data_cells", fs.empty);
        cf_json_int(&j, "footprint_outline", fs.outline);
        cf_json_num(&j, "footprint_share", fs.cells ? (double)fs.filled / (double)fs.cells : 0.0);
        if (o.png)
            cf_json_str(&j, "png", o.png);
        if (map)
            cf_json_num(&j, "scale_end", cf_devmap_scale_end(map));
        if (o.csv)
            cf_json_str(&j, "csv", o.csv);
        if (o.ply)
            cf_json_str(&j, "ply", o.ply);
        if (o.dfq)
            cf_json_str(&j, "dfq", o.dfq);
        if (o.checks)
            cf_checks_json(&cs, &j);
        cf_json_num(&j, "seconds", cli_now() - t0);
        cf_json_end(&j);
    } else {
        printf("cellfit report: %s against %s (signed normal distance, + along Su x Sv)\n",
               o.points, o.surf);
        cf_stats_print(st, stdout);
        if (clamped)
            printf("  %ld points project onto the surface boundary\n", clamped);
        printf("  footprint: %ld of %ld cells of the surface with points (%.1f %%), %ld no data, "
               "%ld on its outline\n",
               fs.filled, fs.cells, fs.cells ? 100.0 * (double)fs.filled / (double)fs.cells : 0.0,
               fs.empty, fs.outline);
        if (o.png)
            printf("  deviation map: %s\n", o.png);
        if (o.csv)
            printf("  per-point deviations (CSV): %s\n", o.csv);
        if (o.ply)
            printf("  coloured points (PLY, scale +/- %.4g mm): %s\n", cf_devmap_scale_end(map),
                   o.ply);
        if (o.dfq)
            printf("  Q-DAS DFQ: %s\n", o.dfq);
        for (int i = 0; i < cs.n; i++) {
            const cf_check_t *c = &cs.c[i];
            if (isnan(c->radius))
                printf("  check %s: %.6g mm at the nearest point\n", c->name,
                       cf_checks_value(&cs, i));
            else if (c->points)
                printf("  check %s: %.6g mm, the mean of %ld points within %g mm\n", c->name,
                       cf_checks_value(&cs, i), c->points, c->radius);
            else
                printf("  check %s: no value (no point within %g mm)\n", c->name, c->radius);
        }
    }
done:
    if (ec != CLI_OK)
        cf_ptsout_abort(&out); /* nothing when closed or never opened */
    cf_checks_free(&cs);
    cf_devmap_free(map);
    cf_fpmap_free(&fpm);
    cf_points_close(pr);
    cf_seedgrid_free(&sg);
    free(buf);
    free(st);
    cf_surf_free(&s);
    return ec;
}
