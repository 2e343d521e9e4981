/* hal_probe_mb.c: the displacement probe read over Modbus input registers
 * (hal_regmap.h): distance as an int32 in micrometres, a status register
 * whose bits say valid, out of range (RIG_ENOSURF) or sensor error; the
 * reading, its status and sequence number come in one request, so they
 * belong together. Retries and reconnection are the transport's. */
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
