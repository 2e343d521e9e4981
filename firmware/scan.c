/* SPDX-License-Identifier: MIT */
/* scan.c: the scan job (scan.h): plan, kinematics, the per-point loop and
 * what each fault means. */
#include "scan.h"
#include <math.h>
#include <string.h>

/* Points along one axis: floor(w / s) + 1, with w / s within 1e-9 of an
 * integer taken as that integer (so 0:10 with step 0.1 has 101 points). */
static long axis_count(double w, double s)
{
    double r = w / s, n = floor(r + 1e-9 * (r > 1 ? r : 1));
    return (long)n + 1;
}

int scan_plan_init(scan_plan_t *p, double x0, double x1, double y0, double y1, double sx, double sy)
{
    if (!p || !isfinite(x0) || !isfinite(x1) || !isfinite(y0) || !isfinite(y1) || !isfinite(sx) ||
        !isfinite(sy) || !(sx > 0) || !(sy > 0) || x1 < x0 || y1 < y0)
        return RIG_EARG;
    if ((x1 - x0) / sx > (double)SCAN_MAX_POINTS || (y1 - y0) / sy > (double)SCAN_MAX_POINTS)
        return RIG_EARG;
    memset(p, 0, sizeof *p);
    p->x0 = x0;
    p->y0 = y0;
    p->dx = sx;
    p->dy = sy;
    p->nx = axis_count(x1 - x0, sx);
    p->ny = axis_count(y1 - y0, sy);
    if ((double)p->nx * (double)p->ny > (double)SCAN_MAX_POINTS)
        return RIG_EARG;
    return RIG_OK;
}

long scan_plan_count(const scan_plan_t *p)
{
    return p ? p->nx * p->ny : 0;
}

void scan_plan_point(const scan_plan_t *p, long k, double *x, double *y, int *row_end)
{
    long j = k / p->nx, i = k % p->nx;
    if (j % 2)
        i = p->nx - 1 - i; /* odd rows run back: no return stroke */
    *x = p->x0 + (double)i * p->dx;
    *y = p->y0 + (double)j * p->dy;
    *row_end = k % p->nx == p->nx - 1;
}

void scan_kin_point(const scan_kin_t *k, double x, double y, double d, double out[3])
{
    out[0] = x + k->cal[0];
    out[1] = y + k->cal[1];
    out[2] = k->z0 - d + k->cal[2];
}

void scan_header(const scan_job_t *job, jnl_header_t *h)
{
    h->z0 = job->kin.z0;
    memcpy(h->cal, job->kin.cal, sizeof h->cal);
    h->planned = (uint64_t)scan_plan_count(&job->plan);
}

static double now(const scan_job_t *job)
{
    return job->clock.ops && job->clock.ops->now ? job->clock.ops->now(job->clock.ctx) : 0.0;
}

/* The job ends: motion stopped (best effort: after a disconnect it cannot
 * be), the end record written and synced. Returns code. */
static int finish(const scan_job_t *job, jnl_t *j, scan_result_t *res, long k, int code, int where)
{
    if (code && job->clock.ops && job->clock.ops->should_stop) {
        /* A job stopped for a reason of its own (should_stop gave a
         * rig_err_t, e.g. RIG_ELOST: the rig's process ended) ends with that
         * reason, whatever the device call it interrupted returned. */
        int why = job->clock.ops->should_stop(job->clock.ctx);
        if (why < 0)
            code = why;
    }
    res->where = code ? where : SCAN_AT_NONE;
    if (code && job->stage.ops->stop)
        job->stage.ops->stop(job->stage.ctx);
    if (j->state == JNL_S_OPEN)
        jnl_end(j, code, now(job)); /* a journal that failed keeps what it synced */
    res->code = code;
    res->fail_index = code ? k : -1;
    return code;
}

/* Before the first move: a stage in e-stop or fault, not homed, or a plan
 * outside the soft limits is refused. */
