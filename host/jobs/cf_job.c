/* SPDX-License-Identifier: MIT */
/* cf_job.c: the cell's fit job on files (through cf_fitjob) and the export
 * of its result (cf_job.h). */
#define _GNU_SOURCE /* renameat2: a rename that never replaces */
#include "cf_job.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_jobfiles.h"
#include "cf_json.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_uuid.h"
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

int cf_job_open(const cf_job_fit_opts_t *o, cf_fitjob_t **j, char *msg, size_t ml)
{
    nf_surf_t s;
    *j = NULL;
    int rc = cf_surfio_read(o->nominal, 0, &s, msg, ml);
    if (rc)
        return rc;
    cf_fitjob_opts_t fo = o->fit;
    fo.stats = 1; /* the cell reports deviations */
    rc = cf_fitjob_open(j, &s, &fo, msg, ml);
    cf_surf_free(&s);
    return rc;
}

int cf_job_check(const cf_job_fit_opts_t *o, char *msg, size_t ml)
{
    cf_fitjob_t *j;
    /* Cheap enough to do at every command: one IGES read, a few inserts. */
    int rc = cf_job_open(o, &j, msg, ml);
    cf_fitjob_close(j);
    return rc;
}

int cf_job_fit(const cf_job_fit_opts_t *o, const cf_job_ctl_t *ctl, cf_job_result_t *out, char *msg,
               size_t ml)
{
    memset(out, 0, sizeof *out);
    cf_fitjob_t *j;
    int rc = cf_job_open(o, &j, msg, ml);
    if (rc)
        return rc;
    cf_points_t *pr = NULL;
    if (!(rc = cf_points_open(&pr, o->points, 0, msg, ml))) {
        cf_fitsrc_t src;
        cf_fitsrc_points_t pc;
        cf_fitsrc_points(&src, &pc, pr, o->points);
        if (o->fit.loop) /* two passes a round: the file parsed once */
            cf_fitsrc_points_cache(&pc, CF_FITSRC_CACHE_MAX);
        rc = cf_fitjob_run(j, &src, ctl, 0, 100, out, msg, ml);
        cf_fitsrc_points_free(&pc);
    }
    cf_points_close(pr);
    cf_fitjob_close(j);
    return rc;
}

