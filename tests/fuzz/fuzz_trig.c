/* SPDX-License-Identifier: MIT */
/* fuzz_trig.c: libFuzzer target for the USB trigger box's packets
 * (hal_trig.c): hal_trig_decode on the raw input, then the identity reply
 * and bulk reads with sequence tracking over the fake USB transport of
 * fuzz_hal.h. Decoded counts never exceed what was asked for; every
 * packet decoded passed its sync byte and CRC. */
#include "fuzz.h"
#include "fuzz_hal.h"
#include "hal_trig.h"
#include <stdio.h>
#include <stdlib.h>

static void fail(const char *why)
{
    fprintf(stderr, "fuzz_trig: %s\n", why);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hal_trig_pkt_t pkts[8];
    size_t count = 99;
    size_t max = size ? data[0] % 9 : 0;
    int rc = hal_trig_decode(data, size, pkts, max, &count);
    if (count > max || (rc == RIG_OK && count * TRIG_PKT_LEN != size))
        fail("decode: count does not match the input");
    for (size_t k = 0; k < count; k++) {
        uint8_t b[TRIG_PKT_LEN];
        hal_trig_encode(&pkts[k], b);
        for (int i = 0; i < TRIG_PKT_LEN; i++)
            if (b[i] != data[k * TRIG_PKT_LEN + i])
                fail("decode: a packet does not encode back to its bytes");
    }

    fz_hal_t f;
    fz_hal_init(&f, HAL_USB, data, size);
    hal_trig_ident_t id;
    rc = hal_trig_ident(&f.h, &id);
    if (rc == RIG_EDISCONNECT)
        return 0;
    hal_trig_seq_t seq = {0, 0, 0};
    while (f.at < f.n) {
        size_t want = fz_hal_byte(&f) % 8 + 1;
        rc = hal_trig_read(&f.h, &seq, pkts, want, &count);
        if (count > want || count > 3)
            fail("read: more packets than asked");
        if (rc == RIG_EPROTO || rc == RIG_ECRC)
            fz_one_line(hal_last_error(&f.h));
        if (rc == RIG_EDISCONNECT)
            break;
    }
    return 0;
}
