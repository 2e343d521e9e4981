/* SPDX-License-Identifier: MIT */
/* cf_plcstats.c: the outbox and scan-loss figures of map version 3
 * (cf_plcstats.h). */
#include "cf_plcstats.h"
#include "cf_log.h"
#include "cf_thread.h"
#include <stdatomic.h>
#include <string.h>
#include <time.h>

static uint32_t clamp_u32(double v)
{
    return v <= 0 ? 0u : v >= 4294967295.0 ? 4294967295u : (uint32_t)v;
}

#if !CF_NO_PLANT
/* One read of the outbox, on the thread; the figures kept on failure. */
static void read_outbox(cf_plcstats_t *ps)
{
    char msg[512];
    if (!ps->db && cf_resdb_open(ps->db_path, &ps->db, msg, sizeof msg)) {
        if (!ps->db_failed) /* tried again each period, said once */
            cf_log(CF_LOG_WARN, "outbox registers: %s (trying again)", msg);
        ps->db = NULL;
        ps->db_failed = 1;
        return;
    }
    cf_resdb_obstat_t st;
    int rc = cf_resdb_outbox_stat(ps->db, &st);
    pthread_mutex_lock(&ps->mu);
    if (!rc) { /* busy or failing now: the registers keep the last figures */
        ps->have = 1;
        ps->pg = st.pending_pg;
        ps->mqtt = st.pending_mqtt;
        ps->dropped = st.dropped;
        ps->oldest = st.oldest;
    }
    pthread_mutex_unlock(&ps->mu);
}

static void *reader_main(void *arg)
{
    cf_plcstats_t *ps = arg;
    pthread_mutex_lock(&ps->mu);
    while (!ps->stop) {
        pthread_mutex_unlock(&ps->mu);
        read_outbox(ps);
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        ts.tv_sec += CF_PLCSRV_STATS_MS / 1000u;
        ts.tv_nsec += (long)(CF_PLCSRV_STATS_MS % 1000u) * 1000000L;
        if (ts.tv_nsec >= 1000000000L)
            ts.tv_sec++, ts.tv_nsec -= 1000000000L;
        pthread_mutex_lock(&ps->mu);
        while (!ps->stop && pthread_cond_timedwait(&ps->cv, &ps->mu, &ts) == 0) {
        }
    }
    pthread_mutex_unlock(&ps->mu);
    return NULL;
}
#endif

int cf_plcstats_start(cf_plcstats_t *ps, const cf_plcrun_t *rr, const char *db_path)
{
    memset(ps, 0, sizeof *ps);
    ps->rr = rr;
    ps->db_path = db_path;
    pthread_mutex_init(&ps->mu, NULL);
    /* Monotonic: a clock step must not stretch or shorten the period. */
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&ps->cv, &ca);
    pthread_condattr_destroy(&ca);
#if CF_NO_PLANT /* no results.db in this build (mk/plant.mk): the outbox registers stay 0 */
    return 0;
#else
    if (!db_path)
        return 0;
    if (cf_thread_start(&ps->th, reader_main, ps)) { /* signals stay with the main thread */
        cf_log(CF_LOG_WARN, "outbox registers: cannot start their thread (left at 0)");
        return -1;
    }
    ps->th_live = 1;
    return 0;
#endif
}

void cf_plcstats_read(void *ctx, cf_plc_stats_t *out)
{
    cf_plcstats_t *ps = ctx;
    memset(out, 0, sizeof *out);
    for (int i = 0; i < CF_PLC_SCAN_COUNTS; i++)
        out->scan[i] = atomic_load(&ps->rr->scan_counts[i]);
    pthread_mutex_lock(&ps->mu);
    out->have_outbox = ps->have;
    out->outbox_pg = clamp_u32((double)ps->pg);
    out->outbox_mqtt = clamp_u32((double)ps->mqtt);
    /* The age from now: it grows each second even while a read waits. */
    out->outbox_age_s = ps->oldest > 0 ? clamp_u32((double)time(NULL) - ps->oldest) : 0;
    out->outbox_dropped = clamp_u32((double)ps->dropped);
    pthread_mutex_unlock(&ps->mu);
}

void cf_plcstats_close(cf_plcstats_t *ps)
{
    if (ps->th_live) {
        pthread_mutex_lock(&ps->mu);
        ps->stop = 1;
        pthread_cond_signal(&ps->cv);
        pthread_mutex_unlock(&ps->mu);
        pthread_join(ps->th, NULL);
        ps->th_live = 0;
    }
#if !CF_NO_PLANT
    if (ps->db)
        cf_resdb_close(ps->db);
#endif
    ps->db = NULL;
    pthread_cond_destroy(&ps->cv);
    pthread_mutex_destroy(&ps->mu);
}
