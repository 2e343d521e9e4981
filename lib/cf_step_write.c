/* SPDX-License-Identifier: MIT */
/* cf_step_write.c: an nf_surf_t as a STEP AP242 file (ISO 10303-21): the
 * surface as the one face of an open shell, with the product structure and
 * the millimetre unit context CAD systems look for (see cf_step.h). */
#include "cf_atomic.h"
#include "cf_err.h"
#include "cf_fmt.h"
#include "cf_iges.h"
#include "cf_step.h"
#include "cf_trim.h"
#include "nf_err.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef struct sw {
    FILE *f;
    long id;               /* last instance number given out */
    long *pid;             /* nu nv + max(nu, nv): control point instances, then a boundary row */
    double *wt;            /* max(nu, nv): a boundary row's weights */
    const cf_trim_t *trim; /* NULL or no loops: the whole surface */
    double edge_err;       /* the trim's 3-D edges: largest error (cf_trim_edge3d) */
    int rc;                /* a failure in the trim's bounds */
} sw_t;

/* A real as Part 21 wants it (a decimal point always, capital E), with the
 * 17 significant digits that read back to the same double. */
static void sw_real(char *b, size_t bl, double x)
{
    cf_fmt17(x, b, bl);
    char *e = strchr(b, 'e');
    if (e)
        *e = 'E';
    if (!strchr(b, '.')) {
        size_t n = strlen(b), at = e ? (size_t)(e - b) : n;
        memmove(b + at + 1, b + at, n - at + 1);
        b[at] = '.';
    }
}

/* A string literal's body: apostrophes doubled, backslashes doubled
 * (Part 21 7.3.4), anything outside printable ASCII replaced by '_',
 * at most max source characters; empty becomes dflt. */
static void sw_str(char *dst, size_t dl, const char *src, size_t max, const char *dflt)
{
    size_t o = 0;
    if (!src || !*src)
        src = dflt;
    for (size_t i = 0; i < max && src[i] && o + 3 < dl; i++) {
        char c = (src[i] >= 0x20 && src[i] < 0x7F) ? src[i] : '_';
        dst[o++] = c;
        if (c == '\'' || c == '\\')
            dst[o++] = c;
    }
    dst[o] = '\0';
}

static long sw_point(sw_t *w, const double *p)
{
    char x[3][40];
    for (int k = 0; k < 3; k++)
        sw_real(x[k], sizeof x[k], p[k]);
    fprintf(w->f, "#%ld=CARTESIAN_POINT('',(%s,%s,%s));\n", ++w->id, x[0], x[1], x[2]);
    return w->id;
}

/* STEP's form of a knot vector, distinct knots and their multiplicities:
 * the list "(m0,m1,...)" (mults = 1) or "(k0,k1,...)" (mults = 0). Exact
 * comparison: equal knots are the same double in a knot vector that
 * nf_knots_check accepted. */
static void sw_kv(FILE *f, const double *U, int m, int mults)
{
    char b[40];
    fputc('(', f);
    for (int i = 0; i < m;) {
        int j = i;
        while (j < m && U[j] == U[i])
            j++;
        if (mults)
            fprintf(f, "%s%d", i ? "," : "", j - i);
        else {
            sw_real(b, sizeof b, U[i]);
            fprintf(f, "%s%s", i ? "," : "", b);
        }
        i = j;
    }
    fputc(')', f);
}

/* "(mults),(knots)" of a curve. */
static void sw_knots(FILE *f, const double *U, int m)
{
    sw_kv(f, U, m, 1);
    fputc(',', f);
    sw_kv(f, U, m, 0);
}

/* A list of n references #first + k * stride (k = 0..n-1), wrapped. */
static void sw_refs(FILE *f, const long *ids, int n)
{
    fputc('(', f);
    for (int k = 0; k < n; k++)
        fprintf(f, "%s#%ld%s", k ? "," : "", ids[k], k % 12 == 11 && k + 1 < n ? "\n" : "");
    fputc(')', f);
}

