/* SPDX-License-Identifier: MIT */
/* cmd_thin.c: `cellfit thin SURF.igs POINTS --quad-tol T [--radius R] [--entity N]
 * --out FILE [--json]`: thinning (Piegl & Tiller 2001, Section 3.3): the
 * surface is decomposed into quadrilaterals to the relative tolerance T
 * (the paper's thinning tolerance, e.g. 0.005 or 0.5%), and for each vertex
 * the nearest measured point within R of it (model units; default half
 * the mean edge of the quadrilaterals) is kept. The points stream through
 * (memory: the decomposition, never the points); the kept ones are written
 * to FILE as x y z, in input order, each once. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cmd.h"
#include "nf_err.h"
#include "nf_quad.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TBATCH 4096
#define THIN_MAXQ 262144L /* quadrilaterals at most (NF_QUAD_BYTES: about 80 MB) */

typedef struct thin_opts {
    const char *surf, *points, *out;
    double tol, radius;
    int json;
    long entity;
} thin_opts_t;

/* A relative tolerance: a fraction in (0, 1), or a percentage "0.5%". */
static int parse_rel(const char *v, void *dst)
{
    char buf[64];
    double *out = dst;
    size_t n = strlen(v);
    if (n > 1 && n < sizeof buf && v[n - 1] == '%') {
        memcpy(buf, v, n - 1);
        buf[n - 1] = '\0';
        if (cli_double(buf, out))
            return -1;
        *out /= 100.0;
    } else if (cli_double(v, out))
        return -1;
    return *out > 0.0 && *out < 1.0 ? 0 : -1;
}

static int positive(const char *v, void *dst)
{
    double d;
    if (cli_double(v, &d) || !(d > 0))
        return -1;
    *(double *)dst = d;
    return 0;
}

