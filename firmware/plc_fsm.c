/* SPDX-License-Identifier: MIT */
/* plc_fsm.c: the job state machine, the handshake, the results latch and
 * the watchdog (plc_fsm.h); the tables below are the whole behaviour, and
 * docs/plc-register-map.md prints them. */
#include "plc_fsm.h"
#include <string.h>

#define ACC(k)                                                                                     \
    {                                                                                              \
        PLC_K_##k, 0                                                                               \
    }
#define REJ(c)                                                                                     \
    {                                                                                              \
        PLC_K_REJECT, PLC_E_##c                                                                    \
    }
/* Columns: NONE HOME SCAN FIT SCAN_FIT ABORT RESET EXPORT ACK_RESULTS */
#define BUSY_ROW                                                                                   \
    {                                                                                              \
        REJ(UNKNOWN_CMD), REJ(BUSY), REJ(BUSY), REJ(BUSY), REJ(BUSY), ACC(ABORT), REJ(BUSY),       \
            REJ(BUSY), REJ(BUSY)                                                                   \
    }
const plc_rule_t plc_cmd_rules[PLC_S_COUNT][PLC_C_COUNT] = {
    [PLC_S_IDLE] = {REJ(UNKNOWN_CMD), ACC(START), ACC(START), ACC(START), ACC(START), ACC(NOOP),
                    REJ(NO_ERROR), ACC(START), ACC(ACK)},
    [PLC_S_HOMING] = BUSY_ROW,
    [PLC_S_SCANNING] = BUSY_ROW,
    [PLC_S_FITTING] = BUSY_ROW,
    [PLC_S_EXPORTING] = BUSY_ROW,
    /* Aborting: a second abort is harmless, anything else waits. */
    [PLC_S_ABORTING] = BUSY_ROW,
    /* In error: reset; abort stops motion again; results from before the
     * error may still be acknowledged. */
    [PLC_S_ERROR] = {REJ(UNKNOWN_CMD), REJ(IN_ERROR), REJ(IN_ERROR), REJ(IN_ERROR), REJ(IN_ERROR),
                     ACC(NOOP), ACC(RESET), REJ(IN_ERROR), ACC(ACK)},
};
#undef BUSY_ROW
#undef ACC
#undef REJ

/* Guards, checked in this order once the table accepts. */
enum {
    G_RIG = 1,        /* a stage and probe are configured (106) */
    G_HOMED = 2,      /* stage homed (107) */
    G_NO_RESULTS = 4, /* no results latched (104) */
    G_RESULTS = 8,    /* results latched (105) */
    G_CHECK = 16      /* the runner accepts the parameters (1xx of its own) */
};
static const uint8_t plc_guards[PLC_C_COUNT] = {
    [PLC_C_HOME] = G_RIG,
    [PLC_C_SCAN] = G_RIG | G_HOMED | G_CHECK,
    [PLC_C_FIT] = G_NO_RESULTS | G_CHECK,
    [PLC_C_SCAN_FIT] = G_RIG | G_HOMED | G_NO_RESULTS | G_CHECK,
    [PLC_C_EXPORT] = G_RESULTS | G_CHECK,
    [PLC_C_ACK_RESULTS] = G_RESULTS,
};

const uint8_t plc_job_phases[PLC_C_COUNT][2] = {
    [PLC_C_HOME] = {PLC_S_HOMING, 0},      [PLC_C_SCAN] = {PLC_S_SCANNING, 0},
    [PLC_C_FIT] = {PLC_S_FITTING, 0},      [PLC_C_SCAN_FIT] = {PLC_S_SCANNING, PLC_S_FITTING},
    [PLC_C_EXPORT] = {PLC_S_EXPORTING, 0},
};

#define NEXT PLC_S_COUNT
/* Columns: OK FAIL ABORTED. IDLE and ERROR run no phase: events leave them. */
const uint8_t plc_event_rules[PLC_S_COUNT][PLC_EV_COUNT] = {
    [PLC_S_IDLE] = {PLC_S_IDLE, PLC_S_IDLE, PLC_S_IDLE},
    [PLC_S_HOMING] = {NEXT, PLC_S_ERROR, PLC_S_IDLE},
    [PLC_S_SCANNING] = {NEXT, PLC_S_ERROR, PLC_S_IDLE},
    [PLC_S_FITTING] = {NEXT, PLC_S_ERROR, PLC_S_IDLE},
    [PLC_S_EXPORTING] = {NEXT, PLC_S_ERROR, PLC_S_IDLE},
    /* Abort wins over whatever the phase ended with. */
    [PLC_S_ABORTING] = {PLC_S_IDLE, PLC_S_IDLE, PLC_S_IDLE},
    [PLC_S_ERROR] = {PLC_S_ERROR, PLC_S_ERROR, PLC_S_ERROR},
};
#undef NEXT

