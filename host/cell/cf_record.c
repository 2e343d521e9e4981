/* SPDX-License-Identifier: MIT */
/* cf_record.c: the recording runner table (cf_record.h). */
#include "cf_record.h"
#include "cf_log.h"
#include "cf_sha256.h"
#include "cf_uuid.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *cmd_name(int cmd)
{
    switch (cmd) {
    case PLC_C_SCAN: return "scan";
    case PLC_C_FIT: return "fit";
    case PLC_C_SCAN_FIT: return "scan_fit";
    case PLC_C_EXPORT: return "export";
    default: return "other";
    }
}

/* The first phase of a job: its identity. */
static void begin(cf_record_t *r, const plc_params_t *p)
{
    if (r->active && r->seq == p->seq && r->cmd == p->cmd)
        return; /* the job's second phase */
    r->active = 1;
    r->seq = p->seq;
    r->cmd = p->cmd;
    if (cf_uuid_new(r->uuid))
        r->uuid[0] = 0;
    cf_resdb_now_iso(r->started);
    cf_forward_state(r->fwd, "busy");
}

static void path_sum(const char *path, char *pbuf, size_t pn, char sum[65])
{
    size_t l = strnlen(path, pn - 1); /* a longer path is cut: never the case for ours */
    memcpy(pbuf, path, l);
    pbuf[l] = 0;
    if (!path[0] || cf_sha256_file(path, sum))
        sum[0] = 0;
}

/* The job's last phase returned rc (0, a PLC code, CF_PLC_ABORTED). */
static void end(cf_record_t *r, const plc_params_t *p, int rc, const plc_results_t *res)
{
    cf_resdb_job_t *j = calloc(1, sizeof *j);
    r->active = 0;
    if (!j || !r->uuid[0]) {
        r->failed++;
        cf_log(CF_LOG_ERROR, "record: job seq %u not recorded (no memory or no UUID)", p->seq);
        free(j);
        return;
    }
    snprintf(j->job_uuid, sizeof j->job_uuid, "%s", r->uuid);
    snprintf(j->cell_id, sizeof j->cell_id, "%s", r->cell_id ? r->cell_id : "");
    j->part_number = (long)p->part;
    j->program = p->program;
    j->result_seq = p->seq;
    snprintf(j->command, sizeof j->command, "%s", cmd_name(p->cmd));
    snprintf(j->started_at, sizeof j->started_at, "%s", r->started);
    cf_resdb_now_iso(j->ended_at);
    snprintf(j->state, sizeof j->state, "%s",
             rc == 0                ? "done"
             : rc == CF_PLC_ABORTED ? "aborted"
                                    : "error");
    j->error_code = rc > 0 ? rc : 0;
    const plc_results_t *f = NULL;
    if (rc == 0 && res && (p->cmd == PLC_C_FIT || p->cmd == PLC_C_SCAN_FIT))
        f = res;
    else if (rc == 0 && p->cmd == PLC_C_EXPORT && r->have_fit)
        f = &r->fit;
    if (f) { /* the very floats the PLC reads from its registers */
        j->has_fit = 1;
        j->fit_status = 0;
        j->rms = f->rms, j->max_dev = f->max, j->min_dev = f->min, j->within_pct = f->within_pct;
        j->verdict = f->verdict;
        j->points = (long)f->points, j->control_points = (long)f->control_points;
    }
    const cf_plcrun_t *rr = r->rr;
    char path[CF_RESDB_PATH];
    if (rc == 0 && p->cmd == PLC_C_EXPORT) {
        snprintf(path, sizeof path, "%.4000s/fitted.igs", rr->last_export);
        path_sum(path, j->surface_path, sizeof j->surface_path, j->surface_sha256);
        snprintf(path, sizeof path, "%.4000s/report.json", rr->last_export);
        path_sum(path, j->report_path, sizeof j->report_path, j->report_sha256);
        path_sum(rr->last_journal, j->journal_path, sizeof j->journal_path, j->journal_sha256);
    } else if (p->cmd == PLC_C_SCAN || p->cmd == PLC_C_SCAN_FIT)
        path_sum(rr->journal, j->journal_path, sizeof j->journal_path, j->journal_sha256);
    int e = cf_resdb_record(r->db, j, r->fwd ? r->targets : 0, r->outbox_max);
    if (e) {
        r->failed++;
        cf_log(CF_LOG_ERROR, "record: job %s (seq %u): %s", j->job_uuid, p->seq,
               cf_resdb_strerror(e));
    } else {
        r->recorded++;
        cf_log(CF_LOG_INFO, "record: job %s seq %u %s %s", j->job_uuid, p->seq, j->command,
               j->state);
    }
    free(j);
    cf_forward_state(r->fwd, rc == 0 || rc == CF_PLC_ABORTED ? "idle" : "error");
    cf_forward_kick(r->fwd);
}

static int last_phase(const plc_params_t *p, int state)
{
    if (p->cmd >= PLC_C_COUNT)
        return 1;
    const uint8_t *ph = plc_job_phases[p->cmd];
    return ph[1] ? state == ph[1] : state == ph[0];
}

static int w_check(void *ctx, int cmd, const plc_params_t *p)
{
    cf_record_t *r = ctx;
    return r->inner.check ? r->inner.check(r->inner.ctx, cmd, p) : 0;
}

static int w_home(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_record_t *r = ctx; /* HOME is not a result: not recorded */
    return r->inner.home(r->inner.ctx, p, ctl);
}

static int w_scan(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_record_t *r = ctx;
    begin(r, p);
    int rc = r->inner.scan(r->inner.ctx, p, ctl);
    if (rc || last_phase(p, PLC_S_SCANNING))
        end(r, p, rc, NULL);
    return rc;
}

static int w_fit(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl, plc_results_t *res)
{
    cf_record_t *r = ctx;
    begin(r, p);
    int rc = r->inner.fit(r->inner.ctx, p, ctl, res);
    r->have_fit = rc == 0;
    if (rc == 0)
        r->fit = *res;
    end(r, p, rc, res);
    return rc;
}

static int w_export(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl)
{
    cf_record_t *r = ctx;
    begin(r, p);
    int rc = r->inner.export_result(r->inner.ctx, p, ctl);
    end(r, p, rc, NULL);
    return rc;
}

static void w_abort(void *ctx)
{
    cf_record_t *r = ctx;
    r->inner.abort(r->inner.ctx);
}

static int w_health(void *ctx)
{
    cf_record_t *r = ctx;
    return r->inner.health ? r->inner.health(r->inner.ctx) : 0;
}

void cf_record_wrap(cf_record_t *rec, cf_runner_t *out)
{
    rec->active = 0;
    rec->have_fit = 0;
    *out = rec->inner;
    out->check = w_check;
    out->home = w_home;
    out->scan = w_scan;
    out->fit = w_fit;
    out->export_result = w_export;
    out->abort = w_abort;
    out->health = rec->inner.health ? w_health : NULL;
    out->ctx = rec;
}

int cf_record_default_path(const char *results_dir, char *buf, size_t n)
{
    int k = snprintf(buf, n, "%s/results.db", results_dir);
    return k < 0 || (size_t)k >= n ? -1 : 0;
}
