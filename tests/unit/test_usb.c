/* SPDX-License-Identifier: MIT */
/* test_usb.c: the pure parts of the USB and serial backends: the trigger
 * box's CRC (against the published CRC-16/CCITT-FALSE check value), packet
 * layout (bytes built by hand from docs/rig-usb.md), decoding faults,
 * sequence tracking across the 16-bit wrap, the identity reply, and the
 * libusb / libserialport error mappings. Opening devices that are not
 * there fails cleanly (the devices themselves: tests/cli/usb.sh). */
#include "cf_test.h"
#include "hal_serial.h"
#include "hal_trig.h"
#include "hal_usb.h"
#include <errno.h>
#include <libserialport.h>
#include <libusb.h>
#include <stdio.h>
#include <string.h>

static void test_crc_check_value(void **state)
{
    (void)state;
    const char *s = "123456789";
    assert_int_equal(hal_trig_crc16((const uint8_t *)s, 9), 0x29B1);
    assert_int_equal(hal_trig_crc16((const uint8_t *)s, 0), 0xFFFF);
}

/* A packet written out byte by byte from the layout in hal_trig.h. */
static void hand_packet(uint8_t b[TRIG_PKT_LEN], uint16_t seq, uint32_t t, int32_t x, int32_t y)
{
    uint32_t ux = (uint32_t)x, uy = (uint32_t)y;
    uint8_t raw[16] = {0xA5,
                       0x02,
                       (uint8_t)seq,
                       (uint8_t)(seq >> 8),
                       (uint8_t)t,
                       (uint8_t)(t >> 8),
                       (uint8_t)(t >> 16),
                       (uint8_t)(t >> 24),
                       (uint8_t)ux,
                       (uint8_t)(ux >> 8),
                       (uint8_t)(ux >> 16),
                       (uint8_t)(ux >> 24),
                       (uint8_t)uy,
                       (uint8_t)(uy >> 8),
                       (uint8_t)(uy >> 16),
                       (uint8_t)(uy >> 24)};
    memcpy(b, raw, 16);
    uint16_t c = hal_trig_crc16(b, 16);
    b[16] = (uint8_t)c;
    b[17] = (uint8_t)(c >> 8);
}

static void test_packet_layout(void **state)
{
    (void)state;
    uint8_t want[TRIG_PKT_LEN], got[TRIG_PKT_LEN];
    hand_packet(want, 0xBEEF, 123456789u, -5, 70000);
    hal_trig_pkt_t p = {
        .flags = TRIG_F_INDEX, .seq = 0xBEEF, .t_us = 123456789u, .enc = {-5, 70000}};
    hal_trig_encode(&p, got);
    assert_memory_equal(got, want, TRIG_PKT_LEN);

    hal_trig_pkt_t d[2];
    size_t n = 99;
    assert_int_equal(hal_trig_decode(want, TRIG_PKT_LEN, d, 2, &n), RIG_OK);
    assert_int_equal(n, 1);
    assert_int_equal(d[0].seq, 0xBEEF);
    assert_int_equal(d[0].t_us, 123456789u);
    assert_int_equal(d[0].enc[0], -5);
    assert_int_equal(d[0].enc[1], 70000);
    assert_int_equal(d[0].flags, TRIG_F_INDEX);
}

