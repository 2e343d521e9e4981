/* SPDX-License-Identifier: MIT */
/* cmd_journal.c: `cellfit journal export|info|recover|fit`: the journal of
 * measured points read back one record at a time: its points as x y z, a
 * summary, recovery of a torn tail, and the streaming fit of its points onto
 * the nominal. Hidden `selftest-write` / `selftest-check` write and verify a
 * journal of known records through the real file store, for the power-cut
 * tests (tests/cli/journal.sh). */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_store_file.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"
#include "cmd_fitopts.h"
#include "jnl.h"
#include "nf_err.h"
#include "rig_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define CMD "journal"

/* An open journal for reading: file store, verified, reader at the start. */
typedef struct jopen {
    cf_store_file_t f;
    rig_store_t st;
    jnl_header_t h;
    jnl_info_t in;
    jnl_reader_t rd;
} jopen_t;

/* One line naming the damaged record (or the header); exit 2. */
static int corrupt(const char *path, const jnl_info_t *in)
{
    if (in->bad_record < 0)
        return cli_error(CMD, CLI_USAGE,
                         "%s: header damaged or incomplete: not a cellfit journal (or torn "
                         "while being created)",
                         path);
    return cli_error(
        CMD, CLI_USAGE,
        "%s: record %lld (byte %llu) damaged (CRC or sequence) with synced records "
        "after it: journal corrupt",
        path, (long long)in->bad_record,
        (unsigned long long)(JNL_HDR_BYTES + (uint64_t)in->bad_record * JNL_REC_BYTES));
}

static int jopen_read(jopen_t *j, const char *path)
{
    char msg[512];
    if (cf_store_file_open(&j->f, path, CF_STORE_READ, &j->st, msg, sizeof msg))
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    int rc = jnl_reader_open(&j->rd, j->st, &j->h, &j->in);
    if (rc == RIG_ECORRUPT) {
        cf_store_file_close(&j->f);
        return corrupt(path, &j->in);
    }
    if (rc) {
        cli_error(CMD, CLI_FAIL, "%s: %s (%s)", path, rig_strerror(rc), j->f.err);
        cf_store_file_close(&j->f);
        return CLI_FAIL;
    }
    return CLI_OK;
}

/* A reader error after verification: the file changed under us. */
static int read_error(const char *path, const jopen_t *j, int rc)
{
    if (rc == RIG_ECORRUPT)
        return cli_error(CMD, CLI_USAGE,
                         "%s: record %llu changed while being read: journal corrupt", path,
                         (unsigned long long)j->rd.next);
    return cli_error(CMD, CLI_FAIL, "%s: %s (%s)", path, rig_strerror(rc), j->f.err);
}

static int valid_point(const jnl_rec_t *r)
{
    return r->type == JNL_T_POINT && !(r->flags & JNL_F_NOSURF);
}

