/* SPDX-License-Identifier: MIT */
/* sim_net.c: cellsim's select() loop: Modbus TCP clients, Modbus RTU and
 * ASCII lines on ttys; each request is counted for the faults, answered by
 * sim_mb.c or sim_ascii.c, framed, damaged as the faults say, and sent at
 * once or held back. A tty that goes away (socat restarted) is reopened by
 * path; a disconnect fault closes a port for its MS. */
#define _DEFAULT_SOURCE /* cfmakeraw */
#include "sim_net.h"
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

static int nonblock(int fd)
{
    int fl = fcntl(fd, F_GETFL);
    return fl < 0 ? -1 : fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

static int tty_open(const char *path)
{
    int fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return -1;
    struct termios t;
    if (tcgetattr(fd, &t) == 0) {
        cfmakeraw(&t);
        t.c_cflag |= CLOCAL | CREAD;
        tcsetattr(fd, TCSANOW, &t);
    }
    tcflush(fd, TCIOFLUSH); /* what was sent while we were away is gone */
    return fd;
}

static int tcp_listen(int port, int *bound)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        return -1;
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t al = sizeof a;
    if (bind(fd, (struct sockaddr *)&a, sizeof a) || listen(fd, 8) ||
        getsockname(fd, (struct sockaddr *)&a, &al) || nonblock(fd)) {
        int e = errno;
        close(fd);
        errno = e;
        return -1;
    }
    *bound = ntohs(a.sin_port);
    return fd;
}

/* The tty's one connection is conn[port index]; tcp clients take the rest. */
static sim_conn_t *tty_conn(sim_net_t *n, int p)
{
    return &n->conn[p];
}

static void conn_reset(sim_conn_t *c)
{
    c->fd = -1;
    c->nin = c->nout = c->nsout = 0;
}

static int port_open(sim_net_t *n, int i)
{
    sim_port_t *p = &n->port[i];
    if (p->wire == SIM_W_TCP) {
        p->fd = tcp_listen(p->tcp_port, &p->tcp_port);
        return p->fd < 0 ? -1 : 0;
    }
    p->fd = tty_open(p->path);
    if (p->fd < 0)
        return -1;
    sim_conn_t *c = tty_conn(n, i);
    conn_reset(c);
    c->fd = p->fd;
    c->port = i;
    return 0;
}

/* Close a port: the listener and its clients, or the tty. */
static void port_down(sim_net_t *n, int i, double ms, const char *why)
{
    sim_port_t *p = &n->port[i];
    if (p->fd >= 0)
        close(p->fd);
    p->fd = -1;
    if (p->wire == SIM_W_TCP) {
        for (int k = n->nports; k < SIM_MAX_CONNS; k++)
            if (n->conn[k].fd >= 0 && n->conn[k].port == i) {
                close(n->conn[k].fd);
                conn_reset(&n->conn[k]);
            }
    } else
        conn_reset(tty_conn(n, i));
    p->down_until = sim_now_ms() + ms;
    if (n->verbose)
        fprintf(stderr, "cellsim: %s %s down for %.0f ms (%s)\n",
                p->wire == SIM_W_TCP ? "tcp" : "tty", p->wire == SIM_W_TCP ? "server" : p->path, ms,
                why);
}

int sim_net_start(sim_net_t *n, char *msg, size_t len)
{
    if (n->nports > SIM_MAX_CONNS)
        n->nports = SIM_MAX_CONNS;
    for (int k = 0; k < SIM_MAX_CONNS; k++)
        conn_reset(&n->conn[k]);
    for (int i = 0; i < n->nports; i++) {
        if (port_open(n, i)) {
            if (n->port[i].wire == SIM_W_TCP)
                snprintf(msg, len, "cannot listen on 127.0.0.1:%d: %s", n->port[i].tcp_port,
                         strerror(errno));
            else
                snprintf(msg, len, "%s: cannot open: %s", n->port[i].path, strerror(errno));
            return -1;
        }
    }
    return 0;
}

void sim_net_stop(sim_net_t *n)
{
    for (int k = n->nports; k < SIM_MAX_CONNS; k++)
        if (n->conn[k].fd >= 0)
            close(n->conn[k].fd);
    for (int i = 0; i < n->nports; i++)
        if (n->port[i].fd >= 0)
            close(n->port[i].fd);
}

