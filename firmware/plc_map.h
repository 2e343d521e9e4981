/* SPDX-License-Identifier: MIT */
/* plc_map.h: the cell's Modbus holding registers as one table (address,
 * name, type, access, range, units), the 32-bit packing in either word
 * order, and write validation: a write to a read-only or unmapped register,
 * or to half of a 32-bit value, is ILLEGAL DATA ADDRESS (exception 02); a
 * value outside its range is ILLEGAL DATA VALUE (03). A request is checked
 * whole before any register changes. No heap: the registers are one array.
 * docs/plc-register-map.md is the same table for PLC programmers
 * (tests/test_plc.c checks it row by row). */
#ifndef PLC_MAP_H
#define PLC_MAP_H

#include <stdint.h>

#define PLC_MAGIC 17222u /* 0x4346, "CF" */
#define PLC_MAP_VERSION                                                                            \
    3u                         /* 2: fit settings, recipe, part ID, job time, fit status, counters;
                           * 3: outbox and on-the-fly loss registers, FIT_REFINE 2 (auto) */
#define PLC_FW_VERSION 0x0100u /* major in the high byte, minor in the low */
#define PLC_TEST_F32 123.456f  /* 0x42F6E979: words 0x42F6, 0xE979 */
#define PLC_TEST_U32 0x12345678u /* 305419896: words 0x1234, 0x5678 */
#define PLC_MAX_FOLDERS 8        /* results folder choices */
#define PLC_MAX_READ 125         /* registers per read (Modbus limit) */
#define PLC_MAX_WRITE 123        /* registers per write (Modbus limit) */

/* Word order of 32-bit values (register WORD_ORDER). */
enum {
    PLC_ORDER_LO_HI = 0, /* low word at the lower address (mbpoll's default, "CDAB") */
    PLC_ORDER_HI_LO = 1  /* high word first ("ABCD", big-endian) */
};

/* Modbus exception codes the map gives. */
enum { PLC_EX_FUNCTION = 1, PLC_EX_ADDRESS = 2, PLC_EX_VALUE = 3, PLC_EX_BUSY = 6 };

/* Register types. CMD is two u16 written together: command code, sequence. */
enum { PLC_T_U16, PLC_T_BITS, PLC_T_U32, PLC_T_F32, PLC_T_STR16, PLC_T_CMD, PLC_T_STR32 };
enum { PLC_RO, PLC_RW };

/* Status bits (register STATUS). */
enum {
    PLC_ST_READY = 1u << 0,    /* IDLE: a job command is accepted */
    PLC_ST_BUSY = 1u << 1,     /* a job is running (or aborting) */
    PLC_ST_DONE = 1u << 2,     /* the job DONE_SEQ has ended (see ERROR, ABORTED) */
    PLC_ST_ERROR = 1u << 3,    /* cell in ERROR, ERROR_CODE says why */
    PLC_ST_RESULTS = 1u << 4,  /* results block valid, latched until acknowledged */
    PLC_ST_ABORTED = 1u << 5,  /* the job DONE_SEQ was aborted */
    PLC_ST_REJECTED = 1u << 6, /* the command ACK_SEQ was refused, CMD_RESULT says why */
    PLC_ST_HOMED = 1u << 7,    /* stage homed */
    PLC_ST_RIG = 1u << 8,      /* stage and probe configured */
    PLC_ST_WD_ARMED = 1u << 9  /* watchdog watching the PLC heartbeat */
};

/* X(name, address, type, access, lo, hi, units, description): the map.
 * Ranges apply to writable registers; a float range is inclusive; a
 * string's range is that of each character (0 pads the end). Version 2
 * added FIT_TOL .. RECIPE, JOB_TIME, FIT_STATUS, PART_ID and the counters
 * (JOBS_OK .. LAST_ERROR); version 3 the plant outbox (OUTBOX_*, issue
 * 18) and the last scan's on-the-fly losses (SCAN_*, issue 19), and
 * FIT_REFINE 2; every earlier address is unchanged. */