static int do_export(int argc, char **argv)
{
    const char *pos[1], *out = NULL;
    int times = 0, records = 0;
    const cf_opt_t opts[] = {{.name = "out",
                              .kind = CF_OPT_STR,
                              .dst = &out,
                              .arg = "FILE",
                              .help = "write the points here",
                              .def = "standard output"},
                             {.name = "records",
                              .kind = CF_OPT_FLAG,
                              .dst = &records,
                              .help = "every record in order, one line each: 'point SEQ CODE SX "
                                      "SY X Y Z', 'gap SEQ KIND ROW NUM COUNT SX SY', 'meta SEQ "
                                      "KEY TEXT', 'end SEQ CODE'"},
                             {.name = "times",
                              .kind = CF_OPT_FLAG,
                              .dst = &times,
                              .help = "CSV with a header, utc,x,y,z: each point's wall-clock UTC "
                                      "(seconds since 1970; docs/journal.md, Dates)"},
                             {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal export",
                          .args = "JOURNAL",
                          .summary = "the journal's measured points as x y z lines (%.17g)",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    const char *path = pos[0];
    jopen_t j;
    int ec = jopen_read(&j, path);
    if (ec)
        return ec;
    FILE *f = out ? fopen(out, "w") : stdout;
    if (!f) {
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_FAIL, "%s: cannot write", out);
    }
    jnl_rec_t r;
    if (times && !(j.h.utc_start > 0)) {
        if (out)
            fclose(f);
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_USAGE,
                         "%s: --times: the journal has no wall-clock start (a board "
                         "without a clock wrote it)",
                         path);
    }
    if (times && records) {
        if (out)
            fclose(f);
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_USAGE, "--times and --records: one or the other");
    }
    if (times)
        fputs("utc,x,y,z\n", f);
    while ((rc = jnl_reader_next(&j.rd, &r)) == 1) {
        if (records) { /* every record, one line each, in journal order */
            if (r.type == JNL_T_GAP)
                fprintf(f, "gap %u %s %lld %llu %llu %.17g %.17g\n", r.seq, jnl_gap_name(r.code),
                        (long long)r.row, (unsigned long long)r.num, (unsigned long long)r.count,
                        r.stage[0], r.stage[1]);
            else if (r.type == JNL_T_META)
                fprintf(f, "meta %u %d %s\n", r.seq, r.code, r.text);
            else if (r.type == JNL_T_END)
                fprintf(f, "end %u %d\n", r.seq, r.code);
            else
                fprintf(f, "point %u %d %.17g %.17g %.17g %.17g %.17g\n", r.seq, r.code, r.stage[0],
                        r.stage[1], r.xyz[0], r.xyz[1], r.xyz[2]);
            continue;
        }
        if (!valid_point(&r))
            continue;
        if (times)
            fprintf(f, "%.3f,%.17g,%.17g,%.17g\n", j.h.utc_start + (r.t - j.h.t_start), r.xyz[0],
                    r.xyz[1], r.xyz[2]);
        else
            fprintf(f, "%.17g %.17g %.17g\n", r.xyz[0], r.xyz[1], r.xyz[2]);
    }
    int werr = ferror(f);
    if (out && fclose(f))
        werr = 1;
    cf_store_file_close(&j.f);
    if (rc < 0)
        return read_error(path, &j, rc);
    if (werr)
        return cli_error(CMD, CLI_FAIL, "%s: write failed", out ? out : "stdout");
    return CLI_OK;
}