/* 0 to go on; otherwise cf_opt_parse's result (-1: --help answered). */
static int parse(int argc, char **argv, thin_opts_t *o)
{
    memset(o, 0, sizeof *o);
    const char *pos[2];
    const cf_opt_t opts[] = {
        {.name = "quad-tol",
         .kind = CF_OPT_FUNC,
         .dst = &o->tol,
         .arg = "REL",
         .help = "the decomposition's relative tolerance (Section 3.3), e.g. 0.005 or 0.5%",
         .fn = parse_rel,
         .fn_what = "a relative tolerance in (0, 1) or a percentage (0.5%)",
         .req = 1},
        {.name = "radius",
         .kind = CF_OPT_FUNC,
         .dst = &o->radius,
         .arg = "R",
         .help = "keep a point only within R of its vertex (model units)",
         .fn = positive,
         .fn_what = "a number > 0",
         .def = "half the mean quadrilateral edge"},
        {.name = "out",
         .kind = CF_OPT_STR,
         .dst = &o->out,
         .arg = "FILE",
         .help = "the kept points, x y z, in input order",
         .req = 1},
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
                          .name = "thin",
                          .args = "SURF.igs POINTS",
                          .summary = "keep the nearest point of POINTS per vertex of SURF's "
                                     "quadrilateral decomposition (Section 3.3)",
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

/* Half the mean edge length of the quadrilaterals: a vertex's share of
 * the surface, so that each point can only be kept by vertices near it. */
static double default_radius(const nf_quad_t *q)
{
    double sum = 0.0;
    long n = 0;
    for (int j = 0; j < q->nv; j++)
        for (int i = 0; i < q->nu; i++) {
            const double *P = q->xyz + 3 * (i + (long)j * q->nu);
            for (int d = 0; d < 2; d++) {
                if ((d == 0 && i + 1 >= q->nu) || (d == 1 && j + 1 >= q->nv))
                    continue;
                const double *R = d == 0 ? P + 3 : P + 3L * q->nu;
                sum += sqrt((R[0] - P[0]) * (R[0] - P[0]) + (R[1] - P[1]) * (R[1] - P[1]) +
                            (R[2] - P[2]) * (R[2] - P[2]));
                n++;
            }
        }
    return n && sum > 0.0 ? 0.5 * sum / (double)n : 1.0;
}

static const long *g_idx; /* qsort's key: the kept point's index per vertex */

static int by_index(const void *a, const void *b)
{
    const long x = g_idx[*(const long *)a], y = g_idx[*(const long *)b];
    return (x > y) - (x < y);
}

int cmd_thin(int argc, char **argv)
{
    thin_opts_t o;
    int rc = parse(argc, argv, &o);
    if (rc)
        return cf_opt_exit(rc);
    char msg[512];
    const double t0 = cli_now();
    nf_surf_t s;
    if (cf_surfio_read(o.surf, (int)o.entity, &s, msg, sizeof msg))
        return cli_error("thin", CLI_USAGE, "%s", msg);
    const size_t qb = NF_QUAD_BYTES(THIN_MAXQ, s.nu, s.nv);
    void *qmem = malloc(qb);
    double *best = malloc(sizeof(double) * (size_t)NF_THIN_DOUBLES(THIN_MAXQ));
    long *idx = malloc(sizeof(long) * (size_t)NF_THIN_LONGS(THIN_MAXQ));
    long *order = malloc(sizeof(long) * (size_t)NF_THIN_VERTS(THIN_MAXQ));
    double *buf = malloc(sizeof(double) * 5 * TBATCH);
    cf_points_t *pr = NULL;
    FILE *out = NULL;
    int ec = CLI_OK;
    if (!qmem || !best || !idx || !order || !buf) {
        ec = cli_error("thin", CLI_FAIL, "out of memory");
        goto done;
    }
    nf_quad_t q;
    const nf_quad_params_t prm = {o.tol, 0.0, 0};
    rc = nf_quad_init(&q, &s, &prm, THIN_MAXQ, qmem, qb);
    if (rc == NF_EBUDGET) {
        ec = cli_error("thin", CLI_FAIL, "%s: --quad-tol %g needs more than %ld quadrilaterals",
                       o.surf, o.tol, THIN_MAXQ);
        goto done;
    } else if (rc) {
        ec = cli_error("thin", CLI_FAIL, "%s: %s", o.surf, nf_strerror(rc));
        goto done;
    }
    const double radius = o.radius > 0 ? o.radius : default_radius(&q);
    nf_thin_t th;
    nf_thin_init(&th, &q, radius, best, idx);
    if (cf_points_open(&pr, o.points, 0, msg, sizeof msg)) {
        ec = cli_error("thin", CLI_USAGE, "%s", msg);
        goto done;
    }
    long got, n = 0;
    while ((got = cf_points_read(pr, buf, TBATCH, msg, sizeof msg)) > 0) {
        const int cols = cf_points_cols(pr);
        for (long k = 0; k < got; k++, n++)
            nf_thin_add(&th, buf + (long)cols * k + (cols - 3), n); /* finite: the reader checks */
    }
    if (got < 0) {
        ec = cli_error("thin", CLI_USAGE, "%s", msg);
        goto done;
    }
    /* Kept points in input order, each once (a point may be nearest to
     * several vertices). */
    const long nvx = nf_thin_verts(&th);
    long nk = 0;
    for (long v = 0; v < nvx; v++)
        if (idx[v] >= 0)
            order[nk++] = v;
    g_idx = idx;
    qsort(order, (size_t)nk, sizeof *order, by_index);
    out = fopen(o.out, "w");
    if (!out) {
        ec = cli_error("thin", CLI_FAIL, "%s: cannot write", o.out);
        goto done;
    }
    long kept = 0;
    for (long m = 0; m < nk; m++) {
        if (m > 0 && idx[order[m]] == idx[order[m - 1]])
            continue;
        const double *P = best + 4 * order[m] + 1;
        fprintf(out, "%.17g %.17g %.17g\n", P[0], P[1], P[2]);
        kept++;
    }
    int bad = ferror(out);
    bad |= fclose(out);
    out = NULL;
    if (bad) {
        ec = cli_error("thin", CLI_FAIL, "%s: cannot write", o.out);
        goto done;
    }
    if (o.json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_int(&j, "points", n);
        cf_json_int(&j, "kept", kept);
        cf_json_int(&j, "quads", nf_quad_count(&q));
        cf_json_int(&j, "vertices", nvx);
        cf_json_num(&j, "rel_tol", o.tol);
        cf_json_num(&j, "radius", radius);
        cf_json_num(&j, "seconds", cli_now() - t0);
        cf_json_end(&j);
    } else {
        printf("thin: %ld points, %ld kept (%ld quadrilaterals, %ld vertices, radius %.6g)\n", n,
               kept, nf_quad_count(&q), nvx, radius);
    }
done:
    if (out)
        fclose(out);
    cf_points_close(pr);
    free(buf);
    free(order);
    free(idx);
    free(best);
    free(qmem);
    cf_surf_free(&s);
    return ec;
}
