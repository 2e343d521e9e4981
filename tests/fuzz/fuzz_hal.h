/* SPDX-License-Identifier: MIT */
/* fuzz_hal.h: a fake hal/ transport for the device-driver fuzz targets: the
 * device's side of the wire is the fuzz input. Byte streams read it a byte
 * at a time (0xFF: the device stays silent for a timeout); register reads
 * take a control byte (a transport error or not) and then the registers,
 * high byte first; USB transfers take a length byte and that many bytes.
 * Input exhausted: RIG_EDISCONNECT, so every driver loop ends. Time is
 * virtual: hal_now_ms and hal_sleep_ms are wrapped (-Wl,--wrap). */
#ifndef FUZZ_HAL_H
#define FUZZ_HAL_H

#include "hal.h"
#include <stddef.h>
#include <stdint.h>

typedef struct fz_hal {
    struct hal h; /* first, as every backend's */
    const uint8_t *d;
    size_t n, at;
} fz_hal_t;

/* A transport of this kind (HAL_TTY, HAL_TCP, HAL_USB) over data. */
void fz_hal_init(fz_hal_t *f, hal_kind_t kind, const uint8_t *data, size_t size);

/* The next input byte (0 once exhausted). */
unsigned fz_hal_byte(fz_hal_t *f);

#endif