/* Frame (RTU or TCP) the reply PDU, damage it as the faults say, queue it. */
static void reply(sim_net_t *n, sim_conn_t *c, int wire, const uint8_t *hdr, int unit,
                  const uint8_t *pdu, int plen, unsigned f, double ms)
{
    uint8_t *o = c->out;
    size_t k = 0;
    if (wire == SIM_W_TCP) {
        o[k++] = hdr[0]; /* transaction id echoed */
        o[k++] = hdr[1];
        o[k++] = 0;
        o[k++] = 0;
        o[k++] = (uint8_t)((plen + 1) >> 8);
        o[k++] = (uint8_t)((plen + 1) & 0xFF);
        o[k++] = (uint8_t)unit;
        memcpy(o + k, pdu, (size_t)plen);
        k += (size_t)plen;
        if (f & ((1u << SIM_F_CRC) | (1u << SIM_F_GARBLE)))
            o[1] ^= 0x01; /* TCP has no CRC: a wrong transaction id is what shows */
    } else if (wire == SIM_W_RTU) {
        o[k++] = (uint8_t)unit;
        memcpy(o + k, pdu, (size_t)plen);
        k += (size_t)plen;
        uint16_t crc = sim_crc16(o, k);
        o[k++] = (uint8_t)(crc & 0xFF); /* CRC low byte first */
        o[k++] = (uint8_t)(crc >> 8);
        if (f & (1u << SIM_F_CRC))
            o[k - 1] ^= 0x01;
        if (f & (1u << SIM_F_GARBLE))
            o[k > 3 ? 2 : 1] ^= 0x10;
    } else {
        memcpy(o, pdu, (size_t)plen);
        k = (size_t)plen;
        if ((f & ((1u << SIM_F_CRC) | (1u << SIM_F_GARBLE))) && k > 3)
            o[3] ^= 0x40; /* no checksum in ASCII: a byte that cannot parse */
    }
    if ((f & (1u << SIM_F_DROP)) && k > 2) {
        size_t at = wire == SIM_W_ASCII ? 1 : k / 2;
        memmove(o + at, o + at + 1, k - at - 1);
        k--;
    }
    c->nout = k;
    c->t_send = sim_now_ms() + ((f & (1u << SIM_F_SLOW)) ? ms : 0);
    (void)n;
}

/* A request has arrived: count it for the faults; 1 when the port went
 * down (the connection is gone). */
static int request(sim_net_t *n, sim_conn_t *c, int wire, const uint8_t *hdr, int unit,
                   const uint8_t *pdu, size_t plen)
{
    double ms;
    unsigned f = sim_faults_event(n->faults, 0, wire, &ms);
    if (f & (1u << SIM_F_DISCONNECT)) {
        port_down(n, c->port, ms, "disconnect fault");
        return 1;
    }
    if (f & (1u << SIM_F_SILENT))
        return 0;
    uint8_t rsp[300];
    int rl;
    if (wire == SIM_W_ASCII) {
        rl = (int)sim_ascii_answer(n->rig->probe, sim_now_ms(), (const char *)pdu, (char *)rsp,
                                   sizeof rsp);
        if (n->rig->probe->stream.ascii_new) { /* the stream's lines go to this line */
            n->rig->probe->stream.ascii_new = 0;
            n->rig->probe->stream.ascii_conn = (int)(c - n->conn);
        }
    } else {
        sim_probe_t *pr = n->rig->probe;
        if (pr)
            pr->stream.popped = 0;
        rl = sim_mb_pdu(n->rig, wire, unit, pdu, plen, rsp, (f & (1u << SIM_F_BUSY)) != 0);
        if (pr && pr->stream.popped) { /* faults keyed to the entries this reply carries */
            double ms2;
            f |= sim_faults_stream(n->faults, wire, pr->stream.popped_lo, pr->stream.popped, &ms2);
            ms = ms2 > ms ? ms2 : ms;
        }
    }
    if (f & (1u << SIM_F_SILENT))
        return 0;
    if (rl > 0)
        reply(n, c, wire, hdr, unit, rsp, rl, f, ms);
    return 0;
}

static void consume(sim_conn_t *c, size_t k)
{
    memmove(c->in, c->in + k, c->nin - k);
    c->nin -= k;
}

