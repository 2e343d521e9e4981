/* cf_job.c: the cell's fit job on files and the export of its result
 * (cf_job.h). The fit is cmd_fit's single pass (Eq. 7) with progress and a
 * stop check between batches; the deviations are cmd_report's. */
#include "cf_job.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_refine.h"
#include "rig_err.h"
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define JBATCH 4096
#define JPROJ_TOL 1e-9

static void progress(const cf_job_ctl_t *c, int pct)
{
    if (c && c->progress)
        c->progress(c->ctx, pct);
}

static int stop(const cf_job_ctl_t *c)
{
    return c && c->should_stop && c->should_stop(c->ctx);
}

/* Insert one knot at the middle of the widest span of U (or V), repeated
 * until the net has n control points that way: the refined nominal is the
 * same surface (Boehm), so P0 keeps its meaning in Eq. 7. */
static int refine_dir(nf_surf_t *s, int n, int in_u, char *msg, size_t ml)
{
    while ((in_u ? s->nu : s->nv) < n) {
        const double *K = in_u ? s->U : s->V;
        int deg = in_u ? s->p : s->q, cnt = in_u ? s->nu : s->nv, best = deg;
        for (int i = deg; i < cnt; i++)
            if (K[i + 1] - K[i] > K[best + 1] - K[best])
                best = i;
        double x = 0.5 * (K[best] + K[best + 1]);
        nf_surf_t out;
        int rc = cf_surf_alloc(&out, s->p, s->q, s->nu + (in_u != 0), s->nv + (in_u == 0));
        if (rc)
            return cf_fail(msg, ml, rc, "out of memory refining the nominal");
        rc = in_u ? nf_refine_insert_u(s, x, 1, &out) : nf_refine_insert_v(s, x, 1, &out);
        if (rc) {
            cf_surf_free(&out);
            return cf_fail(msg, ml, rc, "refining the nominal to %d control points: %s", n,
                           nf_strerror(rc));
        }
        cf_surf_free(s);
        *s = out;
    }
    return 0;
}

/* The nominal, refined to the net asked, and the fit's byte count. */
int cf_job_load_base(const cf_job_fit_opts_t *o, nf_surf_t *s, long *need, char *msg, size_t ml)
{
    int rc = cf_iges_read(o->nominal, 0, s, msg, ml);
    if (rc)
        return rc;
    int nu = o->net_u ? o->net_u : s->nu, nv = o->net_v ? o->net_v : s->nv;
    if (nu < s->nu || nv < s->nv) {
        rc = cf_fail(msg, ml, CF_EARG, "net %d x %d is smaller than the nominal's %d x %d", nu, nv,
                     s->nu, s->nv);
        cf_surf_free(s);
        return rc;
    }
    long b = nf_fit_bytes(nu, nv, s->p, s->q, NF_SOLVER_AUTO);
    if ((double)nu * nv > (double)NF_MAX_CP || b < 0 || b > NF_ARENA_BYTES) {
        cf_surf_free(s);
        return cf_fail(msg, ml, NF_EBUDGET, "a %d x %d net needs %ld bytes, board %s allows %ld",
                       nu, nv, b, BOARD_NAME, (long)NF_ARENA_BYTES);
    }
    if ((rc = refine_dir(s, nu, 1, msg, ml)) || (rc = refine_dir(s, nv, 0, msg, ml))) {
        cf_surf_free(s);
        return rc;
    }
    *need = b;
    return 0;
}

int cf_job_check(const cf_job_fit_opts_t *o, char *msg, size_t ml)
{
    nf_surf_t s;
    long need;
    /* Cheap enough to do at every command: one IGES read, a few inserts. */
    int rc = cf_job_load_base(o, &s, &need, msg, ml);
    if (!rc)
        cf_surf_free(&s);
    return rc;
}

/* x y z rows projected onto s (seed grid pj) into u v x y z rows; with
 * dist, the signed normal distances instead. */
static void project(cf_seedgrid_t *pj, const double *xyz, long n, int cols, double *uv,
                    double *dist)
{
    for (long k = 0; k < n; k++) {
        const double *Q = xyz + (long)cols * k + (cols - 3);
        nf_proj_t pr;
        cf_seedgrid_project(pj, Q, JPROJ_TOL, &pr); /* best point kept on ENOCONV */
        if (dist)
            dist[k] = pr.dist;
        if (uv) {
            double *r = uv + 5 * k;
            r[0] = pr.u, r[1] = pr.v, r[2] = Q[0], r[3] = Q[1], r[4] = Q[2];
        }
    }
}