#define PLC_REGS(X)                                                                                \
    X(MAGIC, 0, U16, RO, 0, 0, "", "17222 (0x4346, \"CF\"): this is a cellfit cell")               \
    X(MAP_VERSION, 1, U16, RO, 0, 0, "", "register map version (3)")                               \
    X(TEST_F32, 2, F32, RO, 0, 0, "", "123.456 in the selected word order")                        \
    X(TEST_U32, 4, U32, RO, 0, 0, "", "305419896 (0x12345678) in the selected word order")         \
    X(FW_VERSION, 6, U16, RO, 0, 0, "", "firmware version, major in the high byte")                \
    X(WORD_ORDER, 7, U16, RW, 0, 1, "", "32-bit word order: 0 low word first, 1 high first")       \
    X(BOARD_NAME, 8, STR16, RO, 0, 0, "",                                                          \
      "board name, ASCII, 2 chars a register, high byte first")                                    \
    X(COMMAND, 20, CMD, RW, 1, 8, "", "command code (20) and sequence (21), written together")     \
    X(PLC_HEARTBEAT, 22, U16, RW, 0, 65535, "",                                                    \
      "PLC heartbeat: change it at least every WATCHDOG_MS")                                       \
    X(WATCHDOG_MS, 23, U16, RW, 0, 60000, "ms", "watchdog timeout, 0 off")                         \
    X(STATUS, 40, BITS, RO, 0, 0, "", "status bits")                                               \
    X(ACK_SEQ, 41, U16, RO, 0, 0, "", "sequence of the last command taken")                        \
    X(DONE_SEQ, 42, U16, RO, 0, 0, "", "sequence of the last job ended")                           \
    X(STATE, 43, U16, RO, 0, 0, "", "state (0 IDLE ... 6 ERROR)")                                  \
    X(PROGRESS, 44, U16, RO, 0, 0, "%", "progress of the running job")                             \
    X(ERROR_CODE, 45, U16, RO, 0, 0, "", "error of the ERROR state (2xx, 3xx), 0 none")            \
    X(CELL_HEARTBEAT, 46, U16, RO, 0, 0, "", "incremented by the cell every 100 ms")               \
    X(CMD_RESULT, 47, U16, RO, 0, 0, "", "0 accepted, else why command ACK_SEQ was refused (1xx)") \
    X(JOB_CMD, 48, U16, RO, 0, 0, "", "command of the job running or last run")                    \
    X(CLIENTS, 49, U16, RO, 0, 0, "", "Modbus clients connected")                                  \
    X(PART_NUMBER, 60, U32, RW, 0, 99999999, "", "part number (names the results folder)")         \
    X(PROGRAM, 62, U16, RW, 0, 9999, "", "program number (recorded in the report)")                \
    X(RESULTS_FOLDER, 63, U16, RW, 0, 7, "", "results folder choice (config results_dir.N)")       \
    X(TOLERANCE, 64, F32, RW, 0.0001, 100, "mm", "tolerance on the normal deviation")              \
    X(ALPHA, 66, F32, RW, 0, 1e6, "", "fit: Greville weight alpha (Eq. 7)")                        \
    X(BETA, 68, F32, RW, 0, 1e6, "", "fit: nominal weight beta (Eq. 7)")                           \
    X(NET_U, 70, U16, RW, 0, 2000, "", "control points in u, 0 the nominal's")                     \
    X(NET_V, 71, U16, RW, 0, 2000, "", "control points in v, 0 the nominal's")                     \
    X(SCAN_X0, 72, F32, RW, -10000, 10000, "mm", "scan region, first corner x")                    \
    X(SCAN_Y0, 74, F32, RW, -10000, 10000, "mm", "scan region, first corner y")                    \
    X(SCAN_X1, 76, F32, RW, -10000, 10000, "mm", "scan region, second corner x")                   \
    X(SCAN_Y1, 78, F32, RW, -10000, 10000, "mm", "scan region, second corner y")                   \
    X(SCAN_STEP, 80, F32, RW, 0.001, 1000, "mm", "scan grid step")                                 \
    X(FIT_TOL, 82, F32, RW, 0, 100, "mm",                                                          \
      "fit loop: refine until FIT_WITHIN % of the points lie within this; 0 one fit, no loop")     \
    X(FIT_WITHIN, 84, F32, RW, 0.01, 100, "%",                                                     \
      "fit loop: share of the points wanted within FIT_TOL")                                       \
    X(FIT_MAX_CP, 86, U32, RW, 0, 4000000, "", "fit loop: control points at most, 0 the board's")  \
    X(FIT_REFINE, 88, U16, RW, 0, 2, "",                                                           \
      "fit loop refinement: 0 uniform (every span halved), 1 residual (worst spans split), 2 "     \
      "auto (knot lines scored per control point added)")                                          \
    X(FIT_ROBUST, 89, U16, RW, 0, 1, "",                                                           \
      "fit: 1 robust (reweighted passes against outliers), 0 off")                                 \
    X(FIT_REPARAM, 90, U16, RW, 0, 100, "",                                                        \
      "fit: reparameterisation passes (points re-projected)")                                      \
    X(RECIPE, 91, U16, RW, 0, 15, "", "nominal choice (config nominal.N), 0 the nominal setting")  \
    X(RMS, 100, F32, RO, 0, 0, "mm", "RMS of the normal deviations")                               \
    X(MAX_DEV, 102, F32, RO, 0, 0, "mm", "largest signed deviation")                               \
    X(MIN_DEV, 104, F32, RO, 0, 0, "mm", "smallest signed deviation")                              \
    X(WITHIN_PCT, 106, F32, RO, 0, 0, "%", "points within tolerance")                              \
    X(VERDICT, 108, U16, RO, 0, 0, "", "0 none, 1 pass (all within tolerance), 2 fail")            \
    X(RESULT_SEQ, 109, U16, RO, 0, 0, "", "sequence of the job these results are from")            \
    X(POINTS, 110, U32, RO, 0, 0, "", "points measured / fitted")                                  \
    X(CONTROL_POINTS, 112, U32, RO, 0, 0, "", "control points of the fitted surface")              \
    X(DURATION_MS, 114, U32, RO, 0, 0, "ms", "job duration")                                       \
    X(RESULT_PART, 116, U32, RO, 0, 0, "", "part number of the job")                               \
    X(JOB_TIME, 118, U32, RO, 0, 0, "s", "UTC time the job was accepted, seconds since 1970")      \
    X(FIT_STATUS, 120, U16, RO, 0, 0, "",                                                          \
      "fit loop: 0 none, 1 met, 2 not met (data limit), 3 not met (max control points), 4 not "    \
      "met "                                                                                       \
      "(no progress)")                                                                             \
    X(PART_ID, 124, STR32, RW, 32, 126, "",                                                        \
      "part ID / serial number, ASCII, 2 chars a register, high byte first, 0 pads the end")       \
    X(JOBS_OK, 140, U32, RO, 0, 0, "", "jobs ended done since the cell started")                   \
    X(JOBS_FAILED, 142, U32, RO, 0, 0, "", "jobs ended in ERROR since the cell started")           \
    X(JOBS_ABORTED, 144, U32, RO, 0, 0, "", "jobs aborted (command, watchdog, fault)")             \
    X(CONN_ACCEPTED, 146, U32, RO, 0, 0, "", "Modbus connections accepted")                        \
    X(CONN_EVICTED, 148, U32, RO, 0, 0, "",                                                        \
      "connections closed to make room for a new one (the longest idle)")                          \
    X(CONN_TIMED_OUT, 150, U32, RO, 0, 0, "",                                                      \
      "connections closed idle or with a frame incomplete for 1 s")                                \
    X(REQ_REFUSED, 152, U32, RO, 0, 0, "", "requests answered with a Modbus exception")            \
    X(CMD_REFUSED, 154, U32, RO, 0, 0, "", "commands refused (CMD_RESULT not 0)")                  \
    X(LAST_ERROR, 156, U16, RO, 0, 0, "", "the last ERROR_CODE shown (kept after RESET), 0 none")  \
    X(OUTBOX_PG, 160, U32, RO, 0, 0, "", "plant outbox: jobs waiting for the PostgreSQL database") \
    X(OUTBOX_MQTT, 162, U32, RO, 0, 0, "", "plant outbox: jobs waiting for the MQTT broker")       \
    X(OUTBOX_AGE, 164, U32, RO, 0, 0, "s",                                                         \
      "plant outbox: age of the oldest waiting entry, 0 none")                                     \
    X(OUTBOX_DROPPED, 166, U32, RO, 0, 0, "",                                                      \
      "plant outbox: entries dropped because it was full (outbox_max)")                            \
    X(SCAN_TRIGGERS, 168, U32, RO, 0, 0, "", "last scan on the fly: triggers fired")               \
    X(SCAN_DROPPED, 170, U32, RO, 0, 0, "",                                                        \
      "last scan on the fly: readings the probe dropped (its buffer full)")                        \
    X(SCAN_NO_READING, 172, U32, RO, 0, 0, "", "last scan on the fly: triggers without a reading") \
    X(SCAN_NO_TRIGGER, 174, U32, RO, 0, 0, "", "last scan on the fly: readings without a trigger") \
    X(SCAN_BOTH_LOST, 176, U32, RO, 0, 0, "",                                                      \
      "last scan on the fly: trigger numbers with neither a position nor a reading")               \
    X(SCAN_DUPLICATES, 178, U32, RO, 0, 0, "",                                                     \
      "last scan on the fly: triggers or readings seen twice (dropped)")                           \
    X(SCAN_OVERRUNS, 180, U32, RO, 0, 0, "", "last scan on the fly: the probe's overrun events")

