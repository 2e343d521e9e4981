/* SPDX-License-Identifier: MIT */
/* cmd_base.c: `cellfit base`: a base surface for parameterising scattered
 * x y z points (Piegl & Tiller 2001, Section 2), written as IGES 128 for
 * `cellfit fit --base`: a plane patch over the points' plane (no curves),
 * or from four boundary curves (IGES 126) the bilinear Coons patch, the
 * bicubic Coons patch with cross derivatives fitted to a random subset of
 * the points, or a tensor-product fit to such a subset, the subset's
 * parameters coming from projection onto the bilinear patch; without
 * --curves the four curves are fitted to the points near the edges of
 * their rectangle in their plane (nf_curvefit). Points are
 * streamed (one or two passes); memory is a function of the nets only.
 * `cellfit base --extract SURF.igs --out CURVES.igs` writes a surface's
 * four boundary curves as entities 126. */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_fitpass.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"
#include "nf_base.h"
#include "nf_coons.h"
#include "nf_curvefit.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_refine.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BATCH 4096
#define PROJ_TOL 1e-9

enum { M_PLANE, M_BILINEAR, M_BICUBIC, M_TENSOR };
static const char *const method_name[] = {"plane", "bilinear", "bicubic", "tensor", NULL};

typedef struct base_opts {
    const char *points, *curves, *out, *extract;
    const char *cname; /* the curves' file, or what made them */
    int method, json, scale, have_de;
    long de[4], nu, nv, degree, seed, entity;
    double subset, tol, margin, band;
    long edge_cp;
} base_opts_t;

/* --de a,b,c,d: four odd directory-entry numbers. */
static int parse_de(const char *s, void *dst)
{
    long *de = dst;
    char buf[128];
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    for (int k = 0; k < 4; k++, tok = strtok_r(NULL, ",", &save))
        if (!tok || cli_int(tok, 1, 9999999, &de[k]) || de[k] % 2 == 0)
            return -1;
    return tok ? -1 : 0;
}

/* A percentage in (0, hi]: the lower end is open, which a cf_opt range
 * (inclusive) cannot say. */
static int pct_in(const char *v, double *dst, double hi)
{
    double d;
    if (cli_double(v, &d) || !(d > 0) || d > hi)
        return -1;
    *dst = d;
    return 0;
}

static int pct100(const char *v, void *dst)
{
    return pct_in(v, dst, 100.0);
}

static int pct50(const char *v, void *dst)
{
    return pct_in(v, dst, 50.0);
}

/* 0 to go on; otherwise cf_opt_parse's result (-1: --help answered) or
 * CLI_USAGE after a line on stderr. */