static int do_info(int argc, char **argv)
{
    const char *pos[1];
    int json = 0;
    const cf_opt_t opts[] = {
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "print the summary as JSON"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal info",
                          .args = "JOURNAL",
                          .summary = "the journal's header, records, ending and torn tail",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    const char *path = pos[0];
    jopen_t j;
    int ec = jopen_read(&j, path);
    if (ec)
        return ec;
    cf_store_file_close(&j.f);
    const jnl_info_t *in = &j.in;
    char hash[24];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)j.h.nominal_hash);
    double span = in->records ? in->t_last - in->t_first : 0.0;
    /* Dates from the wall-clock start, where the board had a clock. */
    char d0[40], d1[40], d2[40];
    const double u0 = j.h.utc_start;
    cli_iso8601(u0, d0, sizeof d0);
    cli_iso8601(u0 > 0 && in->records ? u0 + (in->t_first - j.h.t_start) : 0, d1, sizeof d1);
    cli_iso8601(u0 > 0 && in->records ? u0 + (in->t_last - j.h.t_start) : 0, d2, sizeof d2);
    if (json) {
        cf_json_t o;
        cf_json_begin(&o, stdout);
        cf_json_str(&o, "journal", path);
        cf_json_int(&o, "version", (long)j.h.version);
        cf_json_int(&o, "job_id", (long)j.h.job_id);
        cf_json_str(&o, "nominal", j.h.nominal_name);
        cf_json_str(&o, "nominal_hash", hash);
        cf_json_int(&o, "sync_every", (long)j.h.sync_every);
        cf_json_int(&o, "planned", (long)j.h.planned);
        cf_json_int(&o, "records", (long)in->records);
        cf_json_int(&o, "points", (long)in->points);
        cf_json_int(&o, "flagged", (long)in->flagged);
        cf_json_int(&o, "torn_tail", in->tail_bytes > 0);
        cf_json_int(&o, "torn_tail_bytes", (long)in->tail_bytes);
        cf_json_int(&o, "ended", in->ended);
        cf_json_int(&o, "end_code", in->end_code);
        cf_json_str(&o, "end_error", in->ended ? rig_strerror(in->end_code) : "");
        cf_json_num(&o, "t_start", j.h.t_start);
        cf_json_num(&o, "t_first", in->t_first);
        cf_json_num(&o, "t_last", in->t_last);
        cf_json_num(&o, "span_seconds", span);
        cf_json_str(&o, "started_utc", u0 > 0 ? d0 : NULL);
        cf_json_str(&o, "first_utc", d1[0] ? d1 : NULL);
        cf_json_str(&o, "last_utc", d2[0] ? d2 : NULL);
        cf_json_num(&o, "z0", j.h.z0);
        cf_json_num(&o, "cx", j.h.cal[0]);
        cf_json_num(&o, "cy", j.h.cal[1]);
        cf_json_num(&o, "cz", j.h.cal[2]);
        /* Version 2 (issue 19): the part's ID and the losses journalled. */
        cf_json_str(&o, "part_id", in->part_id);
        cf_json_int(&o, "gaps", (long)in->gaps);
        for (int k = 1; k < JNL_GAP_KINDS; k++) {
            char key[32];
            snprintf(key, sizeof key, "lost_%s", jnl_gap_name(k));
            cf_json_int(&o, key, (long)in->lost[k]);
        }
        cf_json_end(&o);
        return CLI_OK;
    }
    printf("%s: journal v%u, job %llu, nominal '%s' (FNV-1a %s), synced every %u records\n", path,
           (unsigned)j.h.version, (unsigned long long)j.h.job_id, j.h.nominal_name, hash,
           (unsigned)j.h.sync_every);
    printf("  %llu records: %llu points, %llu without a surface; %llu planned\n",
           (unsigned long long)in->records, (unsigned long long)in->points,
           (unsigned long long)in->flagged, (unsigned long long)j.h.planned);
    if (in->part_id[0])
        printf("  part ID '%s'\n", in->part_id);
    if (in->gaps)
        printf("  %llu gap records: lost %llu readings, %llu triggers, %llu on both sides, %llu "
               "profiles\n",
               (unsigned long long)in->gaps, (unsigned long long)in->lost[JNL_GAP_NO_READING],
               (unsigned long long)in->lost[JNL_GAP_NO_TRIGGER],
               (unsigned long long)in->lost[JNL_GAP_BOTH],
               (unsigned long long)in->lost[JNL_GAP_PROFILE]);
    if (in->ended)
        printf("  ended: %s (%d)\n", rig_strerror(in->end_code), in->end_code);
    else
        printf("  not ended (interrupted, or still being written)\n");
    if (in->tail_bytes)
        printf("  torn tail: %llu bytes after the last valid record (dropped: `cellfit journal "
               "recover` cuts them)\n",
               (unsigned long long)in->tail_bytes);
    else
        printf("  no torn tail\n");
    printf("  time %.6g .. %.6g s (span %.6g s); kinematics z0 %.6g, offset (%.6g, %.6g, %.6g)\n",
           in->t_first, in->t_last, span, j.h.z0, j.h.cal[0], j.h.cal[1], j.h.cal[2]);
    if (u0 > 0)
        printf("  started %s; records %s .. %s (UTC)\n", d0, d1[0] ? d1 : "-", d2[0] ? d2 : "-");
    else
        printf("  no wall clock: the board that wrote it has none (times are seconds of its "
               "monotonic clock)\n");
    return CLI_OK;
}

