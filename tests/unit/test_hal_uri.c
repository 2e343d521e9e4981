/* SPDX-License-Identifier: MIT */
/* test_hal_uri.c: the device URI parser (every scheme, strict refusals with
 * their reasons), the errno to rig_err_t mapping of the Modbus backend, the
 * ASCII probe's reply parser, hal_* on a backend that lacks an operation,
 * and the tty backend on a pseudo-terminal this test plays the device on. */
#define _XOPEN_SOURCE 600 /* posix_openpt */
#include "cf_test.h"
#include "hal.h"
#include "hal_rig.h"
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

extern int hal_serial_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg,
                           size_t len) __attribute__((weak));
extern int hal_usb_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len)
    __attribute__((weak));

static char msg[512];

static void test_uri_good(void **state)
{
    (void)state;
    hal_uri_t u;
    assert_int_equal(hal_uri_parse("rtu:/dev/ttyUSB0:19200:8E1:17", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_RTU);
    assert_string_equal(u.path, "/dev/ttyUSB0");
    assert_int_equal(u.baud, 19200);
    assert_int_equal(u.data_bits, 8);
    assert_int_equal(u.parity, 'E');
    assert_int_equal(u.stop_bits, 1);
    assert_int_equal(u.unit, 17);
    assert_int_equal(hal_uri_parse("tcp:127.0.0.1:1502", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_TCP);
    assert_string_equal(u.path, "127.0.0.1");
    assert_int_equal(u.port, 1502);
    assert_int_equal(u.unit, 1); /* default unit */
    assert_int_equal(hal_uri_parse("tcp:plc.local:502:0", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.unit, 0);
    assert_int_equal(hal_uri_parse("tty:/tmp/x/ttyB:115200", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_TTY);
    assert_int_equal(u.parity, 'N'); /* 8N1 when left out */
    assert_int_equal(u.data_bits, 8);
    assert_int_equal(hal_uri_parse("serial:/dev/ttyS0:9600:7O2", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_SERIAL);
    assert_int_equal(u.data_bits, 7);
    assert_int_equal(u.parity, 'O');
    assert_int_equal(u.stop_bits, 2);
    assert_int_equal(hal_uri_parse("usb:0403:6001", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_USB);
    assert_int_equal(u.vid, 0x0403);
    assert_int_equal(u.pid, 0x6001);
    assert_string_equal(u.serial, "");
    assert_int_equal(hal_uri_parse("usb:1D50:60aF:A12B", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.vid, 0x1D50);
    assert_int_equal(u.pid, 0x60AF);
    assert_string_equal(u.serial, "A12B");
    assert_int_equal(hal_uri_parse("gev:127.0.0.1", &u, msg, sizeof msg), RIG_OK);
    assert_int_equal(u.kind, HAL_GEV);
    assert_string_equal(u.path, "127.0.0.1");
    assert_string_equal(u.serial, "");
    assert_int_equal(hal_uri_parse("gev:10.1.2.3:PRF-07", &u, msg, sizeof msg), RIG_OK);
    assert_string_equal(u.path, "10.1.2.3");
    assert_string_equal(u.serial, "PRF-07");
}

/* Each refusal: the code, and the reason names what is wrong. */
static void refuse(const char *uri, const char *reason)
{
    hal_uri_t u;
    msg[0] = '\0';
    int rc = hal_uri_parse(uri, &u, msg, sizeof msg);
    if (rc != RIG_EARG || !strstr(msg, reason) || strchr(msg, '\n'))
        fail_msg("'%s': rc %d, message '%s', want a line with '%s'", uri, rc, msg, reason);
}

static void test_uri_bad(void **state)
{
    (void)state;
    refuse("", "unknown scheme");
    refuse("modbus:/dev/x", "unknown scheme");
    refuse("rtu:/dev/ttyS0:9600:1", "want rtu:PATH:BAUD:8N1:SLAVE");
    refuse("rtu:/dev/ttyS0:9600:8N1:0", "slave address not 1..247");
    refuse("rtu:/dev/ttyS0:9600:8N1:248", "slave address not 1..247");
    refuse("rtu:/dev/ttyS0:9601:8N1:1", "baud rate not a standard rate");
    refuse("rtu:/dev/ttyS0:+9600:8N1:1", "baud rate");
    refuse("rtu:/dev/ttyS0:9600:8X1:1", "frame not");
    refuse("rtu:/dev/ttyS0:9600:6N1:1", "frame not");
    refuse("rtu:/dev/ttyS0:9600:8N3:1", "frame not");
    refuse("rtu::9600:8N1:1", "bad device path");
    refuse("rtu:/dev/tty S0:9600:8N1:1", "bad device path");
    refuse("tcp:127.0.0.1", "want tcp:HOST:PORT[:UNIT]");
    refuse("tcp:127.0.0.1:0", "port not 1..65535");
    refuse("tcp:127.0.0.1:65536", "port not 1..65535");
    refuse("tcp:127.0.0.1:502x", "port not 1..65535");
    refuse("tcp:127.0.0.1:502:256", "unit id not 0..255");
    refuse("tcp::502", "bad host");
    refuse("tty:/dev/pts/3", "want tty:PATH:BAUD[:8N1]");
    refuse("tty:/dev/pts/3:115200:8N1:1", "want tty:PATH:BAUD[:8N1]");
    refuse("serial:/dev/ttyS0", "want serial:PATH:BAUD[:8N1]");
    refuse("usb:403:6001", "vendor id not 4 hex digits");
    refuse("usb:0403:60g1", "product id not 4 hex digits");
    refuse("usb:0403", "want usb:VID:PID[:SERIAL]");
    refuse("gev", "want gev:ADDRESS[:SERIAL]");
    refuse("gev:localhost", "not a dotted IPv4 address");
    refuse("gev:127.0.0.256", "not a dotted IPv4 address");
    refuse("gev:127.0.0.1:", "bad serial number");
    refuse("gev:127.0.0.1:a:b", "want gev:ADDRESS[:SERIAL]");
    refuse("a:b:c:d:e:f:g:h:i", "too many");
    char longp[600];
    memset(longp, 'a', sizeof longp - 1);
    longp[sizeof longp - 1] = '\0';
    refuse(longp, "longer than");
}

static void test_errno_map(void **state)
{
    (void)state;
    assert_int_equal(hal_modbus_errcode(ETIMEDOUT), RIG_ETIMEOUT);
    assert_int_equal(hal_modbus_errcode(EMBBADCRC), RIG_ECRC);
    const int exc[] = {EMBXILFUN, EMBXILADD, EMBXILVAL,  EMBXSFAIL, EMBXACK,
                       EMBXSBUSY, EMBXNACK,  EMBXMEMPAR, EMBXGPATH, EMBXGTAR};
    for (size_t i = 0; i < sizeof exc / sizeof exc[0]; i++)
        assert_int_equal(hal_modbus_errcode(exc[i]), RIG_EEXCEPTION);
    const int proto[] = {EMBBADDATA, EMBBADEXC, EMBUNKEXC, EMBMDATA, EMBBADSLAVE};
    for (size_t i = 0; i < sizeof proto / sizeof proto[0]; i++)
        assert_int_equal(hal_modbus_errcode(proto[i]), RIG_EPROTO);
    const int lost[] = {EIO, ECONNRESET, EBADF, EPIPE, ENOENT, ECONNREFUSED, ENOTCONN};
    for (size_t i = 0; i < sizeof lost / sizeof lost[0]; i++)
        assert_int_equal(hal_modbus_errcode(lost[i]), RIG_EDISCONNECT);
    assert_int_equal(hal_modbus_errcode(EINVAL), RIG_EARG);
    /* Every code a mapping gives has its own string. */
    for (int c = RIG_ELOST; c <= RIG_EARG; c++)
        assert_string_not_equal(rig_strerror(c), "unknown error");
}

static void test_probe_parse(void **state)
{
    (void)state;
    double d = -1;
    assert_int_equal(hal_probe_parse_m0("M0,+01.234", &d), RIG_OK);
    assert_near(d, 1.234, 1e-12);
    assert_int_equal(hal_probe_parse_m0("M0,-12.5", &d), RIG_OK);
    assert_near(d, -12.5, 1e-12);
    assert_int_equal(hal_probe_parse_m0("M0,+123.456", &d), RIG_OK);
    assert_near(d, 123.456, 1e-12);
    assert_int_equal(hal_probe_parse_m0("M0,FFFFFFF", &d), RIG_ENOSURF);
    assert_int_equal(hal_probe_parse_m0("ER,M0,01", &d), RIG_EEXCEPTION);
    const char *bad[] = {"",          "M0",          "M0,",        "M0,1.234",   "M0,+1.",
                         "M0,+.5",    "M0,+01.234x", "M1,+01.234", "M0,+0k.234", "ER,M0,1",
                         "ER,M0,001", "M0,FFFFFF",   "M,+01.234",  "M0,++1.0"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        if (hal_probe_parse_m0(bad[i], &d) != RIG_EPROTO)
            fail_msg("'%s' was not refused as malformed", bad[i]);
}

/* A backend with no operations but close: hal_* answer RIG_EUNSUPPORTED
 * and say which operation in the detail. */
static void nop_close(hal_t *h)
{
    (void)h;
}

static void test_unsupported(void **state)
{
    (void)state;
    static const hal_ops_t none = {.version = RIG_OPS_VERSION, .name = "none", .close = nop_close};
    hal_t h;
    memset(&h, 0, sizeof h);
    h.ops = &none;
    strcpy(h.uri.path, "/dev/null");
    uint16_t r[2] = {0, 0};
    size_t got;
    char b[4];
    assert_int_equal(hal_read_regs(&h, 'h', 0, 2, r), RIG_EUNSUPPORTED);
    assert_non_null(strstr(hal_last_error(&h), "register read"));
    assert_int_equal(hal_write_regs(&h, 0, 2, r), RIG_EUNSUPPORTED);
    assert_int_equal(hal_write(&h, "x", 1), RIG_EUNSUPPORTED);
    assert_non_null(strstr(hal_last_error(&h), "write not supported by the none backend"));
    assert_int_equal(hal_read(&h, b, sizeof b, 10, &got), RIG_EUNSUPPORTED);
    assert_int_equal(hal_flush(&h), RIG_EUNSUPPORTED);
    assert_int_equal(hal_control(&h, 0, 0, 0, 0, b, 0, &got), RIG_EUNSUPPORTED);
    assert_int_equal(hal_bulk(&h, 1, b, sizeof b, &got), RIG_EUNSUPPORTED);
    assert_int_equal(hal_reconnect(&h), RIG_EUNSUPPORTED);
    assert_int_equal(hal_read_regs(NULL, 'h', 0, 1, r), RIG_EARG);
    hal_close(&h);
    /* Backends of another part of the tree: absent here, or present. */
    hal_t *hp = NULL;
    int rc = hal_open("usb:0403:6001", NULL, &hp, msg, sizeof msg);
    if (!hal_usb_open) {
        assert_int_equal(rc, RIG_EUNSUPPORTED);
        assert_non_null(strstr(msg, "backend not built"));
    } else if (rc == RIG_OK)
        hal_close(hp);
    rc = hal_open("serial:/nonexistent/tty:9600", NULL, &hp, msg, sizeof msg);
    if (!hal_serial_open) {
        assert_int_equal(rc, RIG_EUNSUPPORTED);
        assert_non_null(strstr(msg, "backend not built"));
    } else
        assert_int_not_equal(rc, RIG_OK);
    assert_int_equal(hal_open("tty:/nonexistent/tty:9600", NULL, &hp, msg, sizeof msg), RIG_EOPEN);
    assert_non_null(strstr(msg, "/nonexistent/tty"));
    assert_null(hp);
    assert_int_equal(hal_open("bogus:1", NULL, &hp, msg, sizeof msg), RIG_EARG);
}

/* The tty backend on a pty: this test holds the master end. */
static void test_tty_pty(void **state)
{
    (void)state;
    int m = posix_openpt(O_RDWR | O_NOCTTY);
    assert_true(m >= 0);
    assert_int_equal(grantpt(m), 0);
    assert_int_equal(unlockpt(m), 0);
    char uri[300];
    snprintf(uri, sizeof uri, "tty:%s:115200", ptsname(m));
    hal_opts_t o = HAL_OPTS_DEFAULT;
    o.timeout_ms = 100;
    hal_t *h;
    assert_int_equal(hal_open(uri, &o, &h, msg, sizeof msg), RIG_OK);
    assert_int_equal(hal_write(h, "M0\r\n", 4), RIG_OK);
    char b[16] = {0};
    size_t n = 0;
    while (n < 4) {
        ssize_t r = read(m, b + n, sizeof b - 1 - n);
        assert_true(r > 0);
        n += (size_t)r;
    }
    assert_string_equal(b, "M0\r\n"); /* raw: no CR/LF translation, no echo */
    assert_int_equal(write(m, "M0,+01.234\r\n", 12), 12);
    char line[32];
    size_t got = 0, all = 0;
    while (all < 12) {
        assert_int_equal(hal_read(h, line + all, sizeof line - 1 - all, 200, &got), RIG_OK);
        all += got;
    }
    line[all] = '\0';
    assert_string_equal(line, "M0,+01.234\r\n");
    /* Nothing to read: a timeout, nothing returned. */
    assert_int_equal(hal_read(h, line, sizeof line, 30, &got), RIG_ETIMEOUT);
    assert_int_equal(got, 0);
    assert_non_null(strstr(hal_last_error(h), "nothing received"));
    /* Bytes in the input are gone after a flush. */
    assert_int_equal(write(m, "stale", 5), 5);
    struct timespec ts = {0, 20000000L};
    nanosleep(&ts, NULL);
    assert_int_equal(hal_flush(h), RIG_OK);
    assert_int_equal(hal_read(h, line, sizeof line, 30, &got), RIG_ETIMEOUT);
    /* No register operations on a byte stream. */
    uint16_t r[1];
    assert_int_equal(hal_read_regs(h, 'h', 0, 1, r), RIG_EUNSUPPORTED);
    hal_close(h);
    close(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uri_good),    cmocka_unit_test(test_uri_bad),
        cmocka_unit_test(test_errno_map),   cmocka_unit_test(test_probe_parse),
        cmocka_unit_test(test_unsupported), cmocka_unit_test(test_tty_pty),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
