/* SPDX-License-Identifier: MIT */
/* sim_probe.c: the simulated displacement probe. Kinematic model
 * (docs/rig-devices.md): the beam starts at (sx + ox, sy + oy, z0), stage
 * position (sx, sy) and calibration offset (ox, oy), and points along -z;
 * the reading is d = z0 - z(part) + noise, so a point is (sx + ox, sy +
 * oy, z0 - d); out of range when no part is below or d is outside
 * [lo, hi]. Its Modbus input registers are tabled in hal_regmap.h. */
#include "hal_regmap.h"
#include "sim.h"
#include <math.h>

int sim_probe_measure(sim_probe_t *pr, double now, int wire, double *d)
{
    double xy[2], uv[2] = {NAN, NAN};
    sim_stage_pos(pr->stage, now, xy);
    return sim_probe_measure_at(pr, xy, wire, uv, d);
}

int sim_probe_measure_at(sim_probe_t *pr, const double xy[2], int wire, double uv[2], double *d)
{
    double z, ms;
    pr->seq++;
    unsigned f = pr->faults ? sim_faults_event(pr->faults, 1, wire, &ms) : 0;
    if (f & (1u << SIM_F_PROBEERR))
        return 2;
    if (f & (1u << SIM_F_NOSURF))
        return 1;
    if (sim_part_z_near(pr->part, xy[0] + pr->off[0], xy[1] + pr->off[1], uv, &z)) {
        uv[0] = uv[1] = NAN; /* off the part: the next one searches afresh */
        return 1;
    }
    *d = pr->z0 - z + pr->noise * sim_gauss(&pr->rng);
    return *d < pr->lo || *d > pr->hi ? 1 : 0;
}

static void put32(uint16_t *r, int32_t v)
{
    r[0] = (uint16_t)((uint32_t)v >> 16);
    r[1] = (uint16_t)((uint32_t)v & 0xFFFFu);
}

int sim_probe_read_input(sim_probe_t *pr, double now, int addr, int n, uint16_t *out)
{
    if (addr < 0 || addr + n > PRB_NREGS)
        return 2;
    uint16_t r[PRB_NREGS] = {0};
    if (addr <= PRB_SEQ) { /* asking for the reading takes a new one */
        double d = 0;
        int m = sim_probe_measure(pr, now, 0, &d);
        put32(r + PRB_DIST, m ? PRB_NOSURF_RAW : (int32_t)lround(d * 1e3));
        r[PRB_STATUS] = m == 0 ? PRB_ST_VALID : m == 1 ? PRB_ST_NOSURF : PRB_ST_ERROR;
        r[PRB_SEQ] = pr->seq;
    }
    put32(r + PRB_RANGE_LO, (int32_t)lround(pr->lo * 1e3));
    put32(r + PRB_RANGE_HI, (int32_t)lround(pr->hi * 1e3));
    for (int i = 0; i < n; i++)
        out[i] = r[addr + i];
    return 0;
}
