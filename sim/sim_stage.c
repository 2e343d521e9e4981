/* SPDX-License-Identifier: MIT */
/* sim_stage.c: the simulated motion stage behind its holding registers
 * (hal_regmap.h): both axes move together at a set speed, so a move takes
 * max(|dx|, |dy|) / speed plus a settle time, busy then in position;
 * homing, stop, soft limits, E-stop and latched drive faults. */
#include "hal_regmap.h"
#include "rig.h"
#include "sim.h"
#include <math.h>
#include <string.h>

void sim_stage_init(sim_stage_t *st, sim_faults_t *fs)
{
    memset(st, 0, sizeof *st);
    st->faults = fs;
    st->lo[0] = -10.0;
    st->hi[0] = 210.0;
    st->lo[1] = -10.0;
    st->hi[1] = 160.0;
    st->speed = 200.0;
    st->tfault = -1.0;
    /* Power-up somewhere that is not home, unreferenced. */
    st->p0[0] = st->p1[0] = 37.5;
    st->p0[1] = st->p1[1] = 12.25;
}

static void update(sim_stage_t *st, double now)
{
    if (!st->moving)
        return;
    if (st->tfault >= 0 && now >= st->tfault) {
        double xy[2], f = (st->tfault - st->t0) / (st->t1 - st->t0 > 0 ? st->t1 - st->t0 : 1);
        for (int a = 0; a < 2; a++)
            xy[a] = st->p0[a] + f * (st->p1[a] - st->p0[a]);
        memcpy(st->p0, xy, sizeof xy);
        memcpy(st->p1, xy, sizeof xy);
        st->moving = st->homing = st->inpos = 0;
        st->fault = 1;
        st->fault_code = STG_FC_DRIVE;
        st->tfault = -1.0;
        return;
    }
    if (now >= st->t1 + st->settle_ms) {
        memcpy(st->p0, st->p1, sizeof st->p0);
        st->moving = 0;
        st->inpos = 1;
        if (st->homing) {
            st->homing = 0;
            st->homed = 1;
        }
    }
}

void sim_stage_pos(sim_stage_t *st, double now, double xy[2])
{
    update(st, now);
    if (!st->moving) {
        memcpy(xy, st->p1, 2 * sizeof *xy);
        return;
    }
    double f = st->t1 > st->t0 ? (now - st->t0) / (st->t1 - st->t0) : 1.0;
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    for (int a = 0; a < 2; a++)
        xy[a] = st->p0[a] + f * (st->p1[a] - st->p0[a]);
}

uint16_t sim_stage_status(sim_stage_t *st, double now)
{
    update(st, now);
    unsigned b = 0;
    b |= st->homed ? RIG_ST_HOMED : 0;
    b |= st->moving ? RIG_ST_BUSY : 0;
    b |= st->inpos && !st->moving ? RIG_ST_INPOS : 0;
    b |= st->fault ? RIG_ST_FAULT : 0;
    b |= st->estop ? RIG_ST_ESTOP : 0;
    b |= st->limit ? RIG_ST_LIMIT : 0;
    return (uint16_t)b;
}

/* Freeze where we are now (stop, E-stop). */
static void halt(sim_stage_t *st, double now)
{
    double xy[2];
    sim_stage_pos(st, now, xy);
    memcpy(st->p0, xy, sizeof xy);
    memcpy(st->p1, xy, sizeof xy);
    st->moving = st->homing = st->inpos = 0;
    st->tfault = -1.0;
}

static void start(sim_stage_t *st, double now, const double to[2])
{
    double xy[2];
    sim_stage_pos(st, now, xy);
    memcpy(st->p0, xy, sizeof xy);
    memcpy(st->p1, to, sizeof xy);
    double d = fmax(fabs(to[0] - xy[0]), fabs(to[1] - xy[1]));
    st->t0 = now;
    st->t1 = now + 1e3 * d / st->speed;
    st->moving = 1;
    st->inpos = 0;
    st->moves++;
    st->limit = 0;
    if (st->fault_code == STG_FC_LIMIT)
        st->fault_code = STG_FC_NONE;
    double ms;
    st->tfault = -1.0;
    if (st->faults && (sim_faults_event(st->faults, 2, 0, &ms) & (1u << SIM_F_STAGEFAULT)))
        st->tfault = st->t0 + 0.5 * (st->t1 - st->t0);
}

