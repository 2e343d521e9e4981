/* SPDX-License-Identifier: MIT */
/* hal_stage.c: the Modbus motion stage driver (rig_stage_ops_t): a move
 * is one read of status, position and move counter, one write of target
 * and command (registers 0-4, so it is atomic), a check that the stage
 * took it (move counter, result register), then a sleep to the expected
 * arrival and status-and-position reads until in position, a fault, or the
 * move timeout: the travel time plus about four round trips. */
#include "hal_priv.h"
#include "hal_regmap.h"
#include "hal_rig.h"
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static int sfail(hal_stage_t *s, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int sfail(hal_stage_t *s, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->err, sizeof s->err, fmt, ap);
    va_end(ap);
    return code;
}

/* A transport failure: its detail becomes ours. One that gave up on a stop
 * request (hal.h: the device did not answer while a stop was asked) sends
 * STOP (tried once, or not at all when the device is hung) and aborts. */
static int tfail(hal_stage_t *s, int code, const char *what)
{
    if (code == RIG_EABORTED) {
        char why[256];
        snprintf(why, sizeof why, "%s", hal_last_error(s->h));
        uint16_t stop = STG_CMD_STOP;
        hal_write_regs(s->h, STG_COMMAND, 1, &stop);
        return sfail(s, RIG_EABORTED, "stage %s: stopped on request (%s)", what, why);
    }
    return sfail(s, code, "stage %s: %s", what, hal_last_error(s->h));
}

static int32_t get32(const uint16_t *r)
{
    return (int32_t)(((uint32_t)r[0] << 16) | r[1]); /* high word first */
}

static void put32(uint16_t *r, int32_t v)
{
    r[0] = (uint16_t)((uint32_t)v >> 16);
    r[1] = (uint16_t)((uint32_t)v & 0xFFFFu);
}

static int rd(hal_stage_t *s, int addr, int n, uint16_t *r, const char *what)
{
    int rc = hal_read_regs(s->h, 'h', addr, n, r);
    return rc ? tfail(s, rc, what) : RIG_OK;
}

static int wr(hal_stage_t *s, int addr, int n, const uint16_t *r, const char *what)
{
    int rc = hal_write_regs(s->h, addr, n, r);
    return rc ? tfail(s, rc, what) : RIG_OK;
}

const char *hal_stage_error(const void *ctx)
{
    return ctx ? ((const hal_stage_t *)ctx)->err : "no stage";
}

int hal_stage_init(hal_stage_t *s, hal_t *h)
{
    if (!s || !h)
        return RIG_EARG;
    memset(s, 0, sizeof *s);
    s->h = h;
    s->home_timeout_ms = 60000;
    s->poll_ms = 5;
    s->tol_mm = 0.002;
    uint16_t r[9];
    int rc = rd(s, STG_LIM_XLO, 9, r, "reading limits and speed");
    if (rc)
        return rc;
    s->lo[0] = get32(r) * 1e-3;
    s->hi[0] = get32(r + 2) * 1e-3;
    s->lo[1] = get32(r + 4) * 1e-3;
    s->hi[1] = get32(r + 6) * 1e-3;
    s->speed = r[8] ? r[8] : 1;
    if (!(s->lo[0] < s->hi[0] && s->lo[1] < s->hi[1]))
        return sfail(s, RIG_EPROTO, "stage reports empty soft limits [%g, %g] x [%g, %g]", s->lo[0],
                     s->hi[0], s->lo[1], s->hi[1]);
    return RIG_OK;
}

/* Status bits that stop any motion call, as errors. */
static int status_error(hal_stage_t *s, unsigned st, const char *when)
{
    if (st & RIG_ST_ESTOP)
        return sfail(s, RIG_EESTOP, "stage: emergency stop active (%s)", when);
    if (st & RIG_ST_FAULT) {
        uint16_t fc = 0;
        hal_read_regs(s->h, 'h', STG_FAULT, 1, &fc);
        return sfail(s, RIG_EFAULT, "stage: drive fault latched, fault code %u (%s)", fc, when);
    }
    return RIG_OK;
}

static int result_error(hal_stage_t *s, unsigned res, const char *cmd)
{
    switch (res) {
    case STG_RES_OK: return RIG_OK;
    case STG_RES_NOTHOMED: return sfail(s, RIG_ENOTHOMED, "stage refused %s: not homed", cmd);
    case STG_RES_LIMIT: return sfail(s, RIG_ELIMIT, "stage refused %s: outside soft limits", cmd);
    case STG_RES_FAULT: return sfail(s, RIG_EFAULT, "stage refused %s: fault latched", cmd);
    case STG_RES_ESTOP: return sfail(s, RIG_EESTOP, "stage refused %s: emergency stop", cmd);
    default: return sfail(s, RIG_EPROTO, "stage refused %s: result code %u", cmd, res);
    }
}