static int do_recover(int argc, char **argv)
{
    const char *pos[1];
    const cf_opt_t opts[] = {{0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal recover",
                          .args = "JOURNAL",
                          .summary = "cut a torn tail off the journal, keeping every valid record",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int prc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (prc)
        return cf_opt_exit(prc);
    const char *path = pos[0];
    char msg[512];
    cf_store_file_t f;
    rig_store_t st;
    if (cf_store_file_open(&f, path, CF_STORE_WRITE, &st, msg, sizeof msg))
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    jnl_t j;
    jnl_info_t in;
    int rc = jnl_open(&j, st, &in);
    cf_store_file_close(&f);
    if (rc == RIG_ECORRUPT)
        return corrupt(path, &in);
    if (rc)
        return cli_error(CMD, CLI_FAIL, "%s: %s (%s)", path, rig_strerror(rc), f.err);
    printf("%s: %llu records kept, %llu bytes of torn tail cut\n", path,
           (unsigned long long)in.records, (unsigned long long)in.tail_bytes);
    return CLI_OK;
}

static int do_fit(int argc, char **argv)
{
    const char *pos[1], *nominal = NULL, *out = NULL;
    long entity = 0;
    int json = 0, force = 0;
    cf_fitjob_opts_t fo;
    cf_fitjob_defaults(&fo);
    fo.cores = sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1; /* the check pass in halves */
    const cf_opt_t own[] = {
        {.name = "nominal",
         .kind = CF_OPT_STR,
         .dst = &nominal,
         .arg = "N.igs",
         .help = "the nominal surface the journal was measured against",
         .req = 1},
        {.name = "out",
         .kind = CF_OPT_STR,
         .dst = &out,
         .arg = "OUT.igs",
         .help = "the fitted surface",
         .req = 1},
        {.name = "alpha",
         .kind = CF_OPT_DOUBLE,
         .dst = &fo.alpha,
         .arg = "A",
         .help = "pull toward the Greville points (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "beta",
         .kind = CF_OPT_DOUBLE,
         .dst = &fo.beta,
         .arg = "B",
         .help = "pull toward the nominal P0 (Eq. 7)",
         .lo = 0,
         .hi = 1e300},
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &entity,
         .arg = "DE",
         .help = "the surface's directory entry in N.igs (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "force",
         .kind = CF_OPT_FLAG,
         .dst = &force,
         .help = "fit even when the journal names another nominal"},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "print the summary as JSON"},
        {0}};
    /* own, then the fit job's shared options (as `cellfit fit`). */
    cf_opt_t opts[CF_OPT_MAX];
    cmd_fitopts_t fa;
    int m = (int)(sizeof own / sizeof own[0]) - 1;
    memcpy(opts, own, sizeof(cf_opt_t) * (size_t)m);
    m += cmd_fitopts_table(opts + m, &fo, &fa, "reprojection passes onto the fit, each refitted");
    opts[m] = (cf_opt_t){0};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal fit",
                          .args = "JOURNAL",
                          .summary = "fit the journal's measured points onto the nominal",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    if ((rc = cmd_fitopts_check(CMD, &fo, &fa)))
        return rc;
    const char *path = pos[0];
    double t0 = cli_now();
    char msg[1024], name[JNL_NAME_LEN];
    uint64_t hash;
    if (cf_fitsrc_nominal_id(nominal, &hash, name))
        return cli_error(CMD, CLI_USAGE, "%s: cannot read", nominal);
    jopen_t j;
    int ec = jopen_read(&j, path);
    if (ec)
        return ec;
    if (j.h.nominal_hash && j.h.nominal_hash != hash && !force) {
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_USAGE,
                         "%s was measured against '%s' (FNV-1a %016llx), not %s (%016llx): "
                         "give --force to fit anyway",
                         path, j.h.nominal_name, (unsigned long long)j.h.nominal_hash, nominal,
                         (unsigned long long)hash);
    }
    nf_surf_t nom;
    if (cf_surfio_read(nominal, (int)entity, &nom, msg, sizeof msg)) {
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    }
    cf_fitjob_t *fj = NULL;
    cf_fitjob_result_t r;
    memset(&r, 0, sizeof r);
    rc = cf_fitjob_open(&fj, &nom, &fo, msg, sizeof msg);
    cf_surf_free(&nom);
    if (!rc) {
        cf_fitsrc_t src;
        cf_fitsrc_jnl_t jc;
        cf_fitsrc_journal(&src, &jc, &j.rd, path, (long)j.in.points);
        rc = cf_fitjob_run(fj, &src, NULL, 0, 100, &r, msg, sizeof msg);
    }
    cf_fitjob_close(fj);
    if (rc) {
        ec = cli_error(CMD, cf_fitjob_input_error(rc) ? CLI_USAGE : CLI_FAIL, "%s", msg);
        goto out;
    }
    if (cf_surfio_write(out, &r.surf, "cellfit journal fit", cf_version_string(), msg,
                        sizeof msg)) {
        ec = cli_error(CMD, CLI_FAIL, "%s", msg);
        goto out;
    }
    if (json) {
        cf_json_t o;
        cf_json_begin(&o, stdout);
        cf_json_str(&o, "journal", path);
        cf_json_int(&o, "points", r.points);
        cf_json_int(&o, "flagged", (long)j.in.flagged);
        cf_json_int(&o, "control_points", (long)r.surf.nu * r.surf.nv);
        cf_json_num(&o, "alpha", fo.alpha);
        cf_json_num(&o, "beta", fo.beta);
        cf_json_str(&o, "solver", nf_solver_name(r.solve.solver));
        cf_json_int(&o, "iterations", r.solve.iterations);
        cf_json_num(&o, "rel_residual", r.solve.rel_residual);
        cf_json_num(&o, "rms", r.rms);
        cf_json_num(&o, "max_abs", r.max_abs);
        cf_json_num(&o, "nominal_rms", r.nominal_rms);
        cf_json_num(&o, "nominal_max_abs", r.nominal_max);
        cf_json_int(&o, "reparam", fo.reparam);
        cf_json_str(&o, "fit_status", cf_fitjob_status_name(r.status));
        cmd_fitopts_json(&o, &fo, &r);
        cf_json_num(&o, "seconds", cli_now() - t0);
        cf_json_int(&o, "bytes", r.bytes);
        cf_json_str(&o, "out", out);
        cf_json_end(&o);
    } else {
        for (int i = 0; fo.loop && i < r.nrounds; i++)
            cf_round_print(stdout, i, &r.rounds[i], fo.tol, fo.robust);
        printf("cellfit journal fit: %ld points of %s (%llu without a surface), %d x %d control "
               "points\n",
               r.points, path, (unsigned long long)j.in.flagged, r.surf.nu, r.surf.nv);
        printf("  measured vs nominal: rms %.6g  max %.6g;  vs fit: rms %.6g  max %.6g\n",
               r.nominal_rms, r.nominal_max, r.rms, r.max_abs);
        printf("  solver %s, %d iterations, relative residual %.2e; %.3f s\n",
               nf_solver_name(r.solve.solver), r.solve.iterations, r.solve.rel_residual,
               cli_now() - t0);
        if (fo.loop)
            printf("  tolerance %g mm: %.3f %% of the points within (need %g %%): %s\n", fo.tol,
                   r.within_pct, fo.within, r.status == CF_FITJOB_MET ? "met" : "NOT met");
        printf("  wrote %s\n", out);
    }
    /* The best surface is written either way, as `cellfit fit`. */
    ec = cmd_fitopts_verdict(CMD, &fo, &r, out);