static int parse(int argc, char **argv, base_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->method = -1;
    o->subset = 30.0;
    o->seed = 1;
    o->tol = 1e-3;
    o->margin = 0.02;
    o->band = 3.0;
    o->edge_cp = 8;
    const cf_opt_t opts[] = {
        {.name = "points",
         .kind = CF_OPT_STR,
         .dst = &o->points,
         .arg = "FILE",
         .help = "the scattered points, x y z (streamed; '-': standard input)"},
        {.name = "curves",
         .kind = CF_OPT_STR,
         .dst = &o->curves,
         .arg = "CURVES.igs",
         .help = "four boundary curves (IGES 126); without them the edges are fitted to the "
                 "points"},
        {.name = "de",
         .kind = CF_OPT_FUNC,
         .dst = o->de,
         .arg = "a,b,c,d",
         .help = "the four curves' directory entries in CURVES",
         .fn = parse_de,
         .fn_what = "four odd DE numbers a,b,c,d",
         .def = "the first four curves",
         .given = &o->have_de},
        {.name = "method",
         .kind = CF_OPT_CHOICE,
         .dst = &o->method,
         .arg = "M",
         .help = "the base surface",
         .choices = method_name,
         .def = "plane without --curves, bilinear with"},
        {.name = "subset",
         .kind = CF_OPT_FUNC,
         .dst = &o->subset,
         .arg = "PCT",
         .help = "percent of the points that bicubic and tensor fit to",
         .fn = pct100,
         .fn_what = "a percentage in (0, 100]",
         .def = "30"},
        {.name = "seed",
         .kind = CF_OPT_LONG,
         .dst = &o->seed,
         .arg = "S",
         .help = "random seed of the subset",
         .lo = 0,
         .hi = 4611686018427387904.0},
        {.name = "scale",
         .kind = CF_OPT_FLAG,
         .dst = &o->scale,
         .help = "bicubic: scale the cross derivatives (the paper's remedy for overshoot)"},
        {.name = "nu",
         .kind = CF_OPT_LONG,
         .dst = &o->nu,
         .arg = "N",
         .help = "control points in u",
         .lo = 2,
         .hi = NF_MAX_CP,
         .def = "from the method"},
        {.name = "nv",
         .kind = CF_OPT_LONG,
         .dst = &o->nv,
         .arg = "N",
         .help = "control points in v",
         .lo = 2,
         .hi = NF_MAX_CP,
         .def = "from the method"},
        {.name = "degree",
         .kind = CF_OPT_LONG,
         .dst = &o->degree,
         .arg = "P",
         .help = "degree of plane and tensor",
         .lo = 1,
         .hi = NF_MAX_DEGREE,
         .def = "from the method"},
        {.name = "corner-tol",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->tol,
         .arg = "MM",
         .help = "largest gap where two boundary curves meet at a corner",
         .lo = 0,
         .hi = 1e308},
        {.name = "edge-band",
         .kind = CF_OPT_FUNC,
         .dst = &o->band,
         .arg = "PCT",
         .help = "fitted edges: the band of points along each edge, percent of the rectangle",
         .fn = pct50,
         .fn_what = "a percentage in (0, 50]",
         .def = "3"},
        {.name = "edge-cp",
         .kind = CF_OPT_LONG,
         .dst = &o->edge_cp,
         .arg = "N",
         .help = "fitted edges: control points per curve",
         .lo = 4,
         .hi = NF_CURVEFIT_MAX_CP},
        {.name = "margin",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->margin,
         .arg = "F",
         .help = "grow the points' rectangle by this fraction on each side",
         .lo = 0,
         .hi = 1},
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &o->entity,
         .arg = "DE",
         .help = "--extract: the surface's directory entry (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "extract",
         .kind = CF_OPT_STR,
         .dst = &o->extract,
         .arg = "SURF.igs",
         .help = "write SURF's four boundary curves (IGES 126) to --out instead"},
        {.name = "out",
         .kind = CF_OPT_STR,
         .dst = &o->out,
         .arg = "FILE.igs",
         .help = "the base surface (or the curves with --extract)",
         .req = 1},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &o->json, .help = "one JSON object on stdout"},
        {0}};
    const cf_cmd_t cmd = {
        .prog = "cellfit",
        .name = "base",
        .summary = "a base surface for parameterising scattered points (Section 2), for "
                   "`cellfit fit --base`",
        .descr = "Methods: plane (a plane patch over the points' plane), bilinear (the Coons "
                 "patch of the four curves), bicubic (Coons with cross derivatives fitted to a "
                 "random --subset of the points), tensor (a tensor-product fit to that subset). "
                 "Without --curves the four curves are fitted to the points near the edges of "
                 "their rectangle. `cellfit base --extract SURF.igs --out CURVES.igs` writes a "
                 "surface's boundary curves.",
        .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return rc;
    if (o->extract)
        return CLI_OK;
    o->cname = o->curves ? o->curves : "edges fitted to the points";
    if (o->method < 0)
        o->method = o->curves ? M_BILINEAR : M_PLANE;
    if (o->method != M_PLANE && !o->curves && !o->points)
        return cli_error("base", CLI_USAGE,
                         "--method %s needs --curves CURVES.igs or --points FILE (edges "
                         "fitted from the data)",
                         method_name[o->method]);
    if (o->method == M_PLANE && o->curves)
        return cli_error("base", CLI_USAGE, "--method plane takes no --curves");
    if (o->method != M_BILINEAR && !o->points)
        return cli_error("base", CLI_USAGE, "--method %s needs --points FILE",
                         method_name[o->method]);
    if ((o->method == M_BILINEAR || o->method == M_BICUBIC) && o->degree)
        return cli_error("base", CLI_USAGE,
                         "--degree applies to plane and tensor; a Coons patch takes the "
                         "curves' degrees (at least 3 for bicubic)");
    return CLI_OK;
}

/* ------------------------------------------------------------ helpers */

static unsigned long long g_rng;

static double urand(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}

