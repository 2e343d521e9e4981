/* SPDX-License-Identifier: MIT */
/* test_plcsrv.c: the PLC server's framing and PDUs (firmware/plc_mbap.c)
 * against frames written out byte by byte here, and the server itself
 * (host/cf_plcsrv.c) on 127.0.0.1, port 0, in a thread of this process,
 * driven through raw sockets: the idle timeout (a silent connection closed,
 * one sending requests kept), eviction when every slot is taken (the one
 * that never sent a request goes, the active one stays), the 1 s rule for
 * a frame trickled in, and the counters that record them. */
#include "cf_plcsrv.h"
#include "cf_test.h"
#include "plc_mbap.h"
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

/* ---- framing and PDUs ---- */

static void test_mbap_need(void **state)
{
    (void)state;
    /* transaction 0x1234, protocol 0, length 6 (unit + 5-byte PDU), unit 1 */
    const uint8_t h[] = {0x12, 0x34, 0x00, 0x00, 0x00, 0x06, 0x01};
    for (size_t n = 0; n < 6; n++)
        assert_int_equal(plc_mbap_need(h, n), 7); /* the header first */
    assert_int_equal(plc_mbap_need(h, 6), 12);
    assert_int_equal(plc_mbap_need(h, 7), 12);
    uint8_t b[7];
    memcpy(b, h, 7);
    b[3] = 1; /* protocol 1 */
    assert_int_equal(plc_mbap_need(b, 6), PLC_MBAP_BAD);
    b[3] = 0, b[5] = 1; /* length 1: no function code */
    assert_int_equal(plc_mbap_need(b, 6), PLC_MBAP_BAD);
    b[5] = 2; /* the shortest: unit + function */
    assert_int_equal(plc_mbap_need(b, 6), 8);
    b[4] = 0, b[5] = 254; /* 6 + 254 = 260, the largest */
    assert_int_equal(plc_mbap_need(b, 6), 260);
    b[5] = 255;
    assert_int_equal(plc_mbap_need(b, 6), PLC_MBAP_BAD);
    b[4] = 0xFF;
    assert_int_equal(plc_mbap_need(b, 6), PLC_MBAP_BAD);
}

static void test_mbap_pdu(void **state)
{
    (void)state;
    plc_map_t m;
    plc_fsm_t f;
    plc_map_init(&m, PLC_ORDER_LO_HI, "sim");
    plc_fsm_init(&f, &m, 0, 0, NULL, NULL, 0);
    uint8_t r[256];
    plc_action_t act;
    plc_req_t rq;
    /* 03 and 04 at 0 x 2: 17222 (0x4346) and map version 3. */
    for (uint8_t fc = 3; fc <= 4; fc++) {
        const uint8_t q[] = {fc, 0x00, 0x00, 0x00, 0x02};
        const uint8_t want[] = {fc, 4, 0x43, 0x46, 0x00, 0x03};
        assert_int_equal(plc_mbap_pdu(&f, q, sizeof q, r, 0, &act, &rq), sizeof want);
        assert_memory_equal(r, want, sizeof want);
        assert_int_equal(rq.ex, 0);
    }
    /* 06: PLC_HEARTBEAT (22) = 0x0102, echoed. */
    const uint8_t w6[] = {0x06, 0x00, 0x16, 0x01, 0x02};
    assert_int_equal(plc_mbap_pdu(&f, w6, sizeof w6, r, 0, &act, &rq), 5);
    assert_memory_equal(r, w6, 5);
    assert_int_equal(m.reg[22], 0x0102);
    /* 16: HOME (1), sequence 1, heartbeat 3 at 20-22: address and count. */
    const uint8_t w16[] = {0x10, 0x00, 0x14, 0x00, 0x03, 0x06, 0, 1, 0, 1, 0, 3};
    const uint8_t a16[] = {0x10, 0x00, 0x14, 0x00, 0x03};
    assert_int_equal(plc_mbap_pdu(&f, w16, sizeof w16, r, 0, &act, &rq), 5);
    assert_memory_equal(r, a16, 5);
    assert_int_equal(m.reg[PLC_R_ACK_SEQ], 1);
    assert_int_equal(m.reg[PLC_R_CMD_RESULT], PLC_E_NO_RIG); /* taken, refused: no rig */
    /* Exceptions: function 05 (01), a byte count that lies (03), a read of
     * 126 (03), a read past the map (02), a write to MAGIC (02). */
    static const struct {
        uint8_t q[8];
        size_t n;
        uint8_t ex;
    } bad[] = {
        {{0x05, 0, 0, 0xFF, 0}, 5, 1},        {{0x10, 0, 22, 0, 1, 4, 0, 1}, 8, 3},
        {{0x03, 0, 0, 0, 126}, 5, 3},         {{0x03, 0, 181, 0, 2}, 5, 2},
        {{0x06, 0, 0, 0, 1}, 5, 2},           {{0x03, 0, 0, 0}, 4, 3},
        {{0x10, 0, 22, 0, 1, 2, 0, 1}, 7, 3},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        uint32_t n0 = plc_map_u32(&m, PLC_R_REQ_REFUSED);
        assert_int_equal(plc_mbap_pdu(&f, bad[i].q, bad[i].n, r, 0, &act, &rq), 2);
        assert_int_equal(r[0], bad[i].q[0] | 0x80);
        assert_int_equal(r[1], bad[i].ex);
        assert_int_equal(rq.ex, bad[i].ex);
        assert_int_equal(plc_map_u32(&m, PLC_R_REQ_REFUSED), n0 + 1);
    }
    uint8_t q[2] = {0x2B, 0x0E}, rx[2];
    assert_int_equal(plc_mbap_exception(q, PLC_EX_BUSY, rx), 2);
    assert_int_equal(rx[0], 0xAB);
    assert_int_equal(rx[1], 6);
}

