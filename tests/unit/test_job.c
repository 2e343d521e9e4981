/* SPDX-License-Identifier: MIT */
/* test_job.c: the serve job on files (cf_job) by exact reproduction: points
 * sampled on a nominal surface are fitted with alpha = 0 and come back as
 * the nominal itself (deviations at rounding level), also after the net is
 * refined to a size asked for (the refined nominal is the same surface:
 * checked against the nominal at random parameters); the checks refuse
 * nets below the nominal's and beyond the board; stop, progress, empty and
 * missing files; export read back. The fit job itself (cf_fitjob): its
 * tolerance loop reproduces a surface with more knots than the base
 * exactly, stops at max_cp and max_rounds with the status saying so, and
 * a live first pass (a scan's) reproduces the nominal. */
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_job.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "cf_uuid.h"
#include "nf_err.h"
#include "ref_job.h"
#include "rig_err.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[512], msg[1024];
static char nominal[600], uvfile[600], xyzfile[600], empty[600];
static nf_surf_t nom;

static void tmp_path(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/cf_job_%ld_%s", tmpdir, (long)getpid(), name);
}

/* A bicubic 7 x 6 nominal with uneven interior knots, and 60 x 50 points
 * on it written as u v x y z and as x y z. */
static int setup(void **state)
{
    (void)state;
    const char *d = getenv("CF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", d && *d ? d : "/tmp");
    for (char *p = tmpdir + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            mkdir(tmpdir, 0777);
            *p = '/';
        }
    mkdir(tmpdir, 0777);
    if (cf_surf_alloc(&nom, 3, 3, 7, 6))
        return -1;
    static const double U[] = {0, 0, 0, 0, 0.2, 0.45, 0.7, 1, 1, 1, 1};
    static const double V[] = {0, 0, 0, 0, 0.3, 0.55, 1, 1, 1, 1};
    memcpy(nom.U, U, sizeof U);
    memcpy(nom.V, V, sizeof V);
    for (int j = 0; j < 6; j++)
        for (int i = 0; i < 7; i++) {
            double *P = nom.cp + 3 * (i + 7 * j);
            P[0] = 20.0 * i, P[1] = 15.0 * j, P[2] = 3.0 * sin(0.7 * i) * cos(0.5 * j);
        }
    tmp_path(nominal, sizeof nominal, "nominal.igs");
    tmp_path(uvfile, sizeof uvfile, "points.uvxyz");
    tmp_path(xyzfile, sizeof xyzfile, "points.xyz");
    tmp_path(empty, sizeof empty, "empty.xyz");
    if (cf_iges_write_at(nominal, &nom, "test nominal", 1700000000LL, msg, sizeof msg))
        return -1;
    FILE *a = fopen(uvfile, "w"), *b = fopen(xyzfile, "w"), *e = fopen(empty, "w");
    if (!a || !b || !e)
        return -1;
    for (int j = 0; j < 50; j++)
        for (int i = 0; i < 60; i++) {
            double u = (i + 0.5) / 60.0, v = (j + 0.5) / 50.0, P[3];
            nf_surf_eval(&nom, u, v, P);
            fprintf(a, "%.17g %.17g %.17g %.17g %.17g\n", u, v, P[0], P[1], P[2]);
            fprintf(b, "%.17g %.17g %.17g\n", P[0], P[1], P[2]);
        }
    fprintf(e, "# no points\n");
    fclose(a), fclose(b), fclose(e);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    cf_surf_free(&nom);
    remove(nominal), remove(uvfile), remove(xyzfile), remove(empty);
    return 0;
}

static cf_job_fit_opts_t opts(const char *points, int nu, int nv)
{
    cf_job_fit_opts_t o;
    o.nominal = nominal, o.points = points;
    cf_fitjob_defaults(&o.fit);
    o.fit.alpha = 0.0, o.fit.beta = 0.001, o.fit.tol = 1e-6;
    o.fit.net_u = nu, o.fit.net_v = nv;
    return o;
}

static int last_pct, pct_calls, pct_backwards, stop_after = -1;

static void on_progress(void *ctx, int pct)
{
    (void)ctx;
    if (pct < last_pct)
        pct_backwards++;
    last_pct = pct;
    pct_calls++;
}

