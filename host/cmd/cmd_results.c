/* SPDX-License-Identifier: MIT */
/* cmd_results.c: `cellfit results list|show|export|outbox`: the cell's
 * results database (results/results.db, cf_resdb.h) queried: the jobs,
 * one job by its UUID, every column for a spreadsheet or the MES, the
 * outbox to the plant (what waits, what was dropped, the last error). */
#include "cf_cli.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_resdb.h"
#include "cf_resfmt.h"
#include "cmd.h"
#include "cmd_record.h"
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#if CF_NO_PLANT
int cmd_results(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    return cli_error("results", CLI_USAGE,
                     "this cellfit is built without SQLite (libsqlite3-dev): no results database");
}
#else

#define CMD "results"

typedef struct out_ctx {
    int json, csv;
    long n;
} out_ctx_t;

static int print_row(void *ctx, const cf_resdb_job_t *j)
{
    out_ctx_t *o = ctx;
    o->n++;
    if (o->json)
        cf_resfmt_json(stdout, j);
    else if (o->csv)
        cf_resfmt_csv(stdout, j);
    else if (j->has_fit) {
        char mx[32] = "-", mn[32] = "-"; /* NaN: not known (a shell fit's, cf_resdb.h) */
        if (isfinite(j->max_dev))
            snprintf(mx, sizeof mx, "%.6g", j->max_dev);
        if (isfinite(j->min_dev))
            snprintf(mn, sizeof mn, "%.6g", j->min_dev);
        printf("%s  %s  part %ld  seq %ld  %-8s %-7s rms %.6g max %s min %s %s\n", j->ended_at,
               j->job_uuid, j->part_number, j->result_seq, j->command, j->state, j->rms, mx, mn,
               j->verdict == 1   ? "pass"
               : j->verdict == 2 ? "fail"
                                 : "-");
    } else
        printf("%s  %s  part %ld  seq %ld  %-8s %-7s error %ld\n", j->ended_at, j->job_uuid,
               j->part_number, j->result_seq, j->command, j->state, j->error_code);
    return 0;
}

static int outbox(cf_resdb_t *db, int json)
{
    cf_resdb_obstat_t st;
    if (cf_resdb_outbox_stat(db, &st))
        return cli_error(CMD, CLI_FAIL, "outbox: %s", cf_resdb_strerror(CF_RESDB_EIO));
    double age = st.oldest > 0 ? (double)time(NULL) - st.oldest : 0;
    if (json) {
        cf_json_t w;
        cf_json_begin(&w, stdout);
        cf_json_int(&w, "pg", st.pending_pg);
        cf_json_int(&w, "mqtt", st.pending_mqtt);
        cf_json_num(&w, "dropped", (double)st.dropped);
        cf_json_num(&w, "oldest_age_s", age);
        cf_json_str(&w, "last_error", *st.last_error ? st.last_error : NULL);
        cf_json_end(&w);
        return CLI_OK;
    }
    printf("pg      %ld\nmqtt    %ld\ndropped %lld\noldest  %.1f s\nlast error: %s\n",
           st.pending_pg, st.pending_mqtt, st.dropped, age,
           *st.last_error ? st.last_error : "(none)");
    return CLI_OK;
}