static int preflight(const scan_job_t *job)
{
    const rig_stage_ops_t *so = job->stage.ops;
    uint32_t bits = RIG_ST_HOMED;
    int rc = so->status ? so->status(job->stage.ctx, &bits) : RIG_OK;
    if (rc)
        return rc;
    if (bits & RIG_ST_ESTOP)
        return RIG_EESTOP;
    if (bits & RIG_ST_FAULT)
        return RIG_EFAULT;
    if (!(bits & RIG_ST_HOMED)) {
        if (!job->home || !so->home)
            return RIG_ENOTHOMED;
        if ((rc = so->home(job->stage.ctx)) != RIG_OK)
            return rc;
    }
    if (so->limits) {
        double lo[2], hi[2];
        const scan_plan_t *p = &job->plan;
        if ((rc = so->limits(job->stage.ctx, lo, hi)) != RIG_OK)
            return rc;
        double x1 = p->x0 + (double)(p->nx - 1) * p->dx, y1 = p->y0 + (double)(p->ny - 1) * p->dy;
        if (p->x0 < lo[0] || x1 > hi[0] || p->y0 < lo[1] || y1 > hi[1])
            return RIG_ELIMIT;
    }
    return RIG_OK;
}

int scan_run(const scan_job_t *job, jnl_t *j, scan_result_t *res)
{
    if (!job || !j || !res || !job->stage.ops || !job->stage.ops->move_to || !job->probe.ops ||
        !job->probe.ops->read)
        return RIG_EARG;
    memset(res, 0, sizeof *res);
    res->fail_index = -1;
    if (j->state != JNL_S_OPEN)
        return res->code = RIG_ESTATE;
    long planned = scan_plan_count(&job->plan);
    if (planned <= 0)
        return res->code = RIG_EARG;
    int rc = preflight(job);
    if (rc)
        return finish(job, j, res, 0, rc, SCAN_AT_STAGE);
    const rig_stage_ops_t *so = job->stage.ops;
    for (long k = 0; k < planned; k++) {
        if (job->clock.ops && job->clock.ops->should_stop &&
            job->clock.ops->should_stop(job->clock.ctx))
            return finish(job, j, res, k, RIG_EABORTED, SCAN_AT_STOP);
        jnl_rec_t r;
        memset(&r, 0, sizeof r);
        int row_end;
        scan_plan_point(&job->plan, k, &r.stage[0], &r.stage[1], &row_end);
        if ((rc = so->move_to(job->stage.ctx, r.stage[0], r.stage[1])) != RIG_OK)
            return finish(job, j, res, k, rc, SCAN_AT_STAGE);
        /* The point is where the stage says it is, not where it was sent. */
        if (so->position && (rc = so->position(job->stage.ctx, &r.stage[0], &r.stage[1])) != RIG_OK)
            return finish(job, j, res, k, rc, SCAN_AT_STAGE);
        rc = job->probe.ops->read(job->probe.ctx, &r.dist);
        r.type = JNL_T_POINT;
        r.t = now(job);
        r.code = rc;
        if (rc == RIG_OK && !isfinite(r.dist))
            rc = r.code = RIG_EPROTO;
        if (rc == RIG_ENOSURF) {
            r.flags = JNL_F_NOSURF;
            r.dist = r.xyz[0] = r.xyz[1] = r.xyz[2] = NAN;
        } else if (rc)
            return finish(job, j, res, k, rc, SCAN_AT_PROBE);
        else
            scan_kin_point(&job->kin, r.stage[0], r.stage[1], r.dist, r.xyz);
        if (row_end)
            r.flags |= JNL_F_ROWEND;
        if ((rc = jnl_append(j, &r)) != RIG_OK || (row_end && (rc = jnl_sync(j)) != RIG_OK))
            return finish(job, j, res, k, rc, SCAN_AT_JOURNAL);
        res->done++;
        if (r.flags & JNL_F_NOSURF)
            res->flagged++;
        else {
            res->points++;
            if (job->cb.point && (rc = job->cb.point(job->cb.ctx, &r)) != 0)
                return finish(job, j, res, k, rc, SCAN_AT_CALLER);
        }
        if (job->cb.progress)
            job->cb.progress(job->cb.ctx, res->done, planned, jnl_acked(j));
    }
    return finish(job, j, res, planned, RIG_OK, SCAN_AT_NONE);
}
