/* SPDX-License-Identifier: MIT */
/* cmd_scan.c: `cellfit scan`: measure a part on the rig: open the stage and
 * the probe (hal/), plan a serpentine raster over the nominal's extent in
 * x y (or --region), run the scan job (firmware/scan.c) journalling every
 * point to a file, and with --fit stream the points into the fit job as
 * they arrive (projection onto the nominal; cf_fitjob_add), finish the job
 * from the journal and write the fitted surface. A
 * progress bar on a terminal, progress lines otherwise; SIGINT/SIGTERM stop
 * the job cleanly (stage stopped, journal synced). */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_scanfast.h"
#include "cf_store_file.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"
#include "cmd_fitopts.h"
#include "cmd_record.h"
#include "hal_rig.h"
#include "nf_err.h"
#include "rig_err.h"
#include "scan.h"
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#define CMD "scan"

static volatile sig_atomic_t stop_flag;

/* The lines' stop check (hal_set_stop): after Ctrl-C a request is tried
 * once, without the retries, late-reply waits and reconnect loops that
 * would hold a dead line for seconds (serve's ABORT has the same bound). */
static int stop_asked(void *ctx)
{
    (void)ctx;
    return stop_flag != 0;
}

/* The device drivers of hal/: hal_rig_open opens the stage and the probe
 * from their URIs into rig.h tables. */
static int rig_open(const char *stage, const char *probe, rig_stage_t *st, rig_probe_t *pr,
                    void **handle, char *msg, size_t len)
{
    hal_opts_t o = HAL_OPTS_DEFAULT;
    hal_rig_t *r = NULL;
    int rc = hal_rig_open(stage, probe, &o, &r, msg, len);
    if (rc)
        return rc;
    hal_set_stop(r->st.h, stop_asked, NULL);
    hal_set_stop(r->pr.h, stop_asked, NULL);
    *st = r->stage;
    *pr = r->probe;
    *handle = r;
    return RIG_OK;
}

/* Detail of a device failure (the driver's last error), "" if none. */
static const char *rig_detail(const scan_job_t *job, int where)
{
    if (where == SCAN_AT_STAGE)
        return hal_stage_error(job->stage.ctx);
    if (where == SCAN_AT_PROBE)
        return hal_probe_error(job->probe.ctx);
    return "";
}

static void rig_close(void *handle)
{
    if (handle)
        hal_rig_close(handle);
}

typedef struct scan_opts {
    const char *stage, *probe, *nominal, *journal, *fit, *report;
    double step, region[4], alpha, beta, z0, cal[3];
    int have_region, json, home;
    long entity, sync_every, job_id;
    cf_fitjob_opts_t fo; /* --fit: the job's loop, robust passes, reprojection */
    cmd_fitopts_t fa;
    cmd_record_t rec; /* --record, --db */
    /* issue 19: the method and its settings (cf_scanfast.h) */
    const char *method, *geometry;
    const char *part_id; /* the part's ID, a meta record in the journal */
    double period_us, frame_rate, pitch;
    long profiles;
} scan_opts_t;

/* "a:b:c..." into n doubles. */
static int parse_list(const char *s, double *out, int n)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s);
    char *p = buf;
    for (int i = 0; i < n; i++) {
        char *c = i + 1 < n ? strchr(p, ':') : NULL;
        if (i + 1 < n && !c)
            return -1;
        if (c)
            *c = 0;
        if (cli_double(p, &out[i]))
            return -1;
        p = c ? c + 1 : p;
    }
    return 0;
}

static int region_arg(const char *v, void *dst)
{
    double *r = dst;
    return parse_list(v, r, 4) || r[1] < r[0] || r[3] < r[2] ? -1 : 0;
}

static int cal_arg(const char *v, void *dst)
{
    return parse_list(v, dst, 3);
}

