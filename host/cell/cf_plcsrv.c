/* SPDX-License-Identifier: MIT */
/* cf_plcsrv.c: Modbus TCP server of the cell (cf_plcsrv.h): the select()
 * loop over clients, each client's frame collected (plc_mbap_need) and
 * answered (plc_mbap_pdu) under the mutex, the connection slots (eviction,
 * idle and incomplete-frame timeouts, keepalive), the rate limit, the
 * allow-list and the log limiter, the worker thread that runs a job's
 * phases, the watchdog tick. Only this thread touches the sockets; the
 * worker touches the register table only under the mutex. */
#include "cf_plcsrv.h"
#include "cf_log.h"
#include "cf_portfile.h"
#include "cf_thread.h"
#include "plc_mbap.h"
#include "rig_err.h"
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
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
#define MBAP_HDR PLC_MBAP_HDR
#define MBAP_MAX PLC_MBAP_MAX

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
        int none = 0; /* a reason already given (RIG_ELOST) stays */
        atomic_compare_exchange_strong(&s->stop_job, &none, 1);
        s->run->abort(s->run->ctx);
        cf_log(CF_LOG_WARN, "abort: job asked to stop, motion stopped");
    } else if (a == PLC_ACT_START) {
        /* The job's UTC time (JOB_TIME, the report): the state machine has
         * no wall clock. Set before the worker copies the parameters. */
        pthread_mutex_lock(&s->mu);
        s->fsm.job_params.utc = (uint32_t)time(NULL);
        pthread_mutex_unlock(&s->mu);
        join_worker(s); /* the previous job's thread has ended its job already */
        atomic_store(&s->stop_job, 0);
        atomic_store(&s->job_ended, 0);
        /* The worker takes no signals: SIGTERM interrupts the select loop. */
        int rc = cf_thread_start(&s->worker, worker_main, s);
        if (rc) {
            cf_log(CF_LOG_ERROR, "cannot start the job thread: %s", strerror(rc));
            pthread_mutex_lock(&s->mu);
            plc_fsm_event(&s->fsm, PLC_EV_FAIL, PLC_E_MEMORY, NULL);
            pthread_mutex_unlock(&s->mu);
        } else
            s->worker_live = 1;
    }
}

