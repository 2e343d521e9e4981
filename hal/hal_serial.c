/* SPDX-License-Identifier: MIT */
/* hal_serial.c: the serial: byte-stream backend on libserialport. Reads
 * and writes block with the transport's timeouts; a dropped line (write
 * EIO, sp_input_waiting failing) is reopened by name for up to
 * opts.reconnect_ms, then reported as RIG_EDISCONNECT. */
#include "hal_serial.h"
#include <errno.h>
#include <libserialport.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct hal_serial {
    struct hal base;
    struct sp_port *port; /* NULL while the line is down */
} hal_serial_t;

int hal_serial_err(int sp_ret, int err_no, int opening)
{
    if (sp_ret >= 0)
        return RIG_OK;
    switch (sp_ret) {
    case SP_ERR_ARG: return opening ? RIG_EOPEN : RIG_EARG;
    case SP_ERR_SUPP: return RIG_EUNSUPPORTED;
    case SP_ERR_MEM: return RIG_EIO;
    default: break;
    }
    switch (err_no) {
    case ETIMEDOUT:
    case EAGAIN: return RIG_ETIMEOUT;
    case ENOTTY:
    case EINVAL: return opening ? RIG_EOPEN : RIG_EUNSUPPORTED;
    default: return opening ? RIG_EOPEN : RIG_EDISCONNECT;
    }
}

/* "what: libserialport's message" into h->err; returns the mapped code. */
static int fail(struct hal *h, const char *what, int sp_ret, int opening)
{
    int e = errno;
    char *m = sp_last_error_message();
    snprintf(h->err, sizeof h->err, "%s %.100s: %.120s", what, h->uri.path,
             sp_ret == SP_ERR_FAIL && m ? m
             : sp_ret == SP_ERR_ARG     ? "no such port"
                                        : "failed");
    if (m)
        sp_free_error_message(m);
    return hal_serial_err(sp_ret, e, opening);
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

static void drop(hal_serial_t *s)
{
    if (s->port) {
        sp_close(s->port);
        sp_free_port(s->port);
        s->port = NULL;
    }
}

/* Open and configure the port the URI names; RIG_OK or a code with h->err. */
static int attach(hal_serial_t *s)
{
    struct hal *h = &s->base;
    const hal_uri_t *u = &h->uri;
    struct sp_port *p = NULL;
    int rc = sp_get_port_by_name(u->path, &p);
    if (rc != SP_OK)
        return fail(h, "find", rc, 1);
    rc = sp_open(p, SP_MODE_READ_WRITE);
    if (rc != SP_OK) {
        int r = fail(h, "open", rc, 1);
        sp_free_port(p);
        return r;
    }
    enum sp_parity par = u->parity == 'E'   ? SP_PARITY_EVEN
                         : u->parity == 'O' ? SP_PARITY_ODD
                                            : SP_PARITY_NONE;
    const char *what = "set baud rate on";
    rc = sp_set_baudrate(p, u->baud);
    if (rc == SP_OK) {
        what = "set data bits on";
        rc = sp_set_bits(p, u->data_bits);
    }
    if (rc == SP_OK) {
        what = "set parity on";
        rc = sp_set_parity(p, par);
    }
    if (rc == SP_OK) {
        what = "set stop bits on";
        rc = sp_set_stopbits(p, u->stop_bits);
    }
    if (rc == SP_OK) {
        what = "set flow control on";
        rc = sp_set_flowcontrol(p, SP_FLOWCONTROL_NONE);
    }
    if (rc == SP_OK) {
        sp_flush(p, SP_BUF_BOTH);
        s->port = p;
        return RIG_OK;
    }
    int r = fail(h, what, rc, 1);
    sp_close(p);
    sp_free_port(p);
    return r;
}

/* Reopen by name until it works or opts.reconnect_ms have passed. */
static int serial_reconnect(hal_t *h)
{
    hal_serial_t *s = (hal_serial_t *)h;
    char why[sizeof h->err];
    snprintf(why, sizeof why, "%s", h->err);
    drop(s);
    double end = now_ms() + h->opts.reconnect_ms;
    int wait = h->opts.backoff_ms > 0 ? h->opts.backoff_ms : 20;
    for (;;) {
        if (attach(s) == RIG_OK) {
            h->reconnects++;
            return RIG_OK;
        }
        double left = end - now_ms();
        if (left <= 0)
            break;
        if (hal_stopped(h)) { /* an abort does not wait for it to come back (hal.h) */
            snprintf(h->err, sizeof h->err, "line lost (%.100s); reopening given up: stop asked",
                     why);
            return RIG_EDISCONNECT;
        }
        sleep_ms(wait < left ? wait : (int)left + 1);
        wait = wait * 2 > 500 ? 500 : wait * 2;
    }
    char last[sizeof h->err];
    snprintf(last, sizeof last, "%s", h->err);
    snprintf(h->err, sizeof h->err, "line lost (%.100s); reopening for %d ms failed: %.100s", why,
             h->opts.reconnect_ms, last);
    return RIG_EDISCONNECT;
}

/* The line is down or has just failed: reconnect, RIG_EDISCONNECT if not. */
static int line_lost(hal_serial_t *s)
{
    return serial_reconnect(&s->base) == RIG_OK ? RIG_OK : RIG_EDISCONNECT;
}

static int serial_write(hal_t *h, const void *buf, size_t n)
{
    hal_serial_t *s = (hal_serial_t *)h;
    for (int attempt = 0; attempt < 2; attempt++) {
        if (!s->port && line_lost(s))
            return RIG_EDISCONNECT;
        int rc = sp_blocking_write(s->port, buf, n, (unsigned)h->opts.timeout_ms);
        if (rc == (int)n)
            return RIG_OK;
        if (rc >= 0) {
            snprintf(h->err, sizeof h->err, "write %.120s: %d of %zu bytes in %d ms", h->uri.path,
                     rc, n, h->opts.timeout_ms);
            return RIG_ETIMEOUT;
        }
        int code = fail(h, "write", rc, 0);
        if (code != RIG_EDISCONNECT)
            return code;
        drop(s); /* the next pass reconnects and writes again */
    }
    return RIG_EDISCONNECT;
}

static int serial_read(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got)
{
    hal_serial_t *s = (hal_serial_t *)h;
    if (got)
        *got = 0;
    if (!s->port && line_lost(s))
        return RIG_EDISCONNECT;
    int rc = sp_blocking_read(s->port, buf, n, (unsigned)(timeout_ms > 0 ? timeout_ms : 0));
    if (rc > 0) {
        if (got)
            *got = (size_t)rc;
        return RIG_OK;
    }
    if (rc == 0) {
        /* Nothing within the timeout: a silent device, or a line gone
         * (a pulled adapter reads as nothing; sp_input_waiting tells). */
        int w = sp_input_waiting(s->port);
        if (w >= 0) {
            snprintf(h->err, sizeof h->err, "read %.120s: nothing in %d ms", h->uri.path,
                     timeout_ms);
            return RIG_ETIMEOUT;
        }
        fail(h, "input waiting on", w, 0);
    } else {
        int code = fail(h, "read", rc, 0);
        if (code != RIG_EDISCONNECT)
            return code;
    }
    /* What was in flight is gone with the line: after a reconnect the
     * caller asks again (a timeout to its protocol layer). */
    if (line_lost(s))
        return RIG_EDISCONNECT;
    snprintf(h->err, sizeof h->err, "read %.120s: line lost and reopened, reply lost", h->uri.path);
    return RIG_ETIMEOUT;
}

static int serial_flush(hal_t *h)
{
    hal_serial_t *s = (hal_serial_t *)h;
    if (!s->port && line_lost(s))
        return RIG_EDISCONNECT;
    int rc = sp_flush(s->port, SP_BUF_INPUT);
    return rc == SP_OK ? RIG_OK : fail(h, "flush", rc, 0);
}

static void serial_close(hal_t *h)
{
    if (!h)
        return;
    drop((hal_serial_t *)h);
    free(h);
}

static const hal_ops_t serial_ops = {
    .version = RIG_OPS_VERSION,
    .name = "serial",
    .close = serial_close,
    .write = serial_write,
    .read = serial_read,
    .flush = serial_flush,
    .reconnect = serial_reconnect,
};

int hal_serial_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **out, char *msg, size_t len)
{
    static const hal_opts_t defaults = HAL_OPTS_DEFAULT;
    if (!u || !out || u->kind != HAL_SERIAL || !u->path[0]) {
        if (msg && len)
            snprintf(msg, len, "serial: need a serial: URI with a port name");
        return RIG_EARG;
    }
    *out = NULL;
    hal_serial_t *s = calloc(1, sizeof *s);
    if (!s) {
        if (msg && len)
            snprintf(msg, len, "serial: out of memory");
        return RIG_EOPEN;
    }
    s->base.ops = &serial_ops;
    s->base.uri = *u;
    s->base.opts = o ? *o : defaults;
    if (!s->base.uri.baud)
        s->base.uri.baud = 115200;
    if (!s->base.uri.data_bits)
        s->base.uri.data_bits = 8;
    if (!s->base.uri.parity)
        s->base.uri.parity = 'N';
    if (!s->base.uri.stop_bits)
        s->base.uri.stop_bits = 1;
    int rc = attach(s);
    if (rc) {
        if (msg && len)
            snprintf(msg, len, "%s", s->base.err);
        free(s);
        return rc;
    }
    *out = &s->base;
    return RIG_OK;
}