static void command(sim_stage_t *st, double now, uint16_t cmd)
{
    update(st, now);
    if (cmd == STG_CMD_STOP) {
        halt(st, now);
        st->result = STG_RES_OK;
        return;
    }
    if (cmd == STG_CMD_RESET) {
        st->fault = st->limit = 0;
        st->fault_code = st->estop ? STG_FC_ESTOP : STG_FC_NONE;
        st->result = st->estop ? STG_RES_ESTOP : STG_RES_OK;
        return;
    }
    if (cmd != STG_CMD_MOVE && cmd != STG_CMD_HOME) {
        st->result = STG_RES_BADCMD;
        return;
    }
    if (st->estop) {
        st->result = STG_RES_ESTOP;
        return;
    }
    if (st->fault) {
        st->result = STG_RES_FAULT;
        return;
    }
    if (cmd == STG_CMD_HOME) {
        st->homed = 0;
        start(st, now, st->home);
        st->homing = 1;
        st->result = STG_RES_OK;
        return;
    }
    if (!st->homed) {
        st->result = STG_RES_NOTHOMED;
        return;
    }
    double to[2] = {st->tgt_raw[0] * 1e-3, st->tgt_raw[1] * 1e-3};
    if (to[0] < st->lo[0] || to[0] > st->hi[0] || to[1] < st->lo[1] || to[1] > st->hi[1]) {
        st->limit = 1;
        st->fault_code = STG_FC_LIMIT;
        st->result = STG_RES_LIMIT;
        return;
    }
    start(st, now, to);
    st->result = STG_RES_OK;
}

void sim_stage_set_estop(sim_stage_t *st, double now, int on)
{
    if (on && !st->estop) {
        halt(st, now);
        st->fault_code = STG_FC_ESTOP;
    }
    if (!on && st->estop && st->fault_code == STG_FC_ESTOP)
        st->fault_code = STG_FC_NONE;
    st->estop = on != 0;
}

void sim_stage_latch_fault(sim_stage_t *st, double now)
{
    halt(st, now);
    st->fault = 1;
    st->fault_code = STG_FC_DRIVE;
}

static int32_t um(double mm)
{
    return (int32_t)lround(mm * 1e3);
}

static void put32(uint16_t *r, int32_t v)
{
    uint32_t u = (uint32_t)v;
    r[0] = (uint16_t)(u >> 16); /* high word first (hal_regmap.h) */
    r[1] = (uint16_t)(u & 0xFFFFu);
}

int sim_stage_read(sim_stage_t *st, double now, int addr, int n, uint16_t *out)
{
    if (addr >= STG_SIM_ESTOP && addr + n <= STG_SIM_FAULT + 1) {
        for (int i = 0; i < n; i++)
            out[i] = addr + i == STG_SIM_ESTOP ? (uint16_t)st->estop : 0;
        return 0;
    }
    if (addr < 0 || addr + n > STG_NREGS)
        return 2; /* illegal data address */
    uint16_t r[STG_NREGS];
    double xy[2];
    sim_stage_pos(st, now, xy);
    put32(r + STG_TARGET_X, st->tgt_raw[0]);
    put32(r + STG_TARGET_Y, st->tgt_raw[1]);
    r[STG_COMMAND] = 0;
    r[STG_STATUS] = sim_stage_status(st, now);
    put32(r + STG_POS_X, um(xy[0]));
    put32(r + STG_POS_Y, um(xy[1]));
    put32(r + STG_LIM_XLO, um(st->lo[0]));
    put32(r + STG_LIM_XHI, um(st->hi[0]));
    put32(r + STG_LIM_YLO, um(st->lo[1]));
    put32(r + STG_LIM_YHI, um(st->hi[1]));
    r[STG_SPEED] = (uint16_t)lround(st->speed > 65535 ? 65535 : st->speed);
    r[STG_FAULT] = st->fault_code;
    r[STG_MOVES] = st->moves;
    r[STG_RESULT] = st->result;
    memcpy(out, r + addr, (size_t)n * sizeof *out);
    return 0;
}

int sim_stage_write(sim_stage_t *st, double now, int addr, int n, const uint16_t *in)
{
    if (addr >= STG_SIM_ESTOP && addr + n <= STG_SIM_FAULT + 1) {
        for (int i = 0; i < n; i++) {
            if (addr + i == STG_SIM_ESTOP)
                sim_stage_set_estop(st, now, in[i] != 0);
            else if (in[i])
                sim_stage_latch_fault(st, now);
        }
        return 0;
    }
    /* Writable: the targets, the command, the speed; in address order, so
     * one write of registers 0-4 is a complete, atomic move. */
    for (int i = 0; i < n; i++) {
        int a = addr + i;
        if (!(a <= STG_COMMAND || a == STG_SPEED))
            return 2;
        if (a == STG_SPEED && in[i] == 0)
            return 3; /* illegal data value */
    }
    for (int i = 0; i < n; i++) {
        int a = addr + i;
        if (a < STG_COMMAND) {
            uint32_t u = (uint32_t)st->tgt_raw[a / 2];
            u = a % 2 ? (u & 0xFFFF0000u) | in[i] : (u & 0xFFFFu) | ((uint32_t)in[i] << 16);
            st->tgt_raw[a / 2] = (int32_t)u;
        } else if (a == STG_COMMAND)
            command(st, now, in[i]);
        else
            st->speed = in[i];
    }
    return 0;
}
