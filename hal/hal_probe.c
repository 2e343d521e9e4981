/* SPDX-License-Identifier: MIT */
/* hal_probe.c: the laser displacement probe over its ASCII protocol on any
 * byte-stream transport (tty:, serial:): "M0" CR LF asks for a reading,
 * "M0,+01.234" is mm, "M0,FFFFFFF" out of range (RIG_ENOSURF), "ER,M0,nn"
 * an error; "RG" asks for the measuring range. Timeouts and malformed
 * lines are retried with backoff after waiting out a late reply. Streaming:
 * "TP,<us>" and "MS" start one "SQ,<n>,<mm>,<x um>,<y um>" line per
 * trigger, "MQ" stops them and "MQ,<triggers>,<dropped>" ends them. */
#include "hal_priv.h"
#include "hal_regmap.h"
#include "hal_rig.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int hal_probe_pfail(hal_probe_t *p, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(p->err, sizeof p->err, fmt, ap);
    va_end(ap);
    return code;
}

const char *hal_probe_error(const void *ctx)
{
    return ctx ? ((const hal_probe_t *)ctx)->err : "no probe";
}

/* A decimal "+dd.ddd" (sign required, digits both sides of the point). */
static int number(const char *s, const char **end, double *v)
{
    const char *c = s;
    if (*c != '+' && *c != '-')
        return -1;
    c++;
    int a = 0, b = 0;
    while (*c >= '0' && *c <= '9')
        c++, a++;
    if (*c != '.')
        return -1;
    c++;
    while (*c >= '0' && *c <= '9')
        c++, b++;
    if (!a || !b || a > 6)
        return -1;
    *v = strtod(s, NULL);
    *end = c;
    return 0;
}

int hal_probe_parse_m0(const char *line, double *mm)
{
    if (!strncmp(line, "ER,M0,", 6) && strlen(line) == 8 && line[6] >= '0' && line[6] <= '9' &&
        line[7] >= '0' && line[7] <= '9')
        return RIG_EEXCEPTION;
    if (strncmp(line, "M0,", 3))
        return RIG_EPROTO;
    if (!strcmp(line + 3, "FFFFFFF"))
        return RIG_ENOSURF;
    const char *end;
    double v;
    if (number(line + 3, &end, &v) || *end)
        return RIG_EPROTO;
    *mm = v;
    return RIG_OK;
}

/* One line up to CR LF within the timeout (without the terminator). */
static int read_line(hal_probe_t *p, char *line, size_t cap)
{
    hal_t *h = p->h;
    size_t n = 0;
    double t_end = hal_now_ms() + h->opts.timeout_ms;
    for (;;) {
        int left = (int)(t_end - hal_now_ms() + 0.999);
        if (left <= 0)
            return hal_probe_pfail(p, RIG_ETIMEOUT, "probe %s: %s after %d ms", h->uri.path,
                                   n ? "no line end" : "no reply", h->opts.timeout_ms);
        char c;
        size_t got;
        int rc = hal_read(h, &c, 1, left, &got);
        if (rc == RIG_ETIMEOUT)
            continue; /* the loop's clock decides */
        if (rc)
            return hal_probe_pfail(p, rc, "probe: %s", hal_last_error(h));
        if (c == '\n') {
            if (!n || line[n - 1] != '\r')
                return hal_probe_pfail(p, RIG_EPROTO, "probe %s: line end without CR", h->uri.path);
            line[n - 1] = '\0';
            return RIG_OK;
        }
        if (n + 1 >= cap)
            return hal_probe_pfail(p, RIG_EPROTO, "probe %s: reply longer than %zu bytes",
                                   h->uri.path, cap - 1);
        line[n++] = c;
    }
}

/* Ask and read the answer, retrying timeouts and garbage; parse turns the
 * line into values (M0: the distance; RG: the range). */
