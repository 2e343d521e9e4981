/* SPDX-License-Identifier: MIT */
/* plc_fsm.h: the cell's job state machine as a PLC sees it, driven through
 * the register map (plc_map.h):
 *   - one table of states x commands (accept and go where, or refuse with
 *     which 1xx code) and one of states x job events; a refused command
 *     changes nothing but ACK_SEQ and CMD_RESULT;
 *   - the command/acknowledge handshake: a command is taken when COMMAND
 *     and its sequence are written together with a sequence different from
 *     ACK_SEQ; the sequence is echoed in ACK_SEQ at once and in DONE_SEQ
 *     when the job ends; the same command and sequence again is a
 *     retransmission (ignored); sequence 0 (112) and the last sequence
 *     with another command (113) are refused;
 *   - results latched until the PLC acknowledges them (command ACK_RESULTS);
 *   - the watchdog: the PLC heartbeat register unchanged for WATCHDOG_MS
 *     aborts the job (motion) and raises error 201;
 *   - the counters of jobs and refused commands (JOBS_OK .. LAST_ERROR).
 * The job itself runs elsewhere (host/cf_plcsrv.c): plc_fsm_write says when
 * to start or abort it, plc_fsm_event takes its outcome. Time is the
 * caller's millisecond clock (wraps safely). No heap, no clock of its own. */
#ifndef PLC_FSM_H
#define PLC_FSM_H

#include "plc_err.h"
#include "plc_map.h"

typedef enum plc_state {
    PLC_S_IDLE = 0,      /* ready for a job */
    PLC_S_HOMING = 1,    /* stage referencing */
    PLC_S_SCANNING = 2,  /* measuring points */
    PLC_S_FITTING = 3,   /* fitting the surface and the deviation report */
    PLC_S_EXPORTING = 4, /* writing the results folder */
    PLC_S_ABORTING = 5,  /* abort asked, waiting for the job to stop */
    PLC_S_ERROR = 6,     /* ERROR_CODE set; RESET leaves it */
    PLC_S_COUNT
} plc_state_t;

typedef enum plc_cmd {
    PLC_C_NONE = 0,
    PLC_C_HOME = 1,
    PLC_C_SCAN = 2,
    PLC_C_FIT = 3,
    PLC_C_SCAN_FIT = 4,
    PLC_C_ABORT = 5,
    PLC_C_RESET = 6,
    PLC_C_EXPORT = 7,
    PLC_C_ACK_RESULTS = 8,
    PLC_C_COUNT
} plc_cmd_t;

/* What the job reports at the end of a phase. */
typedef enum plc_event { PLC_EV_OK, PLC_EV_FAIL, PLC_EV_ABORTED, PLC_EV_COUNT } plc_event_t;

/* What the caller must do after a write or a tick. */
typedef enum plc_action {
    PLC_ACT_NONE = 0,
    PLC_ACT_START = 1, /* start the job plc_fsm_t.job with job_params */
    PLC_ACT_ABORT = 2  /* stop the running job and any motion now */
} plc_action_t;

/* The job's parameters, copied from the registers when it is accepted:
 * writes during the job do not change it. */
typedef struct plc_params {
    uint32_t part;
    uint16_t program, folder, net_u, net_v, seq;
    uint16_t cmd; /* the job's command (plc_cmd_t) */
    float tol, alpha, beta, x0, y0, x1, y1, step;
    /* map version 2 */
    float fit_tol, fit_within;         /* mm (0: no loop), % */
    uint32_t fit_max_cp;               /* 0: the board's */
    uint16_t fit_refine, fit_robust;   /* PLC_REFINE_*, 0/1 */
    uint16_t fit_reparam, recipe;      /* passes; nominal choice */
    uint32_t utc;                      /* accepted at (UTC s), set by the server */
    char part_id[PLC_PART_ID_LEN + 1]; /* PART_ID, 0-terminated */
} plc_params_t;

/* FIT_REFINE values (cf_refine_t's numbering). */
enum { PLC_REFINE_UNIFORM = 0, PLC_REFINE_RESIDUAL = 1, PLC_REFINE_AUTO = 2 };

/* FIT_STATUS values: how the fit loop ended. */
enum {
    PLC_FIT_NONE = 0,               /* no loop (FIT_TOL 0) or no fit */
    PLC_FIT_MET = 1,                /* FIT_WITHIN % of the points within FIT_TOL */
    PLC_FIT_NOT_MET_DATA = 2,       /* not met: the points cannot support a finer net */
    PLC_FIT_NOT_MET_MAX_CP = 3,     /* not met: FIT_MAX_CP (or the board's) reached */
    PLC_FIT_NOT_MET_NO_PROGRESS = 4 /* not met: refining stopped improving */
};

typedef struct plc_results {
    float rms, max, min, within_pct; /* mm, mm, mm, % */
    uint16_t verdict;                /* 1 pass, 2 fail */
    uint32_t points, control_points, duration_ms;
    uint16_t fit_status; /* PLC_FIT_* */
} plc_results_t;