static int extract(const base_opts_t *o)
{
    char msg[512];
    nf_surf_t s;
    int rc = cf_surfio_read(o->extract, (int)o->entity, &s, msg, sizeof msg);
    if (rc)
        return cli_error("base", CLI_USAGE, "%s", msg);
    nf_curve_t c[4];
    memset(c, 0, sizeof c);
    int ec = CLI_OK;
    /* C0: v = v0, C1: v = v1 (rows), D0: u = u0, D1: u = u1 (columns). */
    for (int k = 0; k < 4 && !ec; k++) {
        int col = k >= 2, n = col ? s.nv : s.nu, p = col ? s.q : s.p;
        int idx = k == 1 ? s.nv - 1 : (k == 3 ? s.nu - 1 : 0);
        if (cf_curve_alloc(&c[k], p, n)) {
            ec = cli_error("base", CLI_FAIL, "out of memory");
            break;
        }
        memcpy(c[k].U, col ? s.V : s.U, sizeof(double) * (size_t)(n + p + 1));
        for (int i = 0; i < n; i++) {
            long at = col ? idx + (long)i * s.nu : i + (long)idx * s.nu;
            memcpy(c[k].cp + 3 * i, s.cp + 3 * at, 3 * sizeof(double));
            c[k].w[i] = s.w[at];
        }
    }
    if (!ec && cf_iges_write_curves(o->out, c, 4, "cellfit boundary curves", msg, sizeof msg))
        ec = cli_error("base", CLI_FAIL, "%s", msg);
    if (!ec && !o->json)
        printf("cellfit base: boundary curves of %s (C0 v=v0, C1 v=v1, D0 u=u0, D1 u=u1) in %s\n",
               o->extract, o->out);
    if (!ec && o->json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "extract", o->extract);
        cf_json_int(&j, "curves", 4);
        cf_json_str(&j, "out", o->out);
        cf_json_end(&j);
    }
    for (int k = 0; k < 4; k++)
        cf_curve_free(&c[k]);
    cf_surf_free(&s);
    return ec;
}

/* Uniform knot vector on [0, 1]. */
static void uniform_knots(double *U, int n, int p)
{
    for (int i = 0; i <= p; i++) {
        U[i] = 0.0;
        U[n + i] = 1.0;
    }
    for (int i = p + 1; i < n; i++)
        U[i] = (double)(i - p) / (n - p);
}

/* Refine s (heap) in place to at least nu x nv control points: the
 * widest spans halved (nf_refine_widest), inserted by Boehm. */
static int refine_to(nf_surf_t *s, int nu, int nv)
{
    for (int dir = 0; dir < 2; dir++) {
        int have = dir ? s->nv : s->nu, want = dir ? nv : nu, r = want - have;
        if (r <= 0)
            continue;
        double *X = malloc(sizeof(double) * (size_t)r);
        nf_surf_t o;
        if (!X || cf_surf_alloc(&o, s->p, s->q, dir ? s->nu : want, dir ? want : s->nv)) {
            free(X);
            return CF_ENOMEM;
        }
        int rc = nf_refine_widest(dir ? s->V : s->U, have, dir ? s->q : s->p, r, X);
        if (!rc)
            rc = dir ? nf_refine_v(s, X, r, &o) : nf_refine_u(s, X, r, &o);
        free(X);
        if (rc) {
            cf_surf_free(&o);
            return rc;
        }
        cf_surf_free(s);
        *s = o;
    }
    return NF_OK;
}

typedef struct result {
    long points, used;
    double gap, normal[3], lam[3], rms;
    int iters, has_rms;
} result_t;

/* Stream the points; call fn on each (or on a seeded random subset). */
typedef int (*point_fn)(void *ctx, const double Q[3], long line);

static int stream(const base_opts_t *o, cf_points_t *r, double frac, point_fn fn, void *ctx,
                  long *seen, long *used)
{
    char msg[512];
    double *buf = malloc(sizeof(double) * 3 * BATCH);
    if (!buf)
        return cli_error("base", CLI_FAIL, "out of memory");
    if (cf_points_rewind(r)) {
        free(buf);
        return cli_error("base", CLI_USAGE, "%s: cannot read the points again", o->points);
    }
    g_rng = 0x9E3779B97F4A7C15ull ^ ((unsigned long long)o->seed * 0xD1B54A32D192ED03ull);
    if (!g_rng)
        g_rng = 1;
    long got, n = 0, u = 0;
    int ec = CLI_OK;
    while (!ec && (got = cf_points_read(r, buf, BATCH, msg, sizeof msg)) > 0) {
        for (long k = 0; k < got && !ec; k++) {
            n++;
            if (frac < 1.0 && urand() >= frac)
                continue;
            u++;
            ec = fn(ctx, buf + 3 * k, cf_points_line(r));
        }
    }
    free(buf);
    if (!ec && got < 0)
        ec = cli_error("base", CLI_USAGE, "%s", msg);
    if (!ec && n == 0)
        ec = cli_error("base", CLI_USAGE, "%s: no points", o->points);
    *seen = n;
    *used = u;
    return ec;
}

/* -------------------------------------------------------------- plane */

typedef struct plane_ctx {
    nf_base_plane_t pl;
    const char *path;
    int pass;
} plane_ctx_t;

