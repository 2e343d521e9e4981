/* SPDX-License-Identifier: MIT */
/* hal_usb.c: the usb: backend on libusb: open by VID:PID (and serial
 * number), claim interface 0, control and bulk transfers with the
 * transport's timeout. A device gone (NO_DEVICE) is looked for again and
 * reopened for up to opts.reconnect_ms, then reported as RIG_EDISCONNECT. */
#include "hal_usb.h"
#include "hal_dl.h"
#include "hal_dl_libs.h"
#include <libusb.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* libusb, loaded by the first usb: open (hal_dl.h): cellfit maps it only
 * for a rig with USB parts. */
/* clang-format off */
#define USB_SYMS(X) \
    X(libusb_init) \
    X(libusb_exit) \
    X(libusb_get_device_list) \
    X(libusb_free_device_list) \
    X(libusb_get_device_descriptor) \
    X(libusb_open) \
    X(libusb_close) \
    X(libusb_get_string_descriptor_ascii) \
    X(libusb_claim_interface) \
    X(libusb_release_interface) \
    X(libusb_clear_halt) \
    X(libusb_control_transfer) \
    X(libusb_bulk_transfer) \
    X(libusb_error_name) \
    X(libusb_strerror)
/* clang-format on */
HAL_DL_TABLE(usb, USB_SYMS)
static hal_dl_t usb_lib = HAL_DL_LIB(usb, HAL_DL_SONAME_USB, HAL_DL_PACKAGE_USB, "a usb: device");

typedef struct hal_usb {
    struct hal base;
    libusb_context *ctx;
    libusb_device_handle *dev; /* NULL while the device is gone */
} hal_usb_t;

int hal_usb_err(int e)
{
    switch (e) {
    case LIBUSB_SUCCESS: return RIG_OK;
    case LIBUSB_ERROR_TIMEOUT: return RIG_ETIMEOUT;
    case LIBUSB_ERROR_NO_DEVICE: return RIG_EDISCONNECT;
    case LIBUSB_ERROR_PIPE: return RIG_EEXCEPTION;
    case LIBUSB_ERROR_OVERFLOW: return RIG_EPROTO;
    case LIBUSB_ERROR_INVALID_PARAM: return RIG_EARG;
    case LIBUSB_ERROR_NOT_SUPPORTED: return RIG_EUNSUPPORTED;
    case LIBUSB_ERROR_NOT_FOUND:
    case LIBUSB_ERROR_ACCESS:
    case LIBUSB_ERROR_BUSY: return RIG_EOPEN;
    case LIBUSB_ERROR_IO:
    case LIBUSB_ERROR_INTERRUPTED:
    case LIBUSB_ERROR_NO_MEM:
    case LIBUSB_ERROR_OTHER:
    default: return RIG_EIO;
    }
}

static int fail(struct hal *h, const char *what, int e)
{
    snprintf(h->err, sizeof h->err, "usb %04x:%04x %s: %s (%s)", h->uri.vid, h->uri.pid, what,
             usb.libusb_error_name(e), usb.libusb_strerror((enum libusb_error)e));
    return hal_usb_err(e);
}

static void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static void drop(hal_usb_t *s)
{
    if (s->dev) {
        usb.libusb_release_interface(s->dev, 0);
        usb.libusb_close(s->dev);
        s->dev = NULL;
    }
}

/* Does the open handle's serial number match the one asked for? */
static int serial_matches(libusb_device_handle *d, const struct libusb_device_descriptor *dd,
                          const char *want)
{
    unsigned char sn[128];
    if (!want[0])
        return 1;
    if (!dd->iSerialNumber)
        return 0;
    int n = usb.libusb_get_string_descriptor_ascii(d, dd->iSerialNumber, sn, sizeof sn);
    return n >= 0 && (size_t)n == strlen(want) && !memcmp(sn, want, (size_t)n);
}