static void test_decode_faults(void **state)
{
    (void)state;
    uint8_t b[3 * TRIG_PKT_LEN];
    hal_trig_pkt_t d[3];
    size_t n;
    for (int k = 0; k < 3; k++)
        hand_packet(b + k * TRIG_PKT_LEN, (uint16_t)k, 0, k, -k);
    assert_int_equal(hal_trig_decode(b, sizeof b, d, 3, &n), RIG_OK);
    assert_int_equal(n, 3);
    /* Every single flipped bit of the second packet is caught. */
    for (int bit = 0; bit < 8 * TRIG_PKT_LEN; bit++) {
        b[TRIG_PKT_LEN + bit / 8] ^= (uint8_t)(1u << (bit % 8));
        int rc = hal_trig_decode(b, sizeof b, d, 3, &n);
        assert_true(rc == RIG_ECRC || (bit < 8 && rc == RIG_EPROTO));
        assert_int_equal(n, 1); /* the first packet still decoded */
        b[TRIG_PKT_LEN + bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
    assert_int_equal(hal_trig_decode(b, sizeof b - 1, d, 3, &n), RIG_EPROTO); /* short */
    assert_int_equal(hal_trig_decode(b, sizeof b, d, 2, &n), RIG_EPROTO);     /* no room */
    assert_int_equal(hal_trig_decode(b, 0, d, 3, &n), RIG_OK);
    assert_int_equal(n, 0);
    assert_int_equal(hal_trig_decode(b, sizeof b, d, 3, NULL), RIG_EARG);
}

static void test_sequence(void **state)
{
    (void)state;
    hal_trig_seq_t s = {0};
    assert_int_equal(hal_trig_seq_check(&s, 65533), 0); /* first seen: no gap */
    assert_int_equal(hal_trig_seq_check(&s, 65534), 0);
    assert_int_equal(hal_trig_seq_check(&s, 65535), 0);
    assert_int_equal(hal_trig_seq_check(&s, 0), 0); /* the wrap is not a gap */
    assert_int_equal(hal_trig_seq_check(&s, 4), 3); /* 1, 2, 3 lost */
    assert_int_equal(hal_trig_seq_check(&s, 4), RIG_EPROTO);
    assert_int_equal(hal_trig_seq_check(&s, 2), RIG_EPROTO);
    assert_int_equal(hal_trig_seq_check(&s, 5), 0);
    assert_int_equal(s.lost, 3);
}

static void test_ident(void **state)
{
    (void)state;
    const uint8_t r[TRIG_IDENT_LEN] = {'C', 'F', 'T', 'B', 1, 4, 5, 6, 0x78, 0x56, 0x34, 0x12, 2};
    hal_trig_ident_t id;
    assert_int_equal(hal_trig_parse_ident(r, sizeof r, &id), RIG_OK);
    assert_int_equal(id.proto, 1);
    assert_int_equal(id.fw_major, 4);
    assert_int_equal(id.fw_minor, 5);
    assert_int_equal(id.fw_patch, 6);
    assert_int_equal(id.serial, 0x12345678u);
    assert_int_equal(id.axes, 2);
    assert_int_equal(hal_trig_parse_ident(r, sizeof r - 1, &id), RIG_EPROTO);
    uint8_t bad[TRIG_IDENT_LEN];
    memcpy(bad, r, sizeof bad);
    bad[3] = 'X';
    assert_int_equal(hal_trig_parse_ident(bad, sizeof bad, &id), RIG_EPROTO);
}

static void test_usb_errors(void **state)
{
    (void)state;
    assert_int_equal(hal_usb_err(LIBUSB_SUCCESS), RIG_OK);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_TIMEOUT), RIG_ETIMEOUT);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_NO_DEVICE), RIG_EDISCONNECT);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_PIPE), RIG_EEXCEPTION);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_OVERFLOW), RIG_EPROTO);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_NOT_FOUND), RIG_EOPEN);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_ACCESS), RIG_EOPEN);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_BUSY), RIG_EOPEN);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_NOT_SUPPORTED), RIG_EUNSUPPORTED);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_INVALID_PARAM), RIG_EARG);
    assert_int_equal(hal_usb_err(LIBUSB_ERROR_IO), RIG_EIO);
    assert_int_equal(hal_usb_err(-1234), RIG_EIO);
}

static void test_serial_errors(void **state)
{
    (void)state;
    assert_int_equal(hal_serial_err(SP_OK, 0, 0), RIG_OK);
    assert_int_equal(hal_serial_err(5, 0, 0), RIG_OK); /* a byte count */
    assert_int_equal(hal_serial_err(SP_ERR_ARG, 0, 1), RIG_EOPEN);
    assert_int_equal(hal_serial_err(SP_ERR_ARG, 0, 0), RIG_EARG);
    assert_int_equal(hal_serial_err(SP_ERR_SUPP, 0, 0), RIG_EUNSUPPORTED);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, EIO, 0), RIG_EDISCONNECT);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, ENXIO, 0), RIG_EDISCONNECT);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, EBADF, 0), RIG_EDISCONNECT);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, ETIMEDOUT, 0), RIG_ETIMEOUT);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, ENOTTY, 0), RIG_EUNSUPPORTED);
    assert_int_equal(hal_serial_err(SP_ERR_FAIL, ENOENT, 1), RIG_EOPEN);
}

static void test_open_missing(void **state)
{
    (void)state;
    char msg[256];
    hal_t *h = (hal_t *)&msg; /* must come back NULL */
    hal_uri_t u = {.kind = HAL_SERIAL, .baud = 9600};
    snprintf(u.path, sizeof u.path, "/dev/cellfit-no-such-port");
    assert_int_equal(hal_serial_open(&u, NULL, &h, msg, sizeof msg), RIG_EOPEN);
    assert_null(h);
    assert_non_null(strstr(msg, "/dev/cellfit-no-such-port"));
    hal_uri_t v = {.kind = HAL_USB, .vid = 0x1209, .pid = 0xCF00};
    h = (hal_t *)&msg;
    assert_int_equal(hal_usb_open(&v, NULL, &h, msg, sizeof msg), RIG_EOPEN);
    assert_null(h);
    assert_true(msg[0]);
    assert_int_equal(hal_usb_open(&u, NULL, &h, msg, sizeof msg), RIG_EARG); /* not usb: */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc_check_value), cmocka_unit_test(test_packet_layout),
        cmocka_unit_test(test_decode_faults),   cmocka_unit_test(test_sequence),
        cmocka_unit_test(test_ident),           cmocka_unit_test(test_usb_errors),
        cmocka_unit_test(test_serial_errors),   cmocka_unit_test(test_open_missing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
