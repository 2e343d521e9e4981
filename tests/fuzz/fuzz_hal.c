/* SPDX-License-Identifier: MIT */
/* fuzz_hal.c: the fake transport and virtual clock of fuzz_hal.h. */
#include "fuzz_hal.h"
#include "fuzz.h"
#include "hal_priv.h"
#include <stdio.h>
#include <string.h>

double __wrap_hal_now_ms(void);
void __wrap_hal_sleep_ms(double ms);

double __wrap_hal_now_ms(void)
{
    fz_clock_ms += 0.001; /* time moves, if slowly, between two looks */
    return fz_clock_ms;
}

void __wrap_hal_sleep_ms(double ms)
{
    if (ms > 0)
        fz_clock_ms += ms;
}

static int more(const fz_hal_t *f)
{
    return f->at < f->n;
}

unsigned fz_hal_byte(fz_hal_t *f)
{
    return more(f) ? f->d[f->at++] : 0;
}

static int f_write(hal_t *h, const void *buf, size_t n)
{
    (void)buf;
    (void)n;
    return more((fz_hal_t *)h) ? RIG_OK : RIG_EDISCONNECT;
}

static int f_read(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got)
{
    fz_hal_t *f = (fz_hal_t *)h;
    *got = 0;
    if (!more(f))
        return RIG_EDISCONNECT;
    if (f->d[f->at] == 0xFF) {
        f->at++;
        fz_clock_ms += timeout_ms > 0 ? timeout_ms : 1;
        return RIG_ETIMEOUT;
    }
    while (*got < n && more(f) && f->d[f->at] != 0xFF)
        ((uint8_t *)buf)[(*got)++] = f->d[f->at++];
    return RIG_OK;
}

static int f_flush(hal_t *h)
{
    (void)h;
    return RIG_OK;
}

static const int f_errs[4] = {RIG_ETIMEOUT, RIG_ECRC, RIG_EEXCEPTION, RIG_EPROTO};

static int f_read_regs(hal_t *h, char kind, int addr, int n, uint16_t *dst)
{
    fz_hal_t *f = (fz_hal_t *)h;
    (void)kind;
    (void)addr;
    if (!more(f))
        return RIG_EDISCONNECT;
    unsigned c = fz_hal_byte(f);
    if (c < 16) /* one read in 16 fails on the wire */
        return hal_fail(h, f_errs[c % 4], "fuzz: transport error %u", c);
    for (int k = 0; k < n; k++) {
        unsigned hi = fz_hal_byte(f);
        dst[k] = (uint16_t)(hi << 8 | fz_hal_byte(f));
    }
    return RIG_OK;
}

static int f_write_regs(hal_t *h, int addr, int n, const uint16_t *src)
{
    fz_hal_t *f = (fz_hal_t *)h;
    (void)addr;
    (void)n;
    (void)src;
    if (!more(f))
        return RIG_EDISCONNECT;
    unsigned c = fz_hal_byte(f);
    return c < 16 ? hal_fail(h, f_errs[c % 4], "fuzz: transport error %u", c) : RIG_OK;
}

/* USB: a length byte, then that many bytes (at most len go to data). */
static int f_xfer(fz_hal_t *f, uint8_t *data, size_t len, size_t *got)
{
    if (!more(f))
        return RIG_EDISCONNECT;
    unsigned k = fz_hal_byte(f);
    if (k == 0xFF)
        return RIG_ETIMEOUT;
    size_t n = 0;
    for (unsigned i = 0; i < k && more(f); i++) {
        uint8_t b = (uint8_t)fz_hal_byte(f);
        if (n < len && data)
            data[n++] = b;
    }
    if (got)
        *got = n;
    return RIG_OK;
}

static int f_control(hal_t *h, uint8_t req_type, uint8_t req, uint16_t val, uint16_t idx,
                     void *data, uint16_t len, size_t *got)
{
    (void)req;
    (void)val;
    (void)idx;
    if (!(req_type & 0x80)) /* OUT: the box takes it or the line is gone */
        return more((fz_hal_t *)h) ? RIG_OK : RIG_EDISCONNECT;
    return f_xfer((fz_hal_t *)h, data, len, got);
}

static int f_bulk(hal_t *h, uint8_t ep, void *data, size_t len, size_t *got)
{
    (void)ep;
    return f_xfer((fz_hal_t *)h, data, len, got);
}

static const hal_ops_t f_stream_ops = {
    RIG_OPS_VERSION, "fuzz-stream", NULL, f_write, f_read, f_flush, NULL, NULL, NULL, NULL, NULL};
static const hal_ops_t f_regs_ops = {RIG_OPS_VERSION, "fuzz-modbus", NULL, NULL, NULL, NULL,
                                     f_read_regs,     f_write_regs,  NULL, NULL, NULL};
static const hal_ops_t f_usb_ops = {RIG_OPS_VERSION, "fuzz-usb", NULL, NULL, NULL, NULL, NULL, NULL,
                                    f_control,       f_bulk,     NULL};

void fz_hal_init(fz_hal_t *f, hal_kind_t kind, const uint8_t *data, size_t size)
{
    memset(f, 0, sizeof *f);
    f->h.ops = kind == HAL_TCP ? &f_regs_ops : kind == HAL_USB ? &f_usb_ops : &f_stream_ops;
    f->h.uri.kind = kind;
    snprintf(f->h.uri.path, sizeof f->h.uri.path, "fuzz");
    f->h.opts.timeout_ms = 50;
    f->h.opts.retries = 2;
    f->h.opts.backoff_ms = 20;
    f->h.opts.reconnect_ms = 100;
    f->h.opts.byte_timeout_ms = 5;
    f->h.opts.late_ms = 50;
    f->d = data;
    f->n = size;
}