static int parse(int argc, char **argv, scan_opts_t *o)
{
    memset(o, 0, sizeof *o);
    o->step = 1.0;
    o->alpha = NF_ALPHA_DEFAULT;
    o->beta = NF_BETA_DEFAULT;
    o->z0 = 50.0; /* cellsim's default beam height */
    o->sync_every = JNL_SYNC_EVERY_DEFAULT;
    o->job_id = (long)time(NULL);
    cf_fitjob_defaults(&o->fo);
    o->fo.cores = sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1; /* the check pass in halves */
    o->period_us = 50;
    const cf_opt_t own[] = {
        {.name = "stage",
         .kind = CF_OPT_STR,
         .dst = &o->stage,
         .arg = "URI",
         .help = "the motion stage (hal: modbus-tcp://, modbus-rtu://, sim://); not for "
                 "--method profiler"},
        {.name = "probe",
         .kind = CF_OPT_STR,
         .dst = &o->probe,
         .arg = "URI",
         .help = "the laser probe (gev:ADDRESS[:SERIAL]: a line profiler)",
         .req = 1},
        {.name = "method",
         .kind = CF_OPT_STR,
         .dst = &o->method,
         .arg = "M",
         .help = "stop (stop-and-go), otf (on the fly: the probe streams a reading per "
                 "trigger), profiler (GigE Vision line profiler)",
         .def = "profiler for a gev: probe, else stop"},
        {.name = "pitch",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->pitch,
         .arg = "MM",
         .help = "distance between raster rows (y)",
         .lo = 1e-300,
         .hi = 1e300,
         .def = "the step"},
        {.name = "period",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->period_us,
         .arg = "US",
         .help = "otf: trigger period; the stage runs at step / period",
         .lo = 20,
         .hi = 1e6},
        {.name = "geometry",
         .kind = CF_OPT_STR,
         .dst = &o->geometry,
         .arg = "'width W height H profiles P x0 X dx DX y0 Y dy DY z0 Z lo LO scale S'",
         .help = "profiler: the scan geometry (cellsim --gev prints it)"},
        {.name = "profiles",
         .kind = CF_OPT_LONG,
         .dst = &o->profiles,
         .arg = "N",
         .help = "profiler: profiles to take",
         .lo = 0,
         .hi = 1e9,
         .def = "one pass, P"},
        {.name = "frame-rate",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->frame_rate,
         .arg = "HZ",
         .help = "profiler: frames/s",
         .lo = 0,
         .hi = 1e6,
         .def = "the device's"},
        {.name = "nominal",
         .kind = CF_OPT_STR,
         .dst = &o->nominal,
         .arg = "NOMINAL.igs",
         .help = "the nominal surface (extent, header identity, fit base)",
         .req = 1},
        {.name = "journal",
         .kind = CF_OPT_STR,
         .dst = &o->journal,
         .arg = "FILE",
         .help = "the journal of measured points (created, never overwritten)",
         .req = 1},
        {.name = "fit",
         .kind = CF_OPT_STR,
         .dst = &o->fit,
         .arg = "OUT.igs",
         .help = "fit the points as they arrive and write the surface here"},
        {.name = "report",
         .kind = CF_OPT_STR,
         .dst = &o->report,
         .arg = "FILE",
         .help = "write the JSON summary here too"},
        {.name = "step",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->step,
         .arg = "MM",
         .help = "grid step in x and y",
         .lo = 1e-300,
         .hi = 1e300},
        {.name = "region",
         .kind = CF_OPT_FUNC,
         .dst = o->region,
         .arg = "x0:x1:y0:y1",
         .help = "the region to scan",
         .fn = region_arg,
         .fn_what = "x0:x1:y0:y1, x0 <= x1, y0 <= y1",
         .def = "the nominal's extent",
         .given = &o->have_region},
        {.name = "alpha",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->alpha,
         .arg = "A",
         .help = "pull toward the Greville points (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "beta",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->beta,
         .arg = "B",
         .help = "pull toward the nominal P0 (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "z0",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->z0,
         .arg = "MM",
         .help = "height of the probe's beam origin",
         .lo = -1e300,
         .hi = 1e300},
        {.name = "cal",
         .kind = CF_OPT_FUNC,
         .dst = o->cal,
         .arg = "cx:cy:cz",
         .help = "probe offset (mm)",
         .fn = cal_arg,
         .fn_what = "cx:cy:cz (mm)",
         .def = "0:0:0"},
        {.name = "sync-every",
         .kind = CF_OPT_LONG,
         .dst = &o->sync_every,
         .arg = "K",
         .help = "journal records per sync",
         .lo = 1,
         .hi = 1000000},
        {.name = "job-id",
         .kind = CF_OPT_LONG,
         .dst = &o->job_id,
         .arg = "N",
         .help = "job number in the journal header",
         .lo = 0,
         .hi = 2147483647.0,
         .def = "the time"},
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &o->entity,
         .arg = "DE",
         .help = "the surface's directory entry in NOMINAL (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "part-id",
         .kind = CF_OPT_STR,
         .dst = &o->part_id,
         .arg = "STR",
         .help = "the part's ID (serial number), kept in the journal (at most 47 characters)"},
        {.name = "home", .kind = CF_OPT_FLAG, .dst = &o->home, .help = "home the stage first"},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &o->json, .help = "print the summary as JSON"},
        {0}};
    /* own, then the fit job's shared options (as `cellfit fit`), with --fit. */
    cf_opt_t opts[CF_OPT_MAX];
    int m = (int)(sizeof own / sizeof own[0]) - 1;
    memcpy(opts, own, sizeof(cf_opt_t) * (size_t)m);
    m += cmd_fitopts_table(opts + m, &o->fo, &o->fa,
                           "--fit: reprojection passes onto the fit, each refitted");
    m += cmd_record_table(opts + m, &o->rec);
    opts[m] = (cf_opt_t){0};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "scan",
                          .summary = "measure a part on the rig into a journal, optionally "
                                     "fitting the points as they arrive",
                          .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return rc;
    if (!o->fit && cmd_fitopts_given(&o->fa))
        return cli_error(CMD, CLI_USAGE,
                         "--tol, --reparam, --robust and the loop's options apply to --fit");
    return cmd_fitopts_check(CMD, &o->fo, &o->fa);
}