/* One boundary curve of the net: n control points ids[k] with weights wt
 * (NULL: non-rational), degree p, knots U (n + p + 1). */
static long sw_curve(sw_t *w, const long *ids, const double *wt, int n, int p, const double *U)
{
    FILE *f = w->f;
    char b[40];
    if (!wt) {
        fprintf(f, "#%ld=B_SPLINE_CURVE_WITH_KNOTS('',%d,", ++w->id, p);
        sw_refs(f, ids, n);
        fputs(",.UNSPECIFIED.,.F.,.F.,", f);
        sw_knots(f, U, n + p + 1);
        fputs(",.UNSPECIFIED.);\n", f);
        return w->id;
    }
    /* Complex entity: partial entities in alphabetical order (Part 21 11.2.5). */
    fprintf(f, "#%ld=(BOUNDED_CURVE()B_SPLINE_CURVE(%d,", ++w->id, p);
    sw_refs(f, ids, n);
    fputs(",.UNSPECIFIED.,.F.,.F.)\nB_SPLINE_CURVE_WITH_KNOTS(", f);
    sw_knots(f, U, n + p + 1);
    fputs(",.UNSPECIFIED.)\nCURVE()GEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_CURVE((", f);
    for (int k = 0; k < n; k++) {
        sw_real(b, sizeof b, wt[k]);
        fprintf(f, "%s%s", k ? "," : "", b);
    }
    fputs("))\nREPRESENTATION_ITEM(''));\n", f);
    return w->id;
}

static void sw_wlist(FILE *f, const nf_surf_t *s)
{
    char b[40];
    fputc('(', f);
    for (int i = 0; i < s->nu; i++) {
        fputs(i ? ",\n(" : "(", f);
        for (int j = 0; j < s->nv; j++) {
            sw_real(b, sizeof b, s->w[i + (long)j * s->nu]);
            fprintf(f, "%s%s", j ? "," : "", b);
        }
        fputc(')', f);
    }
    fputc(')', f);
}

/* The control_points_list: a list per u index (STEP's first index runs
 * along u), each the v row of point ids. */
static void sw_net(FILE *f, const nf_surf_t *s, const long *pid)
{
    fputc('(', f);
    for (int i = 0; i < s->nu; i++) {
        fputs(i ? ",\n(" : "(", f);
        for (int j = 0; j < s->nv; j++)
            fprintf(f, "%s#%ld", j ? "," : "", pid[i + (long)j * s->nu]);
        fputc(')', f);
    }
    fputc(')', f);
}

/* u_multiplicities, v_multiplicities, u_knots, v_knots. */
static void sw_surf_knots(FILE *f, const nf_surf_t *s)
{
    int mu = s->nu + s->p + 1, mv = s->nv + s->q + 1;
    sw_kv(f, s->U, mu, 1);
    fputc(',', f);
    sw_kv(f, s->V, mv, 1);
    fputs(",\n", f);
    sw_kv(f, s->U, mu, 0);
    fputc(',', f);
    sw_kv(f, s->V, mv, 0);
}

static long sw_surface(sw_t *w, const nf_surf_t *s, const long *pid, int rational)
{
    FILE *f = w->f;
    if (!rational) {
        fprintf(f, "#%ld=B_SPLINE_SURFACE_WITH_KNOTS('',%d,%d,\n", ++w->id, s->p, s->q);
        sw_net(f, s, pid);
        fputs(",\n.UNSPECIFIED.,.F.,.F.,.F.,\n", f);
        sw_surf_knots(f, s);
        fputs(",.UNSPECIFIED.);\n", f);
        return w->id;
    }
    fprintf(f, "#%ld=(BOUNDED_SURFACE()B_SPLINE_SURFACE(%d,%d,\n", ++w->id, s->p, s->q);
    sw_net(f, s, pid);
    fputs(",\n.UNSPECIFIED.,.F.,.F.,.F.)\nB_SPLINE_SURFACE_WITH_KNOTS(", f);
    sw_surf_knots(f, s);
    fputs(",", f);
    fputs(".UNSPECIFIED.)\nGEOMETRIC_REPRESENTATION_ITEM()RATIONAL_B_SPLINE_SURFACE(\n", f);
    sw_wlist(f, s);
    fputs(")\nREPRESENTATION_ITEM('')SURFACE());\n", f);
    return w->id;
}

