/* SPDX-License-Identifier: MIT */
/* hal_modbus.c: Modbus RTU and TCP backend (libmodbus): timeouts from
 * hal_opts, bounded retries with exponential backoff, late replies waited
 * out and flushed after a timeout, and reconnection done here by closing
 * and reopening the line (libmodbus's MODBUS_ERROR_RECOVERY_LINK hangs on
 * a dropped RTU line). See /work/shared/HARDWARE-TESTING.md for the faults
 * and what libmodbus returns for each. */
#include "hal.h"
#include "hal_priv.h"
#include <errno.h>
#include <modbus.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct hal_mb {
    struct hal base;
    modbus_t *ctx;
    int up; /* connected: a lost line is closed and reopened before the next request */
} hal_mb_t;

int hal_modbus_errcode(int err)
{
    if (err == ETIMEDOUT)
        return RIG_ETIMEOUT;
    if (err == EMBBADCRC)
        return RIG_ECRC;
    if (err >= EMBXILFUN && err <= EMBXGTAR)
        return RIG_EEXCEPTION;
    if (err == EMBBADDATA || err == EMBBADEXC || err == EMBUNKEXC || err == EMBMDATA ||
        err == EMBBADSLAVE)
        return RIG_EPROTO;
    if (err == EINVAL)
        return RIG_EARG;
    /* EIO, ECONNRESET, EBADF, EPIPE, ENOENT, ECONNREFUSED and whatever else
     * a read or write on the line returns: reopening is the cure. */
    return RIG_EDISCONNECT;
}

static void mb_timeouts(hal_mb_t *m)
{
    const hal_opts_t *o = &m->base.opts;
    modbus_set_response_timeout(m->ctx, (uint32_t)(o->timeout_ms / 1000),
                                (uint32_t)(o->timeout_ms % 1000) * 1000u);
    modbus_set_byte_timeout(m->ctx, (uint32_t)(o->byte_timeout_ms / 1000),
                            (uint32_t)(o->byte_timeout_ms % 1000) * 1000u);
}

/* One connect; a stale reply left in a pty by an earlier session must not
 * answer our first request, hence the flush. */
static int mb_connect(hal_mb_t *m)
{
    if (modbus_connect(m->ctx) == -1)
        return -1;
    modbus_flush(m->ctx);
    m->up = 1;
    return 0;
}

static const char *mb_where(const hal_mb_t *m, char *buf, size_t len)
{
    const hal_uri_t *u = &m->base.uri;
    if (u->kind == HAL_TCP)
        snprintf(buf, len, "tcp:%s:%d unit %d", u->path, u->port, u->unit);
    else
        snprintf(buf, len, "rtu:%s slave %d", u->path, u->unit);
    return buf;
}

/* Close and keep reopening the line for reconnect_ms. */
static int mb_reconnect(hal_t *h)
{
    hal_mb_t *m = (hal_mb_t *)h;
    char where[300];
    modbus_close(m->ctx);
    m->up = 0;
    h->reconnects++;
    double t_end = hal_now_ms() + h->opts.reconnect_ms;
    int wait = h->opts.backoff_ms > 0 ? h->opts.backoff_ms : 10;
    for (;;) {
        if (mb_connect(m) == 0)
            return RIG_OK;
        int e = errno;
        if (hal_stopped(h)) /* an abort does not wait for the line to come back */
            return hal_fail(h, RIG_EABORTED, "%s: line lost, reopening given up: stop asked",
                            mb_where(m, where, sizeof where));
        double left = t_end - hal_now_ms();
        if (left <= 0)
            return hal_fail(h, RIG_EDISCONNECT, "%s: line lost, reopening failed for %d ms: %s",
                            mb_where(m, where, sizeof where), h->opts.reconnect_ms,
                            modbus_strerror(e));
        if (hal_wait_ms(h, wait < left ? wait : left))
            return hal_fail(h, RIG_EABORTED, "%s: line lost, reopening given up: stop asked",
                            mb_where(m, where, sizeof where));
        wait = wait * 2 > 200 ? 200 : wait * 2;
    }
}

enum { MB_RD_H, MB_RD_I, MB_WR };

/* One request, no recovery: libmodbus's result and errno. */
static int mb_once(hal_mb_t *m, int op, int addr, int n, uint16_t *regs)
{
    if (op == MB_RD_H)
        return modbus_read_registers(m->ctx, addr, n, regs);
    if (op == MB_RD_I)
        return modbus_read_input_registers(m->ctx, addr, n, regs);
    if (n == 1) /* function 06: simple devices lack 16 for one register */
        return modbus_write_register(m->ctx, addr, regs[0]) == 1 ? 1 : -1;
    return modbus_write_registers(m->ctx, addr, n, regs);
}

/* A request with the recovery hal.h promises: retries for timeouts, bad
 * frames and a busy device, reconnection for a lost line; a device's
 * refusal (exception other than busy) and caller errors are not retried. */