/* The nominal's extent in x y, from a 65 x 65 sampling of the surface. */
static void nominal_extent(const nf_surf_t *s, double r[4])
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    r[0] = r[2] = INFINITY;
    r[1] = r[3] = -INFINITY;
    for (int i = 0; i <= 64; i++)
        for (int j = 0; j <= 64; j++) {
            double P[3];
            nf_surf_eval(s, u0 + (u1 - u0) * i / 64.0, v0 + (v1 - v0) * j / 64.0, P);
            r[0] = fmin(r[0], P[0]);
            r[1] = fmax(r[1], P[0]);
            r[2] = fmin(r[2], P[1]);
            r[3] = fmax(r[3], P[1]);
        }
}

/* The directory an output goes to exists and takes files: a job whose
 * results cannot be written is refused before the stage moves, not after
 * the scan. */
static int dir_writable(const char *path)
{
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else
        snprintf(dir, sizeof dir, "%.*s", slash == path ? 1 : (int)(slash - path), path);
    return access(dir, W_OK | X_OK) == 0;
}

static void on_signal(int sig)
{
    (void)sig;
    stop_flag = 1;
}

static double clk_now(void *ctx)
{
    (void)ctx;
    return cli_now();
}

static int clk_should_stop(void *ctx)
{
    (void)ctx;
    return stop_flag != 0;
}

static const rig_clock_ops_t host_clock = {RIG_OPS_VERSION, clk_now, clk_should_stop};

typedef struct scan_ctx {
    cf_fitjob_t *fj;
    int tty;
    long last_tenth;
    int fit_err; /* the nf_err_t that ended the job, 0 */
} scan_ctx_t;

static int on_point(void *ctx, const jnl_rec_t *r)
{
    scan_ctx_t *c = ctx;
    char msg[256];
    if (!c->fj)
        return 0;
    int rc = cf_fitjob_add(c->fj, r->xyz, msg, sizeof msg);
    if (rc)
        c->fit_err = rc;
    return rc;
}