/* Write a command (with the target first for a move) and check it was
 * taken: the move counter advanced (a retried write may count twice) and
 * the result register says so. before: the move counter read just before
 * (NULL: read it here). */
static int command(hal_stage_t *s, uint16_t cmd, const int32_t *tgt, const uint16_t *before,
                   const char *name)
{
    uint16_t b0, after[2], w[5];
    int rc;
    if (!before) {
        if ((rc = rd(s, STG_MOVES, 1, &b0, "reading the move counter")))
            return rc;
        before = &b0;
    }
    if (tgt) {
        put32(w + STG_TARGET_X, tgt[0]);
        put32(w + STG_TARGET_Y, tgt[1]);
        w[STG_COMMAND] = cmd;
        rc = wr(s, STG_TARGET_X, 5, w, "writing target and move command");
    } else
        rc = wr(s, STG_COMMAND, 1, &cmd, "writing a command");
    if (rc)
        return rc;
    if ((rc = rd(s, STG_MOVES, 2, after, "reading the command result")))
        return rc;
    if ((rc = result_error(s, after[1], name)))
        return rc;
    if ((cmd == STG_CMD_MOVE || cmd == STG_CMD_HOME) && after[0] == *before)
        return sfail(s, RIG_EPROTO, "stage did not take %s (move counter stays %u)", name,
                     after[0]);
    return RIG_OK;
}

/* The stop after a timeout: best effort, the timeout is the error. */
static int timed_out(hal_stage_t *s, const char *what, int timeout_ms, unsigned st)
{
    uint16_t stop = STG_CMD_STOP;
    hal_write_regs(s->h, STG_COMMAND, 1, &stop);
    return sfail(s, RIG_ETIMEOUT, "stage: %s not done in %d ms (status 0x%02x); stopped", what,
                 timeout_ms, st);
}

/* A stop asked (abort, watchdog): STOP sent, RIG_EABORTED; else RIG_OK. */
static int stop_asked(hal_stage_t *s, const char *what)
{
    if (!s->should_stop || !s->should_stop(s->stop_ctx))
        return RIG_OK;
    uint16_t stop = STG_CMD_STOP;
    hal_write_regs(s->h, STG_COMMAND, 1, &stop);
    return sfail(s, RIG_EABORTED, "stage: %s stopped on request", what);
}

/* Sleep ms in slices of at most 20 ms that see a stop request. */
static int sleep_watching(hal_stage_t *s, double ms, const char *what)
{
    double t_end = hal_now_ms() + ms;
    for (;;) {
        int rc = stop_asked(s, what);
        double left = t_end - hal_now_ms();
        if (rc || left <= 0)
            return rc;
        hal_sleep_ms(left < 20 ? left : 20);
    }
}

/* Poll until the bits in want are set and BUSY clear, a fault, or timeout. */
static int wait_for(hal_stage_t *s, unsigned want, double first_wait_ms, int timeout_ms,
                    const char *what)
{
    double t_end = hal_now_ms() + timeout_ms, t_poll = hal_now_ms() + first_wait_ms;
    for (;;) {
        int rc = stop_asked(s, what);
        if (rc)
            return rc;
        double left = t_poll - hal_now_ms();
        if (left > 0) { /* the wait before polling, in slices that see a stop */
            hal_sleep_ms(left < 20 ? left : 20);
            continue;
        }
        uint16_t st;
        rc = rd(s, STG_STATUS, 1, &st, "reading status");
        if (rc)
            return rc;
        if ((rc = status_error(s, st, what)))
            return rc;
        if ((st & want) == want && !(st & RIG_ST_BUSY))
            return RIG_OK;
        if (hal_now_ms() >= t_end)
            return timed_out(s, what, timeout_ms, st);
        hal_sleep_ms(s->poll_ms);
    }
}

/* Wait for the end of a move to tgt (mm) commanded at t_cmd (ms) and
 * expected to take est ms. Sleep to the expected arrival, then read status
 * and position in one request: while busy, sleep the travel the position
 * says is left (at speed), and once there (settling) poll 0.25 ms, doubling
 * to poll_ms. So a move costs its travel plus about one round trip, not a
 * multiple of the polling interval; the position that comes with the final
 * status is the one checked and kept for st_position. */