static void put16(uint8_t *p, unsigned v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

/* The log limiter's memory of one kind of line: its key, when it was last
 * logged, how many more like it were held back since. */
#define REP_KEYS 4 /* kinds of line per client (they interleave: refusals, rate limit) */
typedef struct rep {
    char key[64];
    uint32_t t;
    unsigned long n;
    int level;
} rep_t;

typedef struct client {
    int fd;
    size_t have;      /* bytes of the frame being received */
    uint32_t t_first; /* when its first byte came (ms) */
    /* Idle since: the last complete request (or the connection). Bytes of a
     * frame never completed do not count: a slowloris stays idle. */
    uint32_t t_active;
    int served;    /* it has sent a complete request */
    double tokens; /* rate limit: requests that may come now */
    uint32_t t_tok;
    rep_t rep[REP_KEYS]; /* the log limiter */
    uint8_t buf[MBAP_MAX];
    char name[32];
} client_t;

/* Lines of one kind held back: their count, once. */
static void rep_flush(const client_t *c, rep_t *r, uint32_t t)
{
    if (r->n)
        cf_log((cf_log_level_t)r->level, "%s: %lu more like \"%s\" in the last %.1f s", c->name,
               r->n, r->key, (double)(uint32_t)(t - r->t) * 1e-3);
    r->n = 0;
    r->t = t;
}

/* Every count due (all: every count, the client is leaving). */
static void rep_tick(client_t *c, uint32_t t, int all)
{
    for (int i = 0; i < REP_KEYS; i++)
        if (c->rep[i].n && (all || (uint32_t)(t - c->rep[i].t) >= CF_PLCSRV_LOG_REPEAT_MS))
            rep_flush(c, &c->rep[i], t);
}

/* 1 when a line of this key may be logged now: the first of its kind at
 * once, the same kind again only CF_PLCSRV_LOG_REPEAT_MS later (the count of
 * those held back logged on its own line). A client sending 1,000 refused
 * commands a second logs a line every few seconds, not 1,000. */
static int rep_pass(client_t *c, int level, const char *key, uint32_t t)
{
    rep_t *r = NULL;
    for (int i = 0; i < REP_KEYS && !r; i++)
        if (c->rep[i].key[0] && !strcmp(c->rep[i].key, key))
            r = &c->rep[i];
    if (r) {
        if ((uint32_t)(t - r->t) < CF_PLCSRV_LOG_REPEAT_MS) {
            r->n++;
            return 0;
        }
        rep_flush(c, r, t);
        return 1;
    }
    r = &c->rep[0]; /* a new kind: an empty slot, else the one logged longest ago */
    for (int i = 1; i < REP_KEYS && r->key[0]; i++)
        if (!c->rep[i].key[0] || (uint32_t)(t - c->rep[i].t) > (uint32_t)(t - r->t))
            r = &c->rep[i];
    rep_flush(c, r, t);
    snprintf(r->key, sizeof r->key, "%s", key);
    r->level = level;
    return 1;
}

/* One request PDU (q, n bytes) into a reply PDU (r); returns its length.
 * The PDU itself is plc_mbap_pdu's; here the lock and the log. */
static size_t handle_pdu(srv_t *s, client_t *c, const uint8_t *q, size_t n, uint8_t *r,
                         plc_action_t *todo)
{
    uint32_t t = now_ms();
    plc_req_t rq;
    pthread_mutex_lock(&s->mu);
    uint32_t ncmd = s->fsm.ncmd;
    size_t rn = plc_mbap_pdu(&s->fsm, q, n, r, t, todo, &rq);
    plc_fsm_t f = s->fsm;
    pthread_mutex_unlock(&s->mu);
    if (f.ncmd != ncmd) {
        char key[64];
        const char *cn = plc_cmd_name(f.last_cmd);
        if (f.cmd_result) {
            /* Refusals repeat (a PLC retrying in a loop): limited per client. */
            snprintf(key, sizeof key, "command %s refused, %u", cn, f.cmd_result);
            if (rep_pass(c, CF_LOG_WARN, key, t))
                cf_log(CF_LOG_WARN, "command %s seq %u: refused, %s (%u), from %s", cn, f.ack_seq,
                       plc_strerror(f.cmd_result), f.cmd_result, c->name);
        } else
            cf_log(CF_LOG_INFO, "command %s seq %u: accepted%s, from %s", cn, f.ack_seq,
                   *todo == PLC_ACT_START ? ", job started" : "", c->name);
    }
    if (rq.ex) {
        char key[64];
        snprintf(key, sizeof key, "function %u: exception %d", rq.fc, rq.ex);
        if (rep_pass(c, CF_LOG_DEBUG, key, t))
            cf_log(CF_LOG_DEBUG, "%s: function %u at %u x %u: exception %d", c->name, rq.fc,
                   rq.addr, rq.cnt, rq.ex);
    }
    return rn;
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
static int rate_ok(srv_t *s, const cf_plcsrv_opts_t *o, client_t *c, uint32_t t)
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
    pthread_mutex_lock(&s->mu);
    plc_map_inc_u32(&s->map, PLC_R_REQ_REFUSED);
    pthread_mutex_unlock(&s->mu);
    if (rep_pass(c, CF_LOG_WARN, "over the rate limit", t))
        cf_log(CF_LOG_WARN, "%s: over %g requests/s: refused (exception 06)", c->name, o->max_rate);
    return 0;
}

/* Bytes from one client: every complete frame answered in turn. 0, or -1
 * when the client must go (closed, malformed header, unanswerable). */
static int client_input(srv_t *s, const cf_plcsrv_opts_t *o, client_t *c)
{
    for (;;) {
        int need = plc_mbap_need(c->buf, c->have);
        if (need == PLC_MBAP_BAD) {
            cf_log(CF_LOG_WARN, "%s: malformed MBAP header (protocol %u, length %u): closed",
                   c->name, (unsigned)c->buf[2] << 8 | c->buf[3],
                   (unsigned)c->buf[4] << 8 | c->buf[5]);
            return -1;
        }
        size_t want = (size_t)need;
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
        uint32_t t = now_ms();
        c->t_active = t; /* a request, answered or refused: the client is alive */
        c->served = 1;
        if (rate_ok(s, o, c, t))
            rn = handle_pdu(s, c, c->buf + MBAP_HDR, want - MBAP_HDR, out + MBAP_HDR, &todo);
        else
            rn = plc_mbap_exception(c->buf + MBAP_HDR, PLC_EX_BUSY, out + MBAP_HDR);
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

/* The scan counts fill SCAN_TRIGGERS .. SCAN_OVERRUNS, two registers each. */
_Static_assert(PLC_R_SCAN_OVERRUNS == PLC_R_SCAN_TRIGGERS + 2 * (CF_PLC_SCAN_COUNTS - 1),
               "cf_plc_stats_t.scan and the SCAN_* registers");

/* Map version 3's outbox and scan registers from the cell (o->stats). */
static void put_stats(srv_t *s, const cf_plcsrv_opts_t *o)
{
    cf_plc_stats_t v;
    memset(&v, 0, sizeof v);
    o->stats(o->stats_ctx, &v);
    pthread_mutex_lock(&s->mu);
    if (v.have_outbox) {
        plc_map_put_u32(&s->map, PLC_R_OUTBOX_PG, v.outbox_pg);
        plc_map_put_u32(&s->map, PLC_R_OUTBOX_MQTT, v.outbox_mqtt);
        plc_map_put_u32(&s->map, PLC_R_OUTBOX_AGE, v.outbox_age_s);
        plc_map_put_u32(&s->map, PLC_R_OUTBOX_DROPPED, v.outbox_dropped);
    }
    for (unsigned i = 0; i < CF_PLC_SCAN_COUNTS; i++)
        plc_map_put_u32(&s->map, PLC_R_SCAN_TRIGGERS + 2 * i, v.scan[i]);
    pthread_mutex_unlock(&s->mu);
}

/* CLIENTS, and one of the connection counters (0: none). */
static void set_clients(srv_t *s, int n, unsigned counter)
{
    pthread_mutex_lock(&s->mu);
    plc_map_put_u16(&s->map, PLC_R_CLIENTS, (uint16_t)n);
    if (counter)
        plc_map_inc_u32(&s->map, counter);
    pthread_mutex_unlock(&s->mu);
}

/* Close client i (its last held-back log lines said) and fill its slot. */
static void drop_client(srv_t *s, client_t *cl, int *nc, int i, unsigned counter)
{
    rep_tick(&cl[i], now_ms(), 1);
    close(cl[i].fd);
    cl[i] = cl[--*nc];
    set_clients(s, *nc, counter);
}

/* The slot to free for a new connection: one that never completed a
 * request (a slowloris, a port scan, a half-open socket) before one that
 * did, then the longest idle. A PLC that lost its connection (cable pulled,
 * rebooted) is served again at once, whatever the slots hold. */
static int evict_choice(const client_t *cl, int nc, uint32_t t)
{
    int best = -1;
    for (int i = 0; i < nc; i++) {
        const client_t *c = &cl[i], *b = best < 0 ? NULL : &cl[best];
        if (!b || c->served < b->served ||
            (c->served == b->served && (uint32_t)(t - c->t_active) > (uint32_t)(t - b->t_active)))
            best = i;
    }
    return best;
}

/* Keepalive: a dead peer that sends nothing is found by the kernel. */
static void keepalive(int fd)
{
    int one = 1, idle = CF_PLCSRV_KA_IDLE_S, intvl = CF_PLCSRV_KA_INTVL_S, cnt = CF_PLCSRV_KA_CNT;
    if (setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one) ||
        setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle) ||
        setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &intvl, sizeof intvl) ||
        setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &cnt, sizeof cnt))
        cf_log(CF_LOG_WARN, "TCP keepalive not set: %s", strerror(errno));
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