/* Take complete requests off the input while no reply is held back. */
static void serve_input(sim_net_t *n, sim_conn_t *c)
{
    int wire = n->port[c->port].wire;
    while (c->fd >= 0 && c->nin && !c->nout) {
        if (wire == SIM_W_TCP) {
            if (c->nin < 7)
                return;
            size_t len = ((size_t)c->in[4] << 8) | c->in[5];
            if (len < 2 || len > 254) { /* not Modbus TCP: drop the client */
                close(c->fd);
                conn_reset(c);
                return;
            }
            if (c->nin < 6 + len)
                return;
            uint8_t hdr[2] = {c->in[0], c->in[1]}, pdu[260];
            int unit = c->in[6];
            memcpy(pdu, c->in + 7, len - 1);
            consume(c, 6 + len);
            if (request(n, c, wire, hdr, unit, pdu, len - 1))
                return;
        } else if (wire == SIM_W_RTU) {
            int fl = sim_rtu_frame_len(c->in, c->nin);
            if (fl == 0 || (fl > 0 && c->nin < (size_t)fl))
                return; /* more to come, or the gap will clear it */
            if (fl < 0) {
                if (sim_now_ms() - c->t_last < n->gap_ms)
                    return;
                fl = (int)c->nin;
            }
            uint8_t fr[300];
            memcpy(fr, c->in, (size_t)fl);
            consume(c, (size_t)fl);
            uint16_t crc = sim_crc16(fr, (size_t)fl - 2);
            if (fl < 4 || fr[fl - 2] != (crc & 0xFF) || fr[fl - 1] != (crc >> 8)) {
                c->nin = 0; /* a bad frame: resynchronise on the next silence */
                return;
            }
            if (request(n, c, wire, NULL, fr[0], fr + 1, (size_t)fl - 3))
                return;
        } else {
            size_t k = 0;
            while (k < c->nin && c->in[k] != '\r' && c->in[k] != '\n')
                k++;
            if (k == c->nin) {
                if (c->nin > 64)
                    c->nin = 0; /* no line end in sight: noise */
                return;
            }
            char line[80];
            size_t m = k < sizeof line - 1 ? k : sizeof line - 1;
            memcpy(line, c->in, m);
            line[m] = '\0';
            consume(c, k + 1);
            if (m && request(n, c, wire, NULL, 0, (const uint8_t *)line, m))
                return;
        }
    }
}

static void tty_lost(sim_net_t *n, int i)
{
    if (n->verbose)
        fprintf(stderr, "cellsim: %s lost, reopening\n", n->port[i].path);
    port_down(n, i, 100, "line lost");
}

static void conn_read(sim_net_t *n, sim_conn_t *c)
{
    int wire = n->port[c->port].wire;
    ssize_t r = read(c->fd, c->in + c->nin, sizeof c->in - c->nin);
    if (r > 0) {
        c->nin += (size_t)r;
        c->t_last = sim_now_ms();
        return;
    }
    if (r < 0 && (errno == EAGAIN || errno == EINTR))
        return;
    if (wire == SIM_W_TCP) { /* client gone */
        close(c->fd);
        conn_reset(c);
    } else
        tty_lost(n, c->port); /* EIO or hang-up: the other end of the pty went */
}

static void conn_send(sim_net_t *n, sim_conn_t *c)
{
    size_t done = 0;
    while (done < c->nout) {
        ssize_t w = write(c->fd, c->out + done, c->nout - done);
        if (w > 0)
            done += (size_t)w;
        else if (w < 0 && errno == EINTR)
            continue;
        else
            break;
    }
    int failed = done < c->nout;
    c->nout = 0;
    if (failed && n->port[c->port].wire == SIM_W_TCP) {
        close(c->fd);
        conn_reset(c);
    }
}

/* The probe's streamed lines on the line that asked for them: what the
 * pty takes now; the rest stays queued (in the FIFO or in sout). */
static void stream_out(sim_net_t *n, sim_conn_t *c)
{
    if (!c->nsout)
        c->nsout =
            sim_ascii_stream_lines(n->rig->probe, sim_now_ms(), (char *)c->sout, sizeof c->sout);
    size_t done = 0;
    while (done < c->nsout) {
        ssize_t w = write(c->fd, c->sout + done, c->nsout - done);
        if (w > 0)
            done += (size_t)w;
        else if (w < 0 && errno == EINTR)
            continue;
        else
            break; /* the pty is full: later */
    }
    memmove(c->sout, c->sout + done, c->nsout - done);
    c->nsout -= done;
}

