/* SPDX-License-Identifier: MIT */
/* sim_stream.c: the simulated probe's streaming mode (hal_regmap.h's
 * PRB_H_* and PRB_FIFO_*): a trigger input simulated inside cellsim fires
 * every period from arming; at each trigger the probe measures the part at
 * the stage's position at that instant and queues the reading with its
 * trigger number and the latched position. Triggers are generated when a
 * request comes in (sim_stream_catch_up, before the request moves the
 * stage on), so nothing needs a thread; a full FIFO drops the newest and
 * counts them. */
#include "hal_regmap.h"
#include "sim.h"
#include <math.h>
#include <stdlib.h>

#define SIM_FIFO_CAP 65536 /* entries: 3.3 s of triggers at 20 kHz */

/* The stage's position at time t (ms) of its present segment, without
 * moving its state on (sim_stage_pos would). */
static void pos_at(const sim_stage_t *st, double t, double xy[2])
{
    if (!st->moving) {
        xy[0] = st->p1[0];
        xy[1] = st->p1[1];
        return;
    }
    double f = st->t1 > st->t0 ? (t - st->t0) / (st->t1 - st->t0) : 1.0;
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    for (int a = 0; a < 2; a++)
        xy[a] = st->p0[a] + f * (st->p1[a] - st->p0[a]);
}

static int32_t um(double mm)
{
    return (int32_t)lround(mm * 1e3);
}

void sim_stream_catch_up(sim_probe_t *pr, double now)
{
    sim_stream_t *s = &pr->stream;
    if (!s->period_us || !s->fifo)
        return;
    double per_ms = s->period_us * 1e-3;
    for (;;) {
        double t = s->t_arm + (double)s->k * per_ms;
        if (t > now)
            return;
        if (s->count == s->cap) {
            /* Full: every trigger up to now is lost, counted, not measured. */
            uint64_t last = (uint64_t)floor((now - s->t_arm) / per_ms);
            s->overrun = (uint16_t)(s->overrun + (uint16_t)(last + 1 - s->k));
            s->k = last + 1;
            return;
        }
        double xy[2], d = 0;
        pos_at(pr->stage, t, xy);
        int m = sim_probe_measure_at(pr, xy, 0, s->uv, &d);
        sim_fifo_ent_t *e = &s->fifo[(s->head + s->count) % s->cap];
        e->seq = (uint16_t)s->k;
        e->status = m == 0 ? PRB_ST_VALID : m == 1 ? PRB_ST_NOSURF : PRB_ST_ERROR;
        e->d_um = m ? PRB_NOSURF_RAW : um(d);
        e->x_um = um(xy[0]);
        e->y_um = um(xy[1]);
        s->count++;
        s->k++;
    }
}

int sim_stream_read_holding(sim_probe_t *pr, int addr, int n, uint16_t *out)
{
    if (addr < 0 || addr + n > PRB_H_NREGS)
        return 2;
    uint16_t r[PRB_H_NREGS] = {(uint16_t)(pr->stream.period_us >> 16),
                               (uint16_t)(pr->stream.period_us & 0xFFFFu)};
    for (int i = 0; i < n; i++)
        out[i] = r[addr + i];
    return 0;
}

int sim_stream_write(sim_probe_t *pr, double now, int addr, int n, const uint16_t *in)
{
    sim_stream_t *s = &pr->stream;
    if (addr != PRB_H_PERIOD || n != 2)
        return 2; /* the period is written whole */
    uint32_t p = ((uint32_t)in[0] << 16) | in[1];
    if (p && (p < PRB_MIN_PERIOD_US || p > PRB_MAX_PERIOD_US))
        return 3;
    if (p && !s->fifo) {
        size_t cap = s->cap ? s->cap : SIM_FIFO_CAP; /* cellsim --fifo sets a smaller one */
        s->fifo = malloc(cap * sizeof *s->fifo);
        if (!s->fifo)
            return 4; /* server device failure */
        s->cap = cap;
    }
    /* Arming restarts the numbering and empties the FIFO; stopping keeps
     * what is queued for the host to read. */
    if (p) {
        s->head = s->count = 0;
        s->k = 0;
        s->overrun = 0;
        s->t_arm = now;
        s->uv[0] = s->uv[1] = NAN;
    }
    s->period_us = p;
    return 0;
}

int sim_stream_read_fifo(sim_probe_t *pr, int addr, int n, uint16_t *out)
{
    sim_stream_t *s = &pr->stream;
    if (addr != PRB_FIFO_COUNT || n < 2 || (n - 2) % PRB_FIFO_ENTRY ||
        (n - 2) / PRB_FIFO_ENTRY > PRB_FIFO_MAX_READ)
        return 2;
    out[0] = (uint16_t)(s->count > 65535 ? 65535 : s->count);
    out[1] = s->overrun;
    int k = (n - 2) / PRB_FIFO_ENTRY;
    s->popped = 0;
    for (int i = 0; i < k; i++) {
        uint16_t *r = out + PRB_FIFO_DATA - PRB_FIFO_COUNT + i * PRB_FIFO_ENTRY;
        if (!s->count) {
            for (int j = 0; j < PRB_FIFO_ENTRY; j++)
                r[j] = 0;
            continue;
        }
        const sim_fifo_ent_t *e = &s->fifo[s->head];
        if (!s->popped++)
            s->popped_lo = e->seq;
        s->head = (s->head + 1) % s->cap;
        s->count--;
        r[PRB_FE_SEQ] = e->seq;
        r[PRB_FE_STATUS] = e->status;
        int32_t v[3] = {e->d_um, e->x_um, e->y_um};
        for (int j = 0; j < 3; j++) {
            r[PRB_FE_DIST + 2 * j] = (uint16_t)((uint32_t)v[j] >> 16);
            r[PRB_FE_DIST + 2 * j + 1] = (uint16_t)((uint32_t)v[j] & 0xFFFFu);
        }
    }
    return 0;
}

void sim_stream_free(sim_probe_t *pr)
{
    free(pr->stream.fifo);
    pr->stream.fifo = NULL;
}