static int mb_request(hal_mb_t *m, int op, int addr, int n, uint16_t *regs)
{
    hal_t *h = &m->base;
    const char *what = op == MB_RD_H   ? "reading holding"
                       : op == MB_RD_I ? "reading input"
                                       : "writing";
    char where[300];
    int backoff = h->opts.backoff_ms, relinks = 0;
    int rc0 = hal_stop_before(h); /* a device already found hung under this stop */
    if (rc0)
        return rc0;
    for (int attempt = 0;; attempt++) {
        if (!m->up) {
            int rc = mb_reconnect(h);
            if (rc)
                return rc;
        }
        errno = 0;
        int got = mb_once(m, op, addr, n, regs);
        if (got == n)
            return RIG_OK;
        int e = got < 0 ? errno : EMBBADDATA;
        int code = hal_modbus_errcode(e);
        hal_fail(h, code, "%s: %s %d register%s at %d: %s (attempt %d of %d)",
                 mb_where(m, where, sizeof where), what, n, n == 1 ? "" : "s", addr,
                 modbus_strerror(e), attempt + 1, h->opts.retries + 1);
        if (code == RIG_EARG || (code == RIG_EEXCEPTION && e != EMBXSBUSY))
            return code;
        int stopped = hal_stop_after(h, code); /* an abort waits for no retry */
        if (stopped) {
            modbus_flush(m->ctx);
            return stopped;
        }
        if (code == RIG_ETIMEOUT) {
            /* The reply may still be on its way: let it arrive and drop it,
             * or it would answer the next request (off by one ever after). */
            if (hal_wait_ms(h, h->opts.late_ms)) {
                modbus_flush(m->ctx);
                return hal_stop_after(h, code);
            }
            modbus_flush(m->ctx);
        } else if (code == RIG_ECRC || code == RIG_EPROTO) {
            hal_sleep_ms(h->opts.byte_timeout_ms); /* the rest of a broken frame */
            modbus_flush(m->ctx);
        } else if (code == RIG_EDISCONNECT) {
            int rc = mb_reconnect(h);
            if (rc) {
                char lost[256];
                snprintf(lost, sizeof lost, "%s", h->err);
                return hal_fail(h, rc, "%s after %s", lost, modbus_strerror(e));
            }
            /* Back on the line: this attempt does not count against the
             * retries, a few times over (a line that keeps dropping fails). */
            if (++relinks <= 3)
                attempt--;
        }
        if (attempt >= h->opts.retries)
            return code;
        if (getenv("HAL_DEBUG"))
            fprintf(stderr, "hal: %s\n", h->err);
        h->retries++;
        if (hal_wait_ms(h, backoff))
            return hal_stop_after(h, code);
        backoff = backoff * 2 > 2000 ? 2000 : backoff * 2;
    }
}

static int mb_read_regs(hal_t *h, char kind, int addr, int n, uint16_t *dst)
{
    return mb_request((hal_mb_t *)h, kind == 'i' ? MB_RD_I : MB_RD_H, addr, n, dst);
}

static int mb_write_regs(hal_t *h, int addr, int n, const uint16_t *src)
{
    uint16_t tmp[128];
    memcpy(tmp, src, (size_t)n * sizeof *src); /* libmodbus takes a non-const table */
    return mb_request((hal_mb_t *)h, MB_WR, addr, n, tmp);
}

static int mb_flush(hal_t *h)
{
    hal_mb_t *m = (hal_mb_t *)h;
    if (m->up && modbus_flush(m->ctx) == -1)
        return hal_fail(h, RIG_EDISCONNECT, "%s: flush: %s", h->uri.path, modbus_strerror(errno));
    return RIG_OK;
}

static void mb_close(hal_t *h)
{
    hal_mb_t *m = (hal_mb_t *)h;
    modbus_close(m->ctx);
    modbus_free(m->ctx);
    free(m);
}

static const hal_ops_t mb_ops = {
    .version = RIG_OPS_VERSION,
    .name = "modbus",
    .close = mb_close,
    .flush = mb_flush,
    .read_regs = mb_read_regs,
    .write_regs = mb_write_regs,
    .reconnect = mb_reconnect,
};

int hal_modbus_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len)
{
    if (!u || !h || (u->kind != HAL_RTU && u->kind != HAL_TCP))
        return RIG_EARG;
    *h = NULL;
    hal_mb_t *m = calloc(1, sizeof *m);
    if (!m)
        return RIG_EOPEN;
    m->base.ops = &mb_ops;
    m->base.uri = *u;
    hal_opts_fill(&m->base.opts, o);
    if (u->kind == HAL_TCP) {
        char port[16];
        snprintf(port, sizeof port, "%d", u->port);
        m->ctx = modbus_new_tcp_pi(u->path, port);
    } else
        m->ctx = modbus_new_rtu(u->path, u->baud, u->parity, u->data_bits, u->stop_bits);
    char where[300];
    mb_where(m, where, sizeof where);
    if (!m->ctx) {
        if (msg && len)
            snprintf(msg, len, "%s: %s", where, modbus_strerror(errno));
        free(m);
        return RIG_EOPEN;
    }
    modbus_set_error_recovery(m->ctx, MODBUS_ERROR_RECOVERY_NONE);
    mb_timeouts(m);
    if (modbus_set_slave(m->ctx, u->unit) == -1 || mb_connect(m) == -1) {
        if (msg && len)
            snprintf(msg, len, "%s: cannot open: %s", where, modbus_strerror(errno));
        modbus_free(m->ctx);
        free(m);
        return RIG_EOPEN;
    }
    *h = &m->base;
    return RIG_OK;
}