static int plane_point(void *ctx, const double Q[3], long line)
{
    plane_ctx_t *c = ctx;
    if (c->pass == 2) {
        nf_base_plane_extent(&c->pl, Q);
        return CLI_OK;
    }
    if (nf_base_plane_add(&c->pl, Q))
        return cli_error("base", CLI_USAGE, "%s:%ld: %s", c->path, line,
                         nf_strerror(NF_ENONFINITE));
    return CLI_OK;
}

static int make_plane(const base_opts_t *o, cf_points_t *r, nf_surf_t *out, result_t *res)
{
    plane_ctx_t c;
    nf_base_plane_init(&c.pl);
    c.path = o->points;
    c.pass = 1;
    int ec = stream(o, r, 1.0, plane_point, &c, &res->points, &res->used);
    if (ec)
        return ec;
    int rc = nf_base_plane_axes(&c.pl);
    if (rc == NF_ENODATA)
        return cli_error("base", CLI_USAGE, "%s: %ld points; a plane needs at least 3", o->points,
                         res->points);
    if (rc)
        return cli_error("base", CLI_USAGE, "%s: the points lie on a line: no plane through them",
                         o->points);
    c.pass = 2;
    if ((ec = stream(o, r, 1.0, plane_point, &c, &res->points, &res->used)))
        return ec;
    int p = o->degree ? (int)o->degree : 3;
    int nu = o->nu ? (int)o->nu : 16, nv = o->nv ? (int)o->nv : 16;
    if (nu <= p || nv <= p)
        return cli_error("base", CLI_USAGE, "net %d x %d too small for degree %d", nu, nv, p);
    if ((long)nu * nv > NF_MAX_CP)
        return cli_error("base", CLI_USAGE, "net %d x %d exceeds the board's %ld control points",
                         nu, nv, (long)NF_MAX_CP);
    if (cf_surf_alloc(out, p, p, nu, nv))
        return cli_error("base", CLI_FAIL, "out of memory");
    nf_base_plane_patch(&c.pl, o->margin, out);
    memcpy(res->normal, c.pl.e[2], sizeof res->normal);
    memcpy(res->lam, c.pl.lam, sizeof res->lam);
    res->iters = c.pl.iters;
    return CLI_OK;
}

/* -------------------------------------------------------------- Coons */

static int read_curves(const base_opts_t *o, nf_curve_t c[4])
{
    char msg[512];
    memset(c, 0, 4 * sizeof *c);
    for (int k = 0; k < 4; k++) {
        int rc = cf_iges_read_curve(o->curves, o->have_de ? (int)o->de[k] : 0, o->have_de ? 0 : k,
                                    &c[k], msg, sizeof msg);
        if (rc) {
            for (int j = 0; j < k; j++)
                cf_curve_free(&c[j]);
            if (rc == CF_ENOTFOUND && !o->have_de)
                return cli_error("base", CLI_USAGE, "%s (four boundary curves needed)", msg);
            return cli_error("base", CLI_USAGE, "%s", msg);
        }
    }
    return CLI_OK;
}

/* Boundary curves from the data (no --curves): the points' plane and
 * rectangle (passes 1 and 2, as for the plane base), then the points near
 * each edge (pass 3) fitted by a cubic curve, parameter = position along
 * the edge. The four are made to meet at the averaged corners. */
typedef struct edge_ctx {
    plane_ctx_t pc;
    nf_curvefit_t f[4];    /* C0 (v = 0), C1 (v = 1), D0 (u = 0), D1 (u = 1) */
    double band[2];        /* band half-widths across e[0] and e[1] */
    double glo[2], ghi[2]; /* the rectangle grown by --margin: the curves' sides */
} edge_ctx_t;

/* Replace the in-plane component of P along axis a by the value x. */
static void snap(const nf_base_plane_t *pl, int a, double x, double P[3])
{
    double d = 0.0;
    for (int k = 0; k < 3; k++)
        d += (P[k] - pl->c[k]) * pl->e[a][k];
    for (int k = 0; k < 3; k++)
        P[k] += (x - d) * pl->e[a][k];
}

