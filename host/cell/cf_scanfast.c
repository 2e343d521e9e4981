/* SPDX-License-Identifier: MIT */
/* cf_scanfast.c: the on-the-fly and profiler scan methods (cf_scanfast.h):
 * rows from the stream into the journal and the caller, losses counted. */
#include "cf_scanfast.h"
#include "cf_cli.h"
#include "cf_err.h"
#include "hal_gev.h"
#include "rig_err.h"
#include "scan_otf.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cf_scanfast_method(const char *name)
{
    static const char *const names[] = {"stop", "otf", "profiler"};
    for (int i = 0; i < 3; i++)
        if (name && !strcmp(name, names[i]))
            return i;
    return -1;
}

cf_scan_method_t cf_scanfast_default_method(const char *probe_uri)
{
    return probe_uri && !strncmp(probe_uri, "gev:", 4) ? CF_SCAN_PROFILER : CF_SCAN_STOP;
}

const char *cf_scanfast_method_name(cf_scan_method_t m)
{
    return m == CF_SCAN_OTF ? "otf" : m == CF_SCAN_PROFILER ? "profiler" : "stop";
}

int cf_scanfast_geom_parse(const char *s, cf_scanfast_geom_t *g)
{
    const char *p = s ? strstr(s, "width ") : NULL;
    if (!p)
        return -1;
    memset(g, 0, sizeof *g);
    if (sscanf(p,
               "width %d height %d profiles %ld x0 %lf dx %lf y0 %lf dy %lf z0 %lf lo %lf scale "
               "%lf",
               &g->width, &g->height, &g->profiles, &g->x0, &g->dx, &g->y0, &g->dy, &g->z0, &g->lo,
               &g->scale) != 10)
        return -1;
    return g->width > 0 && g->height > 0 && g->profiles > 0 && g->scale > 0 ? 0 : -1;
}

void cf_scanfast_header(const scan_kin_t *kin, long planned, jnl_header_t *h)
{
    h->z0 = kin ? kin->z0 : 0;
    if (kin)
        memcpy(h->cal, kin->cal, sizeof h->cal);
    h->planned = (uint64_t)(planned > 0 ? planned : 0);
    /* One sync per row (or frame), by the job: the count alone never
     * forces one (docs/journal.md). */
    h->sync_every = 0x7FFFFFFFu;
}

/* The stop request as it came: a negative value is its reason (RIG_ELOST). */
static int stop_asked(const cf_scanfast_cb_t *cb)
{
    return cb && cb->should_stop ? cb->should_stop(cb->ctx) : 0;
}

/* The code a scan that failed or stopped ends with: a stop's own reason
 * (RIG_ELOST: the rig's process ended) over what the interrupted call said. */
static int end_code(const cf_scanfast_cb_t *cb, int rc)
{
    int why = rc ? stop_asked(cb) : 0;
    return why < 0 ? why : rc;
}

/* One point: journalled (at time t: the caller reads the clock once per row
 * chunk or profile, not per point, 3 % of a profiler scan), then to the
 * caller. */
static int put_point(jnl_t *j, const cf_scanfast_cb_t *cb, const scan_kin_t *kin,
                     const double xyz[3], int rowend, double t, cf_scanfast_res_t *res)
{
    jnl_rec_t r;
    memset(&r, 0, sizeof r);
    r.type = JNL_T_POINT;
    r.flags = rowend ? JNL_F_ROWEND : 0;
    r.stage[0] = xyz[0] - kin->cal[0];
    r.stage[1] = xyz[1] - kin->cal[1];
    r.dist = kin->z0 + kin->cal[2] - xyz[2]; /* scan.h's model, inverted */
    memcpy(r.xyz, xyz, sizeof r.xyz);
    r.t = t;
    int rc = jnl_append(j, &r);
    if (rc) {
        res->where = SCAN_AT_JOURNAL;
        return rc;
    }
    res->points++;
    if (cb && cb->point && (rc = cb->point(cb->ctx, xyz)) != 0) {
        res->where = SCAN_AT_CALLER;
        return rc;
    }
    return 0;
}

/* --- on the fly --- */

typedef struct otf_ctx {
    jnl_t *j;
    const cf_scanfast_cb_t *cb;
    const scan_kin_t *kin;
    cf_scanfast_res_t *res;
} otf_ctx_t;