out:
    cf_fitjob_result_free(&r);
    cf_store_file_close(&j.f);
    return ec;
}

/* The known record of sequence number i (selftest-write / selftest-check). */
static jnl_rec_t known_rec(uint32_t i)
{
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_POINT;
    r.stage[0] = 0.1 * (double)(i % 1000);
    r.stage[1] = 0.1 * (double)(i / 1000);
    r.t = 1e-3 * (double)i;
    if (i % 97 == 13) {
        r.flags = JNL_F_NOSURF;
        r.code = RIG_ENOSURF;
        r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = NAN;
    } else {
        r.dist = 10.0 + sin((double)i);
        r.xyz[0] = r.stage[0];
        r.xyz[1] = r.stage[1];
        r.xyz[2] = 100.0 - r.dist;
    }
    return r;
}

/* A store that writes each append in two pieces with a pause between, so
 * that a kill -9 can tear a record as a power cut would. */
typedef struct torn_store {
    rig_store_t inner;
    unsigned long long seed;
} torn_store_t;

static int torn_append(void *ctx, const void *buf, size_t n)
{
    torn_store_t *t = ctx;
    t->seed = t->seed * 6364136223846793005ULL + 1442695040888963407ULL;
    size_t cut = n > 1 ? 1 + (size_t)((t->seed >> 33) % (n - 1)) : n;
    int rc = t->inner.ops->append(t->inner.ctx, buf, cut);
    if (rc || cut == n)
        return rc;
    struct timespec ts = {0, 20000};
    nanosleep(&ts, NULL);
    return t->inner.ops->append(t->inner.ctx, (const char *)buf + cut, n - cut);
}
static int torn_sync(void *ctx)
{
    torn_store_t *t = ctx;
    return t->inner.ops->sync(t->inner.ctx);
}
static int torn_read(void *ctx, uint64_t off, void *buf, size_t n, size_t *got)
{
    torn_store_t *t = ctx;
    return t->inner.ops->read(t->inner.ctx, off, buf, n, got);
}
static int torn_size(void *ctx, uint64_t *b)
{
    torn_store_t *t = ctx;
    return t->inner.ops->size(t->inner.ctx, b);
}
static int torn_truncate(void *ctx, uint64_t b)
{
    torn_store_t *t = ctx;
    return t->inner.ops->truncate(t->inner.ctx, b);
}
static const rig_store_ops_t torn_ops = {RIG_OPS_VERSION, torn_append, torn_sync,
                                         torn_read,       torn_size,   torn_truncate};