/* One trim curve: 3-D edge on s (cf_trim_edge3d) as the SURFACE_CURVE's
 * curve, the 2-D curve as its PCURVE in a 2-D parametric context; returns
 * the SURFACE_CURVE's id, its 3-D start point's id in *p0. */
static long sw_trim_curve(sw_t *w, const nf_surf_t *s, long surf, long ctx2, const nf_curve_t *c,
                          long *p0)
{
    FILE *f = w->f;
    nf_curve_t e;
    double err;
    int rc = cf_trim_edge3d(s, c, CF_TRIM_EDGE_TOL, &e, &err);
    int n = c->n > e.n ? c->n : e.n;
    long *ids = rc ? NULL : malloc(sizeof(long) * (size_t)n);
    if (rc || !ids) {
        w->rc = rc ? rc : CF_ENOMEM;
        cf_curve_free(&e);
        return 0;
    }
    w->edge_err = fmax(w->edge_err, err);
    for (int k = 0; k < e.n; k++)
        ids[k] = sw_point(w, e.cp + 3 * k);
    *p0 = ids[0]; /* the edge interpolates S(c(t0)): its first control point */
    long c3 = sw_curve(w, ids, NULL, e.n, e.p, e.U);
    int rational = 0;
    for (int k = 0; k < c->n; k++)
        rational |= c->w[k] != 1.0;
    for (int k = 0; k < c->n; k++) {
        char x[2][40];
        sw_real(x[0], sizeof x[0], c->cp[3 * k]);
        sw_real(x[1], sizeof x[1], c->cp[3 * k + 1]);
        fprintf(f, "#%ld=CARTESIAN_POINT('',(%s,%s));\n", ids[k] = ++w->id, x[0], x[1]);
    }
    long c2 = sw_curve(w, ids, rational ? c->w : NULL, c->n, c->p, c->U);
    fprintf(f, "#%ld=DEFINITIONAL_REPRESENTATION('',(#%ld),#%ld);\n", w->id + 1, c2, ctx2);
    fprintf(f, "#%ld=PCURVE('',#%ld,#%ld);\n", w->id + 2, surf, w->id + 1);
    fprintf(f, "#%ld=SURFACE_CURVE('',#%ld,(#%ld),.PCURVE_S1.);\n", w->id + 3, c3, w->id + 2);
    w->id += 3;
    free(ids);
    cf_curve_free(&e);
    return w->id;
}

/* The face's bounds from the trim: per loop an EDGE_LOOP of ORIENTED_EDGEs
 * of EDGE_CURVEs between VERTEX_POINTs (a curve's start is the previous
 * one's end), the first a FACE_OUTER_BOUND; the bound ids into bounds. */
