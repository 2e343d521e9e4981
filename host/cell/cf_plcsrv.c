/* cf_plcsrv.c: Modbus TCP server of the cell (cf_plcsrv.h): the select()
 * loop over clients, MBAP framing per client, requests mapped onto plc_map
 * / plc_fsm, the rate limit and the allow-list, the worker thread that runs
 * a job's phases, the watchdog tick. Only this thread touches the sockets;
 * the worker touches the register table only under the mutex. */
#include "cf_plcsrv.h"
#include "cf_log.h"
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define TICK_MS 20    /* select timeout: watchdog and heartbeat resolution */
#define FRAME_MS 1000 /* the rest of a frame must follow within this */
#define MBAP_HDR 7    /* transaction, protocol, length, unit */
#define MBAP_MAX 260  /* header + the largest PDU (253 bytes) */

typedef struct srv {
    pthread_mutex_t mu;
    plc_map_t map;
    plc_fsm_t fsm;
    const cf_runner_t *run;
    pthread_t worker;
    int worker_live;      /* a thread to join */
    atomic_int stop_job;  /* the running job must stop */
    atomic_int job_ended; /* the worker has returned */
} srv_t;

static uint32_t now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

static void job_progress(void *ctx, int pct)
{
    srv_t *s = ctx;
    pthread_mutex_lock(&s->mu);
    plc_fsm_progress(&s->fsm, pct);
    pthread_mutex_unlock(&s->mu);
}

static int job_should_stop(void *ctx)
{
    srv_t *s = ctx;
    return atomic_load(&s->stop_job);
}

static void log_end(const plc_fsm_t *f, int from)
{
    if (f->state == PLC_S_ERROR)
        cf_log(CF_LOG_ERROR, "job %s seq %u: %s failed: error %u (%s)", plc_cmd_name(f->job),
               f->job_params.seq, plc_state_name(from), f->error, plc_strerror(f->error));
    else if (f->aborted)
        cf_log(CF_LOG_WARN, "job %s seq %u aborted", plc_cmd_name(f->job), f->job_params.seq);
    else if (f->done && f->done_seq == f->job_params.seq && !plc_state_busy(f->state))
        cf_log(CF_LOG_INFO, "job %s seq %u done", plc_cmd_name(f->job), f->job_params.seq);
}

/* The worker: run the job's phases one after another as the state machine
 * names them; the lock is held only between phases. It follows its own job
 * only (the state each event returns): once that has ended it returns, even
 * if a new job has been accepted since (that one gets its own thread). */
static void *worker_main(void *arg)
{
    srv_t *s = arg;
    const cf_runner_t *r = s->run;
    cf_job_ctl_t ctl = {job_progress, job_should_stop, s};
    pthread_mutex_lock(&s->mu);
    int st = s->fsm.state, job = s->fsm.job;
    plc_params_t p = s->fsm.job_params;
    if (st == PLC_S_ABORTING) { /* aborted before the first phase began */
        st = plc_fsm_event(&s->fsm, PLC_EV_ABORTED, 0, NULL);
        log_end(&s->fsm, PLC_S_ABORTING);
    }
    pthread_mutex_unlock(&s->mu);
    while (st >= PLC_S_HOMING && st <= PLC_S_EXPORTING) {
        cf_log(CF_LOG_INFO, "job %s seq %u: %s", plc_cmd_name(job), p.seq, plc_state_name(st));
        plc_results_t res;
        memset(&res, 0, sizeof res);
        int rc = PLC_E_INTERNAL;
        switch (st) {
        case PLC_S_HOMING: rc = r->home(r->ctx, &p, &ctl); break;
        case PLC_S_SCANNING: rc = r->scan(r->ctx, &p, &ctl); break;
        case PLC_S_FITTING: rc = r->fit(r->ctx, &p, &ctl, &res); break;
        case PLC_S_EXPORTING: rc = r->export_result(r->ctx, &p, &ctl); break;
        default: break;
        }
        int from = st;
        pthread_mutex_lock(&s->mu);
        if (rc == 0)
            st = plc_fsm_event(&s->fsm, PLC_EV_OK, 0, from == PLC_S_FITTING ? &res : NULL);
        else if (rc == CF_PLC_ABORTED)
            st = plc_fsm_event(&s->fsm, PLC_EV_ABORTED, 0, NULL);
        else
            st = plc_fsm_event(&s->fsm, PLC_EV_FAIL, rc, NULL);
        if (from == PLC_S_FITTING && rc == 0 && s->fsm.results_valid)
            cf_log(CF_LOG_INFO,
                   "job seq %u: %lu points, %lu control points, rms %.6g max %.6g min %.6g, "
                   "%.2f %% within tolerance: %s",
                   p.seq, (unsigned long)res.points, (unsigned long)res.control_points, res.rms,
                   res.max, res.min, res.within_pct,
                   res.verdict == PLC_VERDICT_PASS ? "pass" : "fail");
        log_end(&s->fsm, from);
        pthread_mutex_unlock(&s->mu);
    }
    atomic_store(&s->job_ended, 1);
    return NULL;
}