void sim_net_poll(sim_net_t *n, double max_ms)
{
    double now = sim_now_ms(), wait = max_ms;
    for (int i = 0; i < n->nports; i++) {
        sim_port_t *p = &n->port[i];
        if (p->fd < 0) {
            if (now >= p->down_until && port_open(n, i) != 0)
                p->down_until = now + 100; /* still gone: try again soon */
            if (p->fd < 0 && p->down_until - now < wait)
                wait = p->down_until - now;
        }
    }
    fd_set rd;
    FD_ZERO(&rd);
    int maxfd = -1;
    for (int i = 0; i < n->nports; i++)
        if (n->port[i].wire == SIM_W_TCP && n->port[i].fd >= 0) {
            FD_SET(n->port[i].fd, &rd);
            maxfd = n->port[i].fd > maxfd ? n->port[i].fd : maxfd;
        }
    for (int k = 0; k < SIM_MAX_CONNS; k++) {
        sim_conn_t *c = &n->conn[k];
        if (c->fd < 0)
            continue;
        if (c->nout) {
            double t = c->t_send - now;
            wait = t < wait ? t : wait;
            continue; /* a device answers one request at a time */
        }
        FD_SET(c->fd, &rd);
        maxfd = c->fd > maxfd ? c->fd : maxfd;
        if (c->nin && n->port[c->port].wire == SIM_W_RTU) {
            double t = c->t_last + n->gap_ms - now;
            wait = t < wait ? t : wait;
        }
    }
    int pending = 0;
    for (int k = 0; k < SIM_MAX_CONNS; k++)
        pending |= n->conn[k].fd >= 0 && n->conn[k].nsout;
    if (n->rig->probe && (n->rig->probe->stream.ascii || pending) && wait > 1)
        wait = 1; /* streaming: lines go out every millisecond */
    wait = wait < 0 ? 0 : wait;
    struct timeval tv = {(time_t)(wait / 1e3),
                         (long)((wait - 1e3 * (double)(time_t)(wait / 1e3)) * 1e3)};
    int r = select(maxfd + 1, &rd, NULL, NULL, &tv);
    if (r < 0)
        FD_ZERO(&rd);
    for (int i = 0; i < n->nports; i++) {
        sim_port_t *p = &n->port[i];
        if (p->wire != SIM_W_TCP || p->fd < 0 || !FD_ISSET(p->fd, &rd))
            continue;
        int fd = accept(p->fd, NULL, NULL);
        if (fd < 0)
            continue;
        int k;
        for (k = n->nports; k < SIM_MAX_CONNS && n->conn[k].fd >= 0; k++)
            ;
        if (k == SIM_MAX_CONNS || nonblock(fd)) {
            close(fd);
            continue;
        }
        conn_reset(&n->conn[k]);
        n->conn[k].fd = fd;
        n->conn[k].port = i;
    }
    for (int k = 0; k < SIM_MAX_CONNS; k++) {
        sim_conn_t *c = &n->conn[k];
        if (c->fd >= 0 && !c->nout && FD_ISSET(c->fd, &rd))
            conn_read(n, c);
    }
    for (int k = 0; k < SIM_MAX_CONNS; k++) {
        sim_conn_t *c = &n->conn[k];
        /* Send what is due, answer what is buffered, until a reply is held
         * back or the input is used up. */
        for (int guard = 0; guard < 64 && c->fd >= 0; guard++) {
            if (c->nout) {
                if (sim_now_ms() < c->t_send)
                    break;
                conn_send(n, c);
                continue;
            }
            size_t before = c->nin;
            serve_input(n, c);
            if (!c->nout && c->nin == before)
                break;
        }
        /* Also once the stream has ended: its last lines (the end line
         * among them) may still wait in sout for a full pty to take them. */
        if (c->fd >= 0 && n->rig->probe &&
            (c->nsout || (n->rig->probe->stream.ascii && n->rig->probe->stream.ascii_conn == k)) &&
            !c->nout)
            stream_out(n, c);
        /* RTU: bytes of an incomplete frame followed by silence are noise. */
        if (c->fd >= 0 && c->nin && n->port[c->port].wire == SIM_W_RTU &&
            sim_now_ms() - c->t_last >= n->gap_ms && sim_rtu_frame_len(c->in, c->nin) >= 0)
            c->nin = 0;
    }
}
