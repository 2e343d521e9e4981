/* SPDX-License-Identifier: MIT */
/* hal_trig.h: driver for the USB trigger/encoder box (docs/rig-usb.md): the
 * vendor protocol's wire constants, packet decoding with CRC and sequence
 * checks (pure, tested without a device), and the calls that talk to a box
 * through the usb: backend (hal_usb.c). sim/umock plays the same box. */
#ifndef HAL_TRIG_H
#define HAL_TRIG_H

#include "hal.h"
#include <stddef.h>
#include <stdint.h>

/* Default USB ids (pid.codes' open-source vendor id; product id ours). */
#define TRIG_VID 0x1209
#define TRIG_PID 0xCF01

/* Vendor requests on endpoint 0 (bmRequestType 0xC0 IN, 0x40 OUT). */
enum {
    TRIG_RT_IN = 0xC0,
    TRIG_RT_OUT = 0x40,
    TRIG_REQ_IDENT = 0x01,  /* IN, TRIG_IDENT_LEN bytes: identity, firmware */
    TRIG_REQ_PERIOD = 0x02, /* OUT, 4 bytes: trigger period in us, LE */
    TRIG_REQ_ARM = 0x03,    /* OUT, no data: wValue 1 arms (seq restarts at 0), 0 disarms */
    TRIG_REQ_STATUS = 0x04  /* IN, TRIG_STATUS_LEN bytes */
};

#define TRIG_EP_IN 0x81    /* bulk IN: encoder packets */
#define TRIG_EP_OUT 0x01   /* bulk OUT: not used by the protocol (loopback tests) */
#define TRIG_MAGIC "CFTB"  /* first bytes of the identity */
#define TRIG_IDENT_LEN 16  /* magic[4] proto fw_major fw_minor fw_patch serial:u32 axes pad[3] */
#define TRIG_STATUS_LEN 8  /* armed flags period_us:u32 pad[2] */
#define TRIG_PKT_LEN 18    /* one trigger: see hal_trig_pkt_t */
#define TRIG_PKT_SYNC 0xA5 /* first byte of every packet */
#define TRIG_MAX_PERIOD 1000000u
#define TRIG_MIN_PERIOD 100u

typedef struct hal_trig_ident {
    int proto; /* protocol version (1) */
    int fw_major, fw_minor, fw_patch;
    uint32_t serial;
    int axes; /* encoder channels carried in each packet (2) */
} hal_trig_ident_t;

/* One trigger packet, little-endian on the wire:
 *   0 sync 0xA5 | 1 flags | 2..3 seq | 4..7 t_us | 8..11 enc[0] | 12..15 enc[1]
 *   | 16..17 CRC-16/CCITT-FALSE of bytes 0..15 */
typedef struct hal_trig_pkt {
    uint8_t flags;  /* TRIG_F_* */
    uint16_t seq;   /* trigger number since arming, wraps at 65536 */
    uint32_t t_us;  /* box time of the trigger, us, wraps */
    int32_t enc[2]; /* encoder counts of x and y at the trigger */
} hal_trig_pkt_t;

enum { TRIG_F_OVERRUN = 1u << 0, TRIG_F_INDEX = 1u << 1 };

/* CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): the check value of
 * "123456789" is 0x29B1. */
uint16_t hal_trig_crc16(const uint8_t *p, size_t n);

/* Encode one packet into TRIG_PKT_LEN bytes (the simulator and tests). */
void hal_trig_encode(const hal_trig_pkt_t *pkt, uint8_t out[TRIG_PKT_LEN]);

/* Decode n bytes (a whole number of packets) into at most max packets.
 * RIG_EPROTO: length not a multiple of TRIG_PKT_LEN, bad sync byte, or more
 * packets than max; RIG_ECRC: a packet failed its CRC. *count is the number
 * decoded before the first bad one. */
int hal_trig_decode(const uint8_t *buf, size_t n, hal_trig_pkt_t *pkts, size_t max, size_t *count);

/* Parse the IDENT reply; RIG_EPROTO on a short reply or a wrong magic. */
int hal_trig_parse_ident(const uint8_t *buf, size_t n, hal_trig_ident_t *id);

/* Sequence tracking across reads: the number of triggers lost before pkt
 * (0 when pkt follows the last one), RIG_EPROTO for a repeated packet. */
typedef struct hal_trig_seq {
    int started;
    uint16_t next;
    unsigned long lost;
} hal_trig_seq_t;
int hal_trig_seq_check(hal_trig_seq_t *s, uint16_t seq);

/* Device calls through an open usb: transport. */
int hal_trig_ident(hal_t *h, hal_trig_ident_t *id);
int hal_trig_set_period(hal_t *h, uint32_t period_us);
int hal_trig_arm(hal_t *h, int on);
/* Wait up to the transport's timeout for at least one packet; *count
 * packets (at most max, up to 3 per transfer) come back and seq (may be
 * NULL) is checked. RIG_ECRC/RIG_EPROTO on a bad packet, with the good
 * ones before it still in pkts[0..*count). RIG_EDISCONNECT when the box
 * was lost: h->reconnects tells whether it was found again (then it has
 * restarted, disarmed, and must be set up again). */
int hal_trig_read(hal_t *h, hal_trig_seq_t *seq, hal_trig_pkt_t *pkts, size_t max, size_t *count);

#endif
