/* SPDX-License-Identifier: MIT */
/* plc_mbap.c: MBAP framing and request PDUs of the PLC server (plc_mbap.h). */
#include "plc_mbap.h"
#include <string.h>

static unsigned be16(const uint8_t *p)
{
    return (unsigned)p[0] << 8 | p[1];
}

static void put16(uint8_t *p, unsigned v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

int plc_mbap_need(const uint8_t *b, size_t have)
{
    if (have < 6)
        return PLC_MBAP_HDR;
    unsigned len = be16(b + 4);
    /* Length counts the unit id and the PDU: at least a function code, at
     * most the 253-byte PDU of the Modbus specification. */
    if (be16(b + 2) != 0 || len < 2 || 6 + len > PLC_MBAP_MAX)
        return PLC_MBAP_BAD;
    return (int)(6 + len);
}

size_t plc_mbap_exception(const uint8_t *q, int ex, uint8_t *r)
{
    r[0] = (uint8_t)(q[0] | 0x80);
    r[1] = (uint8_t)ex;
    return 2;
}

size_t plc_mbap_pdu(plc_fsm_t *f, const uint8_t *q, size_t n, uint8_t *r, uint32_t now_ms,
                    plc_action_t *act, plc_req_t *req)
{
    unsigned fc = q[0], a = n >= 3 ? be16(q + 1) : 0, cnt = 0;
    int ex = 0;
    *act = PLC_ACT_NONE;
    r[0] = (uint8_t)fc;
    if (fc == 0x03 || fc == 0x04) {
        uint16_t w[PLC_MAX_READ];
        cnt = n == 5 ? be16(q + 3) : 0;
        ex = n != 5 ? PLC_EX_VALUE : plc_map_read(f->map, a, cnt, w);
        if (!ex) {
            r[1] = (uint8_t)(2 * cnt);
            for (unsigned k = 0; k < cnt; k++)
                put16(r + 2 + 2 * k, w[k]);
            *req = (plc_req_t){fc, a, cnt, 0};
            return 2 + 2 * cnt;
        }
    } else if (fc == 0x06 || fc == 0x10) {
        uint16_t v[PLC_MAX_WRITE];
        if (fc == 0x06 && n == 5) {
            cnt = 1;
            v[0] = (uint16_t)be16(q + 3);
        } else if (fc == 0x10 && n >= 6) {
            cnt = be16(q + 3);
            if (cnt < 1 || cnt > PLC_MAX_WRITE || q[5] != 2 * cnt || n != 6 + 2 * (size_t)cnt)
                ex = PLC_EX_VALUE;
            for (unsigned k = 0; !ex && k < cnt; k++)
                v[k] = (uint16_t)be16(q + 6 + 2 * k);
        } else
            ex = PLC_EX_VALUE;
        if (!ex)
            ex = plc_fsm_write(f, a, cnt, v, now_ms, act);
        if (!ex) {
            memcpy(r, q, 5); /* function 06 echoes, 16 answers address and count */
            if (fc == 0x10)
                put16(r + 3, cnt);
            *req = (plc_req_t){fc, a, cnt, 0};
            return 5;
        }
    } else
        ex = PLC_EX_FUNCTION;
    *req = (plc_req_t){fc, a, cnt, ex};
    plc_map_inc_u32(f->map, PLC_R_REQ_REFUSED);
    return plc_mbap_exception(q, ex, r);
}