static int otf_row(void *ctx, long row, const double *xyz, const uint64_t *trig, long n, int last)
{
    otf_ctx_t *c = ctx;
    (void)row;
    (void)trig;
    double t = cli_now();
    for (long i = 0; i < n; i++) {
        int rc = put_point(c->j, c->cb, c->kin, xyz + 3 * i, last && i == n - 1, t, c->res);
        if (rc)
            return rc;
    }
    return 0;
}

/* A loss at its trigger numbers (scan_otf_gap_fn): a gap record, in
 * number order with the row's points (issue 19). */
static int otf_gap(void *ctx, long row, int kind, uint64_t num, uint64_t count, const double *xy)
{
    otf_ctx_t *c = ctx;
    int rc = jnl_gap(c->j, kind, row, num, count, xy, cli_now());
    if (rc)
        c->res->where = SCAN_AT_JOURNAL;
    else
        c->res->gap_records++;
    return rc;
}

static void otf_counts(const scan_otf_t *o, unsigned long dropped, cf_scanfast_res_t *res)
{
    const scan_otf_counts_t *c = &o->c;
    res->triggers = (long)c->trig;
    res->nosurf = (long)c->nosurf;
    res->sensor_errors = (long)c->errors;
    res->lost_readings = (long)c->trig_no_read;
    res->lost_triggers = (long)c->read_no_trig;
    res->both_lost = (long)c->both_lost;
    res->dup = (long)(c->dup_read + c->dup_trig);
    res->late = (long)c->late;
    res->overrun = (long)c->overrun;
    res->rows_cut = (long)c->rows_cut;
    res->past_end = (long)c->past_end;
    res->before_start = (long)c->before_start;
    res->dropped_by_probe = (long)dropped;
}

/* Where otf_stream_row is in a row: the stage running with the triggers
 * armed; the row's end latched, the triggers stopped, the stage's BUSY
 * awaited; the stage stopped (BUSY clear or a fault), the stream drained;
 * or stopped by the caller (ABORT, the watchdog), drained likewise. */
typedef enum { OTF_RUN, OTF_SETTLE, OTF_DRAIN, OTF_STOPPED } otf_phase_t;

/* The stream's entries while the stage runs the row, then the stop and
 * the drain. The triggers are stopped at the first of: the row's end
 * position latched (scan_otf_end_seen), the stage's BUSY cleared, a fault;
 * the stage is polled until BUSY clears all the same (the next move must
 * not cut its settling short). What the box fires after the end is
 * dropped by the pairing, so a host late to see the end (a dropped reply,
 * a loaded machine) adds no point, only drain time (issue 19). *fault set
 * when the stage faulted (or E-stop) mid-row. */
