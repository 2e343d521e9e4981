/* SPDX-License-Identifier: MIT */
/* test_hal_stop.c: the transports' stop check (hal.h's should_stop,
 * hal/hal_stop.c) against a Modbus TCP device that accepts the connection
 * and never answers (a hung device): without a stop a request makes its
 * opts.retries retries and times out; with a stop asked it makes one
 * attempt and gives up (RIG_EABORTED, no retry counted); the next request
 * under the same stop is not sent at all; once the stop is withdrawn the
 * device is asked again with its retries. Counts, not timings, are
 * checked. */
#include "hal.h"
#include "hal_priv.h"
#include "rig_err.h"
#include <arpa/inet.h>
#include <netinet/in.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmocka.h>

static int stop_flag;

static int stop_check(void *ctx)
{
    return *(int *)ctx;
}

/* A listener that never accepts: the kernel completes the connection, no
 * byte is ever answered. Returns the fd, *port its port. */
static int hung_listener(int *port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_in sa;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(bind(fd, (struct sockaddr *)&sa, sizeof sa), 0);
    assert_int_equal(listen(fd, 4), 0);
    socklen_t sl = sizeof sa;
    assert_int_equal(getsockname(fd, (struct sockaddr *)&sa, &sl), 0);
    *port = ntohs(sa.sin_port);
    return fd;
}

static void test_modbus_hung(void **state)
{
    (void)state;
    int port, lfd = hung_listener(&port);
    char uri[64], msg[256];
    snprintf(uri, sizeof uri, "tcp:127.0.0.1:%d:1", port);
    hal_opts_t o = HAL_OPTS_DEFAULT;
    o.timeout_ms = 50;
    o.retries = 2;
    o.backoff_ms = 5;
    o.late_ms = 20;
    hal_t *h;
    assert_int_equal(hal_open(uri, &o, &h, msg, sizeof msg), RIG_OK);
    hal_set_stop(h, stop_check, &stop_flag);
    uint16_t r[2];
    /* No stop: the retries, then the timeout. */
    stop_flag = 0;
    assert_int_equal(hal_read_regs(h, 'h', 0, 2, r), RIG_ETIMEOUT);
    assert_int_equal(h->retries, 2);
    assert_int_equal(h->stop_dead, 0);
    /* A stop asked: one attempt, no retry, and the device taken as hung. */
    stop_flag = 1;
    assert_int_equal(hal_read_regs(h, 'h', 0, 2, r), RIG_EABORTED);
    assert_int_equal(h->retries, 2);
    assert_int_equal(h->stop_dead, 1);
    assert_non_null(strstr(hal_last_error(h), "stop asked: gave up after one attempt"));
    /* Under the same stop it is not asked again (a STOP write included). */
    uint16_t w = 3;
    assert_int_equal(hal_write_regs(h, 4, 1, &w), RIG_EABORTED);
    assert_non_null(strstr(hal_last_error(h), "not asked again"));
    assert_int_equal(h->retries, 2);
    /* The stop withdrawn: asked again, with its retries. */
    stop_flag = 0;
    assert_int_equal(hal_read_regs(h, 'h', 0, 2, r), RIG_ETIMEOUT);
    assert_int_equal(h->retries, 4);
    assert_int_equal(h->stop_dead, 0);
    hal_close(h);
    close(lfd);
}

static void test_wait(void **state)
{
    (void)state;
    hal_t h;
    memset(&h, 0, sizeof h);
    /* No check installed: a plain sleep. */
    assert_int_equal(hal_wait_ms(&h, 1), RIG_OK);
    assert_int_equal(hal_stopped(&h), 0);
    hal_set_stop(&h, stop_check, &stop_flag);
    stop_flag = 0;
    assert_int_equal(hal_wait_ms(&h, 1), RIG_OK);
    assert_int_equal(hal_stop_before(&h), RIG_OK);
    assert_int_equal(hal_stop_after(&h, RIG_ETIMEOUT), RIG_OK); /* no stop: the caller retries */
    stop_flag = 1;
    /* A stop asked: the wait ends at once (an hour asked). */
    assert_int_equal(hal_wait_ms(&h, 3600e3), RIG_EABORTED);
    assert_int_equal(hal_stop_before(&h), RIG_OK); /* not yet found hung */
    assert_int_equal(hal_stop_after(&h, RIG_ETIMEOUT), RIG_EABORTED);
    assert_int_equal(hal_stop_before(&h), RIG_EABORTED);
    stop_flag = 0;
    assert_int_equal(hal_stop_before(&h), RIG_OK);
    assert_int_equal(h.stop_dead, 0);
    hal_set_stop(NULL, stop_check, &stop_flag); /* harmless */
    assert_int_equal(hal_stopped(NULL), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wait),
        cmocka_unit_test(test_modbus_hung),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
