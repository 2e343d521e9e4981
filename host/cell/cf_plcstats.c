/* SPDX-License-Identifier: MIT */
/* cf_plcstats.c: the outbox and scan-loss figures of map version 3
 * (cf_plcstats.h). */
#include "cf_plcstats.h"
#include "cf_log.h"
#include <stdatomic.h>
#include <string.h>
#include <time.h>

#if !CF_NO_PLANT
static uint32_t clamp_u32(double v)
{
    return v <= 0 ? 0u : v >= 4294967295.0 ? 4294967295u : (uint32_t)v;
}
#endif

void cf_plcstats_read(void *ctx, cf_plc_stats_t *out)
{
    cf_plcstats_t *ps = ctx;
    memset(out, 0, sizeof *out);
    for (int i = 0; i < CF_PLC_SCAN_COUNTS; i++)
        out->scan[i] = atomic_load(&ps->rr->scan_counts[i]);
#if CF_NO_PLANT /* no results.db in this build (mk/plant.mk): the outbox registers stay 0 */
    return;
#else
    if (!ps->db_path || ps->db_failed)
        return;
    char msg[512];
    if (!ps->db && cf_resdb_open(ps->db_path, &ps->db, msg, sizeof msg)) {
        cf_log(CF_LOG_WARN, "outbox registers: %s (left at 0)", msg);
        ps->db = NULL;
        ps->db_failed = 1;
        return;
    }
    cf_resdb_obstat_t st;
    if (cf_resdb_outbox_stat(ps->db, &st))
        return; /* busy or failing now: the registers keep the last figures */
    out->have_outbox = 1;
    out->outbox_pg = clamp_u32((double)st.pending_pg);
    out->outbox_mqtt = clamp_u32((double)st.pending_mqtt);
    out->outbox_age_s = st.oldest > 0 ? clamp_u32((double)time(NULL) - st.oldest) : 0;
    out->outbox_dropped = clamp_u32((double)st.dropped);
#endif
}

void cf_plcstats_close(cf_plcstats_t *ps)
{
#if !CF_NO_PLANT
    if (ps->db)
        cf_resdb_close(ps->db);
#endif
    ps->db = NULL;
}