/* A fast method's point (cf_scanfast.h): journalled already, into the fit. */
static int on_fast_point(void *ctx, const double xyz[3])
{
    scan_ctx_t *c = ctx;
    char msg[256];
    if (!c->fj)
        return 0;
    int rc = cf_fitjob_add(c->fj, xyz, msg, sizeof msg);
    if (rc)
        c->fit_err = rc;
    return rc;
}

static int on_fast_stop(void *ctx)
{
    (void)ctx;
    return stop_flag != 0;
}

static void on_fast_progress(void *ctx, long rows_done, long rows, long points)
{
    scan_ctx_t *c = ctx;
    long tenth = rows > 0 ? 10 * rows_done / rows : 10;
    if (c->tty)
        fprintf(stderr, "\rscan: row %ld/%ld, %ld points", rows_done, rows, points);
    else if (tenth != c->last_tenth) {
        c->last_tenth = tenth;
        fprintf(stderr, "scan: %ld/%ld rows (%ld%%), %ld points\n", rows_done, rows,
                rows > 0 ? 100 * rows_done / rows : 100, points);
    }
    if (c->tty && rows_done == rows)
        fputc('\n', stderr);
}

static void on_progress(void *ctx, long done, long planned, uint64_t acked)
{
    scan_ctx_t *c = ctx;
    if (c->tty) {
        if (done % 16 && done != planned)
            return;
        int w = (int)(40.0 * (double)done / (double)planned);
        fprintf(stderr, "\rscan [%.*s%*s] %ld/%ld points, %llu acknowledged", w,
                "########################################", 40 - w, "", done, planned,
                (unsigned long long)acked);
        if (done == planned)
            fputc('\n', stderr);
        return;
    }
    long tenth = 10 * done / planned;
    if (tenth != c->last_tenth) {
        c->last_tenth = tenth;
        fprintf(stderr, "scan: %ld/%ld points (%ld%%), %llu acknowledged\n", done, planned,
                100 * done / planned, (unsigned long long)acked);
    }
}

/* The fast methods' counts (cf_scanfast_res_t) into the summary. */
static void summary_fast(cf_json_t *js, int method, const cf_scanfast_res_t *x, double fit_ready,
                         const cf_fitjob_result_t *fr, int held)
{
    cf_json_int(js, "rows", x->rows);
    cf_json_int(js, "rows_done", x->rows_done);
    cf_json_int(js, "gap_records", x->gap_records);
    cf_json_num(js, "scan_seconds", x->seconds);
    cf_json_num(js, "points_per_s", x->seconds > 0 ? (double)x->points / x->seconds : 0);
    /* After the last row: the surface solved from the accumulated stripes
     * (fit_solve_s), and the job done (fit_ready_s: with the check of every
     * point read back from the journal, which is statistics, not the fit). */
    cf_json_num(js, "fit_solve_s", fr ? fr->t_solve : 0);
    cf_json_num(js, "fit_ready_s", fit_ready);
    /* Where the passes after the scan read the points: "held" (the job's
     * memory, issue 19) or "journal" (read back: more than the hold). */
    if (fr)
        cf_json_str(js, "fit_points_from", held ? "held" : "journal");
    if (method == CF_SCAN_OTF) {
        cf_json_num(js, "speed", x->speed);
        cf_json_num(js, "period_us", x->period_us);
        cf_json_int(js, "triggers", x->triggers);
        cf_json_int(js, "nosurf", x->nosurf);
        cf_json_int(js, "sensor_errors", x->sensor_errors);
        cf_json_int(js, "lost_readings", x->lost_readings);
        cf_json_int(js, "lost_triggers", x->lost_triggers);
        cf_json_int(js, "both_lost", x->both_lost);
        cf_json_int(js, "dup", x->dup);
        cf_json_int(js, "late", x->late);
        cf_json_int(js, "overrun", x->overrun);
        cf_json_int(js, "dropped_by_probe", x->dropped_by_probe);
        cf_json_int(js, "rows_cut", x->rows_cut);
        cf_json_int(js, "past_end", x->past_end);
        cf_json_int(js, "before_start", x->before_start);
    } else {
        cf_json_int(js, "frames", x->frames);
        cf_json_int(js, "frames_lost", x->frames_lost);
        cf_json_int(js, "profiles_lost", x->profiles_lost);
        cf_json_int(js, "frames_bad", x->frames_bad);
        cf_json_int(js, "dropouts", x->dropouts);
    }
}

