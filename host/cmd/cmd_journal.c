/* cmd_journal.c: `cellfit journal export|info|recover|fit`: the journal of
 * measured points read back one record at a time: its points as x y z, a
 * summary, recovery of a torn tail, and the streaming fit of its points onto
 * the nominal. Hidden `selftest-write` / `selftest-check` write and verify a
 * journal of known records through the real file store, for the power-cut
 * tests (tests/cli/journal.sh). */
#include "cf_cli.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_points.h"
#include "cf_sfit.h"
#include "cf_store_file.h"
#include "cf_surf.h"
#include "cmd.h"
#include "jnl.h"
#include "nf_err.h"
#include "rig_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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
    const char *path = NULL, *out = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (argv[i][0] == '-' && argv[i][1])
            return cli_error(CMD, CLI_USAGE, "export: unknown option '%s'", argv[i]);
        else if (!path)
            path = argv[i];
        else
            return cli_error(CMD, CLI_USAGE, "export: one JOURNAL only ('%s')", argv[i]);
    }
    if (!path)
        return cli_error(CMD, CLI_USAGE, "usage: cellfit journal export JOURNAL [--out FILE]");
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
    int rc;
    while ((rc = jnl_reader_next(&j.rd, &r)) == 1)
        if (valid_point(&r))
            fprintf(f, "%.17g %.17g %.17g\n", r.xyz[0], r.xyz[1], r.xyz[2]);
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
    const char *path = NULL;
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (argv[i][0] == '-' && argv[i][1])
            return cli_error(CMD, CLI_USAGE, "info: unknown option '%s'", argv[i]);
        else if (!path)
            path = argv[i];
        else
            return cli_error(CMD, CLI_USAGE, "info: one JOURNAL only ('%s')", argv[i]);
    }
    if (!path)
        return cli_error(CMD, CLI_USAGE, "usage: cellfit journal info JOURNAL [--json]");
    jopen_t j;
    int ec = jopen_read(&j, path);
    if (ec)
        return ec;
    cf_store_file_close(&j.f);
    const jnl_info_t *in = &j.in;
    char hash[24];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)j.h.nominal_hash);
    double span = in->records ? in->t_last - in->t_first : 0.0;
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
        cf_json_num(&o, "z0", j.h.z0);
        cf_json_num(&o, "cx", j.h.cal[0]);
        cf_json_num(&o, "cy", j.h.cal[1]);
        cf_json_num(&o, "cz", j.h.cal[2]);
        cf_json_end(&o);
        return CLI_OK;
    }
    printf("%s: journal v%u, job %llu, nominal '%s' (FNV-1a %s), synced every %u records\n", path,
           (unsigned)j.h.version, (unsigned long long)j.h.job_id, j.h.nominal_name, hash,
           (unsigned)j.h.sync_every);
    printf("  %llu records: %llu points, %llu without a surface; %llu planned\n",
           (unsigned long long)in->records, (unsigned long long)in->points,
           (unsigned long long)in->flagged, (unsigned long long)j.h.planned);
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
    return CLI_OK;
}