int plc_state_busy(int s)
{
    return s >= PLC_S_HOMING && s <= PLC_S_ABORTING;
}

const char *plc_state_name(int s)
{
    static const char *const n[PLC_S_COUNT] = {"IDLE",      "HOMING",   "SCANNING", "FITTING",
                                               "EXPORTING", "ABORTING", "ERROR"};
    return s >= 0 && s < PLC_S_COUNT ? n[s] : "?";
}

const char *plc_cmd_name(int c)
{
    static const char *const n[PLC_C_COUNT] = {"NONE",  "HOME",  "SCAN",   "FIT",        "SCAN_FIT",
                                               "ABORT", "RESET", "EXPORT", "ACK_RESULTS"};
    return c >= 0 && c < PLC_C_COUNT ? n[c] : "?";
}

/* Status registers from the machine's fields. */
static void publish(plc_fsm_t *f)
{
    plc_map_t *m = f->map;
    unsigned st = 0;
    st |= f->state == PLC_S_IDLE ? PLC_ST_READY : 0;
    st |= plc_state_busy(f->state) ? PLC_ST_BUSY : 0;
    st |= f->done ? PLC_ST_DONE : 0;
    st |= f->state == PLC_S_ERROR ? PLC_ST_ERROR : 0;
    st |= f->results_valid ? PLC_ST_RESULTS : 0;
    st |= f->aborted ? PLC_ST_ABORTED : 0;
    st |= f->rejected ? PLC_ST_REJECTED : 0;
    st |= f->homed ? PLC_ST_HOMED : 0;
    st |= f->rig ? PLC_ST_RIG : 0;
    /* WATCHDOG_MS 0 is off: nothing watches, whatever the heartbeat did. */
    st |= f->wd_armed && plc_map_u16(m, PLC_R_WATCHDOG_MS) ? PLC_ST_WD_ARMED : 0;
    plc_map_put_u16(m, PLC_R_STATUS, (uint16_t)st);
    plc_map_put_u16(m, PLC_R_ACK_SEQ, f->ack_seq);
    plc_map_put_u16(m, PLC_R_DONE_SEQ, f->done_seq);
    plc_map_put_u16(m, PLC_R_STATE, (uint16_t)f->state);
    plc_map_put_u16(m, PLC_R_PROGRESS, f->progress);
    /* A fault that aborts a job (watchdog, rig gone) shows at once, while
     * ABORTING waits for the job to stop, not only once it has. */
    plc_map_put_u16(m, PLC_R_ERROR_CODE, f->error ? f->error : f->pending_error);
    plc_map_put_u16(m, PLC_R_CELL_HEARTBEAT, f->cell_hb);
    plc_map_put_u16(m, PLC_R_CMD_RESULT, f->cmd_result);
    plc_map_put_u16(m, PLC_R_JOB_CMD, (uint16_t)f->job);
}

static void clear_results(plc_map_t *m)
{
    memset(&m->reg[PLC_R_RMS], 0, (PLC_R_RESULTS_END - PLC_R_RMS) * sizeof m->reg[0]);
}

static void latch_results(plc_fsm_t *f, const plc_results_t *r)
{
    plc_map_t *m = f->map;
    plc_map_put_f32(m, PLC_R_RMS, r->rms);
    plc_map_put_f32(m, PLC_R_MAX_DEV, r->max);
    plc_map_put_f32(m, PLC_R_MIN_DEV, r->min);
    plc_map_put_f32(m, PLC_R_WITHIN_PCT, r->within_pct);
    plc_map_put_u16(m, PLC_R_VERDICT, r->verdict);
    plc_map_put_u16(m, PLC_R_RESULT_SEQ, f->job_params.seq);
    plc_map_put_u32(m, PLC_R_POINTS, r->points);
    plc_map_put_u32(m, PLC_R_CONTROL_POINTS, r->control_points);
    plc_map_put_u32(m, PLC_R_DURATION_MS, r->duration_ms);
    plc_map_put_u32(m, PLC_R_RESULT_PART, f->job_params.part);
    plc_map_put_u32(m, PLC_R_JOB_TIME, f->job_params.utc);
    plc_map_put_u16(m, PLC_R_FIT_STATUS, r->fit_status);
    f->results_valid = 1;
}

