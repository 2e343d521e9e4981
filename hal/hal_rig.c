/* SPDX-License-Identifier: MIT */
/* hal_rig.c: open the stage and the probe from their URIs and hand them
 * out as rig.h tables, for host code (cellfit rig, the scan job). */
#include "hal_rig.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void hal_rig_close(hal_rig_t *r)
{
    if (!r)
        return;
    if (r->st.h)
        hal_close(r->st.h);
    if (r->pr.h)
        hal_close(r->pr.h);
    free(r);
}

int hal_rig_open(const char *stage_uri, const char *probe_uri, const hal_opts_t *o, hal_rig_t **out,
                 char *msg, size_t msglen)
{
    if (!out || (!stage_uri && !probe_uri))
        return RIG_EARG;
    *out = NULL;
    hal_rig_t *r = calloc(1, sizeof *r);
    if (!r)
        return RIG_EOPEN;
    char m[400];
    int rc;
    if (stage_uri) {
        hal_t *h;
        if ((rc = hal_open(stage_uri, o, &h, m, sizeof m))) {
            snprintf(msg, msglen, "stage: %s", m);
            hal_rig_close(r);
            return rc;
        }
        if (h->uri.kind != HAL_RTU && h->uri.kind != HAL_TCP) {
            hal_close(h);
            snprintf(msg, msglen, "stage %s: a Modbus device (rtu: or tcp:)", stage_uri);
            hal_rig_close(r);
            return RIG_EARG;
        }
        if ((rc = hal_stage_init(&r->st, h))) {
            r->st.h = h;
            snprintf(msg, msglen, "%s", r->st.err);
            hal_rig_close(r);
            return rc;
        }
        r->stage.ops = &hal_stage_ops;
        r->stage.ctx = &r->st;
    }
    if (probe_uri) {
        hal_t *h;
        if ((rc = hal_open(probe_uri, o, &h, m, sizeof m))) {
            snprintf(msg, msglen, "probe: %s", m);
            hal_rig_close(r);
            return rc;
        }
        if ((rc = hal_probe_init(&r->pr, h))) {
            r->pr.h = h;
            snprintf(msg, msglen, "%s", r->pr.err);
            hal_rig_close(r);
            return rc;
        }
        r->probe.ops = r->pr.modbus ? &hal_probe_modbus_ops : &hal_probe_ascii_ops;
        r->probe.ctx = &r->pr;
    }
    *out = r;
    return RIG_OK;
}