void cf_job_result_free(cf_job_result_t *r)
{
    cf_fitjob_result_free(r);
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

int cf_job_unique_name(unsigned long part, long long utc, unsigned seq, char *buf, size_t n)
{
    char base[64], uuid[CF_UUID_LEN];
    int rc = cf_uuid_new(uuid);
    if (rc)
        return rc;
    cf_job_folder_name(part, utc, base, sizeof base);
    snprintf(buf, n, "%s_%u_%s", base, seq, uuid);
    return CF_OK;
}

static void iso_utc(long long utc, char *buf, size_t n)
{
    time_t t = (time_t)utc;
    struct tm tm;
    snprintf(buf, n, "1970-01-01T00:00:00Z");
    if (gmtime_r(&t, &tm))
        strftime(buf, n, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

static int write_report(const cf_job_result_t *r, const cf_job_meta_t *meta, const cf_checks_t *cs,
                        const char *path, char *msg, size_t ml)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
    const cf_stats_t *st = r->stats;
    char iso[32];
    cf_json_t j;
    cf_json_begin(&j, f);
    cf_json_int(&j, "part", (long)meta->part);
    if (meta->part_id)
        cf_json_str(&j, "part_id", meta->part_id);
    cf_json_int(&j, "program", (long)meta->program);
    cf_json_int(&j, "seq", (long)meta->seq);
    cf_json_int(&j, "utc", (long)meta->utc);
    iso_utc(meta->utc, iso, sizeof iso);
    cf_json_str(&j, "time", iso);
    if (meta->export_seq)
        cf_json_int(&j, "export_seq", (long)meta->export_seq);
    if (meta->export_utc) {
        cf_json_int(&j, "export_utc", (long)meta->export_utc);
        iso_utc(meta->export_utc, iso, sizeof iso);
        cf_json_str(&j, "export_time", iso);
    }
    cf_json_str(&j, "board", meta->board);
    cf_json_str(&j, "nominal", meta->nominal);
    cf_json_str(&j, "points_file", meta->points ? meta->points : "");
    if (meta->journal)
        cf_json_str(&j, "journal", meta->journal);
    cf_json_str(&j, "verdict", st->max_abs <= st->tol ? "pass" : "fail");
    cf_json_int(&j, "control_points", (long)r->surf.nu * r->surf.nv);
    cf_json_int(&j, "nu", r->surf.nu);
    cf_json_int(&j, "nv", r->surf.nv);
    cf_json_str(&j, "solver", nf_solver_name(r->solve.solver));
    cf_json_str(&j, "fit_status", cf_fitjob_status_name(r->status));
    if (r->status != CF_FITJOB_PLAIN)
        cf_json_int(&j, "rounds", r->nrounds);
    /* Honest edges (issue 14): how much of the net the data determines. */
    cf_json_int(&j, "pinned_cp", r->pinned);
    if (r->fp_cells > 0) { /* as cellfit fit --json's */
        cf_json_obj(&j, "footprint");
        cf_json_int(&j, "cells", r->fp_cells);
        cf_json_int(&j, "filled", r->fp_filled);
        cf_json_int(&j, "empty", r->fp_empty);
        cf_json_int(&j, "outline", r->fp_outline);
        cf_json_close(&j);
    }
    cf_json_num(&j, "seconds", r->seconds);
    cf_stats_json_fields(st, &j);
    if (cs->n) /* as cellfit report --checks --json's */
        cf_checks_json(cs, &j);
    cf_json_end(&j);
    if (fflush(f) || fsync(fileno(f)) || ferror(f)) {
        fclose(f);
        return cf_fail(msg, ml, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
    }
    if (fclose(f))
        return cf_fail(msg, ml, CF_EIO, "%s: cannot write: %s", path, strerror(errno));
    return CF_OK;
}

/* The temporary folder and what is in it, gone. */
static void remove_tmp(const char *tmp)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/fitted.igs", tmp);
    remove(path);
    snprintf(path, sizeof path, "%s/report.json", tmp);
    remove(path);
    for (int i = 0; cf_jobfiles_names[i]; i++) {
        snprintf(path, sizeof path, "%s/%s", tmp, cf_jobfiles_names[i]);
        remove(path);
    }
    rmdir(tmp);
}

int cf_job_export(const cf_job_result_t *r, const cf_job_meta_t *meta, const char *dir, char *msg,
                  size_t ml)
{
    char path[4200], tmp[4096];
    const char *slash = strrchr(dir, '/');
    size_t plen = slash ? (size_t)(slash - dir) + 1 : 0;
    if (strlen(dir) + 32 >= sizeof tmp || !dir[plen])
        return cf_fail(msg, ml, CF_EIO, "%s: not a usable folder name", dir);
    snprintf(tmp, sizeof tmp, "%.*s.%s.tmp.%ld", (int)plen, dir, dir + plen, (long)getpid());
    remove_tmp(tmp); /* a leftover of a crashed export of ours */
    if (mkdir(tmp, 0775))
        return cf_fail(msg, ml, CF_EIO, "%s: cannot create (as %s): %s", dir, tmp, strerror(errno));
    /* A trimmed nominal's trim goes with the fit (the knot range is kept). */
    cf_trim_t trim;
    cf_checks_t cs;
    memset(&cs, 0, sizeof cs);
    int rc = cf_jobfiles_trim(r, meta, &trim, msg, ml);
    if (!rc && meta->checks && *meta->checks)
        rc = cf_checks_read(&cs, meta->checks, msg, ml);
    snprintf(path, sizeof path, "%s/fitted.igs", tmp);
    if (!rc)
        rc = trim.nloops ? cf_iges_write_trimmed_at(path, &r->surf, &trim, "cellfit serve",
                                                    meta->utc, NULL, msg, ml)
                         : cf_iges_write_at(path, &r->surf, "cellfit serve", meta->utc, msg, ml);
    /* What `make demo` writes besides: STEP, per-point CSV, DFQ; then the
     * report, which carries the checks the CSV's pass measured. */
    if (!rc)
        rc = cf_jobfiles_write(r, meta, &trim, &cs, tmp, msg, ml);
    if (!rc) {
        snprintf(path, sizeof path, "%s/report.json", tmp);
        rc = write_report(r, meta, &cs, path, msg, ml);
    }
    cf_checks_free(&cs);
    cf_trim_free(&trim);
    /* No replacing: rename would put an empty dir's name to ours. */
    if (!rc && renameat2(AT_FDCWD, tmp, AT_FDCWD, dir, RENAME_NOREPLACE))
        rc = cf_fail(msg, ml, CF_EIO, "%s: cannot create: %s", dir, strerror(errno));
    if (rc)
        remove_tmp(tmp);
    return rc;
}