typedef struct job_mem {
    void *arena;
    double *buf, *rows;
    cf_points_t *pr;
    cf_seedgrid_t sg;
} job_mem_t;

static void mem_free(job_mem_t *m)
{
    cf_points_close(m->pr);
    cf_seedgrid_free(&m->sg);
    free(m->arena);
    free(m->buf);
    free(m->rows);
}

static int fit_error(int rc, const char *points, char *msg, size_t ml)
{
    if (rc == NF_ENODATA || rc == NF_ESINGULAR)
        return cf_fail(msg, ml, rc, "%s: the points do not determine the surface (%s)", points,
                       nf_strerror(rc));
    return cf_fail(msg, ml, rc, "%s: %s", points, nf_strerror(rc));
}

/* Accumulate every point into f (10..60 %). */
static int accumulate(const cf_job_fit_opts_t *o, const cf_job_ctl_t *ctl, job_mem_t *m,
                      nf_fit_t *f, long total, char *msg, size_t ml)
{
    long got, done = 0;
    int cols = cf_points_cols(m->pr);
    if (cf_points_rewind(m->pr))
        return cf_fail(msg, ml, CF_EIO, "%s: cannot read the points again", o->points);
    while ((got = cf_points_read(m->pr, m->buf, JBATCH, msg, ml)) > 0) {
        if (stop(ctl))
            return RIG_EABORTED;
        const double *uv = m->buf;
        if (cols == 3) {
            project(&m->sg, m->buf, got, 3, m->rows, NULL);
            uv = m->rows;
        }
        long bad = -1;
        int rc = nf_fit_add_rows(f, uv, got, &bad);
        if (rc)
            return cf_fail(msg, ml, rc, "%s: point %ld: %s", o->points, done + bad + 1,
                           nf_strerror(rc));
        done += got;
        progress(ctl, 10 + (int)(50.0 * (double)done / (double)total));
    }
    return got < 0 ? (int)got : 0;
}

/* Deviations of every point to the fitted surface (70..100 %). */
static int deviations(const cf_job_ctl_t *ctl, job_mem_t *m, cf_job_result_t *out, long total,
                      char *msg, size_t ml)
{
    cf_seedgrid_free(&m->sg);
    if (cf_seedgrid_init(&m->sg, &out->fitted, 8))
        return cf_fail(msg, ml, CF_ENOMEM, "out of memory");
    if (cf_points_rewind(m->pr))
        return cf_fail(msg, ml, CF_EIO, "cannot read the points again");
    long got, done = 0;
    int cols = cf_points_cols(m->pr);
    while ((got = cf_points_read(m->pr, m->buf, JBATCH, msg, ml)) > 0) {
        if (stop(ctl))
            return RIG_EABORTED;
        project(&m->sg, m->buf, got, cols, NULL, m->rows);
        for (long k = 0; k < got; k++)
            cf_stats_add(out->st, m->rows[k]);
        done += got;
        progress(ctl, 70 + (int)(30.0 * (double)done / (double)total));
    }
    return got < 0 ? (int)got : 0;
}

