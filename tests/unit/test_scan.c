/* SPDX-License-Identifier: MIT */
/* test_scan.c: the scan job: the raster plan (serpentine order, region,
 * counts) and the kinematic model against closed form, and the job's fault
 * handling. The rig here is a deterministic in-test implementation of
 * rig.h (a stage that goes where it is sent, a probe over a closed-form
 * surface, faults at a chosen point): the project's "real parts" rule
 * allows it for unit tests of the plan and of fault handling; the
 * end-to-end scan runs on the real simulator (cellsim) in tests/cli. The
 * journal goes to the real file store, or to the RAM store when the test
 * counts syncs or fills the disk. */
#include "cf_store_file.h"
#include "cf_test.h"
#include "ref_memstore.h"
#include "scan.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The in-test rig. */
typedef struct trig {
    double x, y;       /* stage position */
    uint32_t status;   /* RIG_ST_* */
    long moves, reads; /* calls made */
    long stops, homes; /* calls made */
    long fail_move_at; /* move number that fails with move_err (-1 never) */
    int move_err;
    long fail_read_at; /* read number that fails with read_err */
    int read_err;
    long stop_at;              /* should_stop answers 1 from this check on */
    int stop_why;              /* ... or this reason (a rig_err_t) when not 0 */
    long checks;               /* should_stop calls */
    double hole[3];            /* no surface within radius hole[2] of (hole[0], hole[1]) */
    double lo[2], hi[2];       /* soft limits */
    double xs[4096], ys[4096]; /* targets in order */
} trig_t;

static const scan_kin_t kin = {120.0, {0.5, -0.25, 0.125}};

/* The part under the probe, in machine coordinates. */
static double surf_z(double X, double Y)
{
    return 5.0 + 0.1 * X - 0.05 * Y + 0.01 * X * Y;
}

static int t_home(void *ctx)
{
    trig_t *t = ctx;
    t->homes++;
    t->status |= RIG_ST_HOMED;
    return RIG_OK;
}

static int t_move(void *ctx, double x, double y)
{
    trig_t *t = ctx;
    long m = t->moves++;
    if (m == t->fail_move_at)
        return t->move_err;
    if (m < 4096)
        t->xs[m] = x, t->ys[m] = y;
    t->x = x;
    t->y = y;
    return RIG_OK;
}

static int t_pos(void *ctx, double *x, double *y)
{
    trig_t *t = ctx;
    *x = t->x;
    *y = t->y;
    return RIG_OK;
}

static int t_status(void *ctx, uint32_t *bits)
{
    *bits = ((trig_t *)ctx)->status;
    return RIG_OK;
}

static int t_stop(void *ctx)
{
    ((trig_t *)ctx)->stops++;
    return RIG_OK;
}

static int t_limits(void *ctx, double lo[2], double hi[2])
{
    trig_t *t = ctx;
    memcpy(lo, t->lo, sizeof t->lo);
    memcpy(hi, t->hi, sizeof t->hi);
    return RIG_OK;
}

/* The reading the kinematic model inverts: d = z0 + cz - z(x + cx, y + cy). */
static int t_read(void *ctx, double *d)
{
    trig_t *t = ctx;
    long r = t->reads++;
    if (r == t->fail_read_at)
        return t->read_err;
    double X = t->x + kin.cal[0], Y = t->y + kin.cal[1];
    if (hypot(X - t->hole[0], Y - t->hole[1]) < t->hole[2])
        return RIG_ENOSURF;
    *d = kin.z0 + kin.cal[2] - surf_z(X, Y);
    return RIG_OK;
}

static double t_now(void *ctx)
{
    return 0.5 * (double)((trig_t *)ctx)->moves;
}

static int t_should_stop(void *ctx)
{
    trig_t *t = ctx;
    if (t->checks++ < t->stop_at)
        return 0;
    return t->stop_why ? t->stop_why : 1;
}

static const rig_stage_ops_t stage_ops = {RIG_OPS_VERSION, t_home, t_move, t_pos,
                                          t_status,        t_stop, NULL,   t_limits};