/* ---- the server on loopback ---- */

static int run_ok(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    (void)ctx, (void)p, (void)ctl;
    return 0;
}

static int fit_ok(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl, plc_results_t *res)
{
    (void)ctx, (void)p, (void)ctl, (void)res;
    return 0;
}

static void no_abort(void *ctx)
{
    (void)ctx;
}

static const cf_runner_t RUNNER = {NULL, run_ok, run_ok, fit_ok, run_ok, no_abort, NULL, NULL, 0};
static volatile sig_atomic_t STOP;
static cf_plcsrv_opts_t OPTS;

static void *server(void *arg)
{
    (void)arg;
    return (void *)(intptr_t)cf_plcsrv_run(&OPTS, &RUNNER, &STOP);
}

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int dial(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in sa;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)port);
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_true(fd >= 0);
    assert_int_equal(connect(fd, (struct sockaddr *)&sa, sizeof sa), 0);
    struct timeval tv = {2, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    return fd;
}

/* Read n registers at a: their values, or -1 when the connection is gone. */
static int read_regs(int fd, unsigned a, unsigned n, uint16_t *out)
{
    uint8_t q[12] = {0, 1, 0, 0, 0, 6, 1, 3, (uint8_t)(a >> 8), (uint8_t)a, 0, (uint8_t)n};
    uint8_t r[260];
    if (send(fd, q, sizeof q, MSG_NOSIGNAL) != (ssize_t)sizeof q)
        return -1;
    size_t want = 9 + 2 * n, got = 0;
    while (got < want) {
        ssize_t k = recv(fd, r + got, want - got, 0);
        if (k <= 0)
            return -1;
        got += (size_t)k;
    }
    for (unsigned i = 0; i < n; i++)
        out[i] = (uint16_t)(r[9 + 2 * i] << 8 | r[10 + 2 * i]);
    return 0;
}

/* 1 when the server has closed fd within the receive timeout (end of
 * stream, or a reset after a byte sent to the closed socket). */