static void join_worker(srv_t *s)
{
    if (s->worker_live) {
        pthread_join(s->worker, NULL);
        s->worker_live = 0;
    }
}

/* Act on what the state machine asked (called without the lock). */
static void act(srv_t *s, plc_action_t a)
{
    if (a == PLC_ACT_ABORT) {
        atomic_store(&s->stop_job, 1);
        s->run->abort(s->run->ctx);
        cf_log(CF_LOG_WARN, "abort: job asked to stop, motion stopped");
    } else if (a == PLC_ACT_START) {
        join_worker(s); /* the previous job's thread has ended its job already */
        atomic_store(&s->stop_job, 0);
        atomic_store(&s->job_ended, 0);
        /* The worker takes no signals: SIGTERM interrupts the select loop. */
        sigset_t all, old;
        sigfillset(&all);
        pthread_sigmask(SIG_SETMASK, &all, &old);
        int rc = pthread_create(&s->worker, NULL, worker_main, s);
        pthread_sigmask(SIG_SETMASK, &old, NULL);
        if (rc) {
            cf_log(CF_LOG_ERROR, "cannot start the job thread: %s", strerror(rc));
            pthread_mutex_lock(&s->mu);
            plc_fsm_event(&s->fsm, PLC_EV_FAIL, PLC_E_MEMORY, NULL);
            pthread_mutex_unlock(&s->mu);
        } else
            s->worker_live = 1;
    }
}

static unsigned be16(const uint8_t *p)
{
    return (unsigned)p[0] << 8 | p[1];
}