/* Addresses: PLC_R_MAGIC == 0 ... */
enum {
#define PLC_X_ADDR(n, a, t, acc, lo, hi, u, d) PLC_R_##n = a,
    PLC_REGS(PLC_X_ADDR)
#undef PLC_X_ADDR
};
/* Table indices: PLC_I_MAGIC == 0 ..., PLC_NENTRIES entries. */
enum {
#define PLC_X_IDX(n, a, t, acc, lo, hi, u, d) PLC_I_##n,
    PLC_REGS(PLC_X_IDX) PLC_NENTRIES
#undef PLC_X_IDX
};

#define PLC_NREGS 182      /* registers 0 .. PLC_NREGS - 1 may be read */
#define PLC_PART_ID_LEN 32 /* characters of PART_ID */
/* The results block, cleared by ACK_RESULTS: RMS .. FIT_STATUS. */
#define PLC_R_RESULTS_END (PLC_R_FIT_STATUS + 1)
#define PLC_R_COMMAND_SEQ (PLC_R_COMMAND + 1) /* the sequence half of COMMAND */

typedef struct plc_reg {
    const char *name;
    uint16_t addr;
    uint8_t type, access;
    double lo, hi; /* inclusive range of a writable register */
    const char *units, *desc;
} plc_reg_t;