static int otf_stream_row(hal_rig_t *rig, scan_otf_t *o, const cf_scanfast_cb_t *cb,
                          double period_us, double t_row, const double to[2],
                          unsigned long *dropped, int *fault, int *where)
{
    /* Bounds, so that a stage that never reports the row's end or a stream
     * whose end never comes is an error, not a hang: the row's travel three
     * times over plus 2 s; 2 s without an entry once stopped. */
    double t_start = cli_now(), t_entry = t_start, t_max = 3 * t_row + 2;
    /* Armed before the move: the row's first triggers fall on the stage
     * standing at its start, and the pairing keeps the last of them
     * (scan_otf_row_start_at), so no trigger of the travel is missed
     * however long the move command takes. */
    otf_phase_t ph = OTF_RUN;
    int rc = hal_probe_stream_start(&rig->pr, (uint32_t)lround(period_us));
    if (rc) {
        *where = SCAN_AT_PROBE;
        return rc;
    }
    if ((rc = hal_stage_move_start(&rig->st, to[0], to[1])) != 0) {
        *where = SCAN_AT_STAGE;
        hal_probe_stream_stop(&rig->pr);
        return rc;
    }
    t_start = t_entry = cli_now();
    double t_poll = cli_now();
    while (!rc) {
        rig_reading_t rd[256];
        rig_trig_event_t pos[256];
        size_t n = 0;
        /* The Modbus FIFO holds entries in number order, all after the
         * row's end once it is latched, and the next arming empties it:
         * not read then (a host that was held up would spend seconds on
         * them). The ASCII stream is read to its end line, which must not
         * be left. */
        int skip = rig->pr.modbus && scan_otf_end_seen(o);
        if (!skip && (rc = hal_probe_stream_read(&rig->pr, rd, pos, 256, &n, dropped)) != 0) {
            *where = SCAN_AT_PROBE;
            break;
        }
        /* Entry by entry, position then reading: a batch of positions
         * past a gap must not push the readings of its first entries out
         * of the window before they are taken (they would count as late). */
        for (size_t i = 0; i < n && !rc; i++)
            if ((rc = scan_otf_trig(o, &pos[i], 1)) == 0)
                rc = scan_otf_read(o, &rd[i], 1);
        if (rc) {
            *where = o->err ? SCAN_AT_CALLER : SCAN_AT_PROBE;
            break;
        }
        if (scan_otf_end_seen(o)) {
            if (ph == OTF_RUN) { /* the row's end latched: no trigger after it is wanted */
                ph = OTF_SETTLE;
                if ((rc = hal_probe_stream_stop(&rig->pr)) != 0) {
                    *where = SCAN_AT_PROBE;
                    break;
                }
            }
            skip = rig->pr.modbus;
        }
        if (ph >= OTF_DRAIN && (skip || (!n && !rig->pr.streaming)))
            break;
        double t_now = cli_now();
        if (n)
            t_entry = t_now;
        if (ph >= OTF_DRAIN && !n && t_now - t_entry > 2.0) {
            rc = RIG_ETIMEOUT;
            *where = SCAN_AT_PROBE;
            snprintf(rig->pr.err, sizeof rig->pr.err,
                     "probe stream: stopped, but its end did not come within 2 s");
            break;
        }
        if (ph <= OTF_SETTLE && t_now - t_start > t_max) {
            rig->stage.ops->stop(rig->stage.ctx);
            rc = RIG_ETIMEOUT;
            *where = SCAN_AT_STAGE;
            snprintf(rig->st.err, sizeof rig->st.err,
                     "stage: the row's move did not end within %.1f s (still busy)", t_max);
            break;
        }
        if (ph <= OTF_SETTLE && stop_asked(cb)) {
            /* ABORT or the watchdog: the stage first, then the stream. */
            rig->stage.ops->stop(rig->stage.ctx);
            if (ph == OTF_RUN)
                rc = hal_probe_stream_stop(&rig->pr);
            ph = OTF_STOPPED;
            continue;
        }
        /* The stage's status when the FIFO is drained, and at least every
         * 20 ms while it is not (a host behind the stream still sees the
         * row end and a fault within the row). */
        double t = cli_now();
        if (ph <= OTF_SETTLE && (n < 256 || t - t_poll >= 0.02)) {
            t_poll = t;
            uint32_t st = 0;
            if ((rc = rig->stage.ops->status(rig->stage.ctx, &st)) != 0) {
                *where = SCAN_AT_STAGE;
                break;
            }
            if (st & (RIG_ST_FAULT | RIG_ST_ESTOP))
                *fault = st & RIG_ST_ESTOP ? RIG_EESTOP : RIG_EFAULT;
            if (*fault || !(st & RIG_ST_BUSY)) {
                /* the row's end (or its fault): stop the triggers, drain */
                if (ph == OTF_RUN && (rc = hal_probe_stream_stop(&rig->pr)) != 0)
                    *where = SCAN_AT_PROBE;
                ph = OTF_DRAIN;
            }
        }
    }
    if (rc && rig->pr.streaming)
        hal_probe_stream_stop(&rig->pr);
    if (!rc && ph == OTF_STOPPED)
        rc = RIG_EABORTED;
    return rc;
}