static void sw_trim_bounds(sw_t *w, const nf_surf_t *s, long surf, long *bounds)
{
    FILE *f = w->f;
    const cf_trim_t *t = w->trim;
    long ctx2 = ++w->id;
    fprintf(f,
            "#%ld=(GEOMETRIC_REPRESENTATION_CONTEXT(2)PARAMETRIC_REPRESENTATION_CONTEXT()"
            "REPRESENTATION_CONTEXT('2D SPACE',''));\n",
            ctx2);
    for (int k = 0; k < t->nloops && !w->rc; k++) {
        const cf_trim_loop_t *l = &t->loop[k];
        long *sc = malloc(sizeof(long) * 3 * (size_t)l->n);
        if (!sc) {
            w->rc = CF_ENOMEM;
            return;
        }
        long *vx = sc + l->n, *oe = vx + l->n;
        for (int i = 0; i < l->n && !w->rc; i++) {
            long p0 = 0;
            sc[i] = sw_trim_curve(w, s, surf, ctx2, &l->c[i], &p0);
            fprintf(f, "#%ld=VERTEX_POINT('',#%ld);\n", vx[i] = ++w->id, p0);
        }
        for (int i = 0; i < l->n && !w->rc; i++) {
            fprintf(f, "#%ld=EDGE_CURVE('',#%ld,#%ld,#%ld,.T.);\n", ++w->id, vx[i],
                    vx[(i + 1) % l->n], sc[i]);
            fprintf(f, "#%ld=ORIENTED_EDGE('',*,*,#%ld,.T.);\n", oe[i] = w->id + 1, w->id);
            w->id++;
        }
        if (!w->rc) {
            fprintf(f, "#%ld=EDGE_LOOP('',", ++w->id);
            sw_refs(f, oe, l->n);
            fputs(");\n", f);
            fprintf(f, "#%ld=%s('',#%ld,.T.);\n", bounds[k] = w->id + 1,
                    k ? "FACE_BOUND" : "FACE_OUTER_BOUND", w->id);
            w->id++;
        }
        free(sc);
    }
}