static void put16(uint8_t *p, unsigned v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

typedef struct client {
    int fd;
    size_t have;            /* bytes of the frame being received */
    uint32_t t_first;       /* when its first byte came (ms) */
    double tokens;          /* rate limit: requests that may come now */
    uint32_t t_tok, t_warn; /* last refill; last warning logged */
    unsigned long limited;  /* requests refused by the limit since the warning */
    uint8_t buf[MBAP_MAX];
    char name[32];
} client_t;

/* One request PDU (q, n bytes) into a reply PDU (r); returns its length.
 * Every length is checked against what the function code needs. */
static size_t handle_pdu(srv_t *s, const client_t *c, const uint8_t *q, size_t n, uint8_t *r,
                         plc_action_t *todo)
{
    unsigned fc = q[0], a = n >= 3 ? be16(q + 1) : 0, cnt = 0;
    int ex = 0;
    uint16_t v[PLC_MAX_WRITE];
    uint32_t t = now_ms();
    *todo = PLC_ACT_NONE;
    r[0] = (uint8_t)fc;
    if (fc == 0x03) {
        uint16_t w[PLC_MAX_READ];
        cnt = n == 5 ? be16(q + 3) : 0;
        if (n != 5)
            ex = PLC_EX_VALUE;
        else {
            pthread_mutex_lock(&s->mu);
            ex = plc_map_read(&s->map, a, cnt, w);
            pthread_mutex_unlock(&s->mu);
        }
        if (!ex) {
            r[1] = (uint8_t)(2 * cnt);
            for (unsigned k = 0; k < cnt; k++)
                put16(r + 2 + 2 * k, w[k]);
            return 2 + 2 * cnt;
        }
    } else if (fc == 0x06 || fc == 0x10) {
        if (fc == 0x06 && n == 5) {
            cnt = 1;
            v[0] = (uint16_t)be16(q + 3);
        } else if (fc == 0x10 && n >= 6) {
            cnt = be16(q + 3);
            if (cnt < 1 || cnt > PLC_MAX_WRITE || q[5] != 2 * cnt || n != 6 + 2 * (size_t)cnt)
                ex = PLC_EX_VALUE;
            for (unsigned k = 0; !ex && k < cnt; k++)
                v[k] = (uint16_t)be16(q + 6 + 2 * k);
        } else
            ex = PLC_EX_VALUE;
        if (!ex) {
            pthread_mutex_lock(&s->mu);
            uint16_t seq0 = s->fsm.ack_seq;
            ex = plc_fsm_write(&s->fsm, a, cnt, v, t, todo);
            plc_fsm_t f = s->fsm;
            pthread_mutex_unlock(&s->mu);
            if (!ex && f.ack_seq != seq0)
                cf_log(f.cmd_result ? CF_LOG_WARN : CF_LOG_INFO, "command %s seq %u: %s%s%s",
                       plc_cmd_name(v[PLC_R_COMMAND - a]), f.ack_seq,
                       f.cmd_result ? "refused, " : "accepted",
                       f.cmd_result ? plc_strerror(f.cmd_result) : "",
                       f.cmd_result ? "" : (*todo == PLC_ACT_START ? ", job started" : ""));
        }
        if (!ex) {
            memcpy(r, q, 5); /* function 06 echoes, 16 answers address and count */
            if (fc == 0x10)
                put16(r + 3, cnt);
            return 5;
        }
    } else
        ex = PLC_EX_FUNCTION;
    cf_log(CF_LOG_DEBUG, "%s: function %u at %u x %u: exception %d", c->name, fc, a, cnt, ex);
    r[0] = (uint8_t)(fc | 0x80);
    r[1] = (uint8_t)ex;
    return 2;
}

/* Send a whole reply or give up on the client (it does not read). */
static int send_all(int fd, const uint8_t *b, size_t n)
{
    while (n > 0) {
        ssize_t k = send(fd, b, n, MSG_NOSIGNAL);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return -1;
        b += k;
        n -= (size_t)k;
    }
    return 0;
}

/* Token bucket: 1 when this request may be served. */
static int rate_ok(const cf_plcsrv_opts_t *o, client_t *c, uint32_t t)
{
    if (o->max_rate <= 0)
        return 1;
    double burst = o->max_rate < 1 ? 1 : o->max_rate;
    c->tokens += (double)(uint32_t)(t - c->t_tok) * 1e-3 * o->max_rate;
    c->tokens = c->tokens > burst ? burst : c->tokens;
    c->t_tok = t;
    if (c->tokens >= 1) {
        c->tokens -= 1;
        return 1;
    }
    c->limited++;
    if ((uint32_t)(t - c->t_warn) >= 1000) {
        cf_log(CF_LOG_WARN, "%s: over %g requests/s: %lu refused (exception 06)", c->name,
               o->max_rate, c->limited);
        c->t_warn = t;
        c->limited = 0;
    }
    return 0;
}

/* Bytes from one client: every complete frame answered in turn. 0, or -1
 * when the client must go (closed, malformed header, unanswerable). */
static int client_input(srv_t *s, const cf_plcsrv_opts_t *o, client_t *c)
{
    for (;;) {
        size_t want = MBAP_HDR;
        if (c->have >= 6)
            want = 6 + be16(c->buf + 4);
        if (c->have >= 6 && (be16(c->buf + 2) != 0 || want < 6 + 2 || want > MBAP_MAX)) {
            cf_log(CF_LOG_WARN, "%s: malformed MBAP header (protocol %u, length %u): closed",
                   c->name, be16(c->buf + 2), be16(c->buf + 4));
            return -1;
        }
        if (c->have < want) {
            ssize_t k = recv(c->fd, c->buf + c->have, want - c->have, MSG_DONTWAIT);
            if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
                return 0;
            if (k <= 0) {
                cf_log(CF_LOG_INFO, "%s left (%s)", c->name, k ? strerror(errno) : "closed");
                return -1;
            }
            if (c->have == 0)
                c->t_first = now_ms();
            c->have += (size_t)k;
            continue;
        }
        /* A whole frame: header echoed, unit id kept, the PDU answered. */
        uint8_t out[MBAP_MAX];
        plc_action_t todo = PLC_ACT_NONE;
        size_t rn;
        if (rate_ok(o, c, now_ms()))
            rn = handle_pdu(s, c, c->buf + MBAP_HDR, want - MBAP_HDR, out + MBAP_HDR, &todo);
        else {
            out[MBAP_HDR] = (uint8_t)(c->buf[MBAP_HDR] | 0x80);
            out[MBAP_HDR + 1] = PLC_EX_BUSY;
            rn = 2;
        }
        memcpy(out, c->buf, 4);
        put16(out + 4, (unsigned)rn + 1);
        out[6] = c->buf[6];
        c->have = 0;
        int bad = send_all(c->fd, out, MBAP_HDR + rn);
        act(s, todo);
        if (bad) {
            cf_log(CF_LOG_WARN, "%s: cannot send the reply (%s): closed", c->name, strerror(errno));
            return -1;
        }
    }
}

static int listen_port(int fd)
{
    struct sockaddr_in sa;
    socklen_t sl = sizeof sa;
    if (getsockname(fd, (struct sockaddr *)&sa, &sl))
        return -1;
    return ntohs(sa.sin_port);
}

static int write_port_file(const char *path, int port)
{
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f)
        return -1;
    fprintf(f, "%d\n", port);
    if (fclose(f) || rename(tmp, path)) {
        remove(tmp);
        return -1;
    }
    return 0;
}

