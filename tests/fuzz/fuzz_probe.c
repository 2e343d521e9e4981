/* SPDX-License-Identifier: MIT */
/* fuzz_probe.c: libFuzzer target for the laser probe's ASCII protocol
 * (hal_probe.c): the input is what the probe sends back, to the range
 * query at init and then to reading after reading, with silences (0xFF),
 * over the fake transport of fuzz_hal.h. An accepted range is finite and
 * not empty; an accepted reading is finite; a failure leaves a one-line
 * detail. hal_probe_parse_m0 also gets the input as one line. */
#include "fuzz.h"
#include "fuzz_hal.h"
#include "hal_rig.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_probe: %s\n", why);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char line[256];
    size_t n = size < sizeof line - 1 ? size : sizeof line - 1;
    memcpy(line, data, n);
    line[n] = '\0';
    double mm = NAN;
    int rc = hal_probe_parse_m0(line, &mm);
    if (rc == RIG_OK && !isfinite(mm))
        fail("parse_m0 accepted a non-finite distance");

    fz_hal_t f;
    hal_probe_t p;
    fz_hal_init(&f, HAL_TTY, data, size);
    rc = hal_probe_init(&p, &f.h);
    if (rc) {
        fz_one_line(hal_probe_error(&p));
        return 0;
    }
    if (!(isfinite(p.lo) && isfinite(p.hi) && p.lo < p.hi))
        fail("accepted a bad measuring range");
    for (int k = 0; k < 64; k++) {
        rc = hal_probe_ascii_ops.read(&p, &mm);
        if (rc == RIG_OK && !isfinite(mm))
            fail("accepted a non-finite distance");
        if (rc)
            fz_one_line(hal_probe_error(&p));
        if (rc == RIG_EDISCONNECT)
            break;
    }
    return 0;
}
