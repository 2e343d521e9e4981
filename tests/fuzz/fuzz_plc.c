/* SPDX-License-Identifier: MIT */
/* fuzz_plc.c: libFuzzer target for the PLC register-write handler: the
 * register map's write validation and the job state machine (plc_map.c,
 * plc_fsm.c), driven by a sequence of Modbus writes and reads, clock
 * ticks, job events and progress reports decoded from the input. A write
 * refused with an exception must change nothing, and its exception is 02 or
 * 03, or 06 (server busy) while a job runs and the write reaches a register
 * other than COMMAND and PLC_HEARTBEAT; a write taken while busy reached
 * only those; the state stays a known one; the status registers follow it. */
#include "fuzz.h"
#include "plc_fsm.h"
#include "plc_map.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct fz_in {
    const uint8_t *d;
    size_t n, at;
} fz_in_t;

static unsigned take(fz_in_t *in)
{
    return in->at < in->n ? in->d[in->at++] : 0;
}

static unsigned take16(fz_in_t *in)
{
    unsigned hi = take(in);
    return hi << 8 | take(in);
}

static int check_code;

/* The job runner's guard: refuses with the code the input chose. */
static int check(void *ctx, int cmd, const plc_params_t *p)
{
    (void)ctx;
    (void)cmd;
    (void)p;
    return check_code;
}

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_plc: %s\n", why);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_in_t in = {data, size, 0};
    plc_map_t m;
    plc_fsm_t f;
    unsigned cfg = take(&in);
    uint32_t now = take16(&in) << 16;
    plc_map_init(&m, cfg & 1, "fuzz");
    plc_fsm_init(&f, &m, (cfg >> 1) & 1, (uint16_t)take16(&in), (cfg & 4) ? check : NULL, NULL,
                 now);
    while (in.at < in.n) {
        unsigned op = take(&in) % 6;
        if (op == 0 || op == 1) { /* write n registers at a (function 16, or 6 when n = 1) */
            unsigned a = take(&in), n = op == 0 ? take(&in) % 8 + 1 : take(&in) % 130;
            uint16_t v[130];
            for (unsigned k = 0; k < n; k++)
                v[k] = (uint16_t)take16(&in);
            plc_map_t m0 = m;
            plc_fsm_t f0 = f;
            plc_action_t act = PLC_ACT_NONE;
            int busy = plc_state_busy(f.state), busy_only = 1;
            for (unsigned k = a; k < a + n; k++)
                busy_only &= plc_fsm_writable(PLC_S_HOMING, plc_map_entry(k));
            int ex = plc_fsm_write(&f, a, n, v, now, &act);
            if (ex && (memcmp(&m0, &m, sizeof m) || memcmp(&f0, &f, sizeof f)))
                fail("a refused write changed the registers or the state");
            /* 06 is the answer while a job runs (issue 15: the harness predated it). */
            if (ex == PLC_EX_BUSY && (!busy || busy_only))
                fail("write: exception 06 when no job runs or for COMMAND / heartbeat");
            if (ex && ex != PLC_EX_ADDRESS && ex != PLC_EX_VALUE && ex != PLC_EX_BUSY)
                fail("write: exception code not 2, 3 or 6");
            if (!ex && busy && !busy_only)
                fail("write taken while busy beyond COMMAND and the heartbeat");
            if (!ex && a + n > PLC_NREGS)
                fail("write beyond the map accepted");
        } else if (op == 2) { /* read */
            unsigned a = take(&in), n = take(&in);
            uint16_t out[256];
            int ex = plc_map_read(&m, a, n, out);
            if (!ex && (n < 1 || n > PLC_MAX_READ || a + n > PLC_NREGS))
                fail("read beyond the map accepted");
        } else if (op == 3) { /* time passes */
            now += take16(&in);
            plc_fsm_tick(&f, now);
        } else if (op == 4) { /* the job ends a phase */
            plc_results_t res = {
                0.01f, 0.02f, -0.02f, 99.0f, PLC_VERDICT_PASS, 100, 64, 1000, PLC_FIT_NOT_MET_DATA};
            unsigned e = take(&in);
            plc_fsm_event(&f, (plc_event_t)(e % PLC_EV_COUNT), 300 + (int)(e >> 2) % 8,
                          (e & 0x80) ? &res : NULL);
        } else {
            unsigned p = take(&in);
            if (p & 1)
                check_code = (int)(100 + p % 16);
            else
                check_code = 0;
            plc_fsm_progress(&f, (int)p - 20);
        }
        if (f.state < 0 || f.state >= PLC_S_COUNT)
            fail("state out of range");
        if (plc_map_u16(&m, PLC_R_STATE) != (uint16_t)f.state)
            fail("STATE register does not show the state");
        if (plc_map_u16(&m, PLC_R_MAGIC) != PLC_MAGIC)
            fail("identity block overwritten");
    }
    return 0;
}