static int closed(int fd)
{
    uint8_t b;
    ssize_t k = recv(fd, &b, 1, 0);
    return k == 0 || (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

static void test_server_slots(void **state)
{
    (void)state;
    char pf[512];
    const char *d = getenv("CF_TEST_TMP");
    d = d && *d ? d : "/tmp";
    mkdir(d, 0777); /* one level: make unit-run's build/<tree>/tmp */
    snprintf(pf, sizeof pf, "%s/cf_plcsrv_%ld.port", d, (long)getpid());
    remove(pf);
    memset(&OPTS, 0, sizeof OPTS);
    OPTS.addr = "127.0.0.1";
    OPTS.max_clients = 2;
    OPTS.port_file = pf;
    OPTS.idle_ms = 1500; /* longer than the 1 s rule, tested below */
    STOP = 0;
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, server, NULL), 0);
    int port = 0;
    for (int i = 0; i < 200 && port <= 0; i++) {
        FILE *f = fopen(pf, "r");
        if (f) {
            if (fscanf(f, "%d", &port) != 1)
                port = 0;
            fclose(f);
        }
        if (port <= 0)
            sleep_ms(10);
    }
    assert_true(port > 0);
    uint16_t w[17];
    /* Idle: a silent connection closes after ~1.5 s; one reading every
     * 0.1 s stays. */
    int silent = dial(port), active = dial(port);
    double t0 = now_s();
    double t_gone = -1;
    for (int i = 0; i < 25; i++) {
        assert_int_equal(read_regs(active, 0, 1, w), 0);
        assert_int_equal(w[0], PLC_MAGIC);
        struct timeval tv = {0, 100000};
        setsockopt(silent, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        if (t_gone < 0 && closed(silent))
            t_gone = now_s() - t0;
    }
    assert_true(t_gone >= 1.5 && t_gone < 2.5); /* not before its time, and then soon */
    close(silent);
    /* Full slots (2): a connection that never sent a request is evicted
     * for a new one, the active one stays. */
    int never = dial(port);
    sleep_ms(50);
    assert_int_equal(read_regs(active, 0, 1, w), 0);
    int fresh = dial(port);
    assert_int_equal(read_regs(fresh, 0, 1, w), 0);
    struct timeval tv = {2, 0};
    setsockopt(never, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    assert_true(closed(never));
    close(never);
    sleep_ms(50); /* idle times a clear 50 ms apart (the server counts ms) */
    assert_int_equal(read_regs(active, 0, 1, w), 0);
    sleep_ms(20);
    /* Both served before: the longest idle goes (active read last). */
    int third = dial(port);
    assert_int_equal(read_regs(third, 0, 1, w), 0);
    assert_true(closed(fresh));
    close(fresh);
    assert_int_equal(read_regs(active, 0, 1, w), 0);
    /* The 1 s rule: a header trickled a byte every 0.3 s is cut. */
    close(third);
    sleep_ms(100); /* the server sees third leave: a free slot, no eviction */
    int slow = dial(port);
    const uint8_t hdr[] = {0, 1, 0, 0, 0, 6, 1};
    int cut = 0;
    t0 = now_s();
    for (size_t i = 0; i < sizeof hdr && !cut; i++) {
        cut = send(slow, hdr + i, 1, MSG_NOSIGNAL) != 1;
        struct timeval st = {0, 300000};
        setsockopt(slow, SOL_SOCKET, SO_RCVTIMEO, &st, sizeof st);
        cut = cut || closed(slow);
        assert_int_equal(read_regs(active, 0, 1, w), 0); /* the others never wait */
    }
    assert_true(cut);
    assert_true(now_s() - t0 >= 1.0);
    close(slow);
    /* The counters: 2 evictions, 2 timeouts (idle, 1 s rule). */
    sleep_ms(50);
    assert_int_equal(read_regs(active, PLC_R_CONN_ACCEPTED, 10, w), 0);
    assert_int_equal(w[0] | w[1] << 16, 6); /* silent, active, never, fresh, third, slow */
    assert_int_equal(w[2] | w[3] << 16, 2);
    assert_int_equal(w[4] | w[5] << 16, 2);
    close(active);
    STOP = 1;
    void *ret;
    pthread_join(th, &ret);
    assert_int_equal((intptr_t)ret, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mbap_need),
        cmocka_unit_test(test_mbap_pdu),
        cmocka_unit_test(test_server_slots),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
