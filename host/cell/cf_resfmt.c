/* SPDX-License-Identifier: MIT */
/* cf_resfmt.c: a results row as JSON or CSV (cf_resfmt.h). The figures are
 * printed with 17 significant digits, so a consumer reads back the very
 * value the PLC read (a float widened to a double). */
#include "cf_resfmt.h"
#include "cf_json.h"
#include <math.h>
#include <string.h>

static const char *nz(const char *s)
{
    return s && *s ? s : NULL;
}

void cf_resfmt_json(FILE *f, const cf_resdb_job_t *j)
{
    cf_json_t w;
    cf_json_begin(&w, f);
    cf_json_str(&w, "job_uuid", j->job_uuid);
    cf_json_str(&w, "cell_id", nz(j->cell_id));
    cf_json_int(&w, "part_number", j->part_number);
    cf_json_str(&w, "part_id", nz(j->part_id));
    cf_json_int(&w, "program", j->program);
    cf_json_int(&w, "result_seq", j->result_seq);
    cf_json_str(&w, "command", nz(j->command));
    cf_json_str(&w, "started_at", nz(j->started_at));
    cf_json_str(&w, "ended_at", nz(j->ended_at));
    cf_json_str(&w, "state", nz(j->state));
    cf_json_int(&w, "error_code", j->error_code);
    if (j->has_fit) {
        cf_json_int(&w, "fit_status", j->fit_status);
        cf_json_num(&w, "rms", j->rms);
        cf_json_num(&w, "max_dev", j->max_dev);
        cf_json_num(&w, "min_dev", j->min_dev);
        cf_json_num(&w, "within_pct", j->within_pct);
        if (j->verdict > 0)
            cf_json_int(&w, "verdict", j->verdict);
        else
            cf_json_null(&w, "verdict");
        cf_json_int(&w, "points", j->points);
        cf_json_int(&w, "control_points", j->control_points);
    } else {
        static const char *const none[] = {"fit_status", "rms",     "max_dev", "min_dev",
                                           "within_pct", "verdict", "points",  "control_points"};
        for (size_t i = 0; i < sizeof none / sizeof none[0]; i++)
            cf_json_null(&w, none[i]);
    }
    cf_json_str(&w, "surface_path", nz(j->surface_path));
    cf_json_str(&w, "surface_sha256", nz(j->surface_sha256));
    cf_json_str(&w, "report_path", nz(j->report_path));
    cf_json_str(&w, "report_sha256", nz(j->report_sha256));
    cf_json_str(&w, "journal_path", nz(j->journal_path));
    cf_json_str(&w, "journal_sha256", nz(j->journal_sha256));
    cf_json_end(&w);
}

int cf_resfmt_json_buf(const cf_resdb_job_t *j, char *buf, size_t n)
{
    FILE *f = fmemopen(buf, n, "w");
    if (!f)
        return -1;
    cf_resfmt_json(f, j);
    long len = ftell(f);
    int bad = ferror(f) || len < 0 || (size_t)len + 1 >= n;
    fclose(f);
    if (bad)
        return -1;
    buf[len] = 0;
    while (len > 0 && buf[len - 1] == '\n') /* one message, no trailing newline */
        buf[--len] = 0;
    return (int)len;
}

void cf_resfmt_csv_header(FILE *f)
{
    fputs("job_uuid,cell_id,part_number,part_id,program,result_seq,command,started_at,ended_at,"
          "state,error_code,fit_status,rms,max_dev,min_dev,within_pct,verdict,points,"
          "control_points,surface_path,surface_sha256,report_path,report_sha256,journal_path,"
          "journal_sha256\n",
          f);
}

/* A CSV field: quoted when it holds a comma, quote or line break. */
static void csv_str(FILE *f, const char *s, int last)
{
    if (strpbrk(s, ",\"\r\n")) {
        fputc('"', f);
        for (; *s; s++) {
            if (*s == '"')
                fputc('"', f);
            fputc(*s, f);
        }
        fputc('"', f);
    } else
        fputs(s, f);
    fputc(last ? '\n' : ',', f);
}

void cf_resfmt_csv(FILE *f, const cf_resdb_job_t *j)
{
    csv_str(f, j->job_uuid, 0);
    csv_str(f, j->cell_id, 0);
    fprintf(f, "%ld,", j->part_number);
    csv_str(f, j->part_id, 0);
    fprintf(f, "%ld,%ld,", j->program, j->result_seq);
    csv_str(f, j->command, 0);
    csv_str(f, j->started_at, 0);
    csv_str(f, j->ended_at, 0);
    csv_str(f, j->state, 0);
    fprintf(f, "%ld,", j->error_code);
    if (j->has_fit) {
        fprintf(f, "%ld,", j->fit_status);
        const double x[4] = {j->rms, j->max_dev, j->min_dev, j->within_pct};
        for (int i = 0; i < 4; i++) /* a figure not known (NaN): an empty field */
            if (isfinite(x[i]))
                fprintf(f, "%.17g,", x[i]);
            else
                fputc(',', f);
        if (j->verdict > 0)
            fprintf(f, "%ld", j->verdict);
        fprintf(f, ",%ld,%ld,", j->points, j->control_points);
    } else
        fputs(",,,,,,,,", f);
    csv_str(f, j->surface_path, 0);
    csv_str(f, j->surface_sha256, 0);
    csv_str(f, j->report_path, 0);
    csv_str(f, j->report_sha256, 0);
    csv_str(f, j->journal_path, 0);
    csv_str(f, j->journal_sha256, 1);
}
