/* SPDX-License-Identifier: MIT */
/* hal_probe_mb.c: the displacement probe read over Modbus input registers
 * (hal_regmap.h): distance as an int32 in micrometres, a status register
 * whose bits say valid, out of range (RIG_ENOSURF) or sensor error; the
 * reading, its status and sequence number come in one request, so they
 * belong together. Retries and reconnection are the transport's. The
 * streaming mode pops the probe's FIFO: readings with their trigger
 * numbers and latched positions (the ASCII variant's is in hal_probe.c). */
#include "hal_priv.h"
#include "hal_regmap.h"
#include "hal_rig.h"

static int32_t get32(const uint16_t *r)
{
    return (int32_t)(((uint32_t)r[0] << 16) | r[1]);
}

int hal_probe_modbus_range(hal_probe_t *p)
{
    uint16_t r[4];
    int rc = hal_read_regs(p->h, 'i', PRB_RANGE_LO, 4, r);
    if (rc)
        return hal_probe_pfail(p, rc, "probe range: %s", hal_last_error(p->h));
    p->lo = get32(r) * 1e-3;
    p->hi = get32(r + 2) * 1e-3;
    if (!(p->lo < p->hi))
        return hal_probe_pfail(p, RIG_EPROTO, "probe reports an empty range [%g, %g] mm", p->lo,
                               p->hi);
    return RIG_OK;
}

static int mb_read(void *ctx, double *mm)
{
    hal_probe_t *p = ctx;
    uint16_t r[4];
    if (!p || !mm)
        return RIG_EARG;
    int rc = hal_read_regs(p->h, 'i', PRB_DIST, 4, r);
    if (rc)
        return hal_probe_pfail(p, rc, "probe reading: %s", hal_last_error(p->h));
    unsigned st = r[PRB_STATUS];
    if (st & PRB_ST_ERROR)
        return hal_probe_pfail(p, RIG_EEXCEPTION, "probe reports a sensor error (status 0x%04x)",
                               st);
    if (st & PRB_ST_NOSURF)
        return hal_probe_pfail(p, RIG_ENOSURF, "probe: no surface within [%g, %g] mm", p->lo,
                               p->hi);
    if (!(st & PRB_ST_VALID) || get32(r) == PRB_NOSURF_RAW)
        return hal_probe_pfail(p, RIG_EPROTO, "probe: reading not valid (status 0x%04x)", st);
    *mm = get32(r) * 1e-3;
    return RIG_OK;
}

static int mb_range(void *ctx, double *lo, double *hi)
{
    hal_probe_t *p = ctx;
    if (!p || !lo || !hi)
        return RIG_EARG;
    *lo = p->lo;
    *hi = p->hi;
    return RIG_OK;
}

const rig_probe_ops_t hal_probe_modbus_ops = {
    .version = RIG_OPS_VERSION,
    .read = mb_read,
    .range = mb_range,
};

int hal_probe_stream_start(hal_probe_t *p, uint32_t period_us)
{
    if (!p || period_us < PRB_MIN_PERIOD_US || period_us > PRB_MAX_PERIOD_US)
        return RIG_EARG;
    if (!p->modbus)
        return hal_probe_ascii_stream_start(p, period_us);
    uint16_t r[2] = {(uint16_t)(period_us >> 16), (uint16_t)(period_us & 0xFFFFu)};
    int rc = hal_write_regs(p->h, PRB_H_PERIOD, 2, r);
    if (rc)
        return hal_probe_pfail(p, rc, "probe stream start: %s", hal_last_error(p->h));
    p->overrun = 0;
    p->streaming = 1;
    return RIG_OK;
}

int hal_probe_stream_stop(hal_probe_t *p)
{
    if (!p)
        return RIG_EARG;
    if (!p->modbus)
        return hal_probe_ascii_stream_stop(p);
    uint16_t r[2] = {0, 0};
    int rc = hal_write_regs(p->h, PRB_H_PERIOD, 2, r);
    if (rc)
        return hal_probe_pfail(p, rc, "probe stream stop: %s", hal_last_error(p->h));
    p->streaming = 0;
    return RIG_OK;
}

int hal_probe_stream_read(hal_probe_t *p, rig_reading_t *rd, rig_trig_event_t *pos, size_t max,
                          size_t *n, unsigned long *dropped)
{
    if (!p || !rd || !pos || !n)
        return RIG_EARG;
    *n = 0;
    if (!p->modbus)
        return hal_probe_ascii_stream_read(p, rd, pos, max, n, dropped);
    while (*n < max) {
        size_t k = max - *n < PRB_FIFO_MAX_READ ? max - *n : PRB_FIFO_MAX_READ;
        uint16_t r[2 + PRB_FIFO_ENTRY * PRB_FIFO_MAX_READ];
        int cnt = 2 + PRB_FIFO_ENTRY * (int)k;
        int rc = hal_read_regs(p->h, 'i', PRB_FIFO_COUNT, cnt, r);
        if (rc)
            return hal_probe_pfail(p, rc, "probe FIFO: %s", hal_last_error(p->h));
        size_t waiting = r[0], got = waiting < k ? waiting : k;
        uint16_t lost = (uint16_t)(r[1] - p->overrun);
        p->overrun = r[1];
        if (dropped)
            *dropped += lost;
        for (size_t i = 0; i < got; i++) {
            const uint16_t *e = r + 2 + PRB_FIFO_ENTRY * i;
            unsigned st = e[PRB_FE_STATUS];
            int32_t d = get32(e + PRB_FE_DIST);
            rig_reading_t x = {e[PRB_FE_SEQ],
                               st & PRB_ST_ERROR                            ? RIG_RD_ERROR
                               : st & PRB_ST_NOSURF                         ? RIG_RD_NOSURF
                               : (st & PRB_ST_VALID) && d != PRB_NOSURF_RAW ? RIG_RD_VALID
                                                                            : RIG_RD_ERROR,
                               d * 1e-3};
            rig_trig_event_t t = {e[PRB_FE_SEQ],
                                  (uint8_t)(lost && !i ? RIG_TRIG_F_OVERRUN : 0),
                                  0,
                                  {get32(e + PRB_FE_X), get32(e + PRB_FE_Y)}};
            rd[*n] = x;
            pos[*n] = t;
            ++*n;
        }
        if (waiting <= k)
            break; /* the FIFO is empty now */
    }
    return RIG_OK;
}