static void params_from_map(const plc_map_t *m, plc_params_t *p, uint16_t seq)
{
    p->part = plc_map_u32(m, PLC_R_PART_NUMBER);
    p->program = plc_map_u16(m, PLC_R_PROGRAM);
    p->folder = plc_map_u16(m, PLC_R_RESULTS_FOLDER);
    p->net_u = plc_map_u16(m, PLC_R_NET_U);
    p->net_v = plc_map_u16(m, PLC_R_NET_V);
    p->seq = seq;
    p->cmd = 0;
    p->tol = plc_map_f32(m, PLC_R_TOLERANCE);
    p->alpha = plc_map_f32(m, PLC_R_ALPHA);
    p->beta = plc_map_f32(m, PLC_R_BETA);
    p->x0 = plc_map_f32(m, PLC_R_SCAN_X0);
    p->y0 = plc_map_f32(m, PLC_R_SCAN_Y0);
    p->x1 = plc_map_f32(m, PLC_R_SCAN_X1);
    p->y1 = plc_map_f32(m, PLC_R_SCAN_Y1);
    p->step = plc_map_f32(m, PLC_R_SCAN_STEP);
    p->fit_tol = plc_map_f32(m, PLC_R_FIT_TOL);
    p->fit_within = plc_map_f32(m, PLC_R_FIT_WITHIN);
    p->fit_max_cp = plc_map_u32(m, PLC_R_FIT_MAX_CP);
    p->fit_refine = plc_map_u16(m, PLC_R_FIT_REFINE);
    p->fit_robust = plc_map_u16(m, PLC_R_FIT_ROBUST);
    p->fit_reparam = plc_map_u16(m, PLC_R_FIT_REPARAM);
    p->recipe = plc_map_u16(m, PLC_R_RECIPE);
    p->utc = 0;
    plc_map_get_str(m, PLC_R_PART_ID, p->part_id, sizeof p->part_id);
}

void plc_fsm_init(plc_fsm_t *f, plc_map_t *m, int rig, uint16_t watchdog_ms, plc_check_fn check,
                  void *check_ctx, uint32_t now_ms)
{
    memset(f, 0, sizeof *f);
    f->map = m;
    f->rig = rig != 0;
    f->check = check;
    f->check_ctx = check_ctx;
    f->state = PLC_S_IDLE;
    f->hb_ms = f->cell_hb_ms = now_ms;
    plc_map_put_u16(m, PLC_R_WATCHDOG_MS, watchdog_ms);
    /* Defaults a PLC may leave alone: the paper's weights, 0.05 mm. */
    plc_map_put_f32(m, PLC_R_TOLERANCE, 0.05f);
    plc_map_put_f32(m, PLC_R_ALPHA, 0.1f);
    plc_map_put_f32(m, PLC_R_BETA, 0.001f);
    plc_map_put_f32(m, PLC_R_SCAN_STEP, 1.0f);
    /* The fit loop as `cellfit fit --tol` runs it, off until FIT_TOL > 0. */
    plc_map_put_f32(m, PLC_R_FIT_WITHIN, 100.0f);
    plc_map_put_u16(m, PLC_R_FIT_REFINE, PLC_REFINE_AUTO);
    publish(f);
}

static uint16_t guard(const plc_fsm_t *f, int cmd, const plc_params_t *p)
{
    unsigned g = plc_guards[cmd];
    if ((g & G_RIG) && !f->rig)
        return PLC_E_NO_RIG;
    if ((g & G_HOMED) && !f->homed)
        return PLC_E_NOT_HOMED;
    if ((g & G_NO_RESULTS) && f->results_valid)
        return PLC_E_RESULTS_LATCHED;
    if ((g & G_RESULTS) && !f->results_valid)
        return PLC_E_NO_RESULTS;
    if ((g & G_CHECK) && f->check) {
        int c = f->check(f->check_ctx, cmd, p);
        if (c)
            return (uint16_t)c;
    }
    return 0;
}

