/* SPDX-License-Identifier: MIT */
/* hal_priv.h: what the hal/ backends and drivers share and nothing else
 * includes: the detail buffer, monotonic time and sleeping. */
#ifndef HAL_PRIV_H
#define HAL_PRIV_H

#include "hal.h"
#include "hal_rig.h"

/* printf into h->err (the detail hal_last_error returns); returns code. */
int hal_fail(hal_t *h, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

double hal_now_ms(void); /* monotonic milliseconds */
void hal_sleep_ms(double ms);
/* Sleep ms in slices of at most HAL_STOP_SLICE_MS that see h's stop check:
 * RIG_OK after the whole wait, RIG_EABORTED as soon as a stop is asked. */
#define HAL_STOP_SLICE_MS 10.0
int hal_wait_ms(hal_t *h, double ms);
/* A request's stop rules (hal.h): RIG_EABORTED (detail in h->err) when a
 * stop is asked and the device already failed a request under it, else
 * RIG_OK. hal_stop_after: after a failed attempt, RIG_EABORTED (the device
 * now taken as hung) when a stop is asked, else RIG_OK. */
int hal_stop_before(hal_t *h);
int hal_stop_after(hal_t *h, int code);

/* Fill o from in (NULL: defaults), a field left 0 taking its default. */
void hal_opts_fill(hal_opts_t *o, const hal_opts_t *in);

/* The probe drivers' detail (hal_probe.c) and range query (hal_probe_mb.c). */
int hal_probe_pfail(hal_probe_t *p, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int hal_probe_modbus_range(hal_probe_t *p);
/* The ASCII protocol's streaming (hal_probe.c), behind hal_probe_stream_*. */
int hal_probe_ascii_stream_start(hal_probe_t *p, uint32_t period_us);
int hal_probe_ascii_stream_stop(hal_probe_t *p);
int hal_probe_ascii_stream_read(hal_probe_t *p, rig_reading_t *r, rig_trig_event_t *pos, size_t max,
                                size_t *n, unsigned long *dropped);

#endif