static int edge_point(void *ctx, const double Q[3], long line)
{
    edge_ctx_t *c = ctx;
    if (c->pc.pass < 3)
        return plane_point(&c->pc, Q, line);
    const nf_base_plane_t *pl = &c->pc.pl;
    double d[3] = {Q[0] - pl->c[0], Q[1] - pl->c[1], Q[2] - pl->c[2]}, x[2];
    for (int a = 0; a < 2; a++)
        x[a] = d[0] * pl->e[a][0] + d[1] * pl->e[a][1] + d[2] * pl->e[a][2];
    double tu = (x[0] - c->glo[0]) / (c->ghi[0] - c->glo[0]);
    double tv = (x[1] - c->glo[1]) / (c->ghi[1] - c->glo[1]);
    int rc = NF_OK;
    if (fabs(x[1] - pl->lo[1]) <= c->band[1])
        rc = nf_curvefit_add(&c->f[0], tu, Q);
    if (!rc && fabs(x[1] - pl->hi[1]) <= c->band[1])
        rc = nf_curvefit_add(&c->f[1], tu, Q);
    if (!rc && fabs(x[0] - pl->lo[0]) <= c->band[0])
        rc = nf_curvefit_add(&c->f[2], tv, Q);
    if (!rc && fabs(x[0] - pl->hi[0]) <= c->band[0])
        rc = nf_curvefit_add(&c->f[3], tv, Q);
    if (rc)
        return cli_error("base", CLI_USAGE, "%s:%ld: %s", c->pc.path, line, nf_strerror(rc));
    return CLI_OK;
}

#define EDGE_RIDGE 1e-6 /* relative to the mean diagonal: a pull of ~1e-6 of the offset */

static int fit_edges(const base_opts_t *o, cf_points_t *r, nf_curve_t c[4], result_t *res)
{
    static const char *const en[4] = {"C0 (v = 0)", "C1 (v = 1)", "D0 (u = 0)", "D1 (u = 1)"};
    edge_ctx_t e;
    memset(&e, 0, sizeof e);
    memset(c, 0, 4 * sizeof *c);
    nf_base_plane_init(&e.pc.pl);
    e.pc.path = o->points;
    e.pc.pass = 1;
    int n = (int)o->edge_cp;
    long len = NF_CURVEFIT_DOUBLES(n);
    double *mem = malloc(sizeof(double) * (size_t)(4 * len));
    if (!mem)
        return cli_error("base", CLI_FAIL, "out of memory");
    int ec = stream(o, r, 1.0, edge_point, &e, &res->points, &res->used);
    int rc = ec ? NF_OK : nf_base_plane_axes(&e.pc.pl);
    if (!ec && rc == NF_ENODATA)
        ec = cli_error("base", CLI_USAGE, "%s: %ld points; edges need at least 3", o->points,
                       res->points);
    else if (!ec && rc)
        ec = cli_error("base", CLI_USAGE, "%s: the points lie on a line: no rectangle for edges",
                       o->points);
    e.pc.pass = 2;
    if (!ec)
        ec = stream(o, r, 1.0, edge_point, &e, &res->points, &res->used);
    const nf_base_plane_t *pl = &e.pc.pl;
    for (int a = 0; a < 2 && !ec; a++) {
        double w = pl->hi[a] - pl->lo[a];
        e.band[a] = o->band / 100.0 * w;
        e.glo[a] = pl->lo[a] - o->margin * w;
        e.ghi[a] = pl->hi[a] + o->margin * w;
    }
    for (int k = 0; k < 4 && !ec; k++)
        if (nf_curvefit_init(&e.f[k], n, mem + k * len, len) || cf_curve_alloc(&c[k], 3, n))
            ec = cli_error("base", CLI_FAIL, "out of memory");
    e.pc.pass = 3;
    if (!ec)
        ec = stream(o, r, 1.0, edge_point, &e, &res->points, &res->used);
    /* Ridge targets: the rectangle's sides, corners (x, y) in the plane. */
    double X[4][3];
    for (int q = 0; q < 4; q++) {
        double x = (q & 1) ? e.ghi[0] : e.glo[0], y = (q & 2) ? e.ghi[1] : e.glo[1];
        for (int k = 0; k < 3; k++)
            X[q][k] = pl->c[k] + x * pl->e[0][k] + y * pl->e[1][k];
    }
    static const int ends[4][2] = {{0, 1}, {2, 3}, {0, 2}, {1, 3}};
    for (int k = 0; k < 4 && !ec; k++) {
        if (e.f[k].npts < n) {
            ec = cli_error("base", CLI_USAGE,
                           "%s: edge %s has %ld points within --edge-band %g %%; %d control "
                           "points need at least as many",
                           o->points, en[k], e.f[k].npts, o->band, n);
            break;
        }
        rc = nf_curvefit_solve(&e.f[k], X[ends[k][0]], X[ends[k][1]], EDGE_RIDGE, &c[k]);
        if (rc)
            ec = cli_error("base", CLI_USAGE, "%s: edge %s: %s", o->points, en[k], nf_strerror(rc));
    }
    free(mem);
    /* The band's points lie inside the data's edge: each curve is put on
     * its side of the grown rectangle (its across component snapped; the
     * curve is linear in its control points), so every point projects
     * inside the patch; along and height stay fitted. */
    for (int k = 0; k < 4 && !ec; k++) {
        int a = k < 2 ? 1 : 0;
        double x = (k & 1) ? e.ghi[a] : e.glo[a];
        for (int i = 0; i < n; i++)
            snap(pl, a, x, c[k].cp + 3 * i);
    }
    if (!ec) { /* clamped cubic: end control point = end point; meet at the
                * mean, in the plane at the rectangle's corner */
        static const int at[4][4] = {{0, 0, 2, 0}, {0, 1, 3, 0}, {1, 0, 2, 1}, {1, 1, 3, 1}};
        for (int q = 0; q < 4; q++) {
            double *a = c[at[q][0]].cp + 3 * (at[q][1] ? n - 1 : 0);
            double *b = c[at[q][2]].cp + 3 * (at[q][3] ? n - 1 : 0);
            for (int k = 0; k < 3; k++)
                a[k] = 0.5 * (a[k] + b[k]);
            snap(pl, 0, (q & 1) ? e.ghi[0] : e.glo[0], a);
            snap(pl, 1, (q & 2) ? e.ghi[1] : e.glo[1], a);
            memcpy(b, a, 3 * sizeof(double));
        }
    }
    if (ec)
        for (int k = 0; k < 4; k++)
            cf_curve_free(&c[k]);
    return ec;
}