static int wait_move(hal_stage_t *s, const double tgt[2], double t_cmd, double est, int timeout_ms)
{
    double t_end = t_cmd + timeout_ms, settle = 0.25;
    int rc = sleep_watching(s, t_cmd + est - hal_now_ms(), "move");
    if (rc)
        return rc;
    for (;;) {
        uint16_t r[5];
        rc = rd(s, STG_STATUS, 5, r, "reading status and position");
        if (rc || (rc = status_error(s, r[0], "move")))
            return rc;
        double px = get32(r + 1) * 1e-3, py = get32(r + 3) * 1e-3;
        if ((r[0] & RIG_ST_INPOS) && !(r[0] & RIG_ST_BUSY)) {
            if (fabs(px - tgt[0]) > s->tol_mm || fabs(py - tgt[1]) > s->tol_mm)
                return sfail(s, RIG_EPROTO,
                             "stage: in position at (%.4f, %.4f), asked (%.4f, %.4f)", px, py,
                             tgt[0], tgt[1]);
            s->at[0] = px;
            s->at[1] = py;
            s->at_valid = 1;
            return RIG_OK;
        }
        double now = hal_now_ms();
        if (now >= t_end)
            return timed_out(s, "move", timeout_ms, r[0]);
        double left = 1e3 * fmax(fabs(tgt[0] - px), fabs(tgt[1] - py)) / s->speed;
        if (left >= 0.25) { /* a stale speed costs <= 0.1 s */
            if ((rc = sleep_watching(s, fmin(fmin(left, 100.0), t_end - now), "move")))
                return rc;
        } else {
            if ((rc = stop_asked(s, "move")))
                return rc;
            hal_sleep_ms(settle);
            settle = fmin(2 * settle, s->poll_ms);
        }
    }
}

static int st_status(void *ctx, uint32_t *bits)
{
    hal_stage_t *s = ctx;
    uint16_t st;
    if (!s || !bits)
        return RIG_EARG;
    s->at_valid = 0;
    int rc = rd(s, STG_STATUS, 1, &st, "reading status");
    if (!rc)
        *bits = st;
    return rc;
}

static int st_position(void *ctx, double *x, double *y)
{
    hal_stage_t *s = ctx;
    uint16_t r[4];
    if (!s || !x || !y)
        return RIG_EARG;
    if (s->at_valid) {
        /* Asked right after a move: the stage said this position together
         * with "in position, not busy", and nothing was sent since. */
        s->at_valid = 0;
        *x = s->at[0];
        *y = s->at[1];
        return RIG_OK;
    }
    int rc = rd(s, STG_POS_X, 4, r, "reading position");
    if (rc)
        return rc;
    *x = get32(r) * 1e-3;
    *y = get32(r + 2) * 1e-3;
    return RIG_OK;
}

static int st_home(void *ctx)
{
    hal_stage_t *s = ctx;
    if (!s)
        return RIG_EARG;
    s->at_valid = 0;
    uint16_t st;
    int rc = rd(s, STG_STATUS, 1, &st, "reading status");
    if (rc || (rc = status_error(s, st, "before homing")))
        return rc;
    if ((rc = command(s, STG_CMD_HOME, NULL, NULL, "homing")))
        return rc;
    return wait_for(s, RIG_ST_HOMED | RIG_ST_INPOS, 0, s->home_timeout_ms, "homing");
}