int cf_scanfast_otf(hal_rig_t *rig, const scan_plan_t *pl, const scan_kin_t *kin, double period_us,
                    jnl_t *j, const cf_scanfast_cb_t *cb, cf_scanfast_res_t *res, char *msg,
                    size_t ml)
{
    memset(res, 0, sizeof *res);
    res->fail_row = -1;
    res->rows = pl->ny;
    if (msg && ml)
        *msg = 0;
    double t0 = cli_now();
    if (!rig || !rig->stage.ops || !rig->probe.ops || !(period_us >= 20 && period_us <= 1e6))
        return res->code = cf_fail(msg, ml, RIG_EARG,
                                   "on the fly: a stage, a probe and a trigger period of 20 us "
                                   "to 1 s are needed");
    static scan_otf_t o; /* 49 kB: not on the stack; one scan at a time per process */
    /* The latched positions come in um (docs/rig-devices.md). */
    const scan_otf_enc_t enc = {{0, 0}, {0.001, 0.001}};
    otf_ctx_t oc = {j, cb, kin, res};
    int rc = scan_otf_init(&o, kin, &enc, otf_row, &oc);
    scan_otf_set_gap(&o, otf_gap);
    /* The speed at which period_us apart the triggers fall dx apart
     * (whole mm/s: the register's unit), then the period that matches it. */
    double old_speed = rig->st.speed;
    double speed = fmin(fmax(round(pl->dx * 1e6 / period_us), 1), 65535);
    res->speed = speed;
    res->period_us = round(pl->dx * 1e6 / speed);
    if (res->period_us < 20)
        res->period_us = 20;
    if (!rc && (rc = hal_stage_set_speed(&rig->st, speed)) != 0)
        res->where = SCAN_AT_STAGE;
    uint32_t bits = 0;
    if (!rc && (rc = rig->stage.ops->status(rig->stage.ctx, &bits)) != 0)
        res->where = SCAN_AT_STAGE;
    if (!rc && !(bits & RIG_ST_HOMED)) {
        rc = RIG_ENOTHOMED;
        res->where = SCAN_AT_STAGE;
    }
    unsigned long dropped = 0;
    for (long row = 0; row < pl->ny && !rc; row++) {
        double xa, xb, y;
        int end;
        scan_plan_point(pl, row * pl->nx, &xa, &y, &end);
        scan_plan_point(pl, row * pl->nx + pl->nx - 1, &xb, &y, &end);
        res->fail_row = row;
        if (stop_asked(cb)) {
            rc = RIG_EABORTED;
            res->where = SCAN_AT_STOP;
            break;
        }
        if ((rc = rig->stage.ops->move_to(rig->stage.ctx, xa, y)) != 0) {
            res->where = SCAN_AT_STAGE;
            break;
        }
        /* The row's end: the first trigger latched within half a step of
         * it (or 2 um, an encoder's jitter at rest) is the row's last. */
        if ((rc = scan_otf_row_begin(&o, row)) != 0 ||
            (rc = scan_otf_row_end_at(&o, xb, y, fmax(pl->dx / 2, 0.002))) != 0 ||
            (rc = scan_otf_row_start_at(&o, xa, y)) != 0)
            break;
        int fault = 0, where = SCAN_AT_NONE;
        const double to[2] = {xb, y};
        rc = otf_stream_row(rig, &o, cb, res->period_us, fabs(xb - xa) / speed, to, &dropped,
                            &fault, &where);
        int erc = scan_otf_row_end(&o, fault != 0, 0);
        if (!rc)
            rc = erc;
        if (rc == RIG_EABORTED)
            where = SCAN_AT_STOP;
        if (!rc && fault) {
            rc = fault;
            where = SCAN_AT_STAGE;
        }
        res->where = where;
        int src = jnl_sync(j); /* the row is durable before the next starts */
        if (!rc && src) {
            rc = src;
            res->where = SCAN_AT_JOURNAL;
        }
        if (rc)
            break;
        res->rows_done = row + 1;
        res->t_last_row = cli_now();
        if (cb && cb->progress)
            cb->progress(cb->ctx, row + 1, pl->ny, res->points);
    }
    otf_counts(&o, dropped, res);
    if (!rc) {
        res->fail_row = -1;
        res->where = SCAN_AT_NONE;
    }
    if (old_speed >= 1)
        (void)hal_stage_set_speed(&rig->st, old_speed); /* best effort: the scan itself stands */
    if (rc == RIG_EABORTED || res->where == SCAN_AT_STAGE)
        rig->stage.ops->stop(rig->stage.ctx);
    rc = end_code(cb, rc);
    jnl_end(j, rc, cli_now());
    res->seconds = cli_now() - t0;
    res->code = rc;
    if (rc && msg && ml && !*msg)
        snprintf(msg, ml, "on the fly: row %ld: %s%s%s", res->fail_row, rig_strerror(rc),
                 res->where == SCAN_AT_STAGE || res->where == SCAN_AT_PROBE ? ": " : "",
                 res->where == SCAN_AT_STAGE   ? rig->st.err
                 : res->where == SCAN_AT_PROBE ? rig->pr.err
                                               : "");
    return rc;
}

/* --- profiler --- */