/* selftest-write JOURNAL [--records N] [--sync-every K] [--points FILE]
 * [--nominal N.igs] [--torn SEED]: known records (or the points of FILE)
 * through the file store; "acked N" on stdout each time N records are
 * durable, so a test that kills this process knows what was promised. */
static int do_selftest_write(int argc, char **argv)
{
    const char *pos[1], *points = NULL, *nominal = NULL;
    long n = 1000, k = JNL_SYNC_EVERY_DEFAULT, seed = -1;
    const cf_opt_t opts[] = {
        {.name = "records",
         .kind = CF_OPT_LONG,
         .dst = &n,
         .arg = "N",
         .help = "known records to write",
         .lo = 0,
         .hi = 100000000},
        {.name = "sync-every",
         .kind = CF_OPT_LONG,
         .dst = &k,
         .arg = "K",
         .help = "records per sync",
         .lo = 1,
         .hi = 1000000},
        {.name = "torn",
         .kind = CF_OPT_LONG,
         .dst = &seed,
         .arg = "SEED",
         .help = "write each record in two pieces, cut where SEED says (-1: whole)",
         .lo = 0,
         .hi = 1000000000},
        {.name = "points",
         .kind = CF_OPT_STR,
         .dst = &points,
         .arg = "FILE",
         .help = "journal the points of FILE instead of known records"},
        {.name = "nominal",
         .kind = CF_OPT_STR,
         .dst = &nominal,
         .arg = "N.igs",
         .help = "the nominal named in the header"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal selftest-write",
                          .args = "JOURNAL",
                          .summary = "write known records through the file store (tests)",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int prc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (prc)
        return cf_opt_exit(prc);
    const char *path = pos[0];
    char msg[512];
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    h.sync_every = (uint32_t)k;
    h.job_id = 1;
    h.z0 = 100.0;
    h.planned = (uint64_t)n;
    if (nominal && cf_fitsrc_nominal_id(nominal, &h.nominal_hash, h.nominal_name))
        return cli_error(CMD, CLI_USAGE, "%s: cannot read", nominal);
    cf_points_t *pr = NULL;
    if (points && cf_points_open(&pr, points, 0, msg, sizeof msg))
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    cf_store_file_t f;
    rig_store_t st;
    if (cf_store_file_open(&f, path, CF_STORE_CREATE, &st, msg, sizeof msg)) {
        cf_points_close(pr);
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    }
    torn_store_t ts = {st, (unsigned long long)seed};
    if (seed >= 0)
        st = (rig_store_t){&torn_ops, &ts};
    setvbuf(stdout, NULL, _IOLBF, 0);
    jnl_t j;
    int rc = jnl_create(&j, st, &h);
    uint64_t acked = 0;
    if (!rc)
        printf("header\n");
    for (uint32_t i = 0; !rc && (pr || i < (uint64_t)n); i++) {
        jnl_rec_t r = known_rec(i);
        if (pr) {
            double row[5];
            long got = cf_points_read(pr, row, 1, msg, sizeof msg);
            if (got <= 0) {
                if (got < 0)
                    rc = cli_error(CMD, CLI_USAGE, "%s", msg);
                break;
            }
            const double *q = row + (cf_points_cols(pr) == 5 ? 2 : 0);
            memset(&r, 0, sizeof r);
            r.type = JNL_T_POINT;
            r.stage[0] = q[0];
            r.stage[1] = q[1];
            r.dist = h.z0 - q[2];
            memcpy(r.xyz, q, sizeof r.xyz);
            r.t = 1e-3 * (double)i;
        }
        if ((rc = jnl_append(&j, &r)) == RIG_OK && jnl_acked(&j) != acked)
            printf("acked %llu\n", (unsigned long long)(acked = jnl_acked(&j)));
    }
    if (rc == RIG_OK && (rc = jnl_end(&j, RIG_OK, 1e-3 * (double)j.nrec)) == RIG_OK)
        printf("acked %llu\nended\n", (unsigned long long)jnl_acked(&j));
    cf_points_close(pr);
    cf_store_file_close(&f);
    if (rc == CLI_USAGE)
        return rc;
    if (rc)
        return cli_error(CMD, CLI_FAIL, "%s: %s (%s)", path, rig_strerror(rc), f.err);
    return CLI_OK;
}

/* selftest-check JOURNAL: every record is the known one of its number. */
static int do_selftest_check(int argc, char **argv)
{
    const char *pos[1];
    const cf_opt_t opts[] = {{0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "journal selftest-check",
                          .args = "JOURNAL",
                          .summary = "check that every record is the known one of its number",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int prc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (prc)
        return cf_opt_exit(prc);
    const char *path = pos[0];
    jopen_t j;
    int ec = jopen_read(&j, path);
    if (ec)
        return ec;
    jnl_rec_t r;
    int rc;
    unsigned long long n = 0;
    while ((rc = jnl_reader_next(&j.rd, &r)) == 1) {
        if (r.type == JNL_T_END)
            continue;
        jnl_rec_t w = known_rec(r.seq);
        if (r.flags != w.flags || r.code != w.code || memcmp(r.stage, w.stage, sizeof w.stage) ||
            memcmp(&r.dist, &w.dist, sizeof w.dist) || memcmp(r.xyz, w.xyz, sizeof w.xyz) ||
            memcmp(&r.t, &w.t, sizeof w.t)) {
            cf_store_file_close(&j.f);
            return cli_error(CMD, CLI_FAIL, "%s: record %u is not the one written", path, r.seq);
        }
        n++;
    }
    cf_store_file_close(&j.f);
    if (rc < 0)
        return read_error(path, &j, rc);
    printf("%llu records as written, %llu bytes of torn tail\n", n,
           (unsigned long long)j.in.tail_bytes);
    return CLI_OK;
}

int cmd_journal(int argc, char **argv)
{
    const char *sub = argc > 1 ? argv[1] : "";
    if (!strcmp(sub, "export"))
        return do_export(argc - 1, argv + 1);
    if (!strcmp(sub, "info"))
        return do_info(argc - 1, argv + 1);
    if (!strcmp(sub, "recover"))
        return do_recover(argc - 1, argv + 1);
    if (!strcmp(sub, "fit"))
        return do_fit(argc - 1, argv + 1);
    if (!strcmp(sub, "selftest-write"))
        return do_selftest_write(argc - 1, argv + 1);
    if (!strcmp(sub, "selftest-check"))
        return do_selftest_check(argc - 1, argv + 1);
    if (sub[0] == '-') { /* --help, or an option before the subcommand */
        const cf_opt_t none[] = {{0}};
        const cf_cmd_t cmd = {.prog = "cellfit",
                              .name = "journal",
                              .args = "export|info|recover|fit JOURNAL ...",
                              .summary = "the journal of measured points read back (`cellfit "
                                         "journal SUB --help` for each)",
                              .opts = none};
        int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
        return rc ? cf_opt_exit(rc) : cli_error(CMD, CLI_USAGE, "need a subcommand");
    }
    return cli_error(CMD, CLI_USAGE,
                     "usage: cellfit journal export|info|recover|fit JOURNAL ... ('%s'?)", sub);
}