static int transact(hal_probe_t *p, const char *req, char *line, size_t cap,
                    int (*parse)(const char *, double *, double *), double *a, double *b)
{
    hal_t *h = p->h;
    int backoff = h->opts.backoff_ms;
    if (hal_stop_before(h)) /* the probe already found hung under this stop */
        return hal_probe_pfail(p, RIG_EABORTED, "probe: %s", hal_last_error(h));
    for (int attempt = 0;; attempt++) {
        int rc = hal_write(h, req, strlen(req));
        if (rc == RIG_OK)
            rc = read_line(p, line, cap);
        else
            hal_probe_pfail(p, rc, "probe: %s", hal_last_error(h));
        if (rc == RIG_OK) {
            rc = parse(line, a, b);
            if (rc == RIG_OK)
                return RIG_OK;
            if (rc == RIG_ENOSURF)
                return hal_probe_pfail(p, rc, "probe %s: out of range ('%s')", h->uri.path, line);
            if (rc == RIG_EEXCEPTION)
                return hal_probe_pfail(p, rc, "probe %s: error reply '%s'", h->uri.path, line);
            hal_probe_pfail(p, rc, "probe %s: malformed reply '%.40s'", h->uri.path, line);
        }
        if (rc == RIG_EDISCONNECT || rc == RIG_EARG || rc == RIG_EUNSUPPORTED || rc == RIG_EABORTED)
            return rc;
        int stopped = hal_stop_after(h, rc); /* an abort waits for no retry (hal.h) */
        if (stopped)
            return hal_probe_pfail(p, stopped, "probe: %s", hal_last_error(h));
        /* Let a late or broken reply finish arriving, then drop it. */
        if (hal_wait_ms(h, rc == RIG_ETIMEOUT ? h->opts.late_ms : h->opts.byte_timeout_ms))
            return hal_probe_pfail(p, hal_stop_after(h, rc), "probe: %s", hal_last_error(h));
        hal_flush(h);
        if (attempt >= h->opts.retries) {
            char d[320];
            snprintf(d, sizeof d, "%s", p->err);
            return hal_probe_pfail(p, rc, "%.280s (after %d attempts)", d, attempt + 1);
        }
        h->retries++;
        if (hal_wait_ms(h, backoff))
            return hal_probe_pfail(p, hal_stop_after(h, rc), "probe: %s", hal_last_error(h));
        backoff = backoff * 2 > 2000 ? 2000 : backoff * 2;
    }
}

static int parse_m0(const char *line, double *a, double *b)
{
    (void)b;
    return hal_probe_parse_m0(line, a);
}

static int parse_rg(const char *line, double *a, double *b)
{
    const char *e;
    if (strncmp(line, "RG,", 3) || number(line + 3, &e, a) || *e != ',' || number(e + 1, &e, b) ||
        *e || !(*a < *b))
        return RIG_EPROTO;
    return RIG_OK;
}

static int ascii_read(void *ctx, double *mm)
{
    hal_probe_t *p = ctx;
    char line[64];
    if (!p || !mm)
        return RIG_EARG;
    return transact(p, "M0\r\n", line, sizeof line, parse_m0, mm, NULL);
}

static int probe_range(void *ctx, double *lo, double *hi)
{
    hal_probe_t *p = ctx;
    if (!p || !lo || !hi)
        return RIG_EARG;
    *lo = p->lo;
    *hi = p->hi;
    return RIG_OK;
}

const rig_probe_ops_t hal_probe_ascii_ops = {
    .version = RIG_OPS_VERSION,
    .read = ascii_read,
    .range = probe_range,
};

int hal_probe_init(hal_probe_t *p, hal_t *h)
{
    if (!p || !h)
        return RIG_EARG;
    memset(p, 0, sizeof *p);
    p->h = h;
    p->modbus = h->uri.kind == HAL_RTU || h->uri.kind == HAL_TCP;
    if (p->modbus)
        return hal_probe_modbus_range(p);
    char line[64];
    return transact(p, "RG\r\n", line, sizeof line, parse_rg, &p->lo, &p->hi);
}

/* "TP,nnnnnnn": the period the probe took, in *a. */
static int parse_tp(const char *line, double *a, double *b)
{
    (void)b;
    if (strncmp(line, "TP,", 3) || strlen(line) != 10 || strspn(line + 3, "0123456789") != 7)
        return RIG_EPROTO;
    *a = strtod(line + 3, NULL);
    return RIG_OK;
}

static int parse_ms(const char *line, double *a, double *b)
{
    (void)a;
    (void)b;
    return strcmp(line, "MS") ? RIG_EPROTO : RIG_OK;
}

int hal_probe_ascii_stream_start(hal_probe_t *p, uint32_t period_us)
{
    char line[64], req[32];
    double got = 0;
    snprintf(req, sizeof req, "TP,%lu\r\n", (unsigned long)period_us);
    int rc = transact(p, req, line, sizeof line, parse_tp, &got, NULL);
    if (!rc && got != (double)period_us)
        return hal_probe_pfail(p, RIG_EPROTO, "probe took period %.0f us, not %lu", got,
                               (unsigned long)period_us);
    if (!rc)
        rc = transact(p, "MS\r\n", line, sizeof line, parse_ms, NULL, NULL);
    if (rc)
        return rc;
    p->sn = 0;
    p->streaming = 1;
    return RIG_OK;
}