static void set_clients(srv_t *s, int n)
{
    pthread_mutex_lock(&s->mu);
    plc_map_put_u16(&s->map, PLC_R_CLIENTS, (uint16_t)n);
    pthread_mutex_unlock(&s->mu);
}

static int open_listener(const cf_plcsrv_opts_t *o)
{
    struct sockaddr_in sa;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)o->port);
    if (inet_pton(AF_INET, o->addr, &sa.sin_addr) != 1) {
        errno = EINVAL;
        return -1;
    }
    int fd = socket(AF_INET, SOCK_STREAM, 0), one = 1;
    if (fd < 0)
        return -1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (bind(fd, (struct sockaddr *)&sa, sizeof sa) || listen(fd, 16)) {
        int e = errno;
        close(fd);
        errno = e;
        return -1;
    }
    fcntl(fd, F_SETFD, FD_CLOEXEC);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    return fd;
}

static int allowed(const cf_plcsrv_opts_t *o, uint32_t addr)
{
    for (int i = 0; i < o->nallow; i++)
        if ((addr & o->allow_mask[i]) == o->allow_net[i])
            return 1;
    return o->nallow == 0;
}

/* A new connection: refused (allow-list, too many) or added. */
static void accept_one(srv_t *s, const cf_plcsrv_opts_t *o, int lfd, client_t *cl, int *nc,
                       uint32_t *t_refused)
{
    struct sockaddr_in sa;
    socklen_t sl = sizeof sa;
    int fd = accept(lfd, (struct sockaddr *)&sa, &sl);
    if (fd < 0)
        return;
    fcntl(fd, F_SETFD, FD_CLOEXEC);
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    char name[32];
    snprintf(name, sizeof name, "client %s:%d", inet_ntoa(sa.sin_addr), ntohs(sa.sin_port));
    const char *why = !allowed(o, ntohl(sa.sin_addr.s_addr)) ? "not in the allow-list"
                      : *nc >= o->max_clients                ? "too many clients"
                                                             : NULL;
    if (why) {
        uint32_t t = now_ms();
        if ((uint32_t)(t - *t_refused) >= 1000) { /* one line a second at most */
            cf_log(CF_LOG_WARN, "%s refused: %s (%d connected)", name, why, *nc);
            *t_refused = t;
        }
        close(fd);
        return;
    }
    client_t *c = &cl[(*nc)++];
    memset(c, 0, sizeof *c);
    c->fd = fd;
    c->t_tok = now_ms();
    c->t_warn = c->t_tok - 1000; /* the first refusal is logged at once */
    c->tokens = o->max_rate < 1 ? 1 : o->max_rate;
    snprintf(c->name, sizeof c->name, "%s", name);
    set_clients(s, *nc);
    cf_log(CF_LOG_INFO, "%s connected (%d)", name, *nc);
}