static int prepare(const base_opts_t *o, const nf_curve_t c[4], int pmin, nf_coons_t *cs,
                   double **mem)
{
    long need = nf_coons_doubles(c, pmin);
    if (need < 0)
        return cli_error("base", CLI_USAGE, "%s: %s", o->cname, nf_coons_strerror((int)need));
    *mem = malloc(sizeof(double) * (size_t)need);
    if (!*mem)
        return cli_error("base", CLI_FAIL, "out of memory");
    int rc = nf_coons_prepare(cs, c, pmin, o->tol, *mem, need);
    if (rc == NF_COONS_ECORNER) {
        static const char *cn[4] = {"(0,0)", "(1,0)", "(0,1)", "(1,1)"};
        char which[64] = "curves 1-4";
        if (o->have_de)
            snprintf(which, sizeof which, "DE %ld,%ld,%ld,%ld", o->de[0], o->de[1], o->de[2],
                     o->de[3]);
        return cli_error("base", CLI_USAGE,
                         "%s: boundary curves (%s) do not meet at corner (u,v) = %s: gap %.6g mm "
                         "> --corner-tol %g",
                         o->cname, which, cn[cs->corner], cs->gap, o->tol);
    }
    if (rc)
        return cli_error("base", CLI_USAGE, "%s: %s", o->cname, nf_coons_strerror(rc));
    return CLI_OK;
}

/* Projection of points onto the bilinear patch, then a consumer. */
typedef struct proj_ctx {
    cf_seedgrid_t g;
    const char *path;
    nf_coons3_t *b3;   /* bicubic: rows of Q = S(u, v) */
    cf_fitpass_t *fit; /* tensor: rows of the fit */
    double ss;         /* sum of squared projection distances */
} proj_ctx_t;

static int proj_point(void *ctx, const double Q[3], long line)
{
    proj_ctx_t *c = ctx;
    if (!(Q[0] - Q[0] == 0.0) || !(Q[1] - Q[1] == 0.0) || !(Q[2] - Q[2] == 0.0))
        return cli_error("base", CLI_USAGE, "%s:%ld: %s", c->path, line,
                         nf_strerror(NF_ENONFINITE));
    nf_proj_t pr;
    cf_seedgrid_project(&c->g, Q, PROJ_TOL, &pr); /* best point kept on ENOCONV */
    c->ss += pr.dist * pr.dist;
    double row[5] = {pr.u, pr.v, Q[0], Q[1], Q[2]};
    int rc = c->b3 ? nf_coons3_add(c->b3, pr.u, pr.v, Q) : cf_fitpass_rows(c->fit, row, 1, 5, NULL);
    if (rc)
        return cli_error("base", CLI_USAGE, "%s:%ld: %s", c->path, line, nf_strerror(rc));
    return CLI_OK;
}

