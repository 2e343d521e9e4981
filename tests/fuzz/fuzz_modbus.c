/* SPDX-License-Identifier: MIT */
/* fuzz_modbus.c: libFuzzer target for the Modbus device drivers: register
 * replies decoded into the stage's limits, status and positions
 * (hal_stage.c) and the Modbus probe's range and readings
 * (hal_probe_mb.c), over the fake transport of fuzz_hal.h on a virtual
 * clock. The input chooses the calls (home, moves inside the limits,
 * position, status, stop, fault reset, probe reads) and is every reply.
 * Accepted values are finite; failures leave a one-line detail. */
#include "fuzz.h"
#include "fuzz_hal.h"
#include "hal_rig.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_modbus: %s\n", why);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_hal_t f;
    fz_hal_init(&f, HAL_TCP, data, size);
    hal_stage_t s;
    hal_probe_t p;
    int have_stage = hal_stage_init(&s, &f.h) == RIG_OK;
    if (!have_stage)
        fz_one_line(hal_stage_error(&s));
    else if (!(isfinite(s.lo[0]) && isfinite(s.hi[1]) && s.lo[0] < s.hi[0] && s.lo[1] < s.hi[1]))
        fail("accepted empty soft limits");
    int have_probe = hal_probe_init(&p, &f.h) == RIG_OK;
    if (!have_probe)
        fz_one_line(hal_probe_error(&p));
    else if (!(isfinite(p.lo) && isfinite(p.hi) && p.lo < p.hi))
        fail("accepted an empty probe range");
    while (f.at < f.n) {
        unsigned op = fz_hal_byte(&f) % 8;
        int rc = RIG_OK;
        double x, y, mm;
        uint32_t bits;
        if (op <= 5 && !have_stage)
            continue;
        switch (op) {
        case 0: rc = hal_stage_ops.home(&s); break;
        case 1: { /* a target inside the limits, from two bytes */
            double a = fz_hal_byte(&f) / 255.0, b = fz_hal_byte(&f) / 255.0;
            rc = hal_stage_ops.move_to(&s, s.lo[0] + a * (s.hi[0] - s.lo[0]),
                                       s.lo[1] + b * (s.hi[1] - s.lo[1]));
            break;
        }
        case 2:
            rc = hal_stage_ops.position(&s, &x, &y);
            if (!rc && !(isfinite(x) && isfinite(y)))
                fail("non-finite position");
            break;
        case 3: rc = hal_stage_ops.status(&s, &bits); break;
        case 4: rc = hal_stage_ops.stop(&s); break;
        case 5: rc = hal_stage_ops.reset_fault(&s); break;
        default:
            if (!have_probe)
                continue;
            rc = hal_probe_modbus_ops.read(&p, &mm);
            if (!rc && !isfinite(mm))
                fail("non-finite probe reading");
            if (rc)
                fz_one_line(hal_probe_error(&p));
            continue;
        }
        if (rc)
            fz_one_line(hal_stage_error(&s));
    }
    return 0;
}
