/* SPDX-License-Identifier: MIT */
/* hal_rig.h: the rig's device drivers on top of hal transports, each
 * implementing a rig.h table: the Modbus motion stage (hal_stage_), the
 * laser displacement probe over its ASCII protocol on any byte stream
 * (tty now, serial later) or over Modbus input registers (hal_probe_), and
 * hal_rig_open, which opens both from their URIs for host code. Register
 * maps and messages: hal_regmap.h, docs/rig-devices.md. */
#ifndef HAL_RIG_H
#define HAL_RIG_H

#include "hal.h"
#include "rig.h"

typedef struct hal_stage {
    hal_t *h;
    double lo[2], hi[2]; /* soft limits read at init, mm */
    double speed;        /* mm/s, read at init (for the wait before polling) */
    int move_timeout_ms; /* 0: 3 x the expected move time + 2 s */
    int home_timeout_ms; /* default 60000 */
    int poll_ms;         /* status polling interval (default 5) */
    double tol_mm;       /* position read back must match the target within (0.002) */
    double at[2];        /* position read with "in position" at the end of the last move */
    int at_valid;        /* 1 until the next call: st_position answers at[] */
    char err[320];       /* detail of the last failure */
    /* Appended: asked at every status poll of a move or homing (and between
     * slices of the wait before polling); non-zero stops the stage and the
     * call returns RIG_EABORTED. The caller's own line sends the stop, so a
     * job's thread never shares its transport. NULL: never. */
    int (*should_stop)(void *ctx);
    void *stop_ctx;
} hal_stage_t;

/* Bind a stage to an open Modbus transport (its unit id is the URI's) and
 * read its limits and speed. */
int hal_stage_init(hal_stage_t *s, hal_t *h);
extern const rig_stage_ops_t hal_stage_ops; /* ctx: hal_stage_t * */

/* On the fly (issue 19): start a move to (x, y) at the stage's speed and
 * return once the stage took it (limits, homed and the result checked as
 * move_to does); its end shows in the status (BUSY clears, FAULT sets).
 * And set the travel speed of both axes (1..65535 mm/s, rounded). */
int hal_stage_move_start(hal_stage_t *s, double x, double y);
int hal_stage_set_speed(hal_stage_t *s, double mm_s);

typedef struct hal_probe {
    hal_t *h;
    int modbus;    /* 1: input registers; 0: ASCII protocol */
    double lo, hi; /* measuring range, mm */
    char err[320];
    /* Appended: streaming (Modbus FIFO or ASCII lines). */
    uint16_t overrun; /* the FIFO's overrun register at the last read */
    int streaming;    /* 1 from start until the stream has ended (ASCII: its end line read) */
    char sbuf[512];   /* ASCII: bytes of lines not yet complete */
    size_t sn;
} hal_probe_t;

/* Bind a probe to an open transport: Modbus (rtu:, tcp:) uses the input
 * registers, a byte stream (tty:, serial:) the ASCII protocol. Reads the
 * measuring range. */
int hal_probe_init(hal_probe_t *p, hal_t *h);
extern const rig_probe_ops_t hal_probe_ascii_ops; /* ctx: hal_probe_t * */
extern const rig_probe_ops_t hal_probe_modbus_ops;

/* Streaming (docs/rig-devices.md): arm one reading per trigger every
 * period_us (numbers restart at 0), stop, and take what has come: up to
 * max entries, each a reading (r) and the position latched at its trigger
 * (pos: enc in um; RIG_TRIG_F_OVERRUN on the first event after the probe
 * dropped entries, *dropped adds how many). For scan_otf, which pairs them
 * by number. Modbus: the FIFO (hal_regmap.h's PRB_H_*, PRB_FIFO_*), popped
 * PRB_FIFO_MAX_READ a request while entries remain; stop ends the stream at
 * once (drain it with reads until none come). ASCII: "TP" and "MS", then
 * the "SQ" lines that have arrived (a read waits at most 5 ms for more);
 * stop sends "MQ", and p->streaming stays 1 until its end line is read (its
 * count of dropped readings added to *dropped). */
int hal_probe_stream_start(hal_probe_t *p, uint32_t period_us);
int hal_probe_stream_stop(hal_probe_t *p);
int hal_probe_stream_read(hal_probe_t *p, rig_reading_t *r, rig_trig_event_t *pos, size_t max,
                          size_t *n, unsigned long *dropped);

/* Parse one ASCII reply line (without CR LF) to a "M0" request: RIG_OK and
 * *mm, RIG_ENOSURF for "M0,FFFFFFF", RIG_EEXCEPTION for "ER,M0,nn",
 * RIG_EPROTO for anything else. */
int hal_probe_parse_m0(const char *line, double *mm);

/* Detail text of the last failure of a driver (ctx of its rig table). */
const char *hal_stage_error(const void *ctx);
const char *hal_probe_error(const void *ctx);

typedef struct hal_rig {
    rig_stage_t stage; /* ops NULL when no stage URI was given */
    rig_probe_t probe; /* ops NULL when no probe URI was given */
    hal_stage_t st;
    hal_probe_t pr;
} hal_rig_t;

/* Open the stage and/or the probe (a NULL URI leaves that one out) with
 * the same options; *out is freed by hal_rig_close. RIG_EARG, RIG_EOPEN,
 * RIG_EUNSUPPORTED, or the error of the first register read; msg says
 * which device and why. */
int hal_rig_open(const char *stage_uri, const char *probe_uri, const hal_opts_t *o, hal_rig_t **out,
                 char *msg, size_t msglen);
void hal_rig_close(hal_rig_t *r);

#endif