/* Find the device the URI names, open it and claim interface 0. */
static int attach(hal_usb_t *s)
{
    struct hal *h = &s->base;
    libusb_device **list = NULL;
    if (!s->ctx) {
        snprintf(h->err, sizeof h->err, "usb: no libusb context");
        return RIG_EOPEN;
    }
    ssize_t n = usb.libusb_get_device_list(s->ctx, &list);
    if (n < 0)
        return fail(h, "list devices", (int)n);
    int rc = LIBUSB_ERROR_NOT_FOUND, seen = 0;
    for (ssize_t i = 0; i < n && !s->dev; i++) {
        struct libusb_device_descriptor dd;
        if (usb.libusb_get_device_descriptor(list[i], &dd) || dd.idVendor != h->uri.vid ||
            dd.idProduct != h->uri.pid)
            continue;
        seen++;
        libusb_device_handle *d = NULL;
        rc = usb.libusb_open(list[i], &d);
        if (rc)
            continue;
        if (!serial_matches(d, &dd, h->uri.serial)) {
            usb.libusb_close(d);
            rc = LIBUSB_ERROR_NOT_FOUND;
            continue;
        }
        rc = usb.libusb_claim_interface(d, 0);
        if (rc) {
            usb.libusb_close(d);
            continue;
        }
        s->dev = d;
    }
    usb.libusb_free_device_list(list, 1);
    if (s->dev)
        return RIG_OK;
    if (rc == LIBUSB_ERROR_NOT_FOUND) {
        snprintf(h->err, sizeof h->err, "usb %04x:%04x%s%s: %s", h->uri.vid, h->uri.pid,
                 h->uri.serial[0] ? " serial " : "", h->uri.serial,
                 seen ? "no device with that serial number" : "no such device");
        return RIG_EOPEN;
    }
    fail(h, "open", rc);
    return RIG_EOPEN;
}

static int usb_reconnect(hal_t *h)
{
    hal_usb_t *s = (hal_usb_t *)h;
    char why[sizeof h->err];
    snprintf(why, sizeof why, "%s", h->err);
    drop(s);
    double end = now_ms() + h->opts.reconnect_ms;
    int wait = h->opts.backoff_ms > 0 ? h->opts.backoff_ms : 20;
    for (;;) {
        /* A fresh context scans the bus again: the old one's device list
         * may still hold the device that left (or miss the one that came
         * back) when hotplug events do not arrive. */
        usb.libusb_exit(s->ctx);
        s->ctx = NULL;
        int e = usb.libusb_init(&s->ctx);
        if (e) {
            s->ctx = NULL;
            fail(h, "init", e);
        } else if (attach(s) == RIG_OK) {
            h->reconnects++;
            return RIG_OK;
        }
        double left = end - now_ms();
        if (left <= 0)
            break;
        if (hal_stopped(h)) { /* an abort does not wait for it to come back (hal.h) */
            snprintf(h->err, sizeof h->err, "device lost (%.100s); reopening given up: stop asked",
                     why);
            return RIG_EDISCONNECT;
        }
        sleep_ms(wait < left ? wait : (int)left + 1);
        wait = wait * 2 > 500 ? 500 : wait * 2;
    }
    char last[sizeof h->err];
    snprintf(last, sizeof last, "%s", h->err);
    snprintf(h->err, sizeof h->err, "device lost (%.100s); looking for it for %d ms: %.100s", why,
             h->opts.reconnect_ms, last);
    return RIG_EDISCONNECT;
}

/* After a failed transfer: NO_DEVICE reconnects (the transfer is not
 * repeated: the caller knows whether it is safe to), a stall clears the
 * halt so the next transfer can go. */
static int after_error(hal_usb_t *s, const char *what, int e, uint8_t ep)
{
    struct hal *h = &s->base;
    int rc = fail(h, what, e);
    if (e == LIBUSB_ERROR_NO_DEVICE) {
        if (usb_reconnect(h))
            return RIG_EDISCONNECT;
        snprintf(h->err, sizeof h->err, "usb %04x:%04x %s: device was lost and reopened",
                 h->uri.vid, h->uri.pid, what);
        return RIG_EDISCONNECT;
    }
    if (e == LIBUSB_ERROR_PIPE && ep)
        usb.libusb_clear_halt(s->dev, ep);
    return rc;
}

