/* SPDX-License-Identifier: MIT */
/* hal.c: hal_open dispatch on the URI scheme, and the hal_* calls, which
 * answer RIG_EUNSUPPORTED for an operation the backend's wire lacks. */
#include "hal.h"
#include "hal_priv.h"
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* Built by another part of the tree (libserialport, libusb) and perhaps not
 * in this build: weak, so their absence links and reads as a null address. */
extern int hal_serial_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg,
                           size_t len) __attribute__((weak));
extern int hal_usb_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len)
    __attribute__((weak));

typedef int (*hal_ctor_t)(const hal_uri_t *, const hal_opts_t *, hal_t **, char *, size_t);

/* Defaults for fields left 0 (an older initializer, or a caller's memset). */
void hal_opts_fill(hal_opts_t *o, const hal_opts_t *in)
{
    const hal_opts_t def = HAL_OPTS_DEFAULT;
    *o = in ? *in : def;
    if (o->timeout_ms <= 0)
        o->timeout_ms = def.timeout_ms;
    if (o->retries < 0)
        o->retries = 0;
    if (o->backoff_ms < 0)
        o->backoff_ms = 0;
    if (o->reconnect_ms < 0)
        o->reconnect_ms = 0;
    if (o->byte_timeout_ms <= 0)
        o->byte_timeout_ms = def.byte_timeout_ms;
    if (o->late_ms <= 0)
        o->late_ms = o->timeout_ms;
}

int hal_open(const char *uri, const hal_opts_t *opts, hal_t **h, char *msg, size_t msglen)
{
    if (msg && msglen)
        msg[0] = '\0';
    if (!h)
        return RIG_EARG;
    *h = NULL;
    hal_uri_t u;
    int rc = hal_uri_parse(uri, &u, msg, msglen);
    if (rc)
        return rc;
    hal_opts_t o;
    hal_opts_fill(&o, opts);
    hal_ctor_t ctor = NULL;
    switch (u.kind) {
    case HAL_RTU:
    case HAL_TCP: ctor = hal_modbus_open; break;
    case HAL_TTY: ctor = hal_tty_open; break;
    case HAL_SERIAL: ctor = hal_serial_open; break;
    case HAL_USB: ctor = hal_usb_open; break;
    case HAL_GEV: break; /* not a byte or register transport: hal_gev_open */
    }
    if (!ctor) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s: backend not built (%s)", uri,
                     u.kind == HAL_USB   ? "libusb"
                     : u.kind == HAL_GEV ? "a profiler: hal_gev_open"
                                         : "libserialport");
        return RIG_EUNSUPPORTED;
    }
    return ctor(&u, &o, h, msg, msglen);
}

int hal_fail(hal_t *h, int code, const char *fmt, ...)
{
    if (h) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(h->err, sizeof h->err, fmt, ap);
        va_end(ap);
    }
    return code;
}

double hal_now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

void hal_sleep_ms(double ms)
{
    if (ms <= 0)
        return;
    struct timespec t = {(time_t)(ms / 1e3), (long)((ms - 1e3 * (double)(time_t)(ms / 1e3)) * 1e6)};
    while (nanosleep(&t, &t) && errno == EINTR)
        ;
}

void hal_close(hal_t *h)
{
    if (h && h->ops && h->ops->close)
        h->ops->close(h);
}

const char *hal_last_error(const hal_t *h)
{
    return h ? h->err : "no device";
}

/* An operation the wire does not have: say which, keep it as the detail. */
static int unsupported(hal_t *h, const char *what)
{
    return hal_fail(h, RIG_EUNSUPPORTED, "%s: %s not supported by the %s backend", h->uri.path,
                    what, h->ops && h->ops->name ? h->ops->name : "?");
}

#define HAL_HAS(h, op) ((h) && (h)->ops && (h)->ops->op)

int hal_write(hal_t *h, const void *buf, size_t n)
{
    if (!HAL_HAS(h, write))
        return h ? unsupported(h, "write") : RIG_EARG;
    if (!buf && n)
        return RIG_EARG;
    return h->ops->write(h, buf, n);
}

int hal_read(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got)
{
    if (!HAL_HAS(h, read))
        return h ? unsupported(h, "read") : RIG_EARG;
    if ((!buf && n) || !got)
        return RIG_EARG;
    *got = 0;
    return h->ops->read(h, buf, n, timeout_ms, got);
}

int hal_flush(hal_t *h)
{
    if (!HAL_HAS(h, flush))
        return h ? unsupported(h, "flush") : RIG_EARG;
    return h->ops->flush(h);
}

int hal_read_regs(hal_t *h, char kind, int addr, int n, uint16_t *dst)
{
    if (!HAL_HAS(h, read_regs))
        return h ? unsupported(h, "register read") : RIG_EARG;
    if ((kind != 'h' && kind != 'i') || addr < 0 || addr > 65535 || n < 1 || n > 125 ||
        addr + n > 65536 || !dst)
        return RIG_EARG;
    return h->ops->read_regs(h, kind, addr, n, dst);
}

int hal_write_regs(hal_t *h, int addr, int n, const uint16_t *src)
{
    if (!HAL_HAS(h, write_regs))
        return h ? unsupported(h, "register write") : RIG_EARG;
    if (addr < 0 || addr > 65535 || n < 1 || n > 123 || addr + n > 65536 || !src)
        return RIG_EARG;
    return h->ops->write_regs(h, addr, n, src);
}

int hal_control(hal_t *h, uint8_t req_type, uint8_t req, uint16_t val, uint16_t idx, void *data,
                uint16_t len, size_t *got)
{
    if (!HAL_HAS(h, control))
        return h ? unsupported(h, "control transfer") : RIG_EARG;
    if ((!data && len) || !got)
        return RIG_EARG;
    return h->ops->control(h, req_type, req, val, idx, data, len, got);
}

int hal_reconnect(hal_t *h)
{
    if (!HAL_HAS(h, reconnect))
        return h ? unsupported(h, "reconnect") : RIG_EARG;
    return h->ops->reconnect(h);
}

int hal_bulk(hal_t *h, uint8_t ep, void *data, size_t len, size_t *got)
{
    if (!HAL_HAS(h, bulk))
        return h ? unsupported(h, "bulk transfer") : RIG_EARG;
    if ((!data && len) || !got)
        return RIG_EARG;
    return h->ops->bulk(h, ep, data, len, got);
}