static int on_stop(void *ctx)
{
    (void)ctx;
    return stop_after >= 0 && pct_calls > stop_after;
}

static const cf_job_ctl_t ctl = {on_progress, on_stop, NULL};

/* |fitted - nominal| at random parameters. */
static double surface_gap(const nf_surf_t *s)
{
    unsigned long long r = 88172645463325252ULL;
    double worst = 0;
    for (int k = 0; k < 2000; k++) {
        r ^= r << 13, r ^= r >> 7, r ^= r << 17;
        double u = (double)(r >> 11) * 0x1p-53;
        r ^= r << 13, r ^= r >> 7, r ^= r << 17;
        double v = (double)(r >> 11) * 0x1p-53, A[3], B[3];
        nf_surf_eval(s, u, v, A);
        nf_surf_eval(&nom, u, v, B);
        for (int c = 0; c < 3; c++)
            worst = fmax(worst, fabs(A[c] - B[c]));
    }
    return worst;
}

static void check_exact(const char *points, int nu, int nv)
{
    cf_job_fit_opts_t o = opts(points, nu, nv);
    cf_job_result_t res;
    last_pct = pct_calls = pct_backwards = 0;
    int rc = cf_job_fit(&o, &ctl, &res, msg, sizeof msg);
    if (rc)
        fail_msg("cf_job_fit: %d %s", rc, msg);
    assert_int_equal(res.points, 3000);
    assert_int_equal(res.surf.nu, nu ? nu : 7);
    assert_int_equal(res.surf.nv, nv ? nv : 6);
    assert_true(res.stats->n == 3000);
    assert_true(res.stats->max_abs < 1e-8);     /* deviations: rounding */
    assert_true(res.stats->within == 3000);     /* tol 1e-6 */
    assert_true(surface_gap(&res.surf) < 1e-8); /* the nominal itself */
    assert_int_equal(pct_backwards, 0);
    assert_int_equal(last_pct, 100);
    cf_job_result_free(&res);
}

static void test_fit_reproduces_nominal(void **state)
{
    (void)state;
    check_exact(uvfile, 0, 0);  /* parameters given */
    check_exact(xyzfile, 0, 0); /* parameters by projection */
}

static void test_refined_net(void **state)
{
    (void)state;
    check_exact(uvfile, 12, 9);
    check_exact(uvfile, 7, 10); /* only v refined */
    cf_job_fit_opts_t o = opts(uvfile, 12, 9);
    assert_int_equal(cf_job_check(&o, msg, sizeof msg), CF_OK);
    o.fit.net_u = 6; /* below the nominal's 7 */
    assert_int_equal(cf_job_check(&o, msg, sizeof msg), CF_EARG);
    assert_non_null(strstr(msg, "smaller"));
    o.fit.net_u = o.fit.net_v = 2000; /* beyond the sim board */
    assert_int_equal(cf_job_check(&o, msg, sizeof msg), NF_EBUDGET);
}

static void test_stop_and_bad_files(void **state)
{
    (void)state;
    cf_job_result_t res;
    cf_job_fit_opts_t o = opts(xyzfile, 0, 0);
    last_pct = pct_calls = 0;
    stop_after = 1; /* during accumulation */
    assert_int_equal(cf_job_fit(&o, &ctl, &res, msg, sizeof msg), RIG_EABORTED);
    assert_null(res.stats);
    assert_null(res.surf.cp);
    stop_after = -1;
    o.points = empty;
    assert_int_equal(cf_job_fit(&o, &ctl, &res, msg, sizeof msg), CF_EEMPTY);
    char missing[600];
    tmp_path(missing, sizeof missing, "missing.xyz");
    o.points = missing;
    assert_int_equal(cf_job_fit(&o, &ctl, &res, msg, sizeof msg), CF_EIO);
    assert_non_null(strstr(msg, "missing.xyz"));
    o.points = uvfile;
    o.nominal = missing;
    assert_int_not_equal(cf_job_fit(&o, &ctl, &res, msg, sizeof msg), CF_OK);
    assert_int_not_equal(cf_job_check(&o, msg, sizeof msg), CF_OK);
}

