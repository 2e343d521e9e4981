/* cf_plcsrv.c: Modbus TCP server of the cell (cf_plcsrv.h): the select()
 * loop over clients, requests mapped onto plc_map / plc_fsm, the worker
 * thread that runs a job's phases, the watchdog tick. libmodbus is not
 * thread-safe: only this thread touches the context; the worker touches
 * the register table only under the mutex. */
#include "cf_plcsrv.h"
#include "cf_log.h"
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
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

#define TICK_MS 20 /* select timeout: watchdog and heartbeat resolution */

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

/* One request from the client whose socket ctx holds. */
static void handle(srv_t *s, modbus_t *ctx, modbus_mapping_t *mb, const uint8_t *q, int len)
{
    int hl = modbus_get_header_length(ctx), fc = q[hl], ex = 0;
    unsigned a = be16(q + hl + 1), n = 0;
    uint16_t v[PLC_MAX_WRITE];
    plc_action_t todo = PLC_ACT_NONE;
    uint32_t t = now_ms();
    if (fc == 0x03) {
        n = be16(q + hl + 3);
        pthread_mutex_lock(&s->mu);
        /* Into libmodbus's mapping, which modbus_reply answers from. */
        ex = plc_map_read(&s->map, a, n, mb->tab_registers + a);
        pthread_mutex_unlock(&s->mu);
    } else if (fc == 0x06 || fc == 0x10) {
        if (fc == 0x06) {
            n = 1;
            v[0] = (uint16_t)be16(q + hl + 3);
        } else {
            n = be16(q + hl + 3);
            unsigned bytes = q[hl + 5];
            if (n < 1 || n > PLC_MAX_WRITE || bytes != 2 * n || hl + 6 + (int)bytes > len)
                ex = PLC_EX_VALUE;
            for (unsigned k = 0; !ex && k < n; k++)
                v[k] = (uint16_t)be16(q + hl + 6 + 2 * k);
        }
        if (!ex) {
            pthread_mutex_lock(&s->mu);
            uint16_t seq0 = s->fsm.ack_seq;
            ex = plc_fsm_write(&s->fsm, a, n, v, t, &todo);
            plc_fsm_t f = s->fsm;
            pthread_mutex_unlock(&s->mu);
            if (!ex && f.ack_seq != seq0)
                cf_log(f.cmd_result ? CF_LOG_WARN : CF_LOG_INFO, "command %s seq %u: %s%s%s",
                       plc_cmd_name(v[PLC_R_COMMAND - a]), f.ack_seq,
                       f.cmd_result ? "refused, " : "accepted",
                       f.cmd_result ? plc_strerror(f.cmd_result) : "",
                       f.cmd_result ? "" : (todo == PLC_ACT_START ? ", job started" : ""));
        }
    } else
        ex = PLC_EX_FUNCTION;
    if (ex) {
        cf_log(CF_LOG_DEBUG, "function %d at %u x %u: exception %d", fc, a, n, ex);
        modbus_reply_exception(ctx, q, (unsigned)ex);
    } else
        modbus_reply(ctx, q, len, mb); /* the echo or the registers copied above */
    act(s, todo);
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
    int *cl = calloc((size_t)o->max_clients, sizeof *cl);
    modbus_t *ctx = modbus_new_tcp(o->addr, o->port);
    modbus_mapping_t *mb = modbus_mapping_new(0, 0, PLC_NREGS, 0);
    if (!cl || !ctx || !mb) {
        cf_log(CF_LOG_ERROR, "cannot set up the Modbus server: %s", modbus_strerror(errno));
        goto out;
    }
    lfd = modbus_tcp_listen(ctx, o->max_clients);
    if (lfd < 0) {
        cf_log(CF_LOG_ERROR, "cannot listen on %s:%d: %s", o->addr, o->port,
               modbus_strerror(errno));
        goto out;
    }
    fcntl(lfd, F_SETFD, FD_CLOEXEC);
    int port = listen_port(lfd);
    if (o->port_file && write_port_file(o->port_file, port)) {
        cf_log(CF_LOG_ERROR, "cannot write the port file %s: %s", o->port_file, strerror(errno));
        goto out;
    }
    /* A client that starts a frame and stalls must not hold the others:
     * the rest of a frame has to follow within the byte timeout. */
    modbus_set_byte_timeout(ctx, 0, 500000);
    cf_log(CF_LOG_INFO,
           "listening on %s:%d (Modbus TCP, %d clients at most, word order %s, "
           "watchdog %u ms, rig %s)",
           o->addr, port, o->max_clients, o->word_order == PLC_ORDER_HI_LO ? "hi-lo" : "lo-hi",
           o->watchdog_ms, r->rig ? "configured" : "not configured");
    uint8_t q[MODBUS_TCP_MAX_ADU_LENGTH];
    while (!*stop) {
        fd_set rd;
        FD_ZERO(&rd);
        FD_SET(lfd, &rd);
        int top = lfd;
        for (int i = 0; i < nc; i++) {
            FD_SET(cl[i], &rd);
            top = cl[i] > top ? cl[i] : top;
        }
        struct timeval tv = {0, TICK_MS * 1000};
        int k = select(top + 1, &rd, NULL, NULL, &tv);
        if (k < 0 && errno != EINTR) {
            cf_log(CF_LOG_ERROR, "select: %s", strerror(errno));
            break;
        }
        pthread_mutex_lock(&s.mu);
        plc_action_t a = plc_fsm_tick(&s.fsm, now_ms());
        if (a == PLC_ACT_ABORT)
            cf_log(CF_LOG_ERROR, "watchdog: PLC heartbeat unchanged for %u ms: error %d",
                   plc_map_u16(&s.map, PLC_R_WATCHDOG_MS), PLC_E_WATCHDOG);
        pthread_mutex_unlock(&s.mu);
        act(&s, a);
        if (atomic_load(&s.job_ended))
            join_worker(&s);
        if (k <= 0)
            continue;
        if (FD_ISSET(lfd, &rd)) {
            struct sockaddr_in sa;
            socklen_t sl = sizeof sa;
            int fd = accept(lfd, (struct sockaddr *)&sa, &sl);
            if (fd >= 0)
                fcntl(fd, F_SETFD, FD_CLOEXEC);
            if (fd >= 0 && nc >= o->max_clients) {
                cf_log(CF_LOG_WARN, "client %s:%d refused: %d clients already",
                       inet_ntoa(sa.sin_addr), ntohs(sa.sin_port), nc);
                close(fd);
            } else if (fd >= 0) {
                cl[nc++] = fd;
                set_clients(&s, nc);
                cf_log(CF_LOG_INFO, "client %s:%d connected (%d)", inet_ntoa(sa.sin_addr),
                       ntohs(sa.sin_port), nc);
            }
        }
        for (int i = 0; i < nc; i++) {
            if (!FD_ISSET(cl[i], &rd))
                continue;
            modbus_set_socket(ctx, cl[i]);
            int len = modbus_receive(ctx, q);
            if (len > 0)
                handle(&s, ctx, mb, q, len);
            else if (len < 0) { /* closed by the peer, or a broken frame */
                cf_log(CF_LOG_INFO, "client left (%s)", modbus_strerror(errno));
                close(cl[i]);
                cl[i--] = cl[--nc];
                set_clients(&s, nc);
            }
        }
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
        close(cl[i]);
    if (lfd >= 0)
        close(lfd);
    if (o->port_file && ret == 0)
        remove(o->port_file);
    if (mb)
        modbus_mapping_free(mb);
    if (ctx)
        modbus_free(ctx);
    free(cl);
    pthread_mutex_destroy(&s.mu);
    return ret;
}