/* A new connection: refused (allow-list) or added, the longest idle
 * evicted when every slot is taken. */
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
    uint32_t t = now_ms();
    if (!allowed(o, ntohl(sa.sin_addr.s_addr))) {
        if ((uint32_t)(t - *t_refused) >= 1000) { /* one line a second at most */
            cf_log(CF_LOG_WARN, "%s refused: not in the allow-list (%d connected)", name, *nc);
            *t_refused = t;
        }
        close(fd);
        return;
    }
    if (*nc >= o->max_clients && *nc == 0) { /* no slot at all (max_clients 0) */
        close(fd);
        return;
    }
    if (*nc >= o->max_clients) {
        int v = evict_choice(cl, *nc, t);
        cf_log(CF_LOG_WARN, "%s: all %d slots taken: %s evicted (%s, idle %u ms)", name,
               o->max_clients, cl[v].name, cl[v].served ? "served before" : "never a request",
               (unsigned)(t - cl[v].t_active));
        drop_client(s, cl, nc, v, PLC_R_CONN_EVICTED);
    }
    keepalive(fd);
    client_t *c = &cl[(*nc)++];
    memset(c, 0, sizeof *c);
    c->fd = fd;
    c->t_tok = c->t_active = t;
    c->tokens = o->max_rate < 1 ? 1 : o->max_rate;
    snprintf(c->name, sizeof c->name, "%s", name);
    set_clients(s, *nc, PLC_R_CONN_ACCEPTED);
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
    plc_map_put_f32(&s.map, PLC_R_FIT_TOL, o->fit_tol);
    if (o->fit_within > 0)
        plc_map_put_f32(&s.map, PLC_R_FIT_WITHIN, o->fit_within);
    plc_map_put_u32(&s.map, PLC_R_FIT_MAX_CP, o->fit_max_cp);
    plc_map_put_u16(&s.map, PLC_R_FIT_REFINE, o->fit_refine);
    plc_map_put_u16(&s.map, PLC_R_FIT_ROBUST, o->fit_robust);
    plc_map_put_u16(&s.map, PLC_R_FIT_REPARAM, o->fit_reparam);

    int ret = -1, lfd = -1, nc = 0;
    uint32_t t_refused = now_ms() - 1000, t_stats = now_ms() - CF_PLCSRV_STATS_MS;
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
    if (o->portfile ? cf_portfile_write(o->portfile, port) != 0
                    : o->port_file && write_port_file(o->port_file, port)) {
        cf_log(CF_LOG_ERROR, "cannot write the port file %s: %s", o->port_file, strerror(errno));
        goto out;
    }
    unsigned idle_ms = o->idle_ms ? o->idle_ms : CF_PLCSRV_IDLE_MS;
    cf_log(CF_LOG_INFO,
           "listening on %s:%d (Modbus TCP, %d clients at most, idle timeout %u ms, %s, rate "
           "limit %g/s, word order %s, watchdog %u ms, rig %s)",
           o->addr, port, o->max_clients, idle_ms, o->nallow ? "allow-list" : "any address",
           o->max_rate, o->word_order == PLC_ORDER_HI_LO ? "hi-lo" : "lo-hi", o->watchdog_ms,
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
        /* The rig gone for good: the job stops for that reason, which its
         * journal's end record keeps (RIG_ELOST), not as a PLC's abort. */
        if (code == PLC_E_RIG_GONE)
            atomic_store(&s.stop_job, RIG_ELOST);
        act(&s, a != PLC_ACT_NONE ? a : w);
        if (atomic_load(&s.job_ended))
            join_worker(&s);
        uint32_t t = now_ms();
        if (o->stats && (uint32_t)(t - t_stats) >= CF_PLCSRV_STATS_MS) {
            put_stats(&s, o);
            t_stats = t;
        }
        for (int i = 0; i < nc; i++) {
            client_t *c = &cl[i];
            int gone = 0;
            unsigned counter = 0;
            if (k > 0 && FD_ISSET(c->fd, &rd))
                gone = client_input(&s, o, c) != 0;
            t = now_ms(); /* after the input: its requests are not in the future */
            /* A frame must be whole within FRAME_MS of its first byte, however
             * its bytes trickle in (each byte would restart a per-byte clock). */
            if (!gone && c->have > 0 && (uint32_t)(t - c->t_first) > FRAME_MS) {
                cf_log(CF_LOG_WARN, "%s: frame incomplete for %d ms (%zu bytes): closed", c->name,
                       FRAME_MS, c->have);
                gone = 1, counter = PLC_R_CONN_TIMED_OUT;
            }
            if (!gone && (uint32_t)(t - c->t_active) > idle_ms) {
                cf_log(CF_LOG_WARN, "%s: no request for %u ms: closed", c->name, idle_ms);
                gone = 1, counter = PLC_R_CONN_TIMED_OUT;
            }
            if (!gone)
                rep_tick(c, t, 0);
            if (gone)
                drop_client(&s, cl, &nc, i--, counter);
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
    if (o->port_file && !o->portfile && ret == 0)
        remove(o->port_file);
    free(cl);
    pthread_mutex_destroy(&s.mu);
    return ret;
}