int hal_probe_ascii_stream_stop(hal_probe_t *p)
{
    int rc = hal_write(p->h, "MQ\r\n", 4);
    return rc ? hal_probe_pfail(p, rc, "probe stream stop: %s", hal_last_error(p->h)) : RIG_OK;
}

/* An integer field of a streamed line up to its comma or end. */
static int field_long(const char *s, const char **end, long *v)
{
    char *e;
    *v = strtol(s, &e, 10);
    if (e == s || (*e != ',' && *e))
        return -1;
    *end = e;
    return 0;
}

/* One streamed line: an entry (1), the end line (2), or RIG_EPROTO. */
static int stream_line(hal_probe_t *p, const char *line, rig_reading_t *r, rig_trig_event_t *t,
                       unsigned long *dropped)
{
    const char *c;
    long seq, x, y, trig, lost;
    if (!strncmp(line, "MQ,", 3)) {
        if (field_long(line + 3, &c, &trig) || *c != ',' || field_long(c + 1, &c, &lost) || *c ||
            lost < 0)
            return RIG_EPROTO;
        if (dropped)
            *dropped += (unsigned long)lost;
        return 2;
    }
    if (strncmp(line, "SQ,", 3) || field_long(line + 3, &c, &seq) || *c != ',' || seq < 0 ||
        seq > 65535)
        return RIG_EPROTO;
    const char *v = c + 1, *ve = strchr(v, ',');
    if (!ve)
        return RIG_EPROTO;
    double d = 0;
    uint8_t st;
    if (!strncmp(v, "FFFFFFF,", 8))
        st = RIG_RD_NOSURF;
    else if (!strncmp(v, "ER01,", 5))
        st = RIG_RD_ERROR;
    else if (number(v, &c, &d) || c != ve)
        return RIG_EPROTO;
    else
        st = RIG_RD_VALID;
    if (field_long(ve + 1, &c, &x) || *c != ',' || field_long(c + 1, &c, &y) || *c)
        return RIG_EPROTO;
    (void)p;
    rig_reading_t rd = {(uint16_t)seq, st, d};
    rig_trig_event_t ev = {(uint16_t)seq, 0, 0, {(int32_t)x, (int32_t)y}};
    *r = rd;
    *t = ev;
    return 1;
}

int hal_probe_ascii_stream_read(hal_probe_t *p, rig_reading_t *rd, rig_trig_event_t *pos,
                                size_t max, size_t *n, unsigned long *dropped)
{
    hal_t *h = p->h;
    int waited = 0;
    while (*n < max) {
        /* Whole lines in the buffer first. */
        char *nl = memchr(p->sbuf, '\n', p->sn);
        if (nl) {
            size_t len = (size_t)(nl - p->sbuf);
            if (!len || p->sbuf[len - 1] != '\r')
                return hal_probe_pfail(p, RIG_EPROTO, "probe stream: line end without CR");
            p->sbuf[len - 1] = '\0';
            int k = stream_line(p, p->sbuf, &rd[*n], &pos[*n], dropped);
            if (k < 0)
                hal_probe_pfail(p, k, "probe stream: bad line '%.40s'", p->sbuf);
            memmove(p->sbuf, nl + 1, p->sn - len - 1);
            p->sn -= len + 1;
            if (k < 0)
                return k;
            if (k == 2) {
                p->streaming = 0;
                return RIG_OK;
            }
            ++*n;
            continue;
        }
        if (p->sn == sizeof p->sbuf)
            return hal_probe_pfail(p, RIG_EPROTO, "probe stream: line longer than %zu bytes",
                                   sizeof p->sbuf);
        if (waited && !p->sn)
            break; /* nothing more came within the wait */
        size_t got = 0;
        int rc = hal_read(h, p->sbuf + p->sn, sizeof p->sbuf - p->sn, 5, &got);
        if (rc == RIG_ETIMEOUT || (!rc && !got)) {
            if (waited)
                break;
            waited = 1;
            continue;
        }
        if (rc)
            return hal_probe_pfail(p, rc, "probe stream: %s", hal_last_error(h));
        p->sn += got;
        waited = 1;
    }
    return RIG_OK;
}