static int st_move_to(void *ctx, double x, double y)
{
    hal_stage_t *s = ctx;
    if (!s || !isfinite(x) || !isfinite(y))
        return s ? sfail(s, RIG_EARG, "stage: target not finite") : RIG_EARG;
    s->at_valid = 0;
    if (x < s->lo[0] || x > s->hi[0] || y < s->lo[1] || y > s->hi[1])
        return sfail(s, RIG_ELIMIT,
                     "stage: target (%g, %g) outside soft limits [%g, %g] x [%g, %g]", x, y,
                     s->lo[0], s->hi[0], s->lo[1], s->hi[1]);
    /* Status, position and move counter in one request (registers 5-20). */
    uint16_t r[STG_MOVES - STG_STATUS + 1];
    int rc = rd(s, STG_STATUS, STG_MOVES - STG_STATUS + 1, r, "reading status and position");
    if (rc || (rc = status_error(s, r[0], "before the move")))
        return rc;
    if (!(r[0] & RIG_ST_HOMED))
        return sfail(s, RIG_ENOTHOMED, "stage: move to (%g, %g) asked before homing", x, y);
    double px = get32(r + 1) * 1e-3, py = get32(r + 3) * 1e-3;
    int32_t tgt[2] = {(int32_t)lround(x * 1e3), (int32_t)lround(y * 1e3)};
    double t_cmd = hal_now_ms();
    if ((rc = command(s, STG_CMD_MOVE, tgt, &r[STG_MOVES - STG_STATUS], "the move")))
        return rc;
    /* The wait counts from the command: the result check above was
     * made while the stage travelled. */
    double est = 1e3 * fmax(fabs(x - px), fabs(y - py)) / s->speed;
    /* A far target at a slow reported speed must not overflow the int (fuzz_modbus). */
    int tmo = s->move_timeout_ms > 0 ? s->move_timeout_ms : (int)fmin(3 * est + 2000, INT_MAX);
    double to[2] = {x, y};
    return wait_move(s, to, t_cmd, est, tmo);
}

/* On the fly: the same checked command as st_move_to (limits, homed, the
 * move counter and result), without the wait; the caller polls the status
 * between its stream reads (BUSY clears at the target, FAULT on a fault). */
int hal_stage_move_start(hal_stage_t *s, double x, double y)
{
    if (!s || !isfinite(x) || !isfinite(y))
        return s ? sfail(s, RIG_EARG, "stage: target not finite") : RIG_EARG;
    s->at_valid = 0;
    if (x < s->lo[0] || x > s->hi[0] || y < s->lo[1] || y > s->hi[1])
        return sfail(s, RIG_ELIMIT,
                     "stage: target (%g, %g) outside soft limits [%g, %g] x [%g, %g]", x, y,
                     s->lo[0], s->hi[0], s->lo[1], s->hi[1]);
    uint16_t r[STG_MOVES - STG_STATUS + 1];
    int rc = rd(s, STG_STATUS, STG_MOVES - STG_STATUS + 1, r, "reading status and position");
    if (rc || (rc = status_error(s, r[0], "before the move")))
        return rc;
    if (!(r[0] & RIG_ST_HOMED))
        return sfail(s, RIG_ENOTHOMED, "stage: move to (%g, %g) asked before homing", x, y);
    int32_t tgt[2] = {(int32_t)lround(x * 1e3), (int32_t)lround(y * 1e3)};
    return command(s, STG_CMD_MOVE, tgt, &r[STG_MOVES - STG_STATUS], "the move");
}

int hal_stage_set_speed(hal_stage_t *s, double mm_s)
{
    if (!s || !(mm_s >= 1 && mm_s <= 65535))
        return s ? sfail(s, RIG_EARG, "stage: speed %g mm/s outside 1..65535", mm_s) : RIG_EARG;
    uint16_t v = (uint16_t)lround(mm_s);
    int rc = wr(s, STG_SPEED, 1, &v, "writing the speed");
    if (!rc)
        s->speed = v;
    return rc;
}

static int st_stop(void *ctx)
{
    hal_stage_t *s = ctx;
    uint16_t c = STG_CMD_STOP;
    if (!s)
        return RIG_EARG;
    s->at_valid = 0;
    return wr(s, STG_COMMAND, 1, &c, "writing stop");
}

static int st_reset_fault(void *ctx)
{
    hal_stage_t *s = ctx;
    if (!s)
        return RIG_EARG;
    s->at_valid = 0;
    uint16_t c = STG_CMD_RESET, res;
    int rc = wr(s, STG_COMMAND, 1, &c, "writing fault reset");
    if (rc || (rc = rd(s, STG_RESULT, 1, &res, "reading the reset result")))
        return rc;
    return result_error(s, res, "the fault reset");
}

static int st_limits(void *ctx, double lo[2], double hi[2])
{
    hal_stage_t *s = ctx;
    if (!s || !lo || !hi)
        return RIG_EARG;
    lo[0] = s->lo[0];
    lo[1] = s->lo[1];
    hi[0] = s->hi[0];
    hi[1] = s->hi[1];
    return RIG_OK;
}

const rig_stage_ops_t hal_stage_ops = {
    .version = RIG_OPS_VERSION,
    .home = st_home,
    .move_to = st_move_to,
    .position = st_position,
    .status = st_status,
    .stop = st_stop,
    .reset_fault = st_reset_fault,
    .limits = st_limits,
};