/* The DATA section's instances. */
static void sw_data(sw_t *w, const nf_surf_t *s, const char *pname)
{
    FILE *f = w->f;
    const long n = (long)s->nu * s->nv;
    int rational = 0;
    for (long i = 0; s->w && i < n; i++)
        rational |= s->w[i] != 1.0;
    /* Product structure (AP242 / AP214 conventions). */
    fputs("#1=APPLICATION_CONTEXT('managed model based 3d engineering');\n"
          "#2=APPLICATION_PROTOCOL_DEFINITION('international standard',"
          "'ap242_managed_model_based_3d_engineering',2014,#1);\n"
          "#3=PRODUCT_CONTEXT('',#1,'mechanical');\n",
          f);
    fprintf(f, "#4=PRODUCT('%s','%s','',(#3));\n", pname, pname);
    fputs("#5=PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#4));\n"
          "#6=PRODUCT_DEFINITION_FORMATION('','',#4);\n"
          "#7=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');\n"
          "#8=PRODUCT_DEFINITION('design','',#6,#7);\n"
          "#9=PRODUCT_DEFINITION_SHAPE('','',#8);\n"
          /* Units: mm, radian, steradian; 1e-7 mm as the distance accuracy. */
          "#10=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n"
          "#11=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));\n"
          "#12=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());\n"
          "#13=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#10,"
          "'distance_accuracy_value','confusion accuracy');\n"
          "#14=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#13))"
          "GLOBAL_UNIT_ASSIGNED_CONTEXT((#10,#11,#12))REPRESENTATION_CONTEXT('Context #1',"
          "'3D Context with UNIT and UNCERTAINTY'));\n"
          "#15=CARTESIAN_POINT('',(0.,0.,0.));\n"
          "#16=DIRECTION('',(0.,0.,1.));\n"
          "#17=DIRECTION('',(1.,0.,0.));\n"
          "#18=AXIS2_PLACEMENT_3D('',#15,#16,#17);\n"
          "#19=SHAPE_DEFINITION_REPRESENTATION(#9,#20);\n",
          f);
    /* #20 is the representation, #21 the surface model, #22 the shell,
     * #23 the face; geometry from #24 on. */
    fputs("#20=MANIFOLD_SURFACE_SHAPE_REPRESENTATION('',(#18,#21),#14);\n"
          "#21=SHELL_BASED_SURFACE_MODEL('',(#22));\n"
          "#22=OPEN_SHELL('',(#23));\n",
          f);
    const long face = 23, bound = 24, loop = 25, oe = 26, ec = 30, vx = 34;
    w->id = 37; /* control points from #38, then the surface and its edge curves */
    long *pid = w->pid;
    double *wt = rational ? w->wt : NULL;
    for (long k = 0; k < n; k++)
        pid[k] = sw_point(w, s->cp + 3 * k);
    long surf = sw_surface(w, s, pid, rational);
    if (w->trim && w->trim->nloops > 0) { /* the face bounded by the trim instead */
        long *b = malloc(sizeof(long) * (size_t)w->trim->nloops);
        if (!b) {
            w->rc = CF_ENOMEM;
            return;
        }
        sw_trim_bounds(w, s, surf, b);
        if (!w->rc) {
            fprintf(f, "#%ld=ADVANCED_FACE('',", face);
            sw_refs(f, b, w->trim->nloops);
            fprintf(f, ",#%ld,.T.);\n", surf);
        }
        free(b);
        return;
    }
    /* Boundary curves, counter-clockwise in (u, v): v = v0 (u up), u = u1
     * (v up), v = v1 (u up, used reversed), u = u0 (v up, used reversed). */
    long *row = pid + n;
    long curve[4];
    for (int c = 0; c < 4; c++) {
        int along_u = c % 2 == 0, cnt = along_u ? s->nu : s->nv;
        for (int k = 0; k < cnt; k++) {
            long at = c == 0   ? k
                      : c == 1 ? s->nu - 1 + (long)k * s->nu
                      : c == 2 ? k + (long)(s->nv - 1) * s->nu
                               : (long)k * s->nu;
            row[k] = pid[at];
            if (wt)
                wt[k] = s->w[at];
        }
        curve[c] =
            along_u ? sw_curve(w, row, wt, cnt, s->p, s->U) : sw_curve(w, row, wt, cnt, s->q, s->V);
    }
    /* Corners: (u0,v0), (u1,v0), (u1,v1), (u0,v1). */
    long corner[4] = {pid[0], pid[s->nu - 1], pid[n - 1], pid[(long)(s->nv - 1) * s->nu]};
    for (int k = 0; k < 4; k++)
        fprintf(f, "#%ld=VERTEX_POINT('',#%ld);\n", vx + k, corner[k]);
    static const int from[4] = {0, 1, 3, 0}, to[4] = {1, 2, 2, 3};
    for (int c = 0; c < 4; c++)
        fprintf(f, "#%ld=EDGE_CURVE('',#%ld,#%ld,#%ld,.T.);\n", ec + c, vx + from[c], vx + to[c],
                curve[c]);
    for (int c = 0; c < 4; c++)
        fprintf(f, "#%ld=ORIENTED_EDGE('',*,*,#%ld,%s);\n", oe + c, ec + c, c < 2 ? ".T." : ".F.");
    fprintf(f, "#%ld=EDGE_LOOP('',(#%ld,#%ld,#%ld,#%ld));\n", loop, oe, oe + 1, oe + 2, oe + 3);
    fprintf(f, "#%ld=FACE_OUTER_BOUND('',#%ld,.T.);\n", bound, loop);
    fprintf(f, "#%ld=ADVANCED_FACE('',(#%ld),#%ld,.T.);\n", face, bound, surf);
}

