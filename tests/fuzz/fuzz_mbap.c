/* SPDX-License-Identifier: MIT */
/* fuzz_mbap.c: libFuzzer target for the PLC server's own framing and
 * request handling (firmware/plc_mbap.c, as host/cf_plcsrv.c drives it):
 * the input is a TCP byte stream cut into reads of any size, with clock
 * ticks and job events between them. Each client frame is collected the way
 * the server does (plc_mbap_need, never more than it asks for) and
 * answered (plc_mbap_pdu). Properties: a frame never outgrows 260 bytes; a
 * malformed header is the only way a connection is dropped; every reply is
 * a well-formed Modbus PDU of the length its function needs; a read
 * returns the registers themselves; an exception changes nothing but the
 * REQ_REFUSED counter; 06 comes only while a job runs, and a write taken
 * while busy touched COMMAND and PLC_HEARTBEAT only. */
#include "fuzz.h"
#include "plc_mbap.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_mbap: %s\n", why);
    abort();
}

static unsigned be16(const uint8_t *p)
{
    return (unsigned)p[0] << 8 | p[1];
}

/* One whole frame (n bytes, header included) answered and checked. */
static void answer(plc_fsm_t *f, plc_map_t *m, const uint8_t *b, size_t n, uint32_t now)
{
    const uint8_t *q = b + PLC_MBAP_HDR;
    size_t qn = n - PLC_MBAP_HDR;
    uint8_t r[PLC_MBAP_MAX];
    memset(r, 0xA5, sizeof r);
    plc_map_t m0 = *m;
    plc_fsm_t f0 = *f;
    int busy = plc_state_busy(f->state);
    plc_action_t act;
    plc_req_t rq;
    size_t rn = plc_mbap_pdu(f, q, qn, r, now, &act, &rq);
    if (rn < 2 || rn > 253)
        fail("reply PDU length outside 2..253");
    if (rq.ex) {
        if (rn != 2 || r[0] != (q[0] | 0x80) || r[1] != rq.ex)
            fail("exception reply malformed");
        if (rq.ex != PLC_EX_FUNCTION && rq.ex != PLC_EX_ADDRESS && rq.ex != PLC_EX_VALUE &&
            rq.ex != PLC_EX_BUSY)
            fail("exception code not 1, 2, 3 or 6");
        if (rq.ex == PLC_EX_BUSY && !busy)
            fail("exception 06 while no job runs");
        if (act != PLC_ACT_NONE)
            fail("a refused request asked for an action");
        if (memcmp(f, &f0, sizeof *f))
            fail("a refused request changed the state machine");
        plc_map_inc_u32(&m0, PLC_R_REQ_REFUSED);
        if (memcmp(m, &m0, sizeof *m))
            fail("a refused request changed a register other than REQ_REFUSED");
        return;
    }
    if (r[0] != q[0])
        fail("reply function code differs");
    if (q[0] == 0x03 || q[0] == 0x04) {
        if (qn != 5 || rq.cnt < 1 || rq.cnt > PLC_MAX_READ || rq.addr + rq.cnt > PLC_NREGS)
            fail("read accepted outside the map or with a bad length");
        if (rn != 2 + 2 * rq.cnt || r[1] != 2 * rq.cnt)
            fail("read reply length");
        for (unsigned k = 0; k < rq.cnt; k++)
            if (be16(r + 2 + 2 * k) != m->reg[rq.addr + k])
                fail("read reply is not the registers");
        if (memcmp(m, &m0, sizeof *m))
            fail("a read changed the registers");
    } else if (q[0] == 0x06 || q[0] == 0x10) {
        if (rn != 5 || memcmp(r + 1, q + 1, 2))
            fail("write reply does not echo the address");
        if (q[0] == 0x06 ? memcmp(r + 3, q + 3, 2) : be16(r + 3) != rq.cnt)
            fail("write reply value / count");
        if (rq.addr + rq.cnt > PLC_NREGS)
            fail("write beyond the map accepted");
        for (unsigned a = rq.addr; busy && a < rq.addr + rq.cnt; a++)
            if (!plc_fsm_writable(PLC_S_HOMING, plc_map_entry(a)))
                fail("a write while busy reached a register other than COMMAND / heartbeat");
    } else
        fail("an unknown function code was answered");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    plc_map_t m;
    plc_fsm_t f;
    size_t at = 0;
    unsigned cfg = size ? data[at++] : 0;
    uint32_t now = cfg << 20;
    plc_map_init(&m, cfg & 1, "fuzz");
    plc_fsm_init(&f, &m, (cfg >> 1) & 1, (uint16_t)((cfg >> 2) * 50), NULL, NULL, now);
    uint8_t buf[PLC_MBAP_MAX];
    size_t have = 0;
    while (at < size) {
        unsigned op = data[at++];
        if (op >= 0xF0) { /* between reads: time passes, or the job ends a phase */
            if (op & 8) {
                plc_results_t res = {0.01f, 0.02f, -0.02f, 99.0f,      PLC_VERDICT_PASS,
                                     100,   64,    1000,   PLC_FIT_MET};
                plc_fsm_event(&f, (plc_event_t)(op % PLC_EV_COUNT), 300 + (int)(op & 7),
                              (op & 4) ? &res : NULL);
            } else {
                now += (op & 7) * 97u;
                plc_fsm_tick(&f, now);
            }
            continue;
        }
        /* A read of up to op bytes, the server's way: never past the frame. */
        size_t chunk = op, k = 0;
        while (k < chunk && at < size) {
            int need = plc_mbap_need(buf, have);
            if (need == PLC_MBAP_BAD) {
                if (have < 6)
                    fail("a header judged before its length field came");
                have = 0; /* the server closes the connection; a new one starts */
                continue;
            }
            if (need < (int)have || need > PLC_MBAP_MAX || (have >= 6 && need < 8))
                fail("frame length outside what was received .. 260");
            if ((size_t)need == have) {
                answer(&f, &m, buf, have, now);
                have = 0;
                continue;
            }
            buf[have++] = data[at++];
            k++;
        }
        int need = plc_mbap_need(buf, have);
        if (need != PLC_MBAP_BAD && (size_t)need == have) {
            answer(&f, &m, buf, have, now);
            have = 0;
        }
        if (plc_map_u16(&m, PLC_R_MAGIC) != PLC_MAGIC)
            fail("identity block overwritten");
        if (plc_map_u16(&m, PLC_R_STATE) != (uint16_t)f.state)
            fail("STATE register does not show the state");
    }
    return 0;
}