static int make_coons(const base_opts_t *o, cf_points_t *r, nf_surf_t *out, result_t *res)
{
    nf_curve_t c[4];
    int ec = o->curves ? read_curves(o, c) : fit_edges(o, r, c, res);
    if (ec)
        return ec;
    nf_coons_t cs;
    double *mem = NULL, *mem3 = NULL, *fmem = NULL;
    nf_surf_t bil, fb;
    memset(&bil, 0, sizeof bil);
    memset(&fb, 0, sizeof fb);
    proj_ctx_t pc;
    memset(&pc, 0, sizeof pc);
    ec = prepare(o, c, o->method == M_BICUBIC ? 3 : 1, &cs, &mem);
    if (ec)
        goto done;
    res->gap = cs.gap;
    int p, q, nu, nv;
    nf_coons_size(&cs, &p, &q, &nu, &nv);
    if ((long)nu * nv > NF_MAX_CP) {
        ec =
            cli_error("base", CLI_USAGE, "Coons net %d x %d exceeds the board's %ld control points",
                      nu, nv, (long)NF_MAX_CP);
        goto done;
    }
    if (cf_surf_alloc(&bil, p, q, nu, nv)) {
        ec = cli_error("base", CLI_FAIL, "out of memory");
        goto done;
    }
    int rc = nf_coons_bilinear(&cs, &bil);
    if (rc) {
        ec = cli_error("base", CLI_USAGE, "%s: %s", o->cname, nf_coons_strerror(rc));
        goto done;
    }
    if (o->method == M_BILINEAR) {
        *out = bil;
        memset(&bil, 0, sizeof bil);
        goto refine;
    }
    pc.path = o->points;
    if (cf_seedgrid_init(&pc.g, &bil, 8)) {
        ec = cli_error("base", CLI_FAIL, "out of memory");
        goto done;
    }
    nf_coons3_t b3;
    cf_fitpass_t fit;
    char msg[512];
    if (o->method == M_BICUBIC) {
        int K = nf_coons3_unknowns(&cs);
        long need = NF_COONS3_DOUBLES(K, nu, nv);
        mem3 = malloc(sizeof(double) * (size_t)need);
        if (!mem3) {
            ec = cli_error("base", CLI_FAIL, "out of memory");
            goto done;
        }
        if ((rc = nf_coons3_init(&b3, &cs, mem3, need))) {
            ec = cli_error("base", CLI_USAGE, "%s: %s", o->cname, nf_coons_strerror(rc));
            goto done;
        }
        pc.b3 = &b3;
    } else {
        /* The fit's space: --nu/--nv/--degree (uniform knots), else the
         * bilinear patch's; P0 (the beta term's nominal) is the bilinear
         * patch sampled at the Greville points. */
        int fp = o->degree ? (int)o->degree : p, fq = o->degree ? (int)o->degree : q;
        int fnu = o->nu ? (int)o->nu : nu, fnv = o->nv ? (int)o->nv : nv;
        if (fnu <= fp || fnv <= fq || (long)fnu * fnv > NF_MAX_CP) {
            ec = cli_error("base", CLI_USAGE, "net %d x %d not usable with degree %d x %d", fnu,
                           fnv, fp, fq);
            goto done;
        }
        if (o->nu || o->nv || o->degree) {
            if (cf_surf_alloc(&fb, fp, fq, fnu, fnv)) {
                ec = cli_error("base", CLI_FAIL, "out of memory");
                goto done;
            }
            uniform_knots(fb.U, fnu, fp);
            uniform_knots(fb.V, fnv, fq);
            for (int j = 0; j < fnv; j++)
                for (int i = 0; i < fnu; i++)
                    nf_surf_eval(&bil, nf_greville(i, fp, fb.U), nf_greville(j, fq, fb.V),
                                 fb.cp + 3 * (i + (long)j * fnu));
        } else if (cf_surf_copy(&fb, &bil)) {
            ec = cli_error("base", CLI_FAIL, "out of memory");
            goto done;
        }
        long need = cf_fitpass_bytes(&fb, NF_SOLVER_AUTO, 1);
        if (need < 0 || need > NF_ARENA_BYTES) {
            ec = cli_error("base", CLI_USAGE, "a %d x %d fit needs %ld bytes; board %s allows %ld",
                           fb.nu, fb.nv, need, BOARD_NAME, (long)NF_ARENA_BYTES);
            goto done;
        }
        fmem = malloc((size_t)need);
        if (!fmem) {
            ec = cli_error("base", CLI_FAIL, "out of memory");
            goto done;
        }
        if ((rc = cf_fitpass_begin(&fit, fmem, (size_t)need, &fb, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT,
                                   NF_SOLVER_AUTO, 1, "tensor fit", msg, sizeof msg))) {
            ec = cli_error("base", CLI_USAGE, "%s", msg);
            goto done;
        }
        pc.fit = &fit;
    }
    ec = stream(o, r, o->subset / 100.0, proj_point, &pc, &res->points, &res->used);
    if (ec)
        goto done;
    if (o->method == M_BICUBIC) {
        rc = nf_coons3_solve(&b3);
        if (rc) {
            ec = cli_error("base", CLI_USAGE,
                           "bicubic Coons: %ld points (%.3g %%) do not determine the %d cross-"
                           "derivative unknowns: %s (give a larger --subset)",
                           res->used, o->subset, b3.K, nf_strerror(rc));
            goto done;
        }
        if (o->scale) /* the paper's remedy for overshoot, "if needed" */
            nf_coons3_scale(&b3);
        if (cf_surf_alloc(out, p, q, nu, nv)) {
            ec = cli_error("base", CLI_FAIL, "out of memory");
            goto done;
        }
        nf_coons3_surface(&b3, out);
    } else {
        nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
        char what[64];
        snprintf(what, sizeof what, "tensor fit to %ld points", res->used);
        if ((rc = cf_fitpass_solve(&fit, &so, &fb, what, msg, sizeof msg))) {
            ec = cli_error("base", CLI_USAGE, "%s", msg);
            goto done;
        }
        *out = fb;
        memset(&fb, 0, sizeof fb);
    }
    res->rms = res->used ? sqrt(pc.ss / (double)res->used) : 0.0;
    res->has_rms = 1;
refine:
    if (o->method != M_TENSOR && (o->nu > out->nu || o->nv > out->nv)) {
        rc = refine_to(out, (int)o->nu, (int)o->nv);
        if (rc)
            ec = cli_error("base", CLI_FAIL, "knot insertion: %s", cf_strerror(rc));
    }
done:
    cf_seedgrid_free(&pc.g);
    free(mem);
    free(mem3);
    free(fmem);
    cf_surf_free(&bil);
    cf_surf_free(&fb);
    for (int k = 0; k < 4; k++)
        cf_curve_free(&c[k]);
    if (ec)
        cf_surf_free(out);
    return ec;
}