int cf_scanfast_profiler(const char *uri, const cf_scanfast_geom_t *g, long profiles,
                         double frame_rate, jnl_t *j, const cf_scanfast_cb_t *cb,
                         cf_scanfast_res_t *res, char *msg, size_t ml)
{
    memset(res, 0, sizeof *res);
    res->fail_row = -1;
    if (msg && ml)
        *msg = 0;
    long want = profiles > 0 ? profiles : g->profiles;
    res->rows = want;
    double t0 = cli_now();
    hal_gev_t *gv = NULL;
    hal_gev_opts_t o = {g->width, g->height, frame_rate, 0, 32, 0};
    int rc = hal_gev_open(&gv, uri, &o, msg, ml);
    if (rc) {
        res->where = SCAN_AT_PROBE;
        return res->code = rc;
    }
    int w = 0, h = 0;
    hal_gev_size(gv, &w, &h);
    if (w != g->width || h != g->height) {
        hal_gev_close(gv);
        res->where = SCAN_AT_PROBE;
        return res->code = cf_fail(msg, ml, RIG_EUNSUPPORTED,
                                   "%s: frames of %d x %d, the geometry says %d x %d", uri, w, h,
                                   g->width, g->height);
    }
    /* The profiler looks down from z0: scan.h's model with the stage at
     * the profile's x and the point's y, no calibration offset. */
    const scan_kin_t kin = {g->z0, {0, 0, 0}};
    rc = hal_gev_start(gv);
    long seen = 0;
    while (!rc && seen < want) {
        if (stop_asked(cb)) {
            rc = RIG_EABORTED;
            res->where = SCAN_AT_STOP;
            break;
        }
        hal_gev_frame_t f;
        if ((rc = hal_gev_next(gv, &f, 5000)) != 0) {
            res->where = SCAN_AT_PROBE;
            break;
        }
        /* Profile r of frame id k is profile k * height + r of the scan,
         * k as on the wire (1..65535, docs/rig-profiler.md). */
        for (uint64_t lost = f.gap_before; lost > 0 && seen < want && !rc; lost--) {
            /* A lost frame: one gap record per profile it held, at the
             * profile's own number and x (never a shifted row). */
            uint64_t wire = (f.id - lost - 1) % 65535 + 1;
            for (int r = 0; r < f.height && seen < want && !rc; r++, seen++) {
                uint64_t n = wire * (uint64_t)f.height + (uint64_t)r;
                const double at[2] = {g->x0 + (double)(n % (uint64_t)g->profiles) * g->dx, g->y0};
                if ((rc = jnl_gap(j, JNL_GAP_PROFILE, -1, n, 1, at, cli_now())) != 0)
                    res->where = SCAN_AT_JOURNAL;
                else
                    res->gap_records++;
                res->profiles_lost++;
            }
        }
        uint64_t wire = (f.id - 1) % 65535 + 1;
        for (int r = 0; r < f.height && seen < want && !rc; r++, seen++) {
            uint64_t n = wire * (uint64_t)f.height + (uint64_t)r;
            double x = g->x0 + (double)(n % (uint64_t)g->profiles) * g->dx;
            const uint16_t *row = f.range + (size_t)r * (size_t)f.width;
            int last = f.width - 1;
            double t = cli_now();
            while (last >= 0 && !row[last])
                last--;
            for (int i = 0; i <= last && !rc; i++) {
                if (!row[i]) {
                    res->dropouts++;
                    continue;
                }
                double xyz[3] = {x, g->y0 + i * g->dy, g->z0 - (g->lo + row[i] * g->scale)};
                rc = put_point(j, cb, &kin, xyz, i == last, t, res);
            }
            res->dropouts += f.width - 1 - last;
            if (!rc)
                res->rows_done++;
        }
        int src = jnl_sync(j); /* one sync a frame */
        if (!rc && src) {
            rc = src;
            res->where = SCAN_AT_JOURNAL;
        }
        res->frames++;
        res->t_last_row = cli_now();
        if (!rc && cb && cb->progress)
            cb->progress(cb->ctx, seen, want, res->points);
    }
    if (rc)
        res->fail_row = seen;
    hal_gev_stats_t st;
    hal_gev_stats(gv, &st);
    res->frames_lost = (long)st.frames_gap;
    res->frames_bad = (long)st.frames_bad;
    if (rc && msg && ml && !*msg)
        snprintf(msg, ml, "%s: %s", uri, hal_gev_error(gv));
    hal_gev_stop(gv);
    hal_gev_close(gv);
    rc = end_code(cb, rc);
    jnl_end(j, rc, cli_now());
    res->seconds = cli_now() - t0;
    return res->code = rc;
}
