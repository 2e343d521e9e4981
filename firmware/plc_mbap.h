/* SPDX-License-Identifier: MIT */
/* plc_mbap.h: Modbus TCP framing and request handling of the cell's PLC
 * server as pure functions over bytes (no socket, no clock, no lock, no
 * heap), so the server (host/cf_plcsrv.c) keeps only sockets and timing,
 * and a fuzz target (tests/fuzz/fuzz_mbap.c) reaches the same code:
 *   - plc_mbap_need: how many bytes the frame being received needs in all,
 *     from its MBAP header (transaction, protocol 0, length 2..254, unit);
 *   - plc_mbap_pdu: one request PDU answered from the register map and the
 *     state machine (plc_map.h, plc_fsm.h): 03 and 04 read (input registers
 *     are the holding registers), 06 and 16 write, anything else exception
 *     01; every length checked against what its function code needs. */
#ifndef PLC_MBAP_H
#define PLC_MBAP_H

#include "plc_fsm.h"
#include <stddef.h>
#include <stdint.h>

#define PLC_MBAP_HDR 7    /* transaction, protocol, length, unit */
#define PLC_MBAP_MAX 260  /* header + the largest PDU (253 bytes) */
#define PLC_MBAP_BAD (-1) /* plc_mbap_need: malformed header, close the connection */

/* The frame's whole length (header included) as far as have bytes of it
 * tell: PLC_MBAP_HDR until the length field is in, then 6 + length;
 * PLC_MBAP_BAD for a protocol id other than 0 or a length outside 2..254.
 * The frame is complete when the result equals have. */
int plc_mbap_need(const uint8_t *b, size_t have);

/* What a request was, for the server's log and counters. */
typedef struct plc_req {
    unsigned fc, addr, cnt; /* function, address, count (0 when absent) */
    int ex;                 /* exception answered, 0 none */
} plc_req_t;

/* Answer the PDU q (n >= 1 bytes) into r (room for 253 bytes): returns the
 * reply PDU's length. Writes go through plc_fsm_write (*act: what the
 * caller must do next); an exception counts in REQ_REFUSED. */
size_t plc_mbap_pdu(plc_fsm_t *f, const uint8_t *q, size_t n, uint8_t *r, uint32_t now_ms,
                    plc_action_t *act, plc_req_t *req);

/* The reply to a request refused before it was parsed (the rate limit):
 * the function code with the exception bit, and the exception. */
size_t plc_mbap_exception(const uint8_t *q, int ex, uint8_t *r);

#endif
