/* SPDX-License-Identifier: MIT */
/* hal_tty.c: byte-stream backend on a tty or pseudo-terminal with termios
 * (raw, baud, parity, stop bits), poll() timeouts, and reconnection by
 * reopening the path when the line is lost (EIO, hang-up): for the ptys
 * socat makes, which libserialport cannot open. */
#define _DEFAULT_SOURCE /* cfmakeraw, the high baud rates */
#include "hal.h"
#include "hal_priv.h"
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

typedef struct hal_tty {
    struct hal base;
    int fd; /* -1 while the line is lost */
} hal_tty_t;

static speed_t tty_speed(int baud)
{
    static const struct {
        int b;
        speed_t s;
    } map[] = {{300, B300},         {600, B600},         {1200, B1200},       {2400, B2400},
               {4800, B4800},       {9600, B9600},       {19200, B19200},     {38400, B38400},
               {57600, B57600},     {115200, B115200},   {230400, B230400},   {460800, B460800},
               {500000, B500000},   {576000, B576000},   {921600, B921600},   {1000000, B1000000},
               {1152000, B1152000}, {1500000, B1500000}, {2000000, B2000000}, {3000000, B3000000},
               {4000000, B4000000}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (map[i].b == baud)
            return map[i].s;
    return B0;
}

/* Open the path raw with the URI's line settings; -1 and errno on failure. */
static int tty_open_fd(const hal_uri_t *u)
{
    int fd = open(u->path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return -1;
    struct termios t;
    speed_t sp = tty_speed(u->baud);
    if (tcgetattr(fd, &t) == 0) {
        cfmakeraw(&t);
        t.c_cflag |= CLOCAL | CREAD;
        t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
        t.c_cflag |= u->data_bits == 7 ? CS7 : CS8;
        if (u->parity != 'N')
            t.c_cflag |= PARENB | (u->parity == 'O' ? PARODD : 0);
        if (u->stop_bits == 2)
            t.c_cflag |= CSTOPB;
        t.c_cc[VMIN] = 0;
        t.c_cc[VTIME] = 0;
        if (sp != B0) {
            cfsetispeed(&t, sp);
            cfsetospeed(&t, sp);
        }
        if (tcsetattr(fd, TCSANOW, &t) != 0) {
            int e = errno;
            close(fd);
            errno = e;
            return -1;
        }
    } else if (errno != ENOTTY) {
        int e = errno;
        close(fd);
        errno = e;
        return -1;
    }
    tcflush(fd, TCIOFLUSH); /* stale bytes of an earlier session */
    return fd;
}

static int tty_reconnect(hal_t *h)
{
    hal_tty_t *t = (hal_tty_t *)h;
    if (t->fd >= 0)
        close(t->fd);
    t->fd = -1;
    h->reconnects++;
    double t_end = hal_now_ms() + h->opts.reconnect_ms;
    int wait = h->opts.backoff_ms > 0 ? h->opts.backoff_ms : 10;
    for (;;) {
        t->fd = tty_open_fd(&h->uri);
        if (t->fd >= 0)
            return RIG_OK;
        int e = errno;
        double left = t_end - hal_now_ms();
        if (left <= 0)
            return hal_fail(h, RIG_EDISCONNECT, "tty:%s: line lost, reopening failed for %d ms: %s",
                            h->uri.path, h->opts.reconnect_ms, strerror(e));
        if (hal_wait_ms(h, wait < left ? wait : left)) /* an abort does not wait for the line */
            return hal_fail(h, RIG_EABORTED, "tty:%s: line lost, reopening given up: stop asked",
                            h->uri.path);
        wait = wait * 2 > 200 ? 200 : wait * 2;
    }
}

/* A lost line found mid-call: reopen it; the bytes in flight are gone. */
static int tty_lost(hal_t *h, const char *op, int e)
{
    char why[128];
    snprintf(why, sizeof why, "%s", e ? strerror(e) : "hang-up");
    int rc = tty_reconnect(h);
    if (rc)
        return rc;
    return hal_fail(h, RIG_ETIMEOUT, "tty:%s: %s: %s; line reopened, data in flight lost",
                    h->uri.path, op, why);
}

static int tty_write(hal_t *h, const void *buf, size_t n)
{
    hal_tty_t *t = (hal_tty_t *)h;
    const unsigned char *p = buf;
    if (t->fd < 0) {
        int rc = tty_reconnect(h);
        if (rc)
            return rc;
    }
    double t_end = hal_now_ms() + h->opts.timeout_ms;
    size_t done = 0;
    while (done < n) {
        ssize_t w = write(t->fd, p + done, n - done);
        if (w > 0) {
            done += (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0 && errno != EAGAIN)
            return tty_lost(h, "write", errno);
        int left = (int)(t_end - hal_now_ms());
        if (left <= 0)
            return hal_fail(h, RIG_ETIMEOUT, "tty:%s: write blocked for %d ms", h->uri.path,
                            h->opts.timeout_ms);
        struct pollfd pf = {t->fd, POLLOUT, 0};
        poll(&pf, 1, left);
    }
    return RIG_OK;
}

/* Up to n bytes: waits up to timeout_ms for the first, then returns what
 * is there. RIG_ETIMEOUT when nothing came. */
static int tty_read(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got)
{
    hal_tty_t *t = (hal_tty_t *)h;
    *got = 0;
    if (n == 0)
        return RIG_OK;
    if (t->fd < 0) {
        int rc = tty_reconnect(h);
        if (rc)
            return rc;
    }
    if (timeout_ms < 0)
        timeout_ms = h->opts.timeout_ms;
    double t_end = hal_now_ms() + timeout_ms;
    for (;;) {
        ssize_t r = read(t->fd, buf, n);
        if (r > 0) {
            *got = (size_t)r;
            return RIG_OK;
        }
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0 && errno != EAGAIN)
            return tty_lost(h, "read", errno);
        int left = (int)(t_end - hal_now_ms() + 0.999);
        if (left <= 0)
            return hal_fail(h, RIG_ETIMEOUT, "tty:%s: nothing received in %d ms", h->uri.path,
                            timeout_ms);
        struct pollfd pf = {t->fd, POLLIN, 0};
        int pr = poll(&pf, 1, left);
        if (pr > 0 && !(pf.revents & POLLIN) && (pf.revents & (POLLHUP | POLLERR | POLLNVAL)))
            return tty_lost(h, "read", 0);
    }
}

static int tty_flush(hal_t *h)
{
    hal_tty_t *t = (hal_tty_t *)h;
    if (t->fd >= 0)
        tcflush(t->fd, TCIFLUSH);
    return RIG_OK;
}

static void tty_close(hal_t *h)
{
    hal_tty_t *t = (hal_tty_t *)h;
    if (t->fd >= 0)
        close(t->fd);
    free(t);
}

static const hal_ops_t tty_ops = {
    .version = RIG_OPS_VERSION,
    .name = "tty",
    .close = tty_close,
    .write = tty_write,
    .read = tty_read,
    .flush = tty_flush,
    .reconnect = tty_reconnect,
};

int hal_tty_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len)
{
    if (!u || !h || u->kind != HAL_TTY)
        return RIG_EARG;
    *h = NULL;
    hal_tty_t *t = calloc(1, sizeof *t);
    if (!t)
        return RIG_EOPEN;
    t->base.ops = &tty_ops;
    t->base.uri = *u;
    hal_opts_fill(&t->base.opts, o);
    t->fd = tty_open_fd(u);
    if (t->fd < 0) {
        if (msg && len)
            snprintf(msg, len, "tty:%s: cannot open: %s", u->path, strerror(errno));
        free(t);
        return RIG_EOPEN;
    }
    *h = &t->base;
    return RIG_OK;
}