static const rig_probe_ops_t probe_ops = {RIG_OPS_VERSION, t_read, NULL};
static const rig_clock_ops_t clock_ops = {RIG_OPS_VERSION, t_now, t_should_stop};

static trig_t rig;
static ref_memstore_t ms;

static void rig_reset(void)
{
    memset(&rig, 0, sizeof rig);
    rig.status = RIG_ST_HOMED;
    rig.fail_move_at = rig.fail_read_at = rig.stop_at = 1L << 40;
    rig.lo[0] = rig.lo[1] = -1000;
    rig.hi[0] = rig.hi[1] = 1000;
}

static scan_job_t job_on(double x0, double x1, double y0, double y1, double s)
{
    scan_job_t job;
    memset(&job, 0, sizeof job);
    job.stage = (rig_stage_t){&stage_ops, &rig};
    job.probe = (rig_probe_t){&probe_ops, &rig};
    job.clock = (rig_clock_t){&clock_ops, &rig};
    job.kin = kin;
    assert_int_equal(scan_plan_init(&job.plan, x0, x1, y0, y1, s, s), RIG_OK);
    return job;
}

static jnl_header_t header(const scan_job_t *job)
{
    jnl_header_t h;
    memset(&h, 0, sizeof h);
    h.sync_every = 64;
    h.job_id = 7;
    scan_header(job, &h);
    return h;
}

static void test_plan(void **state)
{
    (void)state;
    scan_plan_t p;
    assert_int_equal(scan_plan_init(&p, -5, 5, 2, 6, 1, 2), RIG_OK);
    assert_int_equal(p.nx, 11);
    assert_int_equal(p.ny, 3);
    assert_int_equal(scan_plan_count(&p), 33);
    /* Closed form: row j = k / 11 at y = 2 + 2 j, column k mod 11 counted
     * from the left on even rows and from the right on odd ones. */
    for (long k = 0; k < 33; k++) {
        double x, y;
        int end;
        scan_plan_point(&p, k, &x, &y, &end);
        long j = k / 11, c = k % 11;
        assert_near(y, 2.0 + 2.0 * (double)j, 0);
        assert_near(x, j % 2 ? 5.0 - (double)c : -5.0 + (double)c, 0);
        assert_int_equal(end, c == 10);
    }
    /* A step that divides the width includes the far edge despite rounding;
     * one that does not stops short of it. */
    assert_int_equal(scan_plan_init(&p, 0, 1, 0, 0.3, 0.1, 0.1), RIG_OK);
    assert_int_equal(p.nx, 11);
    assert_int_equal(p.ny, 4);
    assert_int_equal(scan_plan_init(&p, 0, 1, 0, 0, 0.3, 0.3), RIG_OK);
    assert_int_equal(p.nx, 4);
    assert_int_equal(p.ny, 1);
    assert_int_equal(scan_plan_init(&p, 0, 1, 0, 1, 0, 1), RIG_EARG);
    assert_int_equal(scan_plan_init(&p, 1, 0, 0, 1, 1, 1), RIG_EARG);
    assert_int_equal(scan_plan_init(&p, 0, NAN, 0, 1, 1, 1), RIG_EARG);
    assert_int_equal(scan_plan_init(&p, 0, 1e6, 0, 1e6, 0.01, 0.01), RIG_EARG);
}

static void test_kinematics(void **state)
{
    (void)state;
    double P[3];
    scan_kin_point(&kin, 10.0, -3.0, 20.0, P);
    assert_near(P[0], 10.5, 0);
    assert_near(P[1], -3.25, 0);
    assert_near(P[2], 120.0 - 20.0 + 0.125, 0);
}

typedef struct seen {
    long points, progress_calls, last_done, last_planned;
    uint64_t last_acked;
    double maxerr;
} seen_t;

static int on_point(void *ctx, const jnl_rec_t *r)
{
    seen_t *s = ctx;
    s->points++;
    double e = fabs(r->xyz[2] - surf_z(r->xyz[0], r->xyz[1]));
    s->maxerr = e > s->maxerr ? e : s->maxerr;
    return 0;
}