static int usb_control(hal_t *h, uint8_t req_type, uint8_t req, uint16_t val, uint16_t idx,
                       void *data, uint16_t len, size_t *got)
{
    hal_usb_t *s = (hal_usb_t *)h;
    if (got)
        *got = 0;
    if (!s->dev && usb_reconnect(h))
        return RIG_EDISCONNECT;
    int e = 0;
    /* Control requests are idempotent in our devices: a timeout is retried. */
    for (int a = 0; a <= h->opts.retries; a++) {
        if (a)
            h->retries++;
        e = usb.libusb_control_transfer(s->dev, req_type, req, val, idx, (unsigned char *)data, len,
                                        (unsigned)h->opts.timeout_ms);
        if (e >= 0) {
            if (got)
                *got = (size_t)e;
            return RIG_OK;
        }
        if (e != LIBUSB_ERROR_TIMEOUT)
            break;
    }
    char what[64];
    snprintf(what, sizeof what, "control %s request 0x%02x", (req_type & 0x80) ? "IN" : "OUT", req);
    return after_error(s, what, e, 0);
}

static int usb_bulk(hal_t *h, uint8_t ep, void *data, size_t len, size_t *got)
{
    hal_usb_t *s = (hal_usb_t *)h;
    int done = 0;
    if (got)
        *got = 0;
    if (len > 0x7fffffff)
        return RIG_EARG;
    if (!s->dev && usb_reconnect(h))
        return RIG_EDISCONNECT;
    int e = usb.libusb_bulk_transfer(s->dev, ep, (unsigned char *)data, (int)len, &done,
                                     (unsigned)h->opts.timeout_ms);
    if (got)
        *got = (size_t)done;
    if (e == 0)
        return RIG_OK;
    char what[64];
    snprintf(what, sizeof what, "bulk %s endpoint 0x%02x", (ep & 0x80) ? "IN" : "OUT", ep);
    if (e == LIBUSB_ERROR_TIMEOUT && done > 0 && (ep & 0x80))
        return RIG_OK; /* part of it came: the caller sees how much */
    return after_error(s, what, e, ep);
}

static void usb_close(hal_t *h)
{
    if (!h)
        return;
    hal_usb_t *s = (hal_usb_t *)h;
    drop(s);
    if (s->ctx)
        usb.libusb_exit(s->ctx);
    free(s);
}

static const hal_ops_t usb_ops = {
    .version = RIG_OPS_VERSION,
    .name = "usb",
    .close = usb_close,
    .control = usb_control,
    .bulk = usb_bulk,
    .reconnect = usb_reconnect,
};

int hal_usb_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **out, char *msg, size_t len)
{
    static const hal_opts_t defaults = HAL_OPTS_DEFAULT;
    if (!u || !out || u->kind != HAL_USB) {
        if (msg && len)
            snprintf(msg, len, "usb: need a usb:VID:PID URI");
        return RIG_EARG;
    }
    *out = NULL;
    if (hal_dl_load(&usb_lib)) {
        if (msg && len)
            snprintf(msg, len, "%s", hal_dl_error(&usb_lib));
        return RIG_EUNSUPPORTED;
    }
    hal_usb_t *s = calloc(1, sizeof *s);
    if (!s) {
        if (msg && len)
            snprintf(msg, len, "usb: out of memory");
        return RIG_EOPEN;
    }
    s->base.ops = &usb_ops;
    s->base.uri = *u;
    s->base.opts = o ? *o : defaults;
    int e = usb.libusb_init(&s->ctx);
    int rc = e ? fail(&s->base, "init", e) : attach(s);
    if (rc) {
        if (msg && len)
            snprintf(msg, len, "%s", s->base.err);
        usb_close(&s->base);
        return rc == RIG_EUNSUPPORTED ? rc : RIG_EOPEN;
    }
    *out = &s->base;
    return RIG_OK;
}