static int do_recover(int argc, char **argv)
{
    if (argc != 2 || argv[1][0] == '-')
        return cli_error(CMD, CLI_USAGE, "usage: cellfit journal recover JOURNAL");
    const char *path = argv[1];
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
    const char *path = NULL, *nominal = NULL, *out = NULL;
    double alpha = NF_ALPHA_DEFAULT, beta = NF_BETA_DEFAULT;
    long entity = 0, reparam = 0;
    int json = 0, force = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--json"))
            json = 1;
        else if (!strcmp(a, "--force"))
            force = 1;
        else if (a[0] != '-' && !path)
            path = a;
        else if (a[0] != '-')
            return cli_error(CMD, CLI_USAGE, "fit: one JOURNAL only ('%s')", a);
        else if (!v)
            return cli_error(CMD, CLI_USAGE, "fit: option %s needs a value", a);
        else {
            if (!strcmp(a, "--nominal"))
                nominal = v;
            else if (!strcmp(a, "--out"))
                out = v;
            else if (!strcmp(a, "--alpha")) {
                if (cli_double(v, &alpha) || alpha < 0)
                    return cli_error(CMD, CLI_USAGE, "--alpha '%s': need a number >= 0", v);
            } else if (!strcmp(a, "--beta")) {
                if (cli_double(v, &beta) || beta < 0)
                    return cli_error(CMD, CLI_USAGE, "--beta '%s': need a number >= 0", v);
            } else if (!strcmp(a, "--entity")) {
                if (cli_int(v, 1, 9999999, &entity))
                    return cli_error(CMD, CLI_USAGE, "--entity '%s': need a DE number", v);
            } else if (!strcmp(a, "--reparam")) {
                if (cli_int(v, 0, 100, &reparam))
                    return cli_error(CMD, CLI_USAGE, "--reparam '%s': need 0..100", v);
            } else
                return cli_error(CMD, CLI_USAGE, "fit: unknown option '%s'", a);
            i++;
        }
    }
    if (!path || !nominal || !out)
        return cli_error(CMD, CLI_USAGE,
                         "usage: cellfit journal fit JOURNAL --nominal N.igs --out OUT.igs "
                         "[--reparam K] [--alpha A] [--beta B] [--entity N] [--force] [--json]");
    double t0 = cli_now();
    char msg[512], name[JNL_NAME_LEN];
    uint64_t hash;
    if (cf_sfit_nominal_id(nominal, &hash, name))
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
    nf_surf_t nom, fit;
    memset(&fit, 0, sizeof fit);
    if (cf_iges_read(nominal, (int)entity, &nom, msg, sizeof msg)) {
        cf_store_file_close(&j.f);
        return cli_error(CMD, CLI_USAGE, "%s", msg);
    }
    cf_sfit_t sf;
    memset(&sf, 0, sizeof sf);
    nf_solve_stats_t sst = {NF_SOLVER_AUTO, 0, 0.0};
    double dev_rms = 0, dev_max = 0;
    if (cf_surf_copy(&fit, &nom)) {
        ec = cli_error(CMD, CLI_FAIL, "out of memory");
        goto out_nom;
    }
    /* Pass 0 projects onto the nominal; each --reparam pass reads the
     * journal again and projects onto the previous fit, refitting in the
     * same space with the same P0 (Section 2.2). */
    for (long pass = 0; pass <= reparam; pass++) {
        ec = cf_sfit_init(&sf, &nom, pass ? &fit : NULL, alpha, beta, CMD);
        if (ec)
            goto out_nom;
        jnl_reader_rewind(&j.rd);
        jnl_rec_t r;
        int rc;
        while ((rc = jnl_reader_next(&j.rd, &r)) == 1) {
            if (!valid_point(&r))
                continue;
            int e = cf_sfit_add(&sf, r.xyz);
            if (e) {
                ec = cli_error(CMD, CLI_USAGE, "%s: record %u: %s", path, r.seq, nf_strerror(e));
                goto out_fit;
            }
        }
        if (rc < 0) {
            ec = read_error(path, &j, rc);
            goto out_fit;
        }
        if (pass == 0) {
            dev_rms = sf.points ? sqrt(sf.dev_ss / (double)sf.points) : 0;
            dev_max = sf.dev_max;
        }
        if ((ec = cf_sfit_solve(&sf, &fit, &sst, CMD)) != 0)
            goto out_fit;
        if (pass < reparam)
            cf_sfit_free(&sf);
    }
    cf_sfit_resid_t res;
    int rc;
    if ((rc = cf_sfit_residuals(&fit, &j.rd, &res)) != 0) {
        ec = rc == CF_ENOMEM ? cli_error(CMD, CLI_FAIL, "out of memory") : read_error(path, &j, rc);
        goto out_fit;
    }
    if (cf_iges_write(out, &fit, "cellfit journal fit", msg, sizeof msg)) {
        ec = cli_error(CMD, CLI_FAIL, "%s", msg);
        goto out_fit;
    }
    if (json) {
        cf_json_t o;
        cf_json_begin(&o, stdout);
        cf_json_str(&o, "journal", path);
        cf_json_int(&o, "points", sf.points);
        cf_json_int(&o, "flagged", (long)j.in.flagged);
        cf_json_int(&o, "control_points", (long)nom.nu * nom.nv);
        cf_json_num(&o, "alpha", alpha);
        cf_json_num(&o, "beta", beta);
        cf_json_str(&o, "solver", nf_solver_name(sst.solver));
        cf_json_int(&o, "iterations", sst.iterations);
        cf_json_num(&o, "rel_residual", sst.rel_residual);
        cf_json_num(&o, "rms", res.rms);
        cf_json_num(&o, "max_abs", res.max);
        cf_json_num(&o, "nominal_rms", dev_rms);
        cf_json_num(&o, "nominal_max_abs", dev_max);
        cf_json_int(&o, "reparam", reparam);
        cf_json_num(&o, "seconds", cli_now() - t0);
        cf_json_int(&o, "bytes", sf.need);
        cf_json_str(&o, "out", out);
        cf_json_end(&o);
    } else {
        printf("cellfit journal fit: %ld points of %s (%llu without a surface), %d x %d control "
               "points\n",
               sf.points, path, (unsigned long long)j.in.flagged, nom.nu, nom.nv);
        printf("  measured vs nominal: rms %.6g  max %.6g;  vs fit: rms %.6g  max %.6g\n", dev_rms,
               sf.dev_max, res.rms, res.max);
        printf("  solver %s, %d iterations, relative residual %.2e; %.3f s\n",
               nf_solver_name(sst.solver), sst.iterations, sst.rel_residual, cli_now() - t0);
        printf("  wrote %s\n", out);
    }