static void on_progress(void *ctx, long done, long planned, uint64_t acked)
{
    seen_t *s = ctx;
    s->progress_calls++;
    assert_int_equal(done, s->last_done + 1);
    assert_true(acked <= (uint64_t)done);
    s->last_done = done;
    s->last_planned = planned;
    s->last_acked = acked;
}

/* A whole scan over a surface with a hole, journalled to a file: every
 * point where the closed form puts it, the hole flagged, serpentine order
 * in the journal, the end record RIG_OK. */
static void test_scan_file(void **state)
{
    (void)state;
    rig_reset();
    rig.hole[0] = 3.0, rig.hole[1] = 2.0, rig.hole[2] = 1.6;
    scan_job_t job = job_on(0, 9, 0, 5, 0.5); /* 19 x 11 */
    seen_t seen;
    memset(&seen, 0, sizeof seen);
    job.cb = (scan_cb_t){on_point, on_progress, &seen};
    char path[512], msg[256];
    const char *d = getenv("CF_TEST_TMP");
    snprintf(path, sizeof path, "%s", d && *d ? d : "/tmp");
    mkdir(path, 0777);
    snprintf(path + strlen(path), sizeof path - strlen(path), "/test_scan_%ld.jnl", (long)getpid());
    unlink(path);
    cf_store_file_t f;
    rig_store_t st;
    assert_int_equal(cf_store_file_open(&f, path, CF_STORE_CREATE, &st, msg, sizeof msg), RIG_OK);
    jnl_t j;
    jnl_header_t h = header(&job);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    scan_result_t res;
    assert_int_equal(scan_run(&job, &j, &res), RIG_OK);
    long in_hole = 0;
    for (int jy = 0; jy < 11; jy++)
        for (int ix = 0; ix < 19; ix++)
            in_hole += hypot(0.5 * ix + 0.5 - 3.0, 0.5 * jy - 0.25 - 2.0) < 1.6;
    assert_true(in_hole > 0);
    assert_int_equal(res.done, 209);
    assert_int_equal(res.flagged, in_hole);
    assert_int_equal(res.points, 209 - in_hole);
    assert_int_equal(res.fail_index, -1);
    assert_int_equal(seen.points, 209 - in_hole);
    assert_int_equal(seen.last_done, 209);
    assert_int_equal(seen.last_planned, 209);
    assert_true(seen.maxerr < 1e-12);
    assert_int_equal(jnl_acked(&j), 210);
    cf_store_file_close(&f);

    assert_int_equal(cf_store_file_open(&f, path, CF_STORE_READ, &st, msg, sizeof msg), RIG_OK);
    jnl_reader_t rd;
    jnl_info_t in;
    assert_int_equal(jnl_reader_open(&rd, st, &h, &in), RIG_OK);
    assert_int_equal(h.planned, 209);
    assert_near(h.z0, kin.z0, 0);
    assert_near(h.cal[2], kin.cal[2], 0);
    assert_int_equal(in.records, 210);
    assert_int_equal(in.ended, 1);
    assert_int_equal(in.end_code, RIG_OK);
    jnl_rec_t r;
    for (long k = 0; k < 209; k++) {
        assert_int_equal(jnl_reader_next(&rd, &r), 1);
        long jy = k / 19, c = k % 19, ix = jy % 2 ? 18 - c : c;
        assert_near(r.stage[0], 0.5 * (double)ix, 0);
        assert_near(r.stage[1], 0.5 * (double)jy, 0);
        assert_int_equal(!!(r.flags & JNL_F_ROWEND), c == 18);
        double X = r.stage[0] + 0.5, Y = r.stage[1] - 0.25;
        if (hypot(X - 3.0, Y - 2.0) < 1.6) {
            assert_int_equal(r.flags & JNL_F_NOSURF, JNL_F_NOSURF);
            assert_int_equal(r.code, RIG_ENOSURF);
            assert_true(isnan(r.xyz[2]));
        } else {
            assert_int_equal(r.flags & JNL_F_NOSURF, 0);
            assert_near(r.xyz[0], X, 0);
            assert_near(r.xyz[1], Y, 0);
            assert_near(r.xyz[2], surf_z(X, Y), 1e-12);
            assert_near(r.dist, kin.z0 + kin.cal[2] - surf_z(X, Y), 0);
        }
    }
    assert_int_equal(jnl_reader_next(&rd, &r), 1);
    assert_int_equal(r.type, JNL_T_END);
    assert_int_equal(jnl_reader_next(&rd, &r), 0);
    cf_store_file_close(&f);
    unlink(path);
}

