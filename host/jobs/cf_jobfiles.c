/* SPDX-License-Identifier: MIT */
/* cf_jobfiles.c: an export's STEP, per-point CSV and DFQ files (cf_jobfiles.h). */
#include "cf_jobfiles.h"
#include "cf_dfqset.h"
#include "cf_err.h"
#include "cf_fitsrc.h"
#include "cf_log.h"
#include "cf_points.h"
#include "cf_ptsout.h"
#include "cf_seedgrid.h"
#include "cf_step.h"
#include "cf_store_file.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "rig_err.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define JF_BATCH 4096L /* points read at a time */

const char *const cf_jobfiles_names[] = {"fitted.stp", "deviations.csv", "report.dfq", NULL};

/* Every point of src projected on s into the CSV at path, and into the
 * checks cs (NULL: none). */
static int write_csv(const nf_surf_t *s, double tol, cf_fitsrc_t *src, cf_checks_t *cs,
                     const char *path, char *msg, size_t ml)
{
    cf_seedgrid_t sg;
    memset(&sg, 0, sizeof sg);
    double *rows = malloc(sizeof(double) * 5 * JF_BATCH);
    if (!rows || cf_seedgrid_init(&sg, s, 8)) {
        free(rows);
        cf_seedgrid_free(&sg);
        return cf_fail(msg, ml, CF_ENOMEM, "%s: out of memory", path);
    }
    cf_ptsout_t o;
    int rc = cf_ptsout_open(&o, path, NULL, tol, 0, NULL, NULL, msg, ml);
    long got = 0;
    if (!rc && (rc = src->rewind(src->ctx, msg, ml)) == 0) {
        while ((got = src->read(src->ctx, rows, JF_BATCH, msg, ml)) > 0)
            for (long k = 0; k < got; k++) {
                const double *Q = rows + (size_t)k * src->cols + (src->cols - 3);
                nf_proj_t pj;
                cf_seedgrid_project(&sg, Q, 1e-9, &pj); /* best point kept on ENOCONV */
                cf_ptsout_pt_t p = {Q[0], Q[1], Q[2], pj.u, pj.v, pj.dist, NAN};
                cf_ptsout_add(&o, &p);
                if (cs)
                    cf_checks_add(cs, Q, pj.dist);
            }
        rc = got < 0 ? (int)got : cf_ptsout_close(&o, msg, ml);
        if (got < 0)
            cf_ptsout_abort(&o);
    } else if (!rc) {
        cf_ptsout_abort(&o);
    }
    free(rows);
    cf_seedgrid_free(&sg);
    return rc;
}

/* The job's points (its points file, else its journal) into the CSV. */
static int deviations(const cf_job_result_t *r, const cf_job_meta_t *meta, cf_checks_t *cs,
                      const char *path, char *msg, size_t ml)
{
    cf_fitsrc_t src;
    int rc;
    if (meta->points && *meta->points) {
        cf_points_t *pr = NULL;
        cf_fitsrc_points_t pc;
        if (!(rc = cf_points_open(&pr, meta->points, 0, msg, ml))) {
            /* One pass: no cache (cf_fitsrc_points_free in case one is set). */
            cf_fitsrc_points(&src, &pc, pr, meta->points);
            rc = write_csv(&r->surf, r->stats->tol, &src, cs, path, msg, ml);
            cf_fitsrc_points_free(&pc);
        }
        cf_points_close(pr);
        return rc;
    }
    if (!meta->journal || !*meta->journal)
        return CF_OK; /* nothing to name the points by */
    cf_store_file_t fl;
    rig_store_t st;
    jnl_reader_t rd;
    jnl_header_t h;
    jnl_info_t in;
    fl.fd = -1;
    if ((rc = cf_store_file_open(&fl, meta->journal, CF_STORE_READ, &st, msg, ml)))
        return rc;
    if ((rc = jnl_reader_open(&rd, st, &h, &in)) != 0) {
        rc = cf_fail(msg, ml, CF_EIO, "%s: %s", meta->journal, rig_strerror(rc));
    } else {
        cf_fitsrc_jnl_t jc;
        cf_fitsrc_journal(&src, &jc, &rd, meta->journal, (long)in.points);
        rc = write_csv(&r->surf, r->stats->tol, &src, cs, path, msg, ml);
    }
    cf_store_file_close(&fl);
    return rc;
}

int cf_jobfiles_trim(const cf_job_result_t *r, const cf_job_meta_t *meta, cf_trim_t *trim,
                     char *msg, size_t ml)
{
    double u0, u1, v0, v1;
    memset(trim, 0, sizeof *trim);
    if (!meta->nominal || !*meta->nominal)
        return CF_OK;
    int rc = cf_surfio_read_trim(meta->nominal, 0, trim, msg, ml);
    if (rc || !trim->nloops)
        return rc;
    nf_surf_domain(&r->surf, &u0, &u1, &v0, &v1);
    if ((rc = cf_trim_check(trim, &r->surf, 1e-9 * fmax(u1 - u0, v1 - v0), msg, ml)))
        cf_trim_free(trim);
    return rc;
}

int cf_jobfiles_write(const cf_job_result_t *r, const cf_job_meta_t *meta, const cf_trim_t *trim,
                      cf_checks_t *cs, const char *dir, char *msg, size_t ml)
{
    char path[4200];
    if (!r->stats)
        return cf_fail(msg, ml, CF_EARG, "export: the result has no deviations");
    snprintf(path, sizeof path, "%s/fitted.stp", dir);
    int rc = trim && trim->nloops
                 ? cf_step_write_trimmed_at(path, &r->surf, trim, "cellfit serve",
                                            cf_version_string(), meta->utc, NULL, msg, ml)
                 : cf_step_write_at(path, &r->surf, "cellfit serve", cf_version_string(), meta->utc,
                                    msg, ml);
    if (!rc) {
        snprintf(path, sizeof path, "%s/deviations.csv", dir);
        if (cs)
            cf_checks_reset(cs);
        rc = deviations(r, meta, cs, path, msg, ml);
    }
    char why[256];
    for (int i = 0; !rc && cs && i < cs->n; i++)
        if (cf_checks_missing(cs, i, why, sizeof why))
            cf_log(CF_LOG_WARN, "export: %s", why);
    if (!rc) {
        char number[32];
        const char *nom = meta->nominal ? meta->nominal : "";
        const char *base = strrchr(nom, '/');
        cf_dfq_char_t *c = malloc(sizeof *c * (size_t)(CF_DFQSET_FIGURES + (cs ? cs->n : 0)));
        if (!c)
            return cf_fail(msg, ml, CF_ENOMEM, "export: out of memory");
        snprintf(number, sizeof number, "%lu", meta->part);
        cf_dfq_part_t part = {number, base ? base + 1 : nom, meta->part_id, meta->utc};
        int n = cf_dfqset_chars(r->stats, 99, cs, c);
        snprintf(path, sizeof path, "%s/report.dfq", dir);
        rc = cf_dfq_write(path, &part, c, n, msg, ml);
        free(c);
    }
    return rc;
}