int cf_job_fit(const cf_job_fit_opts_t *o, const cf_job_ctl_t *ctl, cf_job_result_t *out, char *msg,
               size_t ml)
{
    double t0 = cli_now();
    memset(out, 0, sizeof *out);
    job_mem_t m;
    memset(&m, 0, sizeof m);
    nf_surf_t base;
    long need = 0;
    progress(ctl, 0);
    int rc = cf_job_load_base(o, &base, &need, msg, ml);
    if (rc)
        return rc;
    out->bytes = need;
    out->st = malloc(sizeof *out->st);
    m.arena = malloc((size_t)need);
    m.buf = malloc(sizeof(double) * 5 * JBATCH);
    m.rows = malloc(sizeof(double) * 5 * JBATCH);
    if (!out->st || !m.arena || !m.buf || !m.rows || cf_surf_copy(&out->fitted, &base)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "cannot allocate %ld bytes", need);
        goto fail;
    }
    if ((rc = cf_stats_init(out->st, o->tol)) ||
        (rc = cf_points_open(&m.pr, o->points, 0, msg, ml)))
        goto fail;
    /* Pass 1 counts the points, for progress and the empty file. */
    long got, total = 0;
    while ((got = cf_points_read(m.pr, m.buf, JBATCH, msg, ml)) > 0) {
        if (stop(ctl)) {
            rc = RIG_EABORTED;
            goto fail;
        }
        total += got;
    }
    if (got < 0) {
        rc = (int)got;
        goto fail;
    }
    if (total == 0) {
        rc = cf_fail(msg, ml, CF_EEMPTY, "%s: no points", o->points);
        goto fail;
    }
    progress(ctl, 10);
    if (cf_points_cols(m.pr) == 3 && cf_seedgrid_init(&m.sg, &base, 8)) {
        rc = cf_fail(msg, ml, CF_ENOMEM, "out of memory");
        goto fail;
    }
    nf_arena_t ar;
    nf_fit_t f;
    nf_arena_init(&ar, m.arena, (size_t)need);
    nf_fit_params_t prm = {o->alpha, o->beta, NF_SOLVER_AUTO};
    if ((rc = nf_fit_init(&f, &base, &prm, &ar))) {
        rc = fit_error(rc, o->points, msg, ml);
        goto fail;
    }
    if ((rc = accumulate(o, ctl, &m, &f, total, msg, ml)))
        goto fail;
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    rc = nf_fit_finish(&f);
    if (!rc)
        rc = nf_fit_solve(&f, NF_SOLVER_AUTO, &so, &out->solve);
    if (rc) {
        rc = fit_error(rc, o->points, msg, ml);
        goto fail;
    }
    memcpy(out->fitted.cp, f.P, sizeof(double) * (size_t)(3 * f.n));
    progress(ctl, 70);
    if ((rc = deviations(ctl, &m, out, total, msg, ml)))
        goto fail;
    out->points = total;
    out->seconds = cli_now() - t0;
    mem_free(&m);
    cf_surf_free(&base);
    return 0;
fail:
    mem_free(&m);
    cf_surf_free(&base);
    cf_job_result_free(out);
    return rc;
}

void cf_job_result_free(cf_job_result_t *r)
{
    cf_surf_free(&r->fitted);
    free(r->st);
    memset(r, 0, sizeof *r);
}

void cf_job_folder_name(unsigned long part, long long utc, char *buf, size_t n)
{
    time_t t = (time_t)utc;
    struct tm tm;
    char ts[32] = "19700101T000000Z";
    if (gmtime_r(&t, &tm))
        strftime(ts, sizeof ts, "%Y%m%dT%H%M%SZ", &tm);
    snprintf(buf, n, "%lu_%s", part, ts);
}

int cf_job_export(const cf_job_result_t *r, const cf_job_meta_t *meta, const char *dir, char *msg,
                  size_t ml)
{
    char path[4096], tmp[4200];
    if (mkdir(dir, 0775) && errno != EEXIST)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot create: %s", dir, strerror(errno));
    snprintf(path, sizeof path, "%s/fitted.igs", dir);
    int rc = cf_iges_write_at(path, &r->fitted, "cellfit serve", meta->utc, msg, ml);
    if (rc)
        return rc;
    snprintf(path, sizeof path, "%s/report.json", dir);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot write: %s", tmp, strerror(errno));
    const cf_stats_t *st = r->st;
    cf_json_t j;
    cf_json_begin(&j, f);
    cf_json_int(&j, "part", (long)meta->part);
    cf_json_int(&j, "program", (long)meta->program);
    cf_json_int(&j, "seq", (long)meta->seq);
    cf_json_int(&j, "utc", (long)meta->utc);
    cf_json_str(&j, "board", meta->board);
    cf_json_str(&j, "nominal", meta->nominal);
    cf_json_str(&j, "points_file", meta->points ? meta->points : "");
    if (meta->journal)
        cf_json_str(&j, "journal", meta->journal);
    cf_json_str(&j, "verdict", st->max_abs <= st->tol ? "pass" : "fail");
    cf_json_int(&j, "control_points", (long)r->fitted.nu * r->fitted.nv);
    cf_json_int(&j, "nu", r->fitted.nu);
    cf_json_int(&j, "nv", r->fitted.nv);
    cf_json_str(&j, "solver", nf_solver_name(r->solve.solver));
    cf_json_num(&j, "seconds", r->seconds);
    cf_stats_json_fields(st, &j);
    cf_json_end(&j);
    if (fclose(f) || rename(tmp, path)) {
        remove(tmp);
        return cf_fail(msg, ml, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
    }
    return 0;
}