/* A job on the RAM store; returns its code, leaves the journal checked:
 * consistent, synced to the last byte, ending with the job's code. */
static int run_mem(scan_job_t *job, scan_result_t *res, jnl_info_t *in)
{
    rig_store_t st;
    ref_memstore_init(&ms, &st);
    jnl_t j;
    jnl_header_t h = header(job);
    assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
    int rc = scan_run(job, &j, res);
    assert_int_equal(rc, res->code);
    assert_int_equal(ms.durable, ms.size);
    jnl_header_t h2;
    assert_int_equal(jnl_scan(st, &h2, in), RIG_OK);
    assert_int_equal(in->tail_bytes, 0);
    if (rc != RIG_EFULL) {
        assert_int_equal(in->ended, 1);
        assert_int_equal(in->end_code, rc);
        assert_int_equal(in->records, (uint64_t)res->done + 1);
    }
    return rc;
}

static void test_sync_rows(void **state)
{
    (void)state;
    rig_reset();
    scan_job_t job = job_on(0, 9, 0, 4, 1); /* 10 x 5: a sync at each of 5 row ends */
    scan_result_t res;
    jnl_info_t in;
    assert_int_equal(run_mem(&job, &res, &in), RIG_OK);
    assert_int_equal(ms.syncs, 1 + 5 + 1); /* header, row ends, end record */
}

static int refuse_third(void *ctx, const jnl_rec_t *r)
{
    (void)ctx;
    return r->seq == 3 ? -5 : 0;
}