static void summary(FILE *f, const scan_opts_t *o, const scan_plan_t *pl, const scan_result_t *res,
                    const jnl_t *j, const cf_fitjob_result_t *fr, double secs, int method,
                    const cf_scanfast_res_t *fast, double fit_ready, int held)
{
    cf_json_t js;
    cf_json_begin(&js, f);
    cf_json_str(&js, "journal", o->journal);
    cf_json_int(&js, "job_id", o->job_id);
    cf_json_str(&js, "part_id", o->part_id ? o->part_id : "");
    cf_json_str(&js, "nominal", o->nominal);
    cf_json_num(&js, "x0", pl->x0);
    cf_json_num(&js, "y0", pl->y0);
    cf_json_num(&js, "step", o->step);
    cf_json_int(&js, "nx", pl->nx);
    cf_json_int(&js, "ny", pl->ny);
    cf_json_int(&js, "planned", scan_plan_count(pl));
    cf_json_int(&js, "done", res->done);
    cf_json_int(&js, "points", res->points);
    cf_json_int(&js, "flagged", res->flagged);
    cf_json_int(&js, "acknowledged_records", (long)jnl_acked(j));
    cf_json_int(&js, "code", res->code);
    cf_json_str(&js, "error", res->code ? rig_strerror(res->code) : "");
    cf_json_int(&js, "fail_index", res->fail_index);
    if (fr) {
        cf_json_str(&js, "fit", o->fit);
        cf_json_str(&js, "solver", nf_solver_name(fr->solve.solver));
        cf_json_int(&js, "iterations", fr->solve.iterations);
        cf_json_num(&js, "rms", fr->rms);
        cf_json_num(&js, "max_abs", fr->max_abs);
        cf_json_num(&js, "nominal_rms", fr->nominal_rms);
        cf_json_num(&js, "nominal_max_abs", fr->nominal_max);
        cf_json_str(&js, "fit_status", cf_fitjob_status_name(fr->status));
        cf_json_int(&js, "reparam", o->fo.reparam);
        cmd_fitopts_json(&js, &o->fo, fr);
    }
    cf_json_str(&js, "method", cf_scanfast_method_name((cf_scan_method_t)method));
    if (method != CF_SCAN_STOP)
        summary_fast(&js, method, fast, fit_ready, fr, held);
    cf_json_num(&js, "seconds", secs);
    /* The process's peak resident memory so far (make bench prints it for
     * 10^6 and 10^7 points: flat in the points). */
    struct rusage ru;
    cf_json_int(&js, "peak_rss_kb", getrusage(RUSAGE_SELF, &ru) ? -1 : (long)ru.ru_maxrss);
    cf_json_end(&js);
}