enum { PLC_VERDICT_NONE = 0, PLC_VERDICT_PASS = 1, PLC_VERDICT_FAIL = 2 };

/* The job runner's view of a command about to be accepted: 0 or a 1xx code
 * (parameters it cannot use, files not configured). May be NULL. */
typedef int (*plc_check_fn)(void *ctx, int cmd, const plc_params_t *p);

typedef struct plc_fsm {
    plc_map_t *map;
    plc_check_fn check;
    void *check_ctx;
    int state, job, phase; /* job: the plc_cmd_t running or last run */
    int rig, homed, results_valid, done, aborted, rejected;
    uint16_t ack_seq, done_seq, cmd_result, error, progress, pending_error;
    uint16_t ack_cmd;  /* the command code ack_seq was taken with */
    uint16_t last_cmd; /* the command code of the last decision */
    uint32_t ncmd;     /* commands decided (taken or refused), for the server's log */
    plc_params_t job_params;
    /* watchdog and heartbeats */
    int wd_armed;
    uint16_t plc_hb, cell_hb;
    uint32_t hb_ms, cell_hb_ms;
} plc_fsm_t;

#define PLC_CELL_HB_MS 100u /* CELL_HEARTBEAT period */

/* Bind to a map (already plc_map_init'ed), set defaults in the parameter
 * block, publish the status. rig: a stage and probe are configured. */
void plc_fsm_init(plc_fsm_t *f, plc_map_t *m, int rig, uint16_t watchdog_ms, plc_check_fn check,
                  void *check_ctx, uint32_t now_ms);

/* A Modbus write of n registers at a: 0 and the registers stored (and a
 * command taken, the heartbeat noted), or a Modbus exception code and
 * nothing changed. While a job runs (or aborts) only COMMAND (whose rule
 * refuses all but ABORT with 102) and PLC_HEARTBEAT may be written, alone
 * or in one request (20-22); a write touching any other register is
 * PLC_EX_BUSY (06). *act says what the caller must do. */
int plc_fsm_write(plc_fsm_t *f, unsigned a, unsigned n, const uint16_t *v, uint32_t now_ms,
                  plc_action_t *act);

/* The command rule alone (plc_fsm_write calls it for a new sequence). */
plc_action_t plc_fsm_command(plc_fsm_t *f, int cmd, uint16_t seq, uint32_t now_ms);

/* The end of the current phase: OK (res: the fit's results when the phase
 * was FITTING, else NULL), FAIL with a 3xx code, or ABORTED. Returns the new
 * state; a state among HOMING..EXPORTING means: run that phase next. */
int plc_fsm_event(plc_fsm_t *f, plc_event_t ev, int code, const plc_results_t *res);

/* A fault of the cell outside the handshake (the rig's process ended):
 * as the watchdog, a running job is aborted and ends in ERROR code, an idle
 * cell goes to ERROR code (an earlier error stays the one shown). With
 * lose_rig the rig is gone for good: RIG clears, HOME and SCAN are 106. */
plc_action_t plc_fsm_fault(plc_fsm_t *f, uint16_t code, int lose_rig);

/* Progress of the running job, 0..100. */
void plc_fsm_progress(plc_fsm_t *f, int pct);

/* Call often (every few tens of ms): advances CELL_HEARTBEAT and checks the
 * watchdog. PLC_ACT_ABORT when it tripped with a job running. */
plc_action_t plc_fsm_tick(plc_fsm_t *f, uint32_t now_ms);

/* 1 when the entry r may be written in state s (while busy: COMMAND and
 * PLC_HEARTBEAT only; otherwise every read/write register). */
int plc_fsm_writable(int s, const plc_reg_t *r);

/* 1 for HOMING, SCANNING, FITTING, EXPORTING, ABORTING. */
int plc_state_busy(int state);
const char *plc_state_name(int state);
const char *plc_cmd_name(int cmd);

/* The transition tables, for the docs and tests: what cmd does in state s
 * before the guards (*next: the state it goes to, or *code: 1xx refusal),
 * and where event ev leads from a phase (PLC_S_COUNT: the job's next phase,
 * or IDLE after its last). */
typedef enum plc_rule_kind {
    PLC_K_REJECT, /* refuse with code */
    PLC_K_START,  /* start the job */
    PLC_K_ABORT,  /* stop the job: ABORTING */
    PLC_K_NOOP,   /* accepted, nothing to do (abort when idle) */
    PLC_K_RESET,  /* leave ERROR */
    PLC_K_ACK     /* clear the latched results */
} plc_rule_kind_t;

typedef struct plc_rule {
    uint8_t kind;  /* plc_rule_kind_t */
    uint16_t code; /* PLC_K_REJECT: the 1xx code */
} plc_rule_t;

extern const plc_rule_t plc_cmd_rules[PLC_S_COUNT][PLC_C_COUNT];
extern const uint8_t plc_event_rules[PLC_S_COUNT][PLC_EV_COUNT];
extern const uint8_t plc_job_phases[PLC_C_COUNT][2]; /* up to two phases, 0 ends */

#endif