static void test_faults(void **state)
{
    (void)state;
    scan_result_t res;
    jnl_info_t in;
    scan_job_t job;
    int faults[] = {RIG_EFAULT, RIG_EESTOP, RIG_ETIMEOUT, RIG_EDISCONNECT, RIG_ELIMIT};
    for (int f = 0; f < 5; f++) { /* the stage fails at move 17: the job ends there */
        rig_reset();
        rig.fail_move_at = 17;
        rig.move_err = faults[f];
        job = job_on(0, 9, 0, 4, 1);
        assert_int_equal(run_mem(&job, &res, &in), faults[f]);
        assert_int_equal(res.done, 17);
        assert_int_equal(res.fail_index, 17);
        assert_int_equal(res.where, SCAN_AT_STAGE);
        assert_int_equal(rig.stops, 1);
        assert_int_equal(rig.reads, 17);
    }
    /* The probe line is lost at read 5 (after the HAL's retries). */
    rig_reset();
    rig.fail_read_at = 5;
    rig.read_err = RIG_EDISCONNECT;
    job = job_on(0, 9, 0, 4, 1);
    assert_int_equal(run_mem(&job, &res, &in), RIG_EDISCONNECT);
    assert_int_equal(res.done, 5);
    assert_int_equal(res.where, SCAN_AT_PROBE);
    assert_int_equal(in.points, 5);
    /* The fitter refuses point 3: the job ends with its code. */
    rig_reset();
    job = job_on(0, 9, 0, 4, 1);
    job.cb = (scan_cb_t){refuse_third, NULL, NULL};
    assert_int_equal(run_mem(&job, &res, &in), -5);
    assert_int_equal(res.where, SCAN_AT_CALLER);
    assert_int_equal(res.done, 4); /* journalled before the call */
    /* Stop asked before point 9: stage stopped, RIG_EABORTED. */
    rig_reset();
    rig.stop_at = 9;
    job = job_on(0, 9, 0, 4, 1);
    assert_int_equal(run_mem(&job, &res, &in), RIG_EABORTED);
    assert_int_equal(res.done, 9);
    assert_int_equal(res.where, SCAN_AT_STOP);
    assert_int_equal(rig.moves, 9);
    assert_int_equal(rig.stops, 1);
    /* A stop with a reason (the rig lost for good): the job and its
     * journal end with the reason, not RIG_EABORTED. */
    rig_reset();
    rig.stop_at = 9;
    rig.stop_why = RIG_ELOST;
    assert_int_equal(run_mem(&job, &res, &in), RIG_ELOST);
    assert_int_equal(in.end_code, RIG_ELOST);
    assert_int_equal(res.done, 9);
    assert_int_equal(res.where, SCAN_AT_STOP);
    /* ... also when the reason comes while a move is in progress: the move
     * gave up (RIG_EABORTED from the transport), the reason wins. */
    rig_reset();
    rig.fail_move_at = 12;
    rig.move_err = RIG_EABORTED;
    rig.stop_at = 13; /* the check before move 12 passes, the one after it stops */
    rig.stop_why = RIG_ELOST;
    assert_int_equal(run_mem(&job, &res, &in), RIG_ELOST);
    assert_int_equal(in.end_code, RIG_ELOST);
    assert_int_equal(res.done, 12);
    assert_int_equal(res.where, SCAN_AT_STAGE);
    /* E-stop or a latched fault before the start: no move at all. */
    rig_reset();
    rig.status |= RIG_ST_ESTOP;
    assert_int_equal(run_mem(&job, &res, &in), RIG_EESTOP);
    assert_int_equal(rig.moves, 0);
    rig_reset();
    rig.status |= RIG_ST_FAULT;
    assert_int_equal(run_mem(&job, &res, &in), RIG_EFAULT);
    assert_int_equal(rig.moves, 0);
    /* A plan beyond the soft limits is refused before moving. */
    rig_reset();
    rig.hi[0] = 8.5;
    assert_int_equal(run_mem(&job, &res, &in), RIG_ELIMIT);
    assert_int_equal(rig.moves, 0);
    /* Not homed: homed on request, refused otherwise. */
    rig_reset();
    rig.status = 0;
    assert_int_equal(run_mem(&job, &res, &in), RIG_ENOTHOMED);
    assert_int_equal(rig.moves, 0);
    job.home = 1;
    assert_int_equal(run_mem(&job, &res, &in), RIG_OK);
    assert_int_equal(rig.homes, 1);
    assert_int_equal(res.done, 50);
}

/* The disk fills during the scan: the job ends RIG_EFULL and the journal
 * holds whole records only, each where the plan put it. */
static void test_full(void **state)
{
    (void)state;
    for (size_t limit = JNL_HDR_BYTES + 10 * JNL_REC_BYTES;
         limit < JNL_HDR_BYTES + 12 * JNL_REC_BYTES; limit += 13) {
        rig_reset();
        scan_job_t job = job_on(0, 9, 0, 4, 1);
        rig_store_t st;
        ref_memstore_init(&ms, &st);
        ms.limit = limit;
        jnl_t j;
        jnl_header_t h = header(&job);
        assert_int_equal(jnl_create(&j, st, &h), RIG_OK);
        scan_result_t res;
        assert_int_equal(scan_run(&job, &j, &res), RIG_EFULL);
        assert_int_equal(res.where, SCAN_AT_JOURNAL);
        long whole = (long)((limit - JNL_HDR_BYTES) / JNL_REC_BYTES);
        assert_int_equal(res.done, whole);
        assert_int_equal(rig.stops, 1);
        jnl_info_t in;
        assert_int_equal(jnl_open(&j, st, &in), RIG_OK);
        assert_int_equal(in.records, whole);
        assert_int_equal(in.tail_bytes, 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plan),      cmocka_unit_test(test_kinematics),
        cmocka_unit_test(test_scan_file), cmocka_unit_test(test_sync_rows),
        cmocka_unit_test(test_faults),    cmocka_unit_test(test_full),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