plc_action_t plc_fsm_command(plc_fsm_t *f, int cmd, uint16_t seq, uint32_t now_ms)
{
    (void)now_ms;
    plc_action_t act = PLC_ACT_NONE;
    plc_rule_t r = {PLC_K_REJECT, PLC_E_UNKNOWN_CMD};
    plc_params_t p;
    memset(&p, 0, sizeof p); /* copied whole into the job (and compared by the tests) */
    if (cmd > PLC_C_NONE && cmd < PLC_C_COUNT)
        r = plc_cmd_rules[f->state][cmd];
    uint16_t code = r.code;
    if (r.kind != PLC_K_REJECT) {
        params_from_map(f->map, &p, seq);
        p.cmd = (uint16_t)cmd;
        code = guard(f, cmd, &p);
    }
    f->ack_seq = seq;
    f->ack_cmd = f->last_cmd = (uint16_t)cmd;
    f->cmd_result = code;
    f->rejected = code != 0;
    f->ncmd++;
    if (code) {
        plc_map_inc_u32(f->map, PLC_R_CMD_REFUSED);
        publish(f);
        return PLC_ACT_NONE; /* refused: nothing else changes */
    }
    switch (r.kind) {
    case PLC_K_START:
        f->job = cmd;
        f->job_params = p;
        f->phase = 0;
        f->state = plc_job_phases[cmd][0];
        f->done = f->aborted = 0;
        f->progress = 0;
        act = PLC_ACT_START;
        break;
    case PLC_K_ABORT:
        f->state = PLC_S_ABORTING;
        act = PLC_ACT_ABORT;
        break;
    case PLC_K_NOOP:
        /* Abort while idle or in error: nothing runs, but stop motion anyway. */
        act = PLC_ACT_ABORT;
        break;
    case PLC_K_RESET:
        f->state = PLC_S_IDLE;
        f->error = 0;
        break;
    case PLC_K_ACK:
        f->results_valid = 0;
        clear_results(f->map);
        break;
    default: break;
    }
    publish(f);
    return act;
}

/* The job ended (done, failed or aborted). */
static void job_end(plc_fsm_t *f, int state, uint16_t error, int aborted)
{
    plc_map_inc_u32(f->map, aborted                ? PLC_R_JOBS_ABORTED
                            : state == PLC_S_ERROR ? PLC_R_JOBS_FAILED
                                                   : PLC_R_JOBS_OK);
    if (error)
        plc_map_put_u16(f->map, PLC_R_LAST_ERROR, error);
    f->state = state;
    f->error = error;
    f->aborted = aborted;
    f->done = 1;
    f->done_seq = f->job_params.seq;
    f->pending_error = 0;
}

int plc_fsm_event(plc_fsm_t *f, plc_event_t ev, int code, const plc_results_t *res)
{
    if (ev >= PLC_EV_COUNT || !plc_state_busy(f->state))
        return f->state; /* no phase running: nothing to end */
    int from = f->state, to = plc_event_rules[from][ev];
    if (to == PLC_S_COUNT) { /* phase done: the job's next, or the end */
        if (from == PLC_S_HOMING)
            f->homed = 1;
        if (from == PLC_S_FITTING && res)
            latch_results(f, res);
        int next = f->phase + 1 < 2 ? plc_job_phases[f->job][f->phase + 1] : 0;
        if (next) {
            f->phase++;
            f->state = next;
        } else {
            f->progress = 100;
            job_end(f, PLC_S_IDLE, 0, 0);
        }
    } else if (to == PLC_S_ERROR) {
        /* A stage that faulted or was e-stopped has to be referenced again. */
        if (from == PLC_S_HOMING || code == PLC_E_STAGE || code == PLC_E_ESTOP)
            f->homed = 0;
        job_end(f, PLC_S_ERROR, (uint16_t)(code ? code : PLC_E_INTERNAL), 0);
    } else {
        /* Aborted: homing interrupted loses the reference. The watchdog's
         * abort ends in ERROR with its code. */
        if (from == PLC_S_HOMING || (from == PLC_S_ABORTING && f->job == PLC_C_HOME))
            f->homed = 0;
        uint16_t pe = f->pending_error;
        job_end(f, pe ? PLC_S_ERROR : PLC_S_IDLE, pe, 1);
    }
    publish(f);
    return f->state;
}

void plc_fsm_progress(plc_fsm_t *f, int pct)
{
    if (!plc_state_busy(f->state))
        return;
    f->progress = (uint16_t)(pct < 0 ? 0 : pct > 100 ? 100 : pct);
    publish(f);
}

/* Abort a running job to end in ERROR code, or go to ERROR when idle. */
static plc_action_t raise_error(plc_fsm_t *f, uint16_t code)
{
    if (plc_state_busy(f->state)) {
        f->pending_error = code;
        f->state = PLC_S_ABORTING;
        return PLC_ACT_ABORT;
    }
    if (f->state != PLC_S_ERROR) { /* an earlier error stays the one shown */
        f->state = PLC_S_ERROR;
        f->error = code;
        plc_map_put_u16(f->map, PLC_R_LAST_ERROR, code);
        return PLC_ACT_ABORT;
    }
    return PLC_ACT_NONE;
}

plc_action_t plc_fsm_fault(plc_fsm_t *f, uint16_t code, int lose_rig)
{
    if (lose_rig) {
        f->rig = 0;
        f->homed = 0;
    }
    plc_action_t act = raise_error(f, code);
    publish(f);
    return act;
}