out_fit:
    cf_sfit_free(&sf);
out_nom:
    cf_surf_free(&fit);
    cf_surf_free(&nom);
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
    const char *path = NULL, *points = NULL, *nominal = NULL;
    long n = 1000, k = JNL_SYNC_EVERY_DEFAULT, seed = -1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (a[0] != '-' && !path) {
            path = a;
            continue;
        }
        if (!v)
            return cli_error(CMD, CLI_USAGE, "selftest-write: '%s' needs a value", a);
        if (!strcmp(a, "--records") && !cli_int(v, 0, 100000000, &n))
            ;
        else if (!strcmp(a, "--sync-every") && !cli_int(v, 1, 1000000, &k))
            ;
        else if (!strcmp(a, "--torn") && !cli_int(v, 0, 1000000000, &seed))
            ;
        else if (!strcmp(a, "--points"))
            points = v;
        else if (!strcmp(a, "--nominal"))
            nominal = v;
        else
            return cli_error(CMD, CLI_USAGE, "selftest-write: bad option '%s %s'", a, v);
        i++;
    }
    if (!path)
        return cli_error(CMD, CLI_USAGE, "usage: cellfit journal selftest-write JOURNAL ...");
    char msg[512];
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    h.sync_every = (uint32_t)k;
    h.job_id = 1;
    h.z0 = 100.0;
    h.planned = (uint64_t)n;
    if (nominal && cf_sfit_nominal_id(nominal, &h.nominal_hash, h.nominal_name))
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
    if (argc != 2)
        return cli_error(CMD, CLI_USAGE, "usage: cellfit journal selftest-check JOURNAL");
    jopen_t j;
    int ec = jopen_read(&j, argv[1]);
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
            return cli_error(CMD, CLI_FAIL, "%s: record %u is not the one written", argv[1], r.seq);
        }
        n++;
    }
    cf_store_file_close(&j.f);
    if (rc < 0)
        return read_error(argv[1], &j, rc);
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
    return cli_error(CMD, CLI_USAGE,
                     "usage: cellfit journal export|info|recover|fit JOURNAL ... ('%s'?)", sub);
}