int cmd_results(int argc, char **argv)
{
    const char *pos[2], *dbpath = "results/results.db", *since = NULL;
    long part = -1;
    int json = 0, csv = 0, npos = 0;
    const cf_opt_t opts[] = {
        {.name = "db",
         .kind = CF_OPT_STR,
         .dst = &dbpath,
         .arg = "PATH",
         .help = "the cell's results database (serve's RESULTS_DIR/results.db), or a results "
                 "folder (its results.db)."},
        {.name = "part",
         .kind = CF_OPT_LONG,
         .dst = &part,
         .arg = "N",
         .help = "only jobs of part number N (-1: every part).",
         .lo = -1,
         .hi = 4294967295.0},
        {.name = "since",
         .kind = CF_OPT_STR,
         .dst = &since,
         .arg = "T",
         .help = "only jobs ended at or after T (UTC ISO 8601, or a prefix: 2026-12-02).",
         .def = "any time"},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "one JSON object per job."},
        {.name = "csv", .kind = CF_OPT_FLAG, .dst = &csv, .help = "CSV with a header line."},
        {0}};
    const cf_cmd_t cmd = {
        .prog = "cellfit",
        .name = CMD,
        .args = "list|show UUID|export|outbox",
        .summary = "the jobs recorded in the cell's results database, and its outbox",
        .descr = "list: the jobs, oldest first (--part, --since); show UUID: one job, every "
                 "column; export: every column of the jobs selected (CSV unless --json); "
                 "outbox: deliveries waiting for the plant database (pg) and the broker "
                 "(mqtt), entries dropped because the outbox was full, the last error.",
        .opts = opts,
        .min_pos = 1,
        .max_pos = 2};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, &npos);
    if (rc)
        return cf_opt_exit(rc);
    const char *sub = pos[0];
    int want = !strcmp(sub, "show") ? 2 : 1;
    if (strcmp(sub, "list") && strcmp(sub, "show") && strcmp(sub, "export") &&
        strcmp(sub, "outbox"))
        return cli_error(CMD, CLI_USAGE, "'%s': list, show UUID, export or outbox", sub);
    if (npos != want)
        return cli_error(CMD, CLI_USAGE, "%s takes %s", sub, want == 2 ? "a UUID" : "no argument");
    if (json && csv)
        return cli_error(CMD, CLI_USAGE, "--json or --csv, not both");
    char msg[512], path[4096];
    cf_resdb_t *db;
    if (cmd_record_db_path(dbpath, path, sizeof path))
        return cli_error(CMD, CLI_USAGE, "--db %s: path too long", dbpath);
    dbpath = path;
    FILE *probe = fopen(dbpath, "rb"); /* querying never creates a database */
    if (!probe)
        return cli_error(CMD, CLI_USAGE,
                         "%s: no results database there (--db: serve's results folder or its "
                         "results.db)",
                         dbpath);
    fclose(probe);
    /* Only ours is opened: cf_resdb_open would migrate (write into) any
     * file, an empty one or another application's SQLite database too. */
    int ce = cf_resdb_check(dbpath, msg, sizeof msg);
    if (ce == CF_RESDB_ESCHEMA)
        return cli_error(CMD, CLI_USAGE, "%s: query it with a cellfit that new", msg);
    if (ce == CF_RESDB_ENOLIB) /* msg names the package: no hint about --db */
        return cli_error(CMD, CLI_FAIL, "%s", msg);
    if (ce)
        return cli_error(CMD, ce == CF_RESDB_EOPEN ? CLI_FAIL : CLI_USAGE,
                         "%s; --db takes the results.db that `cellfit serve` or `cellfit fit "
                         "--record` wrote, or their results folder",
                         msg);
    if (cf_resdb_open(dbpath, &db, msg, sizeof msg))
        return cli_error(CMD, CLI_FAIL, "%s", msg);
    int ec = CLI_OK;
    out_ctx_t o = {json, csv || (!json && !strcmp(sub, "export")), 0};
    if (!strcmp(sub, "outbox"))
        ec = outbox(db, json);
    else if (!strcmp(sub, "show")) {
        cf_resdb_job_t j;
        int e = cf_resdb_get(db, pos[1], &j);
        if (e)
            ec = cli_error(CMD, e == CF_RESDB_ENOTFOUND ? CLI_USAGE : CLI_FAIL, "%s: %s", pos[1],
                           cf_resdb_strerror(e));
        else if (json)
            cf_resfmt_json(stdout, &j);
        else {
            cf_resfmt_csv_header(stdout);
            cf_resfmt_csv(stdout, &j);
        }
    } else {
        if (o.csv)
            cf_resfmt_csv_header(stdout);
        if (cf_resdb_query(db, part, since, print_row, &o))
            ec = cli_error(CMD, CLI_FAIL, "%s: %s", dbpath, cf_resdb_strerror(CF_RESDB_EIO));
    }
    cf_resdb_close(db);
    return ec;
}
#endif
