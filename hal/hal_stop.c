/* SPDX-License-Identifier: MIT */
/* hal_stop.c: the stop check every backend's waits see (hal.h's
 * should_stop), so that an ABORT lands within one request's timeout even
 * when the device hangs: retries, late-reply waits and reconnect loops give
 * up with RIG_EABORTED as soon as a stop is asked, and a device that failed
 * a request under a stop is not asked again until the stop is withdrawn. */
#include "hal.h"
#include "hal_priv.h"
#include "rig_err.h"
#include <stdio.h>
#include <string.h>

void hal_set_stop(hal_t *h, int (*fn)(void *ctx), void *ctx)
{
    if (!h)
        return;
    h->should_stop = fn;
    h->stop_ctx = ctx;
    h->stop_dead = 0;
}

int hal_stopped(hal_t *h)
{
    if (!h || !h->should_stop)
        return 0;
    if (h->should_stop(h->stop_ctx))
        return 1;
    h->stop_dead = 0; /* the stop is over: the next job asks the device again */
    return 0;
}

int hal_wait_ms(hal_t *h, double ms)
{
    double t_end = hal_now_ms() + ms;
    for (;;) {
        if (hal_stopped(h))
            return RIG_EABORTED;
        double left = t_end - hal_now_ms();
        if (left <= 0)
            return RIG_OK;
        hal_sleep_ms(left < HAL_STOP_SLICE_MS ? left : HAL_STOP_SLICE_MS);
    }
}

int hal_stop_before(hal_t *h)
{
    if (!hal_stopped(h) || !h->stop_dead)
        return RIG_OK;
    return hal_fail(h, RIG_EABORTED, "%s: stop asked, the device did not answer: not asked again",
                    h->uri.path);
}

int hal_stop_after(hal_t *h, int code)
{
    if (!hal_stopped(h))
        return RIG_OK;
    h->stop_dead = 1;
    char was[sizeof h->err];
    memcpy(was, h->err, sizeof was);
    return hal_fail(h, RIG_EABORTED, "stop asked: gave up after one attempt (%s: %.180s)",
                    rig_strerror(code), was);
}