int cmd_base(int argc, char **argv)
{
    base_opts_t o;
    int ec = parse(argc, argv, &o);
    if (ec)
        return cf_opt_exit(ec);
    if (o.extract)
        return extract(&o);
    char msg[512];
    double t0 = cli_now();
    cf_points_t *r = NULL;
    if (o.points && cf_points_open(&r, o.points, 3, msg, sizeof msg))
        return cli_error("base", CLI_USAGE, "%s", msg);
    nf_surf_t out;
    memset(&out, 0, sizeof out);
    result_t res;
    memset(&res, 0, sizeof res);
    ec = o.method == M_PLANE ? make_plane(&o, r, &out, &res) : make_coons(&o, r, &out, &res);
    cf_points_close(r);
    if (ec)
        return ec;
    if (cf_surfio_write(o.out, &out, "cellfit base surface", cf_version_string(), msg,
                        sizeof msg)) {
        cf_surf_free(&out);
        return cli_error("base", CLI_FAIL, "%s", msg);
    }
    double t1 = cli_now();
    if (o.json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "method", method_name[o.method]);
        cf_json_int(&j, "points", res.points);
        cf_json_int(&j, "used", res.used);
        cf_json_int(&j, "nu", out.nu);
        cf_json_int(&j, "nv", out.nv);
        cf_json_int(&j, "p", out.p);
        cf_json_int(&j, "q", out.q);
        if (o.method == M_PLANE) {
            cf_json_num(&j, "nx", res.normal[0]);
            cf_json_num(&j, "ny", res.normal[1]);
            cf_json_num(&j, "nz", res.normal[2]);
            cf_json_num(&j, "spread_normal", sqrt(res.lam[2] > 0 ? res.lam[2] : 0));
            cf_json_int(&j, "iterations", res.iters);
        } else {
            cf_json_num(&j, "corner_gap", res.gap);
            cf_json_str(&j, "curves", o.curves ? o.curves : "fitted");
        }
        if (res.has_rms)
            cf_json_num(&j, "rms_to_bilinear", res.rms);
        cf_json_num(&j, "seconds", t1 - t0);
        cf_json_str(&j, "out", o.out);
        cf_json_end(&j);
    } else {
        printf("cellfit base: %s base surface, %d x %d control points, degree %d x %d\n",
               method_name[o.method], out.nu, out.nv, out.p, out.q);
        if (o.method == M_PLANE)
            printf("  plane through %ld points: normal (%.6f, %.6f, %.6f), %d power iterations\n",
                   res.points, res.normal[0], res.normal[1], res.normal[2], res.iters);
        else
            printf("  boundary curves from %s, corners within %.3g mm\n", o.cname, res.gap);
        if (res.has_rms)
            printf("  %ld of %ld points (%.3g %%, seed %ld) projected onto the bilinear patch, rms "
                   "distance %.6g\n",
                   res.used, res.points, o.subset, o.seed, res.rms);
        printf("  %.3f s, wrote %s\n", t1 - t0, o.out);
    }
    cf_surf_free(&out);
    return CLI_OK;
}
