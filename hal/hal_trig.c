/* SPDX-License-Identifier: MIT */
/* hal_trig.c: the USB trigger/encoder box driver: packet and identity
 * decoding with CRC and sequence checks, and the vendor requests over the
 * usb: transport (protocol in docs/rig-usb.md). */
#include "hal_trig.h"
#include <stdio.h>
#include <string.h>

uint16_t hal_trig_crc16(const uint8_t *p, size_t n)
{
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < n; i++) {
        crc ^= (uint16_t)(p[i] << 8);
        for (int b = 0; b < 8; b++)
            crc = (uint16_t)((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
    }
    return crc;
}

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static uint16_t get16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

void hal_trig_encode(const hal_trig_pkt_t *pkt, uint8_t out[TRIG_PKT_LEN])
{
    out[0] = TRIG_PKT_SYNC;
    out[1] = pkt->flags;
    put16(out + 2, pkt->seq);
    put32(out + 4, pkt->t_us);
    put32(out + 8, (uint32_t)pkt->enc[0]);
    put32(out + 12, (uint32_t)pkt->enc[1]);
    put16(out + 16, hal_trig_crc16(out, 16));
}

int hal_trig_decode(const uint8_t *buf, size_t n, hal_trig_pkt_t *pkts, size_t max, size_t *count)
{
    if (!count || (n && (!buf || !pkts)))
        return RIG_EARG;
    *count = 0;
    if (n % TRIG_PKT_LEN)
        return RIG_EPROTO;
    if (n / TRIG_PKT_LEN > max)
        return RIG_EPROTO;
    for (size_t k = 0; k < n / TRIG_PKT_LEN; k++) {
        const uint8_t *p = buf + k * TRIG_PKT_LEN;
        if (p[0] != TRIG_PKT_SYNC)
            return RIG_EPROTO;
        if (hal_trig_crc16(p, 16) != get16(p + 16))
            return RIG_ECRC;
        pkts[k].flags = p[1];
        pkts[k].seq = get16(p + 2);
        pkts[k].t_us = get32(p + 4);
        pkts[k].enc[0] = (int32_t)get32(p + 8);
        pkts[k].enc[1] = (int32_t)get32(p + 12);
        *count = k + 1;
    }
    return RIG_OK;
}

int hal_trig_parse_ident(const uint8_t *buf, size_t n, hal_trig_ident_t *id)
{
    if (!buf || !id)
        return RIG_EARG;
    if (n < TRIG_IDENT_LEN || memcmp(buf, TRIG_MAGIC, 4))
        return RIG_EPROTO;
    id->proto = buf[4];
    id->fw_major = buf[5];
    id->fw_minor = buf[6];
    id->fw_patch = buf[7];
    id->serial = get32(buf + 8);
    id->axes = buf[12];
    return RIG_OK;
}

int hal_trig_seq_check(hal_trig_seq_t *s, uint16_t seq)
{
    if (!s)
        return RIG_EARG;
    if (!s->started) {
        s->started = 1;
        s->next = (uint16_t)(seq + 1);
        return 0;
    }
    /* Forward distance modulo 2^16: more than half the range back is a
     * repeat (or a reset of the box), not a gap. */
    uint16_t gap = (uint16_t)(seq - s->next);
    if (gap >= 0x8000)
        return RIG_EPROTO;
    s->next = (uint16_t)(seq + 1);
    s->lost += gap;
    return (int)gap;
}

int hal_trig_ident(hal_t *h, hal_trig_ident_t *id)
{
    uint8_t buf[TRIG_IDENT_LEN + 8];
    size_t got = 0;
    if (!h || !id || !h->ops->control)
        return RIG_EARG;
    int rc = h->ops->control(h, TRIG_RT_IN, TRIG_REQ_IDENT, 0, 0, buf, sizeof buf, &got);
    if (rc)
        return rc;
    rc = hal_trig_parse_ident(buf, got, id);
    if (rc)
        snprintf(h->err, sizeof h->err, "trigger box identity: %zu bytes, magic %.4s", got,
                 got >= 4 ? (const char *)buf : "?");
    return rc;
}

int hal_trig_set_period(hal_t *h, uint32_t period_us)
{
    uint8_t buf[4];
    if (!h || !h->ops->control || period_us < TRIG_MIN_PERIOD || period_us > TRIG_MAX_PERIOD)
        return RIG_EARG;
    put32(buf, period_us);
    return h->ops->control(h, TRIG_RT_OUT, TRIG_REQ_PERIOD, 0, 0, buf, sizeof buf, NULL);
}

int hal_trig_arm(hal_t *h, int on)
{
    if (!h || !h->ops->control)
        return RIG_EARG;
    return h->ops->control(h, TRIG_RT_OUT, TRIG_REQ_ARM, on ? 1 : 0, 0, NULL, 0, NULL);
}

int hal_trig_read(hal_t *h, hal_trig_seq_t *seq, hal_trig_pkt_t *pkts, size_t max, size_t *count)
{
    uint8_t buf[3 * TRIG_PKT_LEN];
    size_t got = 0;
    if (!h || !pkts || !count || !max || !h->ops->bulk)
        return RIG_EARG;
    *count = 0;
    size_t want = (max < 3 ? max : 3) * TRIG_PKT_LEN;
    int rc = h->ops->bulk(h, TRIG_EP_IN, buf, want, &got);
    if (rc)
        return rc;
    int bad = hal_trig_decode(buf, got, pkts, max, count);
    if (bad)
        snprintf(h->err, sizeof h->err, "trigger packet %zu of a %zu-byte transfer: %s", *count,
                 got, bad == RIG_ECRC ? "CRC mismatch" : "bad length or sync byte");
    /* The packets before a bad one are good and kept (*count of them). */
    for (size_t k = 0; seq && k < *count; k++) {
        if (hal_trig_seq_check(seq, pkts[k].seq) < 0) {
            snprintf(h->err, sizeof h->err, "trigger seq %u repeats (expected %u)",
                     (unsigned)pkts[k].seq, (unsigned)seq->next);
            return RIG_EPROTO;
        }
    }
    return bad;
}
