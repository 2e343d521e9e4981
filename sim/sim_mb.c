/* SPDX-License-Identifier: MIT */
/* sim_mb.c: the simulator's Modbus server side: request PDUs (functions
 * 03, 04, 06, 16) answered from the stage and probe models, exceptions
 * for the rest (the probe unit's holding registers and FIFO are its
 * streaming mode, sim_stream.c), the RTU CRC and RTU request lengths. Framing is done here
 * rather than by libmodbus's server so that faults can touch single bytes
 * and one bus can carry two unit ids (stage and probe). */
#include "hal_regmap.h"
#include "sim.h"

uint16_t sim_crc16(const uint8_t *p, size_t n)
{
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int b = 0; b < 8; b++)
            crc = (crc & 1) ? (uint16_t)((crc >> 1) ^ 0xA001) : (uint16_t)(crc >> 1);
    }
    return crc;
}

int sim_rtu_frame_len(const uint8_t *buf, size_t n)
{
    if (n < 2)
        return 0;
    switch (buf[1]) {
    case 3:
    case 4:
    case 6: return 8;
    case 16: return n < 7 ? 0 : 9 + buf[6];
    default: return -1;
    }
}

static int exc(const uint8_t *req, uint8_t *rsp, int code)
{
    rsp[0] = (uint8_t)(req[0] | 0x80);
    rsp[1] = (uint8_t)code;
    return 2;
}

static int get16(const uint8_t *p)
{
    return (p[0] << 8) | p[1];
}

int sim_mb_pdu(sim_rig_t *r, int wire, int unit, const uint8_t *req, size_t n, uint8_t *rsp,
               int busy)
{
    int is_stage = unit == r->stage_unit || (wire == SIM_W_TCP && (unit == 0 || unit == 255));
    int is_probe = unit == r->probe_unit && r->probe;
    if (!is_stage && !is_probe) {
        if (wire == SIM_W_RTU)
            return -1;              /* another slave's frame on the bus */
        return exc(req, rsp, 0x0B); /* gateway target device failed to respond */
    }
    if (n < 1)
        return -1;
    if (busy)
        return exc(req, rsp, 6);
    double now = sim_now_ms();
    /* Triggers up to now first, while the stage is still on the segment
     * they fell in. */
    if (r->probe)
        sim_stream_catch_up(r->probe, now);
    uint8_t fc = req[0];
    uint16_t regs[125];
    if (fc == 3 || fc == 4) {
        if (n != 5)
            return exc(req, rsp, 3);
        int addr = get16(req + 1), cnt = get16(req + 3);
        if (cnt < 1 || cnt > 125)
            return exc(req, rsp, 3);
        int e;
        if (fc == 3)
            e = is_stage ? sim_stage_read(r->stage, now, addr, cnt, regs)
                         : sim_stream_read_holding(r->probe, addr, cnt, regs);
        else if (!is_probe)
            e = 2;
        else if (addr >= PRB_FIFO_COUNT)
            e = sim_stream_read_fifo(r->probe, addr, cnt, regs);
        else
            e = sim_probe_read_input(r->probe, now, addr, cnt, regs);
        if (e)
            return exc(req, rsp, e);
        rsp[0] = fc;
        rsp[1] = (uint8_t)(2 * cnt);
        for (int i = 0; i < cnt; i++) {
            rsp[2 + 2 * i] = (uint8_t)(regs[i] >> 8);
            rsp[3 + 2 * i] = (uint8_t)(regs[i] & 0xFF);
        }
        return 2 + 2 * cnt;
    }
    if (fc == 6 || fc == 16) {
        int addr = get16(req + 1), cnt = 1;
        if (fc == 6) {
            if (n != 5)
                return exc(req, rsp, 3);
            regs[0] = (uint16_t)get16(req + 3);
        } else {
            if (n < 6)
                return exc(req, rsp, 3);
            cnt = get16(req + 3);
            if (cnt < 1 || cnt > 123 || req[5] != 2 * cnt || n != (size_t)(6 + 2 * cnt))
                return exc(req, rsp, 3);
            for (int i = 0; i < cnt; i++)
                regs[i] = (uint16_t)get16(req + 6 + 2 * i);
        }
        int e = is_stage ? sim_stage_write(r->stage, now, addr, cnt, regs)
                         : sim_stream_write(r->probe, now, addr, cnt, regs);
        if (e)
            return exc(req, rsp, e);
        /* 06 echoes the request; 16 answers address and count. */
        for (int i = 0; i < 5; i++)
            rsp[i] = req[i];
        return 5;
    }
    return exc(req, rsp, 1); /* illegal function */
}