extern const plc_reg_t plc_regs[PLC_NENTRIES];

/* Registers an entry of this type spans. */
int plc_type_words(int type);
const char *plc_type_name(int type); /* "u16", "u32", "float32", ... */

/* The entry covering address a, or NULL for an unmapped address. */
const plc_reg_t *plc_map_entry(unsigned a);

typedef struct plc_map {
    uint16_t reg[PLC_NREGS];
    int order; /* PLC_ORDER_* */
} plc_map_t;

/* Zero every register, then the identity block (board: up to 16 chars). */
void plc_map_init(plc_map_t *m, int order, const char *board);

/* 32-bit packing: w[0] is the lower address. */
void plc_pack_u32(uint32_t v, int order, uint16_t w[2]);
uint32_t plc_unpack_u32(const uint16_t w[2], int order);
uint32_t plc_f32_bits(float f);
float plc_bits_f32(uint32_t u);

/* Typed access to one entry's registers in the map's word order. */
void plc_map_put_u16(plc_map_t *m, unsigned a, uint16_t v);
void plc_map_put_u32(plc_map_t *m, unsigned a, uint32_t v);
void plc_map_put_f32(plc_map_t *m, unsigned a, float v);
uint16_t plc_map_u16(const plc_map_t *m, unsigned a);
uint32_t plc_map_u32(const plc_map_t *m, unsigned a);
float plc_map_f32(const plc_map_t *m, unsigned a);

/* A u32 counter register plus one (wraps). */
void plc_map_inc_u32(plc_map_t *m, unsigned a);

/* A string entry (PART_ID) into out (n >= 1): its characters up to the
 * first 0, at most n - 1, then a 0. */
void plc_map_get_str(const plc_map_t *m, unsigned a, char *out, unsigned n);

/* Change the word order, re-packing every 32-bit register. */
void plc_map_set_order(plc_map_t *m, int order);

/* Read n registers from a: 0, or PLC_EX_ADDRESS beyond the map, PLC_EX_VALUE
 * for n outside 1..PLC_MAX_READ. Unmapped addresses inside read 0. */
int plc_map_read(const plc_map_t *m, unsigned a, unsigned n, uint16_t *out);

/* Check a write of n registers at a (0 or a Modbus exception code), then
 * store it; plc_map_store assumes plc_map_check_write passed. */
int plc_map_check_write(const plc_map_t *m, unsigned a, unsigned n, const uint16_t *v);
void plc_map_store(plc_map_t *m, unsigned a, unsigned n, const uint16_t *v);

#endif