plc_action_t plc_fsm_tick(plc_fsm_t *f, uint32_t now_ms)
{
    plc_action_t act = PLC_ACT_NONE;
    while ((uint32_t)(now_ms - f->cell_hb_ms) >= PLC_CELL_HB_MS) {
        f->cell_hb++;
        f->cell_hb_ms += PLC_CELL_HB_MS;
    }
    uint32_t wd = plc_map_u16(f->map, PLC_R_WATCHDOG_MS);
    if (f->wd_armed && wd && (uint32_t)(now_ms - f->hb_ms) > wd) {
        /* The PLC is gone: stop motion, raise 201, disarm until it
         * heartbeats again. */
        f->wd_armed = 0;
        act = raise_error(f, PLC_E_WATCHDOG);
    }
    publish(f);
    return act;
}

int plc_fsm_writable(int s, const plc_reg_t *r)
{
    if (!r || r->access != PLC_RW)
        return 0;
    return !plc_state_busy(s) || r->addr == PLC_R_COMMAND || r->addr == PLC_R_PLC_HEARTBEAT;
}

/* A command refused by the sequence rules: like a refusal of the table,
 * only ACK_SEQ, CMD_RESULT and REJECTED change (ACK_SEQ echoes what was
 * written, so the PLC's wait for its sequence ends). */
static void refuse_seq(plc_fsm_t *f, uint16_t cmd, uint16_t seq, uint16_t code)
{
    f->last_cmd = cmd; /* ack_cmd stays: the command the sequence was taken with */
    f->ack_seq = seq;
    f->cmd_result = code;
    f->rejected = 1;
    f->ncmd++;
    plc_map_inc_u32(f->map, PLC_R_CMD_REFUSED);
}

int plc_fsm_write(plc_fsm_t *f, unsigned a, unsigned n, const uint16_t *v, uint32_t now_ms,
                  plc_action_t *act)
{
    *act = PLC_ACT_NONE;
    int ex = plc_map_check_write(f->map, a, n, v);
    if (ex)
        return ex;
    /* A running job's parameters and the cell's settings stay as they were:
     * only the command (ABORT) and the heartbeat get through, alone or in
     * one block (20-22, as PLC programs write them). plc_map_check_write has
     * proved every entry is covered whole. */
    for (unsigned k = a; k < a + n;) {
        const plc_reg_t *r = plc_map_entry(k);
        if (!plc_fsm_writable(f->state, r))
            return PLC_EX_BUSY;
        k = r->addr + (unsigned)plc_type_words(r->type);
    }
    plc_map_t *m = f->map;
    uint16_t old_order = m->reg[PLC_R_WORD_ORDER];
    plc_map_store(m, a, n, v);
    if (a <= PLC_R_WORD_ORDER && PLC_R_WORD_ORDER < a + n) {
        /* Only a single-register write reaches here (its neighbours are
         * read-only): re-pack every 32-bit value in the new order. */
        m->reg[PLC_R_WORD_ORDER] = old_order;
        plc_map_set_order(m, v[PLC_R_WORD_ORDER - a]);
    }
    if (a <= PLC_R_WATCHDOG_MS && PLC_R_WATCHDOG_MS < a + n)
        f->hb_ms = now_ms; /* a new timeout counts from now, not from an old heartbeat */
    if (a <= PLC_R_PLC_HEARTBEAT && PLC_R_PLC_HEARTBEAT < a + n) {
        uint16_t hb = v[PLC_R_PLC_HEARTBEAT - a];
        if (hb != f->plc_hb) { /* armed by the first change */
            f->plc_hb = hb;
            f->hb_ms = now_ms;
            f->wd_armed = 1;
        }
    }
    if (a <= PLC_R_COMMAND && PLC_R_COMMAND_SEQ < a + n) {
        uint16_t cmd = v[PLC_R_COMMAND - a], seq = v[PLC_R_COMMAND_SEQ - a];
        if (seq == 0) /* a PLC's zeroed block or a counter not started: never a command */
            refuse_seq(f, cmd, seq, PLC_E_SEQ_ZERO);
        else if (seq != f->ack_seq)
            *act = plc_fsm_command(f, cmd, seq, now_ms);
        else if (cmd != f->ack_cmd) /* a PLC bug: would be lost if ignored */
            refuse_seq(f, cmd, seq, PLC_E_SEQ_REUSED);
        /* else the same command and sequence again: a retransmission, ignored */
    }
    publish(f);
    return 0;
}