static void test_export(void **state)
{
    (void)state;
    char name[64], dir[700], path[800];
    cf_job_folder_name(4711, 1700000000LL, name, sizeof name);
    assert_string_equal(name, "4711_20231114T221320Z");
    cf_job_fit_opts_t o = opts(uvfile, 0, 0);
    cf_job_result_t res;
    assert_int_equal(cf_job_fit(&o, NULL, &res, msg, sizeof msg), CF_OK);
    tmp_path(dir, sizeof dir, name);
    cf_job_meta_t meta = {4711,         12,   5,         nominal, uvfile,       "sim",
                          1700000000LL, NULL, "SN 42/A", 9,       1700000003LL, NULL};
    assert_int_equal(cf_job_export(&res, &meta, dir, msg, sizeof msg), CF_OK);
    /* Never over an existing folder: refused. */
    assert_int_equal(cf_job_export(&res, &meta, dir, msg, sizeof msg), CF_EIO);
    /* Unique names: same part and second, another UUID. */
    char u1[128], u2[128];
    assert_int_equal(cf_job_unique_name(4711, 1700000000LL, 5, u1, sizeof u1), CF_OK);
    assert_int_equal(cf_job_unique_name(4711, 1700000000LL, 5, u2, sizeof u2), CF_OK);
    assert_int_equal(strncmp(u1, "4711_20231114T221320Z_5_", 24), 0);
    assert_true(cf_uuid_valid(u1 + 24));
    assert_string_not_equal(u1, u2);
    snprintf(path, sizeof path, "%s/fitted.igs", dir);
    nf_surf_t back;
    assert_int_equal(cf_iges_read(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_memory_equal(back.cp, res.surf.cp, sizeof(double) * 3 * 42);
    cf_surf_free(&back);
    remove(path);
    snprintf(path, sizeof path, "%s/report.json", dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char js[8192];
    size_t n = fread(js, 1, sizeof js - 1, f);
    fclose(f);
    js[n] = 0;
    assert_non_null(strstr(js, "\"part\": 4711"));
    assert_non_null(strstr(js, "\"points\": 3000"));
    assert_non_null(strstr(js, "\"verdict\": \"pass\""));
    /* The job's identity: its sequence, its UTC second as a number and in
     * ISO 8601 (1700000000 is 2023-11-14 22:13:20 UTC), the part ID, the
     * export's own sequence and time. */
    assert_non_null(strstr(js, "\"seq\": 5"));
    assert_non_null(strstr(js, "\"utc\": 1700000000"));
    assert_non_null(strstr(js, "\"time\": \"2023-11-14T22:13:20Z\""));
    assert_non_null(strstr(js, "\"part_id\": \"SN 42/A\""));
    assert_non_null(strstr(js, "\"export_seq\": 9"));
    assert_non_null(strstr(js, "\"export_time\": \"2023-11-14T22:13:23Z\""));
    remove(path);
    rmdir(dir);
    /* A folder that cannot be made: CF_EIO naming it. */
    snprintf(path, sizeof path, "%s/no/such", dir);
    assert_int_equal(cf_job_export(&res, &meta, path, msg, sizeof msg), CF_EIO);
    assert_non_null(strstr(msg, "no/such"));
    cf_job_result_free(&res);
}

/* Whole file at path into buf (NUL-terminated). */
static void slurp(const char *path, char *buf, size_t n)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t got = fread(buf, 1, n - 1, f);
    fclose(f);
    buf[got] = 0;
}

/* The config's checks (meta->checks) in the export: one characteristic
 * each after the five in report.dfq, a zone without a point as a value not
 * measured (K0002 255), the array in report.json; a malformed file fails
 * the export and leaves no folder. The values themselves are checked by
 * brute force in tests/cli/checks.sh and plc.sh. */
static void test_export_checks(void **state)
{
    (void)state;
    char dir[700], path[800], checks[600];
    static char text[65536];
    cf_job_fit_opts_t o = opts(uvfile, 0, 0);
    cf_job_result_t res;
    assert_int_equal(cf_job_fit(&o, NULL, &res, msg, sizeof msg), CF_OK);
    tmp_path(checks, sizeof checks, "checks.txt");
    FILE *f = fopen(checks, "w");
    assert_non_null(f);
    fputs("# two checks\nnear 0 0 0\nfar 1e6 1e6 0 1\n", f);
    fclose(f);
    tmp_path(dir, sizeof dir, "with_checks");
    cf_job_meta_t meta = {4712,         12,   6,    nominal, uvfile, "sim",
                          1700000000LL, NULL, NULL, 0,       0,      checks};
    assert_int_equal(cf_job_export(&res, &meta, dir, msg, sizeof msg), CF_OK);
    snprintf(path, sizeof path, "%s/report.dfq", dir);
    slurp(path, text, sizeof text);
    assert_non_null(strstr(text, "K0100 7\n"));
    assert_non_null(strstr(text, "K2002/6 near\n"));
    assert_non_null(strstr(text, "K2002/7 far\n"));
    assert_null(strstr(text, "K0002/6 "));
    assert_non_null(strstr(text, "K0002/7 255\n"));
    snprintf(path, sizeof path, "%s/report.json", dir);
    slurp(path, text, sizeof text);
    assert_non_null(strstr(text, "\"checks\": [{\"name\": \"near\""));
    assert_non_null(strstr(text, "\"radius\": 1, \"points\": 0, \"deviation\": null}]"));
    static const char *const files[] = {"fitted.igs", "fitted.stp", "report.json", "report.dfq",
                                        "deviations.csv"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        assert_int_equal(remove(path), 0);
    }
    assert_int_equal(rmdir(dir), 0);
    f = fopen(checks, "w");
    assert_non_null(f);
    fputs("near 0 0\n", f);
    fclose(f);
    tmp_path(dir, sizeof dir, "bad_checks");
    assert_int_equal(cf_job_export(&res, &meta, dir, msg, sizeof msg), CF_EPARSE);
    assert_non_null(strstr(msg, "checks.txt:1:"));
    struct stat sb;
    assert_int_not_equal(stat(dir, &sb), 0);
    remove(checks);
    cf_job_result_free(&res);
}

/* The fit job's loop by exact reproduction: points on a bicubic S* with
 * the interior knot 0.5 in u and v (5 x 5), fitted from a Bezier base
 * (4 x 4, a plane) with alpha = beta = 0. Round 0 cannot represent S*;
 * one uniform (or residual: the only span's midpoint) refinement inserts
 * 0.5 both ways, and S* comes back exactly: status met after 2 rounds. */
static nf_surf_t star, bez;
static char starfile[600];

static int loop_setup(void)
{
    if (cf_surf_alloc(&star, 3, 3, 5, 5) || cf_surf_alloc(&bez, 3, 3, 4, 4))
        return -1;
    static const double K5[] = {0, 0, 0, 0, 0.5, 1, 1, 1, 1}, K4[] = {0, 0, 0, 0, 1, 1, 1, 1};
    memcpy(star.U, K5, sizeof K5), memcpy(star.V, K5, sizeof K5);
    memcpy(bez.U, K4, sizeof K4), memcpy(bez.V, K4, sizeof K4);
    for (int j = 0; j < 5; j++)
        for (int i = 0; i < 5; i++) {
            double *P = star.cp + 3 * (i + 5 * j);
            P[0] = 10.0 * i, P[1] = 10.0 * j, P[2] = 2.0 * sin(1.3 * i + 0.4 * j);
        }
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *P = bez.cp + 3 * (i + 4 * j);
            P[0] = 40.0 * i / 3.0, P[1] = 40.0 * j / 3.0, P[2] = 0.0;
        }
    tmp_path(starfile, sizeof starfile, "star.uvxyz");
    FILE *f = fopen(starfile, "w");
    if (!f)
        return -1;
    for (int j = 0; j < 40; j++)
        for (int i = 0; i < 40; i++) {
            double u = (i + 0.5) / 40.0, v = (j + 0.5) / 40.0, P[3];
            nf_surf_eval(&star, u, v, P);
            fprintf(f, "%.17g %.17g %.17g %.17g %.17g\n", u, v, P[0], P[1], P[2]);
        }
    return fclose(f);
}

/* Run the job on starfile from bez with the loop's limits. */
static int run_loop(cf_refine_t how, long max_cp, long max_rounds, cf_fitjob_result_t *r)
{
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.alpha = o.beta = 0.0;
    o.solver = NF_SOLVER_CHOL;
    o.tol = 1e-6;
    o.loop = 1;
    o.refine = how;
    o.max_cp = max_cp;
    o.max_rounds = max_rounds;
    cf_fitjob_t *j;
    int rc = cf_fitjob_open(&j, &bez, &o, msg, sizeof msg);
    if (rc)
        return rc;
    rc = ref_job_file(j, starfile, 5, r, msg, sizeof msg);
    cf_fitjob_close(j);
    return rc;
}

static void test_fitjob_loop(void **state)
{
    (void)state;
    assert_int_equal(loop_setup(), 0);
    for (int how = 0; how < 2; how++) {
        cf_fitjob_result_t r;
        int rc = run_loop((cf_refine_t)how, 1000, 12, &r);
        if (rc)
            fail_msg("%s", msg);
        assert_int_equal(r.status, CF_FITJOB_MET);
        assert_int_equal(r.nrounds, 2);
        assert_true(r.rounds[0].within_pct < 50.0); /* the plane misses S* */
        assert_int_equal(r.surf.nu, 5);
        assert_int_equal(r.surf.nv, 5);
        assert_true(r.max_abs < 1e-8);
        assert_true(ref_job_gap(&r.surf, &star) < 1e-8);
        assert_int_equal(r.points, 1600);
        assert_string_equal(cf_fitjob_status_name(r.status), "met");
        cf_fitjob_result_free(&r);
    }
    /* Limits: 25 control points refused by max_cp 20; one round only. */
    cf_fitjob_result_t r;
    assert_int_equal(run_loop(CF_REFINE_UNIFORM, 20, 12, &r), 0);
    assert_int_equal(r.status, CF_FITJOB_NOT_MET_MAX_CP);
    assert_int_equal(r.surf.nu * r.surf.nv, 16);
    assert_non_null(strstr(r.why, "--max-cp"));
    cf_fitjob_result_free(&r);
    assert_int_equal(run_loop(CF_REFINE_UNIFORM, 1000, 1, &r), 0);
    assert_int_equal(r.status, CF_FITJOB_NOT_MET_NO_PROGRESS);
    assert_int_equal(r.nrounds, 1);
    cf_fitjob_result_free(&r);
    /* A base net above max_cp is refused before any point. */
    assert_int_equal(run_loop(CF_REFINE_UNIFORM, 10, 12, &r), CF_EARG);
    remove(starfile);
    cf_surf_free(&star);
    cf_surf_free(&bez);
}

/* Live points (a scan's first pass): the nominal's x y z points added one
 * at a time, the rest of the job from the file: the nominal comes back. */
static void test_fitjob_live(void **state)
{
    (void)state;
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.alpha = 0.0;
    o.beta = 0.001;
    o.reparam = 1;
    cf_fitjob_t *j;
    assert_int_equal(cf_fitjob_open(&j, &nom, &o, msg, sizeof msg), 0);
    cf_points_t *pr = NULL;
    assert_int_equal(cf_points_open(&pr, xyzfile, 3, msg, sizeof msg), 0);
    double q[3];
    long n = 0;
    while (cf_points_read(pr, q, 1, msg, sizeof msg) == 1) {
        assert_int_equal(cf_fitjob_add(j, q, msg, sizeof msg), 0);
        n++;
    }
    assert_int_equal(n, 3000);
    cf_fitsrc_t src;
    cf_fitsrc_points_t pc;
    cf_fitsrc_points(&src, &pc, pr, xyzfile);
    cf_fitjob_result_t r;
    assert_int_equal(cf_fitjob_run(j, &src, NULL, 0, 100, &r, msg, sizeof msg), 0);
    assert_int_equal(r.points, 3000);
    assert_int_equal(r.status, CF_FITJOB_PLAIN);
    assert_true(r.nominal_max < 1e-8); /* the points are on the nominal */
    assert_true(surface_gap(&r.surf) < 1e-8);
    assert_true(r.max_abs < 1e-8);
    cf_fitjob_result_free(&r);
    cf_points_close(pr);
    cf_fitjob_close(j);
}

/* One job on bumpy points (the nominal's, z moved by a smooth bump and a
 * few spikes): live (added one at a time; the later passes read the held
 * points) or not (every pass reads the file). */
static int run_bumpy(const char *file, int live, cf_fitjob_result_t *r)
{
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.reparam = 2;
    o.tol = 0.02;
    o.stats = 1;
    cf_fitjob_t *j;
    int rc = cf_fitjob_open(&j, &nom, &o, msg, sizeof msg);
    if (rc)
        return rc;
    cf_points_t *pr = NULL;
    if ((rc = cf_points_open(&pr, file, 3, msg, sizeof msg)) == 0) {
        double q[3];
        while (live && !rc && cf_points_read(pr, q, 1, msg, sizeof msg) == 1)
            rc = cf_fitjob_add(j, q, msg, sizeof msg);
        cf_fitsrc_t src;
        cf_fitsrc_points_t pc;
        cf_fitsrc_points(&src, &pc, pr, file);
        if (!rc)
            rc = cf_fitjob_run(j, &src, NULL, 0, 100, r, msg, sizeof msg);
    }
    cf_points_close(pr);
    cf_fitjob_close(j);
    return rc;
}

/* Issue 19: after a live scan the job reads the points it held (no
 * journal read back): the fit, its distances and the statistics are
 * exactly those of the job that reads the file for every pass. */
static void test_fitjob_held(void **state)
{
    (void)state;
    char bumpy[600];
    tmp_path(bumpy, sizeof bumpy, "bumpy.xyz");
    FILE *f = fopen(bumpy, "w");
    assert_non_null(f);
    for (int j = 0; j < 50; j++)
        for (int i = 0; i < 60; i++) {
            double P[3];
            nf_surf_eval(&nom, (i + 0.5) / 60.0, (j + 0.5) / 50.0, P);
            P[2] += 0.05 * sin(P[0] / 7.0) * cos(P[1] / 5.0) + ((i * 7 + j * 3) % 97 ? 0 : 0.3);
            fprintf(f, "%.17g %.17g %.17g\n", P[0], P[1], P[2]);
        }
    assert_int_equal(fclose(f), 0);
    cf_fitjob_result_t a, b;
    assert_int_equal(run_bumpy(bumpy, 1, &a), 0);
    assert_int_equal(run_bumpy(bumpy, 0, &b), 0);
    assert_int_equal(a.points, 3000);
    assert_int_equal(b.points, 3000);
    assert_true(b.rms > 1e-3 && b.max_abs > 0.1); /* the bump and the spikes are there */
    /* Rounding only: the live pass adds one point at a time, the file's
     * pass a batch (the sums in another order). */
    assert_true(fabs(a.rms - b.rms) <= 1e-12 * b.rms);
    assert_true(fabs(a.max_abs - b.max_abs) <= 1e-12);
    assert_true(fabs(a.nominal_rms - b.nominal_rms) <= 1e-12);
    assert_true(a.within_pct == b.within_pct);
    assert_true(ref_job_gap(&a.surf, &b.surf) <= 1e-10); /* 3e-12 mm on a 120 mm part seen */
    assert_non_null(a.stats);
    assert_non_null(b.stats);
    assert_int_equal(a.stats->n, b.stats->n);
    assert_true(fabs(a.stats->max - b.stats->max) <= 1e-12);
    assert_true(fabs(a.stats->min - b.stats->min) <= 1e-12);
    assert_true(fabs(cf_stats_rms(a.stats) - cf_stats_rms(b.stats)) <= 1e-12 * b.rms);
    cf_fitjob_result_free(&a);
    cf_fitjob_result_free(&b);
    remove(bumpy);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_reproduces_nominal),
        cmocka_unit_test(test_refined_net),
        cmocka_unit_test(test_stop_and_bad_files),
        cmocka_unit_test(test_export),
        cmocka_unit_test(test_export_checks),
        cmocka_unit_test(test_fitjob_loop),
        cmocka_unit_test(test_fitjob_live),
        cmocka_unit_test(test_fitjob_held),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