int cmd_scan(int argc, char **argv)
{
    scan_opts_t o;
    int ec = parse(argc, argv, &o);
    if (ec)
        return cf_opt_exit(ec);
    double t0 = cli_now();
    char msg[512];
    int method = o.method ? cf_scanfast_method(o.method) : (int)cf_scanfast_default_method(o.probe);
    cf_scanfast_geom_t geom;
    if (method < 0)
        return cli_error(CMD, CLI_USAGE, "--method %s: want stop, otf or profiler", o.method);
    if (method != CF_SCAN_PROFILER && !o.stage)
        return cli_error(CMD, CLI_USAGE, "--stage is needed for --method %s",
                         cf_scanfast_method_name((cf_scan_method_t)method));
    if (method == CF_SCAN_PROFILER && cf_scanfast_geom_parse(o.geometry, &geom))
        return cli_error(CMD, CLI_USAGE,
                         "--method profiler needs --geometry 'width W height H profiles P x0 X "
                         "dx DX y0 Y dy DY z0 Z lo LO scale S' (cellsim --gev prints it)");
    nf_surf_t nom;
    if (cf_surfio_read(o.nominal, (int)o.entity, &nom, msg, sizeof msg))
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    if (cf_fitsrc_nominal_id(o.nominal, &h.nominal_hash, h.nominal_name)) {
        cf_surf_free(&nom);
        return cli_error(CMD, CLI_USAGE, "%s: cannot read", o.nominal);
    }
    scan_job_t job;
    memset(&job, 0, sizeof job);
    if (!o.have_region)
        nominal_extent(&nom, o.region);
    if (method == CF_SCAN_PROFILER) {
        /* The profiler's plan, for the summary: profiles along x, points along y. */
        job.plan = (scan_plan_t){
            geom.x0,   geom.y0, geom.dx, geom.dy, o.profiles > 0 ? o.profiles : geom.profiles,
            geom.width};
    } else if (scan_plan_init(&job.plan, o.region[0], o.region[1], o.region[2], o.region[3], o.step,
                              o.pitch > 0 ? o.pitch : o.step)) {
        cf_surf_free(&nom);
        return cli_error(
            CMD, CLI_USAGE, "region %g:%g:%g:%g with step %g: no plan (at most %ld points)",
            o.region[0], o.region[1], o.region[2], o.region[3], o.step, SCAN_MAX_POINTS);
    }
    job.kin.z0 = o.z0;
    memcpy(job.kin.cal, o.cal, sizeof o.cal);
    job.home = o.home;
    cf_fitjob_t *fj = NULL;
    cf_fitjob_result_t fr;
    memset(&fr, 0, sizeof fr);
    if (o.fit) {
        o.fo.alpha = o.alpha;
        o.fo.beta = o.beta;
        if ((ec = cf_fitjob_open(&fj, &nom, &o.fo, msg, sizeof msg)) != 0) {
            cf_surf_free(&nom);
            return cli_error(CMD, ec == CF_ENOMEM ? CLI_FAIL : CLI_USAGE, "%s", msg);
        }
    }
    const char *outs[2] = {o.fit, o.report};
    for (int i = 0; i < 2; i++)
        if (outs[i] && !dir_writable(outs[i])) {
            ec = cli_error(CMD, CLI_USAGE,
                           "%s: its directory does not exist or is not writable (checked before "
                           "the scan)",
                           outs[i]);
            goto out;
        }
    cf_store_file_t f;
    rig_store_t st;
    f.fd = -1;
    if (cf_store_file_open(&f, o.journal, CF_STORE_CREATE, &st, msg, sizeof msg)) {
        ec = cli_error(CMD, CLI_USAGE, "%s (a journal is never overwritten)", msg);
        goto out;
    }
    void *devs = NULL;
    int rc = method == CF_SCAN_PROFILER
                 ? RIG_OK
                 : rig_open(o.stage, o.probe, &job.stage, &job.probe, &devs, msg, sizeof msg);
    if (rc) {
        cf_store_file_close(&f);
        unlink(o.journal); /* nothing measured: leave no empty journal behind */
        ec = cli_error(CMD, rc == RIG_EARG ? CLI_USAGE : CLI_FAIL, "%s [%d]; nothing measured", msg,
                       rc);
        goto out;
    }
    /* The fast methods sync once a row: their records are written 64 KiB
     * at a time (819 records), not one write each (docs/journal.md). */
    if (method != CF_SCAN_STOP)
        (void)cf_store_file_buffer(&f, 65536); /* without memory: one write a record */
    h.sync_every = (uint32_t)o.sync_every;
    h.job_id = (uint64_t)o.job_id;
    h.t_start = cli_now();
    h.utc_start = cli_utc_now(); /* the cell controller has a wall clock: records date */
    scan_header(&job, &h);
    if (method != CF_SCAN_STOP)
        cf_scanfast_header(method == CF_SCAN_OTF ? &job.kin : &(scan_kin_t){geom.z0, {0, 0, 0}},
                           scan_plan_count(&job.plan), &h);
    jnl_t j;
    if ((rc = jnl_create(&j, st, &h)) != RIG_OK) {
        ec = cli_error(CMD, CLI_FAIL, "%s: %s [%d] (%s); nothing measured", o.journal,
                       rig_strerror(rc), rc, f.err);
        unlink(o.journal); /* jnl_create cut it to 0 bytes: no empty journal behind */
        goto out_dev;
    }
    if (o.part_id && *o.part_id && (rc = jnl_meta(&j, JNL_META_PART_ID, o.part_id, h.t_start))) {
        ec = cli_error(CMD, CLI_FAIL, "%s: the part ID: %s [%d]; nothing measured", o.journal,
                       rig_strerror(rc), rc);
        goto out_dev;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    scan_ctx_t sc = {fj, isatty(2), -1, 0};
    job.clock = (rig_clock_t){&host_clock, NULL};
    job.cb = (scan_cb_t){on_point, on_progress, &sc};
    scan_result_t res;
    cf_scanfast_res_t fast;
    memset(&fast, 0, sizeof fast);
    if (method == CF_SCAN_STOP)
        rc = scan_run(&job, &j, &res);
    else {
        /* The fast methods (cf_scanfast.h): the same journal, live fit and
         * stop flag; their row counts into the stop-and-go result. */
        if (!o.home || (rc = job.stage.ops ? job.stage.ops->home(job.stage.ctx) : 0) == 0) {
            cf_scanfast_cb_t fcb = {on_fast_point, on_fast_progress, on_fast_stop, &sc};
            msg[0] = 0;
            rc = method == CF_SCAN_OTF
                     ? cf_scanfast_otf(devs, &job.plan, &job.kin, o.period_us, &j, &fcb, &fast, msg,
                                       sizeof msg)
                     : cf_scanfast_profiler(o.probe, &geom, o.profiles, o.frame_rate, &j, &fcb,
                                            &fast, msg, sizeof msg);
        } else {
            fast.where = SCAN_AT_STAGE;
            jnl_end(&j, rc, cli_now());
        }
        memset(&res, 0, sizeof res);
        res.points = fast.points;
        res.flagged = fast.flagged;
        res.done = fast.points + fast.flagged;
        res.fail_index = fast.fail_row;
        res.code = rc;
        res.where = fast.where;
    }
    if (sc.tty && rc)
        fputc('\n', stderr);
    int fitted = 0, held = 0;
    double t_fit0 = 0, fit_ready = 0;
    if (rc) {
        double x = NAN, y = NAN;
        int end;
        if (method == CF_SCAN_OTF && res.fail_index >= 0 && res.fail_index < job.plan.ny)
            scan_plan_point(&job.plan, res.fail_index * job.plan.nx, &x, &y, &end);
        else if (method == CF_SCAN_STOP && res.fail_index >= 0 &&
                 res.fail_index < scan_plan_count(&job.plan))
            scan_plan_point(&job.plan, res.fail_index, &x, &y, &end);
        static const char *const at[] = {"", "stage", "probe", "journal", "fit", "stop"};
        const char *det = method == CF_SCAN_STOP ? rig_detail(&job, res.where) : msg;
        ec = cli_error(CMD, CLI_FAIL,
                       "job ended at %s %ld (x %g, y %g): %s: %s [%d]%s%s; %s holds %llu "
                       "acknowledged records",
                       method == CF_SCAN_STOP ? "grid point" : "row", res.fail_index, x, y,
                       at[res.where], sc.fit_err ? nf_strerror(sc.fit_err) : rig_strerror(rc), rc,
                       *det ? ": " : "", det, o.journal, (unsigned long long)jnl_acked(&j));
    } else if (fj) {
        /* The first pass took the points as they arrived; the job holds
         * them (cf_fitjob_held) for the residuals and later passes, up to
         * CF_FITJOB_HOLD_ROWS, and else reads them back from the journal
         * (verified first: a pass over the whole file). */
        jnl_reader_t rd;
        jnl_header_t h2;
        jnl_info_t in;
        cf_fitsrc_t src;
        cf_fitsrc_jnl_t jc;
        held = cf_fitjob_held(fj);
        t_fit0 = fast.t_last_row > 0 ? fast.t_last_row : cli_now();
        if (!held && (rc = jnl_reader_open(&rd, st, &h2, &in)) != 0) {
            ec = cli_error(CMD, CLI_FAIL, "%s: cannot read the journal back: %d", o.journal, rc);
            goto out_dev;
        }
        if (!held)
            cf_fitsrc_journal(&src, &jc, &rd, o.journal, (long)in.points);
        if ((rc = cf_fitjob_run(fj, held ? NULL : &src, NULL, 0, 100, &fr, msg, sizeof msg)) != 0) {
            ec = cli_error(CMD, cf_fitjob_input_error(rc) ? CLI_USAGE : CLI_FAIL, "%s", msg);
            goto out_dev;
        }
        if (cf_surfio_write(o.fit, &fr.surf, "cellfit scan", cf_version_string(), msg,
                            sizeof msg)) {
            ec = cli_error(CMD, CLI_FAIL, "%s", msg);
            goto out_dev;
        }
        fitted = 1;
        fit_ready = cli_now() - t_fit0;
    }
    double secs = cli_now() - t0;
    if (o.report) {
        FILE *rf = fopen(o.report, "w");
        int werr = rf ? 0 : errno;
        if (rf) {
            summary(rf, &o, &job.plan, &res, &j, fitted ? &fr : NULL, secs, method, &fast,
                    fit_ready, held);
            werr = ferror(rf) ? errno : 0;
            if (fclose(rf) && !werr)
                werr = errno ? errno : EIO;
        }
        if (werr && !ec)
            ec = cli_error(CMD, CLI_FAIL, "%s: cannot write the report: %s", o.report,
                           strerror(werr));
    }
    if (o.json)
        summary(stdout, &o, &job.plan, &res, &j, fitted ? &fr : NULL, secs, method, &fast,
                fit_ready, held);
    else if (!rc) {
        printf("cellfit scan: %ld points (%ld x %ld grid, step %g), %ld without a surface; "
               "journal %s\n",
               res.done, job.plan.nx, job.plan.ny, o.step, res.flagged, o.journal);
        if (method != CF_SCAN_STOP)
            printf("  %s: %.0f points/s over %ld rows; lost: %ld readings, %ld triggers, %ld on "
                   "both sides, %ld overrun, %ld profiles (%ld frames)\n",
                   cf_scanfast_method_name((cf_scan_method_t)method),
                   fast.seconds > 0 ? (double)fast.points / fast.seconds : 0, fast.rows_done,
                   fast.lost_readings, fast.lost_triggers, fast.both_lost, fast.overrun,
                   fast.profiles_lost, fast.frames_lost);
        if (fitted)
            printf("  fit: rms %.6g  max %.6g (vs nominal rms %.6g); wrote %s\n", fr.rms,
                   fr.max_abs, fr.nominal_rms, o.fit);
        if (fitted && o.fo.loop)
            printf("  tolerance %g mm: %.3f %% of the points within (need %g %%): %s, %d x %d "
                   "control points after %d rounds\n",
                   o.fo.tol, fr.within_pct, o.fo.within,
                   fr.status == CF_FITJOB_MET ? "met" : "NOT met", fr.surf.nu, fr.surf.nv,
                   fr.nrounds);
    }
    const cmd_record_job_t rj = {.command = o.fit ? "scan_fit" : "scan",
                                 .t0 = t0,
                                 .code = rc,
                                 .fit = fitted ? &fr : NULL,
                                 .fo = &o.fo,
                                 .surface = fitted ? o.fit : NULL,
                                 .report = o.report,
                                 .journal = o.journal};
    if (cmd_record(CMD, &o.rec, &rj) && !ec)
        ec = CLI_FAIL;
    if (fitted && !ec) /* a tolerance not met fails the work, as `cellfit fit` */
        ec = cmd_fitopts_verdict(CMD, &o.fo, &fr, o.fit);
out_dev:
    rig_close(devs);
    cf_store_file_close(&f);
out:
    cf_fitjob_result_free(&fr);
    cf_fitjob_close(fj);
    cf_surf_free(&nom);
    return ec;
}