int hal_serial_list(hal_serial_port_t *out, size_t max, size_t *count, char *msg, size_t msglen)
{
    struct sp_port **ports = NULL;
    if (!count || (max && !out))
        return RIG_EARG;
    *count = 0;
    int rc = sp_list_ports(&ports);
    if (rc != SP_OK) {
        char *m = sp_last_error_message();
        if (msg && msglen)
            snprintf(msg, msglen, "list serial ports: %s", rc == SP_ERR_FAIL && m ? m : "failed");
        if (m)
            sp_free_error_message(m);
        return rc == SP_ERR_SUPP ? RIG_EUNSUPPORTED : RIG_EOPEN;
    }
    size_t n = 0;
    for (; ports[n]; n++) {
        if (n >= max)
            continue;
        hal_serial_port_t *q = &out[n];
        memset(q, 0, sizeof *q);
        const char *d = sp_get_port_description(ports[n]);
        snprintf(q->name, sizeof q->name, "%s", sp_get_port_name(ports[n]));
        snprintf(q->description, sizeof q->description, "%s", d ? d : q->name);
        int vid = 0, pid = 0;
        if (sp_get_port_transport(ports[n]) == SP_TRANSPORT_USB &&
            sp_get_port_usb_vid_pid(ports[n], &vid, &pid) == SP_OK) {
            const char *sn = sp_get_port_usb_serial(ports[n]);
            q->usb = 1;
            q->vid = (uint16_t)vid;
            q->pid = (uint16_t)pid;
            snprintf(q->serial, sizeof q->serial, "%s", sn ? sn : "");
        }
    }
    *count = n;
    sp_free_port_list(ports);
    return RIG_OK;
}