int cf_plcsrv_run(const cf_plcsrv_opts_t *o, const cf_runner_t *r, volatile sig_atomic_t *stop)
{
    static srv_t s; /* one server a process; its table outlives no call */
    memset(&s, 0, sizeof s);
    pthread_mutex_init(&s.mu, NULL);
    s.run = r;
    plc_map_init(&s.map, o->word_order, BOARD_NAME);
    plc_fsm_init(&s.fsm, &s.map, r->rig, (uint16_t)o->watchdog_ms, r->check, r->ctx, now_ms());
    plc_map_put_f32(&s.map, PLC_R_TOLERANCE, o->tol);
    plc_map_put_f32(&s.map, PLC_R_ALPHA, o->alpha);
    plc_map_put_f32(&s.map, PLC_R_BETA, o->beta);

    int ret = -1, lfd = -1, nc = 0;
    uint32_t t_refused = now_ms() - 1000;
    client_t *cl = calloc((size_t)o->max_clients, sizeof *cl);
    if (!cl) {
        cf_log(CF_LOG_ERROR, "cannot set up the Modbus server: out of memory");
        goto out;
    }
    lfd = open_listener(o);
    if (lfd < 0) {
        cf_log(CF_LOG_ERROR, "cannot listen on %s:%d: %s", o->addr, o->port, strerror(errno));
        goto out;
    }
    int port = listen_port(lfd);
    if (o->port_file && write_port_file(o->port_file, port)) {
        cf_log(CF_LOG_ERROR, "cannot write the port file %s: %s", o->port_file, strerror(errno));
        goto out;
    }
    cf_log(CF_LOG_INFO,
           "listening on %s:%d (Modbus TCP, %d clients at most, %s, rate limit %g/s, word "
           "order %s, watchdog %u ms, rig %s)",
           o->addr, port, o->max_clients, o->nallow ? "allow-list" : "any address", o->max_rate,
           o->word_order == PLC_ORDER_HI_LO ? "hi-lo" : "lo-hi", o->watchdog_ms,
           r->rig ? "configured" : "not configured");
    while (!*stop) {
        fd_set rd;
        FD_ZERO(&rd);
        FD_SET(lfd, &rd);
        int top = lfd;
        for (int i = 0; i < nc; i++) {
            FD_SET(cl[i].fd, &rd);
            top = cl[i].fd > top ? cl[i].fd : top;
        }
        struct timeval tv = {0, TICK_MS * 1000};
        int k = select(top + 1, &rd, NULL, NULL, &tv);
        if (k < 0 && errno != EINTR) {
            cf_log(CF_LOG_ERROR, "select: %s", strerror(errno));
            break;
        }
        int code = r->health ? r->health(r->ctx) : 0;
        pthread_mutex_lock(&s.mu);
        plc_action_t a = code ? plc_fsm_fault(&s.fsm, (uint16_t)code, 1) : PLC_ACT_NONE;
        plc_action_t w = plc_fsm_tick(&s.fsm, now_ms());
        if (w == PLC_ACT_ABORT)
            cf_log(CF_LOG_ERROR, "watchdog: PLC heartbeat unchanged for %u ms: error %d",
                   plc_map_u16(&s.map, PLC_R_WATCHDOG_MS), PLC_E_WATCHDOG);
        pthread_mutex_unlock(&s.mu);
        act(&s, a != PLC_ACT_NONE ? a : w);
        if (atomic_load(&s.job_ended))
            join_worker(&s);
        uint32_t t = now_ms();
        for (int i = 0; i < nc; i++) {
            client_t *c = &cl[i];
            int gone = 0;
            if (k > 0 && FD_ISSET(c->fd, &rd))
                gone = client_input(&s, o, c) != 0;
            if (!gone && c->have > 0 && (uint32_t)(t - c->t_first) > FRAME_MS) {
                cf_log(CF_LOG_WARN, "%s: frame incomplete for %d ms (%zu bytes): closed", c->name,
                       FRAME_MS, c->have);
                gone = 1;
            }
            if (gone) {
                close(c->fd);
                cl[i--] = cl[--nc];
                set_clients(&s, nc);
            }
        }
        if (k > 0 && FD_ISSET(lfd, &rd))
            accept_one(&s, o, lfd, cl, &nc, &t_refused);
    }
    ret = 0;
    cf_log(CF_LOG_INFO, "stopping");
out:
    /* Shutdown: a running job is aborted and waited for. */
    if (s.worker_live) {
        atomic_store(&s.stop_job, 1);
        r->abort(r->ctx);
        join_worker(&s);
    }
    for (int i = 0; i < nc; i++)
        close(cl[i].fd);
    if (lfd >= 0)
        close(lfd);
    if (o->port_file && ret == 0)
        remove(o->port_file);
    free(cl);
    pthread_mutex_destroy(&s.mu);
    return ret;
}
