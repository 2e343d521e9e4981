/* SPDX-License-Identifier: MIT */
/* hal_regmap.h: the register maps of the Modbus motion stage and the Modbus
 * displacement probe, and the ASCII probe's messages, as tabled in
 * docs/rig-devices.md (the table a person wiring a real device works
 * from). The drivers (hal_stage.c, hal_probe.c) and the simulator (sim/)
 * both follow it; the tests also read the registers with mbpoll and
 * pymodbus by raw address, so a shared mistake here would show.
 *
 * 32-bit values occupy two registers, HIGH word first (the lower address
 * holds bits 31..16: "big-endian word order", ABCD). Lengths are signed
 * micrometres. */
#ifndef HAL_REGMAP_H
#define HAL_REGMAP_H

/* Stage: holding registers (functions 03, 06, 16). */
enum {
    STG_TARGET_X = 0, /* 0-1 int32 um, read/write */
    STG_TARGET_Y = 2, /* 2-3 int32 um, read/write */
    STG_COMMAND = 4,  /* write STG_CMD_*; reads 0 once the command was taken */
    STG_STATUS = 5,   /* RIG_ST_* bits (rig.h), read only */
    STG_POS_X = 6,    /* 6-7 int32 um, actual position, read only */
    STG_POS_Y = 8,    /* 8-9 */
    STG_LIM_XLO = 10, /* 10-17: soft limits x lo, x hi, y lo, y hi, int32 um, read only */
    STG_LIM_XHI = 12,
    STG_LIM_YLO = 14,
    STG_LIM_YHI = 16,
    STG_SPEED = 18,  /* mm/s, 1..65535, read/write */
    STG_FAULT = 19,  /* STG_FC_*: why FAULT / LIMIT is set, read only */
    STG_MOVES = 20,  /* commands accepted since power-up, mod 65536, read only */
    STG_RESULT = 21, /* STG_RES_*: outcome of the last command written, read only */
    STG_NREGS = 22,
    STG_SIM_ESTOP = 100, /* simulator only: 1 presses the E-stop, 0 releases it */
    STG_SIM_FAULT = 101  /* simulator only: writing 1 latches a drive fault now */
};

enum { STG_CMD_MOVE = 1, STG_CMD_HOME = 2, STG_CMD_STOP = 3, STG_CMD_RESET = 4 };

enum { STG_FC_NONE = 0, STG_FC_DRIVE = 1, STG_FC_ESTOP = 2, STG_FC_LIMIT = 3 };

enum {
    STG_RES_OK = 0,
    STG_RES_NOTHOMED = 1, /* move refused: not homed */
    STG_RES_LIMIT = 2,    /* move refused: target outside the soft limits */
    STG_RES_FAULT = 3,    /* refused: a fault is latched (reset first) */
    STG_RES_ESTOP = 4,    /* refused: E-stop active */
    STG_RES_BADCMD = 5    /* unknown command */
};

/* Probe: input registers (function 04). */
enum {
    PRB_DIST = 0,     /* 0-1 int32 um; PRB_NOSURF_RAW when out of range */
    PRB_STATUS = 2,   /* PRB_ST_* bits */
    PRB_SEQ = 3,      /* measurements taken, mod 65536 */
    PRB_RANGE_LO = 4, /* 4-5 int32 um, measuring range */
    PRB_RANGE_HI = 6, /* 6-7 */
    PRB_NREGS = 8
};

enum { PRB_ST_VALID = 1u << 0, PRB_ST_NOSURF = 1u << 1, PRB_ST_ERROR = 1u << 2 };

/* Probe streaming (on the fly, docs/rig-devices.md): one reading per
 * trigger input into a FIFO, each with its trigger number and the encoder
 * positions latched at the trigger. Holding registers (functions 03, 06,
 * 16) arm it; input registers from PRB_FIFO_COUNT read it, and a read of
 * PRB_FIFO_COUNT with 2 + 8 k registers pops up to k entries at once. */
enum {
    PRB_H_PERIOD = 0, /* 0-1 uint32 us between triggers: > 0 arms (numbers from 0, FIFO
                       * emptied), 0 stops */
    PRB_H_NREGS = 2
};
enum {
    PRB_FIFO_COUNT = 8,   /* entries waiting, before this read's pops (saturates at 65535) */
    PRB_FIFO_OVERRUN = 9, /* entries dropped on a full FIFO since arming, mod 65536 */
    PRB_FIFO_DATA = 10,   /* PRB_FIFO_ENTRY registers an entry, oldest first: */
    PRB_FE_SEQ = 0,       /*   trigger number since arming, mod 65536 */
    PRB_FE_STATUS = 1,    /*   PRB_ST_* */
    PRB_FE_DIST = 2,      /*   2-3 int32 um (PRB_NOSURF_RAW out of range) */
    PRB_FE_X = 4,         /*   4-5 int32 um, x latched at the trigger */
    PRB_FE_Y = 6,         /*   6-7 int32 um, y latched at the trigger */
    PRB_FIFO_ENTRY = 8,
    PRB_FIFO_MAX_READ = 14 /* entries in one read (2 + 8 x 14 = 114 registers) */
};
#define PRB_MIN_PERIOD_US 20u
#define PRB_MAX_PERIOD_US 1000000u

#define PRB_NOSURF_RAW 0x7FFFFFFF

/* Default unit ids: the stage and the probe on one bus or server. */
#define HAL_STAGE_UNIT 1
#define HAL_PROBE_UNIT 2

#endif