static int sw_write(const char *path, const nf_surf_t *s, const cf_trim_t *trim, const char *name,
                    const char *version, long long utc, double *edge_err, char *msg, size_t msglen)
{
    if (!path || !*path || !s)
        return cf_fail(msg, msglen, CF_EARG, "cf_step_write: bad arguments");
    int rc = nf_surf_check(s);
    if (rc)
        return cf_fail(msg, msglen, rc, "%s: not written: invalid surface: %s", path,
                       nf_strerror(rc));
    char pname[260], fname[260], ver[140], date[40];
    const char *base = strrchr(path, '/');
    sw_str(pname, sizeof pname, name, 64, "surface");
    sw_str(fname, sizeof fname, base ? base + 1 : path, 120, "surface.stp");
    sw_str(ver, sizeof ver, version, 60, "");
    time_t t = (time_t)utc;
    struct tm tm;
    if (!gmtime_r(&t, &tm) || tm.tm_year + 1900 > 9999 || tm.tm_year + 1900 < 0) {
        t = 0;
        gmtime_r(&t, &tm);
    }
    snprintf(date, sizeof date, "%04d-%02d-%02dT%02d:%02d:%02d", tm.tm_year + 1900, tm.tm_mon + 1,
             tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec);

    size_t pl = strlen(path), side = (size_t)(s->nu > s->nv ? s->nu : s->nv);
    char *tmp = malloc(pl + 5);
    sw_t w = {NULL,
              0,
              malloc(sizeof(long) * ((size_t)s->nu * (size_t)s->nv + side)),
              malloc(sizeof(double) * side),
              trim,
              0.0,
              CF_OK};
    if (!tmp || !w.pid || !w.wt) {
        free(tmp);
        free(w.pid);
        free(w.wt);
        return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", path);
    }
    memcpy(tmp, path, pl);
    memcpy(tmp + pl, ".tmp", 5);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        rc = cf_fail(msg, msglen, CF_EIO, "%s: cannot create: %s", tmp, strerror(errno));
        free(tmp);
        free(w.pid);
        free(w.wt);
        return rc;
    }
    fputs("ISO-10303-21;\nHEADER;\n", f);
    fprintf(f, "FILE_DESCRIPTION(('cellfit: NURBS surface %s as one face'),'2;1');\n", pname);
    fprintf(f, "FILE_NAME('%s','%s',(''),(''),'cellfit %s','cellfit%s%s','');\n", fname, date,
            "cf_step 1", *ver ? " " : "", ver);
    fputs("FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIB_LF { 1 0 10303 442 1 1 4 "
          "}'));\nENDSEC;\nDATA;\n",
          f);
    w.f = f;
    sw_data(&w, s, pname);
    fputs("ENDSEC;\nEND-ISO-10303-21;\n", f);
    int werr = ferror(f) ? (errno ? errno : EIO) : 0;
    if (w.rc && !werr) { /* a trim curve's edge: nothing written */
        fclose(f);
        remove(tmp);
        free(tmp);
        free(w.pid);
        free(w.wt);
        return cf_fail(msg, msglen, w.rc, "%s: not written: %s", path,
                       w.rc == CF_ENOMEM ? "out of memory" : "a trim edge cannot be interpolated");
    }
    if (edge_err)
        *edge_err = w.edge_err;
    if (!werr && (fflush(f) || fsync(fileno(f))))
        werr = errno ? errno : EIO;
    if (fclose(f) && !werr)
        werr = errno ? errno : EIO;
    if (!werr && rename(tmp, path))
        werr = errno;
    if (werr) {
        remove(tmp);
        rc = cf_fail(msg, msglen, CF_EIO, "%s: write failed: %s", path, strerror(werr));
    }
    free(tmp);
    free(w.pid);
    free(w.wt);
    return rc;
}

int cf_step_write_at(const char *path, const nf_surf_t *s, const char *name, const char *version,
                     long long utc, char *msg, size_t msglen)
{
    return sw_write(path, s, NULL, name, version, utc, NULL, msg, msglen);
}

int cf_step_write_trimmed_at(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                             const char *name, const char *version, long long utc, double *edge_err,
                             char *msg, size_t msglen)
{
    if (!t || t->nloops < 1)
        return cf_fail(msg, msglen, CF_EARG, "cf_step_write_trimmed: no trim");
    return sw_write(path, s, t, name, version, utc, edge_err, msg, msglen);
}

int cf_step_write(const char *path, const nf_surf_t *s, const char *name, const char *version,
                  char *msg, size_t msglen)
{
    return cf_step_write_at(path, s, name, version, cf_atomic_stamp(), msg, msglen);
}
