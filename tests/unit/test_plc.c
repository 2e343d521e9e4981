/* SPDX-License-Identifier: MIT */
/* test_plc.c: the PLC interface without a network: the register table
 * (no overlaps, every row in docs/plc-register-map.md), 32-bit packing in
 * both word orders against hand-made words, write validation, every command
 * in every state against a matrix written out here (accepted, or refused
 * with its code and nothing else changed), the sequence handshake, the
 * results latch and the watchdog on a logical clock; writes refused while
 * a job runs, faults raised outside the handshake, rig errors to PLC codes. */
#include "cf_plcdoc.h"
#include "cf_plcrun.h"
#include "cf_test.h"
#include "plc_fsm.h"
#include "scan.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the table ---- */

static void test_table_layout(void **state)
{
    (void)state;
    unsigned end = 0;
    for (int i = 0; i < PLC_NENTRIES; i++) {
        const plc_reg_t *r = &plc_regs[i];
        unsigned w = (unsigned)plc_type_words(r->type);
        if (i > 0)
            assert_true(r->addr >= end); /* increasing, no overlap */
        end = r->addr + w;
        assert_true(end <= PLC_NREGS);
        if (r->type == PLC_T_U32 || r->type == PLC_T_F32)
            assert_int_equal(r->addr % 2, 0); /* 32-bit values on even addresses */
        if (r->access == PLC_RW)
            assert_true(r->lo <= r->hi);
        for (unsigned a = r->addr; a < end; a++)
            assert_ptr_equal(plc_map_entry(a), r);
        for (int j = 0; j < i; j++)
            assert_string_not_equal(plc_regs[j].name, r->name);
    }
    assert_int_equal(end, PLC_NREGS); /* the scan's losses end the map */
    /* Map version 2 kept every version 1 address and added these; version 3
     * kept every version 2 address and added the outbox and scan blocks. */
    assert_int_equal(PLC_MAP_VERSION, 3);
    assert_int_equal(PLC_R_RESULT_PART, 116);
    assert_int_equal(PLC_R_FIT_TOL, 82);
    assert_int_equal(PLC_R_RECIPE, 91);
    assert_int_equal(PLC_R_JOB_TIME, 118);
    assert_int_equal(PLC_R_FIT_STATUS, 120);
    assert_int_equal(PLC_R_PART_ID, 124);
    assert_int_equal(plc_type_words(PLC_T_STR32), PLC_PART_ID_LEN / 2);
    assert_int_equal(PLC_R_JOBS_OK, 140);
    assert_int_equal(PLC_R_LAST_ERROR, 156);
    assert_int_equal(PLC_R_OUTBOX_PG, 160);
    assert_int_equal(PLC_R_OUTBOX_DROPPED, 166);
    assert_int_equal(PLC_R_SCAN_TRIGGERS, 168);
    assert_int_equal(PLC_R_SCAN_OVERRUNS, 180);
    assert_null(plc_map_entry(157)); /* reserved: reads 0 */
    /* The numbers the docs and PLC programs use. */
    assert_int_equal(PLC_R_MAGIC, 0);
    assert_int_equal(PLC_R_COMMAND, 20);
    assert_int_equal(PLC_R_COMMAND_SEQ, 21);
    assert_int_equal(PLC_R_PLC_HEARTBEAT, 22);
    assert_int_equal(PLC_R_STATUS, 40);
    assert_int_equal(PLC_R_PART_NUMBER, 60);
    assert_int_equal(PLC_R_RMS, 100);
    assert_null(plc_map_entry(16));
    assert_null(plc_map_entry(30));
    assert_null(plc_map_entry(PLC_NREGS));
    assert_int_equal(PLC_MAGIC, 0x4346);
    assert_int_equal(PLC_MAGIC, ('C' << 8) | 'F');
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    static char buf[1 << 17];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    return buf;
}

/* Every generated row is a line of the docs, verbatim: the doc cannot drift
 * from the code. */
static void test_docs_match(void **state)
{
    (void)state;
    const char *dir = getenv("CF_SRCDIR");
    char path[4096], row[512], line[520];
    snprintf(path, sizeof path, "%s/docs/plc-register-map.md", dir ? dir : ".");
    const char *doc = slurp(path);
    if (!doc)
        fail_msg("cannot read %s (run from the source tree or set CF_SRCDIR)", path);
    for (int i = 0; i < PLC_NENTRIES; i++) {
        cf_plcdoc_reg_row(i, row, sizeof row);
        snprintf(line, sizeof line, "\n%s\n", row);
        if (!strstr(doc, line))
            fail_msg("docs/plc-register-map.md lacks the row\n%s", row);
    }
    for (int s = 0; s < PLC_S_COUNT; s++) {
        cf_plcdoc_state_row(s, row, sizeof row);
        snprintf(line, sizeof line, "\n%s\n", row);
        if (!strstr(doc, line))
            fail_msg("docs/plc-register-map.md lacks the state row\n%s", row);
    }
    static const int codes[] = {101, 102, 103, 104, 105, 106, 107, 108, 109, 110,
                                111, 112, 113, 114, 201, 202, 203, 301, 302, 303,
                                304, 305, 306, 307, 308, 309, 310, 311};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        snprintf(line, sizeof line, "\n| %d | ", codes[i]);
        if (!strstr(doc, line))
            fail_msg("docs/plc-register-map.md: no row for error %d", codes[i]);
        assert_string_not_equal(plc_strerror(codes[i]), "unknown error code");
    }
    assert_string_equal(plc_strerror(999), "unknown error code");
}

/* ---- packing ---- */

static void test_packing(void **state)
{
    (void)state;
    uint16_t w[2];
    plc_pack_u32(0x12345678u, PLC_ORDER_LO_HI, w);
    assert_int_equal(w[0], 0x5678);
    assert_int_equal(w[1], 0x1234);
    plc_pack_u32(0x12345678u, PLC_ORDER_HI_LO, w);
    assert_int_equal(w[0], 0x1234);
    assert_int_equal(w[1], 0x5678);
    /* 123.456f: sign 0, exponent 133 (2^6), mantissa 0x76E979. */
    assert_int_equal(plc_f32_bits(123.456f), 0x42F6E979u);
    assert_int_equal(plc_f32_bits(-2.0f), 0xC0000000u);
    uint32_t x = 0x9E3779B9u;
    for (int k = 0; k < 1000; k++) {
        x ^= x << 13, x ^= x >> 17, x ^= x << 5;
        for (int o = 0; o < 2; o++) {
            plc_pack_u32(x, o, w);
            assert_int_equal(plc_unpack_u32(w, o), x);
            assert_int_equal(w[o == PLC_ORDER_LO_HI ? 0 : 1], x & 0xFFFF);
        }
    }
    /* The identity block in both orders, and re-packing on a change. */
    plc_map_t m;
    plc_map_init(&m, PLC_ORDER_LO_HI, "sim-board-name-longer-than-16");
    assert_int_equal(m.reg[0], 17222);
    assert_int_equal(m.reg[2], 0xE979);
    assert_int_equal(m.reg[3], 0x42F6);
    assert_int_equal(m.reg[4], 0x5678);
    assert_int_equal(m.reg[5], 0x1234);
    assert_int_equal(m.reg[8], ('s' << 8) | 'i');
    assert_int_equal(m.reg[15], ('-' << 8) | 'l'); /* chars 14, 15; cut at 16 */
    plc_map_put_f32(&m, PLC_R_TOLERANCE, 0.25f);
    plc_map_set_order(&m, PLC_ORDER_HI_LO);
    assert_int_equal(m.reg[2], 0x42F6);
    assert_int_equal(m.reg[3], 0xE979);
    assert_int_equal(m.reg[PLC_R_WORD_ORDER], 1);
    assert_true(plc_map_f32(&m, PLC_R_TEST_F32) == 123.456f);
    assert_int_equal(plc_map_u32(&m, PLC_R_TEST_U32), 0x12345678u);
    assert_true(plc_map_f32(&m, PLC_R_TOLERANCE) == 0.25f);
}

/* ---- write validation ---- */

static void test_write_validation(void **state)
{
    (void)state;
    plc_map_t m, before;
    plc_map_init(&m, PLC_ORDER_HI_LO, "sim");
    uint16_t v[PLC_MAX_WRITE] = {0};
    for (int i = 0; i < PLC_NENTRIES; i++) {
        const plc_reg_t *r = &plc_regs[i];
        unsigned w = (unsigned)plc_type_words(r->type);
        v[0] = v[1] = 1;
        if (r->access == PLC_RO) {
            assert_int_equal(plc_map_check_write(&m, r->addr, w, v), PLC_EX_ADDRESS);
            continue;
        }
        if (w == 2) { /* half of a pair, either half */
            assert_int_equal(plc_map_check_write(&m, r->addr, 1, v), PLC_EX_ADDRESS);
            assert_int_equal(plc_map_check_write(&m, r->addr + 1, 1, v), PLC_EX_ADDRESS);
        }
        /* Just outside the range is refused, the limits themselves taken. */
        if (r->type == PLC_T_F32) {
            float lo = (float)r->lo, hi = (float)r->hi;
            plc_pack_u32(plc_f32_bits(nextafterf(hi, INFINITY)), m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), PLC_EX_VALUE);
            plc_pack_u32(plc_f32_bits(nextafterf(lo, -INFINITY)), m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), PLC_EX_VALUE);
            plc_pack_u32(plc_f32_bits(NAN), m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), PLC_EX_VALUE);
            plc_pack_u32(plc_f32_bits(hi), m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), 0);
            plc_pack_u32(plc_f32_bits(lo), m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), 0);
        } else if (r->type == PLC_T_U32) {
            plc_pack_u32((uint32_t)r->hi + 1, m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), PLC_EX_VALUE);
            plc_pack_u32((uint32_t)r->hi, m.order, v);
            assert_int_equal(plc_map_check_write(&m, r->addr, 2, v), 0);
        } else if (r->type == PLC_T_STR32) {
            /* Printable ASCII, 0s only at the end, one bad byte refuses it all. */
            uint16_t str[16] = {('S' << 8) | 'N', ('-' << 8) | '4', ('2' << 8) | ' ', '~' << 8};
            assert_int_equal(plc_map_check_write(&m, r->addr, 16, str), 0);
            str[3] = ('~' << 8) | 0x7F;
            assert_int_equal(plc_map_check_write(&m, r->addr, 16, str), PLC_EX_VALUE);
            str[3] = 0x1F << 8;
            assert_int_equal(plc_map_check_write(&m, r->addr, 16, str), PLC_EX_VALUE);
            str[3] = 'x'; /* a character after the terminating 0 */
            assert_int_equal(plc_map_check_write(&m, r->addr, 16, str), PLC_EX_VALUE);
            str[3] = 0;
            str[15] = 'x';
            assert_int_equal(plc_map_check_write(&m, r->addr, 16, str), PLC_EX_VALUE);
            assert_int_equal(plc_map_check_write(&m, r->addr, 15, str), PLC_EX_ADDRESS);
        } else { /* U16 and the command code */
            v[1] = 7;
            if (r->hi < 65535) {
                v[0] = (uint16_t)(r->hi + 1);
                assert_int_equal(plc_map_check_write(&m, r->addr, w, v), PLC_EX_VALUE);
            }
            if (r->lo > 0) {
                v[0] = (uint16_t)(r->lo - 1);
                assert_int_equal(plc_map_check_write(&m, r->addr, w, v), PLC_EX_VALUE);
            }
            v[0] = (uint16_t)r->hi;
            assert_int_equal(plc_map_check_write(&m, r->addr, w, v), 0);
        }
    }
    /* Gaps, beyond the end, sizes outside Modbus's limits. */
    assert_int_equal(plc_map_check_write(&m, 16, 1, v), PLC_EX_ADDRESS);
    assert_int_equal(plc_map_check_write(&m, PLC_NREGS, 1, v), PLC_EX_ADDRESS);
    assert_int_equal(plc_map_check_write(&m, 60, 0, v), PLC_EX_VALUE);
    assert_int_equal(plc_map_check_write(&m, 60, PLC_MAX_WRITE + 1, v), PLC_EX_VALUE);
    uint16_t rd[PLC_MAX_READ];
    assert_int_equal(plc_map_read(&m, 0, PLC_MAX_READ, rd), 0);
    assert_int_equal(plc_map_read(&m, PLC_NREGS - PLC_MAX_READ, PLC_MAX_READ, rd), 0);
    assert_int_equal(plc_map_read(&m, PLC_NREGS - 1, 2, rd), PLC_EX_ADDRESS);
    assert_int_equal(plc_map_read(&m, 0, PLC_MAX_READ + 1, rd), PLC_EX_VALUE);
    assert_int_equal(plc_map_read(&m, 0, 0, rd), PLC_EX_VALUE);
    assert_int_equal(plc_map_read(&m, 16, 4, rd), 0); /* gaps read as 0 */
    assert_int_equal(rd[0], 0);
    /* A write of the whole parameter block with one bad value stores
     * nothing; without it, everything. */
    plc_fsm_t f;
    plc_fsm_init(&f, &m, 0, 0, NULL, NULL, 0);
    uint16_t blk[22];
    memcpy(blk, &m.reg[60], sizeof blk);
    plc_pack_u32(plc_f32_bits(2.5f), m.order, blk + 4); /* tolerance */
    blk[10] = 2001;                                     /* NET_U out of range */
    before = m;
    plc_action_t act;
    assert_int_equal(plc_fsm_write(&f, 60, 22, blk, 0, &act), PLC_EX_VALUE);
    assert_memory_equal(&m, &before, sizeof m);
    blk[10] = 40;
    assert_int_equal(plc_fsm_write(&f, 60, 22, blk, 0, &act), 0);
    assert_true(plc_map_f32(&m, PLC_R_TOLERANCE) == 2.5f);
    assert_int_equal(m.reg[PLC_R_NET_U], 40);
    assert_int_equal(act, PLC_ACT_NONE);
    /* The word order register, alone, re-packs the map. */
    v[0] = PLC_ORDER_LO_HI;
    assert_int_equal(plc_fsm_write(&f, PLC_R_WORD_ORDER, 1, v, 0, &act), 0);
    assert_int_equal(m.order, PLC_ORDER_LO_HI);
    assert_int_equal(m.reg[2], 0xE979);
    assert_true(plc_map_f32(&m, PLC_R_TOLERANCE) == 2.5f);
}

/* ---- the state machine ---- */

static plc_map_t M;
static plc_fsm_t F;
static uint16_t SEQ;
static int check_code; /* what the fake runner check answers */

static int fake_check(void *ctx, int cmd, const plc_params_t *p)
{
    (void)ctx, (void)cmd, (void)p;
    return check_code;
}

/* Write command + sequence in one request, as a PLC does. */
static plc_action_t cmd(int code)
{
    uint16_t v[2] = {(uint16_t)code, ++SEQ};
    plc_action_t act = PLC_ACT_NONE;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(F.ack_seq, SEQ);
    assert_int_equal(M.reg[PLC_R_ACK_SEQ], SEQ);
    return act;
}

static const plc_results_t RES = {
    0.5f, 1.25f, -0.75f, 87.5f, PLC_VERDICT_FAIL, 1000, 192, 1234, PLC_FIT_NOT_MET_MAX_CP};

static void fresh(int rig)
{
    plc_map_init(&M, PLC_ORDER_LO_HI, "sim");
    plc_fsm_init(&F, &M, rig, 0, fake_check, NULL, 0);
    SEQ = 0;
    check_code = 0;
}

/* The situations a command can meet; each sets up the machine. */
enum {
    X_IDLE_NORIG,
    X_IDLE_RIG,
    X_IDLE_HOMED,
    X_IDLE_RESULTS,
    X_HOMING,
    X_SCANNING,
    X_FITTING,
    X_EXPORTING,
    X_ABORTING,
    X_ERROR,
    X_COUNT
};

static void setup_situation(int x)
{
    fresh(x != X_IDLE_NORIG);
    switch (x) {
    case X_IDLE_HOMED:
        cmd(PLC_C_HOME);
        plc_fsm_event(&F, PLC_EV_OK, 0, NULL);
        break;
    case X_IDLE_RESULTS:
        cmd(PLC_C_FIT);
        plc_fsm_event(&F, PLC_EV_OK, 0, &RES);
        break;
    case X_HOMING: cmd(PLC_C_HOME); break;
    case X_SCANNING:
        cmd(PLC_C_HOME);
        plc_fsm_event(&F, PLC_EV_OK, 0, NULL);
        cmd(PLC_C_SCAN);
        break;
    case X_FITTING: cmd(PLC_C_FIT); break;
    case X_EXPORTING:
        cmd(PLC_C_FIT);
        plc_fsm_event(&F, PLC_EV_OK, 0, &RES);
        cmd(PLC_C_EXPORT);
        break;
    case X_ABORTING:
        cmd(PLC_C_FIT);
        cmd(PLC_C_ABORT);
        break;
    case X_ERROR:
        cmd(PLC_C_FIT);
        plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_FIT, NULL);
        break;
    default: break;
    }
}

/* Expected outcome of each command in each situation, written out by hand
 * from the issue and the docs: a code > 0 is a refusal, A_<state> an
 * acceptance that leads to that state. */
#define A(s) (-1 - PLC_S_##s)
static const int expect[X_COUNT][PLC_C_COUNT] = {
    /*              NONE  HOME        SCAN          FIT         SCAN_FIT      ABORT        RESET     EXPORT        ACK */
    [X_IDLE_NORIG] = {101, 106, 106, A(FITTING), 106, A(IDLE), 109, 105, 105},
    [X_IDLE_RIG] = {101, A(HOMING), 107, A(FITTING), 107, A(IDLE), 109, 105, 105},
    [X_IDLE_HOMED] = {101, A(HOMING), A(SCANNING), A(FITTING), A(SCANNING), A(IDLE), 109, 105, 105},
    [X_IDLE_RESULTS] = {101, A(HOMING), 107, 104, 107, A(IDLE), 109, A(EXPORTING), A(IDLE)},
    [X_HOMING] = {101, 102, 102, 102, 102, A(ABORTING), 102, 102, 102},
    [X_SCANNING] = {101, 102, 102, 102, 102, A(ABORTING), 102, 102, 102},
    [X_FITTING] = {101, 102, 102, 102, 102, A(ABORTING), 102, 102, 102},
    [X_EXPORTING] = {101, 102, 102, 102, 102, A(ABORTING), 102, 102, 102},
    [X_ABORTING] = {101, 102, 102, 102, 102, A(ABORTING), 102, 102, 102},
    /* In error, results from before it may still be acknowledged: none here. */
    [X_ERROR] = {101, 103, 103, 103, 103, A(ERROR), A(IDLE), 103, 105},
};
static const int situation_state[X_COUNT] = {
    PLC_S_IDLE,     PLC_S_IDLE,    PLC_S_IDLE,      PLC_S_IDLE,     PLC_S_HOMING,
    PLC_S_SCANNING, PLC_S_FITTING, PLC_S_EXPORTING, PLC_S_ABORTING, PLC_S_ERROR};

static void test_every_command_every_state(void **state)
{
    (void)state;
    for (int x = 0; x < X_COUNT; x++)
        for (int c = 0; c < PLC_C_COUNT; c++) {
            setup_situation(x);
            assert_int_equal(F.state, situation_state[x]);
            plc_fsm_t f0 = F;
            plc_map_t m0 = M;
            plc_action_t act = c ? cmd(c) : plc_fsm_command(&F, c, ++SEQ, 0);
            int want = expect[x][c];
            if (want > 0) {
                /* Refused: the code, and nothing else changed. */
                if (F.cmd_result != want)
                    fail_msg("situation %d, command %s: got %d, want refusal %d", x,
                             plc_cmd_name(c), F.cmd_result, want);
                assert_int_equal(act, PLC_ACT_NONE);
                assert_int_equal(M.reg[PLC_R_CMD_RESULT], want);
                assert_true(M.reg[PLC_R_STATUS] & PLC_ST_REJECTED);
                f0.ack_seq = F.ack_seq, f0.cmd_result = F.cmd_result, f0.rejected = 1;
                f0.ack_cmd = f0.last_cmd = (uint16_t)c;
                f0.ncmd++;
                assert_memory_equal(&F, &f0, sizeof F);
                /* ... but the refusal counter */
                assert_int_equal(plc_map_u32(&M, PLC_R_CMD_REFUSED),
                                 plc_map_u32(&m0, PLC_R_CMD_REFUSED) + 1);
                memcpy(&m0.reg[PLC_R_CMD_REFUSED], &M.reg[PLC_R_CMD_REFUSED], 4);
                m0.reg[PLC_R_ACK_SEQ] = M.reg[PLC_R_ACK_SEQ];
                m0.reg[PLC_R_CMD_RESULT] = M.reg[PLC_R_CMD_RESULT];
                m0.reg[PLC_R_STATUS] |= PLC_ST_REJECTED;
                m0.reg[PLC_R_COMMAND] = M.reg[PLC_R_COMMAND];
                m0.reg[PLC_R_COMMAND_SEQ] = M.reg[PLC_R_COMMAND_SEQ];
                assert_memory_equal(&M, &m0, sizeof M);
            } else {
                if (F.cmd_result != 0 || F.state != -1 - want)
                    fail_msg("situation %d, command %s: result %d state %s, want accepted -> %s", x,
                             plc_cmd_name(c), F.cmd_result, plc_state_name(F.state),
                             plc_state_name(-1 - want));
                assert_false(M.reg[PLC_R_STATUS] & PLC_ST_REJECTED);
                assert_int_equal(M.reg[PLC_R_STATE], F.state);
                int starts = c == PLC_C_HOME || c == PLC_C_SCAN || c == PLC_C_FIT ||
                             c == PLC_C_SCAN_FIT || c == PLC_C_EXPORT;
                assert_int_equal(act, starts             ? PLC_ACT_START
                                      : c == PLC_C_ABORT ? PLC_ACT_ABORT
                                                         : PLC_ACT_NONE);
            }
        }
    /* The runner's own refusal (parameters) goes through unchanged. */
    fresh(0);
    check_code = PLC_E_TOO_BIG;
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_NONE);
    assert_int_equal(F.cmd_result, PLC_E_TOO_BIG);
    assert_int_equal(F.state, PLC_S_IDLE);
}

static void test_handshake(void **state)
{
    (void)state;
    fresh(1);
    /* Sequence 0 (a zeroed block, a counter not started) is refused. */
    uint16_t v[2] = {PLC_C_HOME, 0};
    plc_action_t act;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_NONE);
    assert_int_equal(F.state, PLC_S_IDLE);
    assert_int_equal(M.reg[PLC_R_CMD_RESULT], PLC_E_SEQ_ZERO);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_REJECTED);
    /* HOME, then the same request again (a PLC retransmission): one job. */
    assert_int_equal(cmd(PLC_C_HOME), PLC_ACT_START);
    v[1] = SEQ;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_NONE);
    uint16_t home = SEQ;
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_BUSY);
    assert_false(M.reg[PLC_R_STATUS] & (PLC_ST_READY | PLC_ST_DONE));
    plc_fsm_progress(&F, 40);
    assert_int_equal(M.reg[PLC_R_PROGRESS], 40);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_OK, 0, NULL), PLC_S_IDLE);
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], home);
    assert_int_equal(M.reg[PLC_R_STATUS] & (PLC_ST_READY | PLC_ST_DONE | PLC_ST_HOMED),
                     PLC_ST_READY | PLC_ST_DONE | PLC_ST_HOMED);
    /* SCAN_FIT: two phases, one DONE_SEQ at the end, results latched. */
    assert_int_equal(cmd(PLC_C_SCAN_FIT), PLC_ACT_START);
    uint16_t job = SEQ;
    assert_int_equal(F.state, PLC_S_SCANNING);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_DONE);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_OK, 0, NULL), PLC_S_FITTING);
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], home); /* not yet */
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_NONE);
    assert_int_equal(F.cmd_result, PLC_E_BUSY);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_OK, 0, &RES), PLC_S_IDLE);
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], job);
    assert_int_equal(M.reg[PLC_R_PROGRESS], 100);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_RESULTS);
    assert_true(plc_map_f32(&M, PLC_R_RMS) == 0.5f);
    assert_true(plc_map_f32(&M, PLC_R_MAX_DEV) == 1.25f);
    assert_true(plc_map_f32(&M, PLC_R_MIN_DEV) == -0.75f);
    assert_true(plc_map_f32(&M, PLC_R_WITHIN_PCT) == 87.5f);
    assert_int_equal(M.reg[PLC_R_VERDICT], PLC_VERDICT_FAIL);
    assert_int_equal(M.reg[PLC_R_RESULT_SEQ], job);
    assert_int_equal(plc_map_u32(&M, PLC_R_POINTS), 1000);
    assert_int_equal(plc_map_u32(&M, PLC_R_CONTROL_POINTS), 192);
    assert_int_equal(plc_map_u32(&M, PLC_R_DURATION_MS), 1234);
    /* Latched: writes elsewhere and refused commands leave them. */
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_NONE);
    assert_int_equal(F.cmd_result, PLC_E_RESULTS_LATCHED);
    assert_true(plc_map_f32(&M, PLC_R_RMS) == 0.5f);
    cmd(PLC_C_ACK_RESULTS);
    assert_int_equal(F.cmd_result, 0);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_RESULTS);
    for (unsigned a = PLC_R_RMS; a < PLC_R_RESULTS_END; a++)
        assert_int_equal(M.reg[a], 0);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_OK), 2); /* the counters are not results */
    /* A failed job: DONE and ERROR, code kept until reset. */
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_START);
    job = SEQ;
    plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_POINTS, NULL);
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], job);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_POINTS);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_ERROR);
    assert_false(M.reg[PLC_R_STATUS] & (PLC_ST_READY | PLC_ST_RESULTS));
    cmd(PLC_C_RESET);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], 0);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_READY);
    /* Abort mid-job: ready again, ABORTED, no results; homing aborted
     * loses the reference. */
    cmd(PLC_C_FIT);
    job = SEQ;
    assert_int_equal(cmd(PLC_C_ABORT), PLC_ACT_ABORT);
    assert_int_equal(F.state, PLC_S_ABORTING);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL), PLC_S_IDLE);
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], job);
    assert_int_equal(M.reg[PLC_R_STATUS] &
                         (PLC_ST_READY | PLC_ST_ABORTED | PLC_ST_RESULTS | PLC_ST_ERROR),
                     PLC_ST_READY | PLC_ST_ABORTED);
    cmd(PLC_C_FIT); /* a fit finishing while the abort is under way: abort wins */
    cmd(PLC_C_ABORT);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_OK, 0, &RES), PLC_S_IDLE);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_RESULTS);
    cmd(PLC_C_HOME);
    cmd(PLC_C_ABORT);
    plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_HOMED);
    /* Events with no job running change nothing. */
    plc_fsm_t f0 = F;
    assert_int_equal(plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_FIT, NULL), PLC_S_IDLE);
    assert_memory_equal(&F, &f0, sizeof F);
}

/* While a job runs only COMMAND and the heartbeat may be written. */
static void test_busy_writes(void **state)
{
    (void)state;
    fresh(1);
    plc_action_t act;
    uint16_t tol[2], hb = 7, wd = 500, order = 1, part[2] = {4711, 0};
    plc_pack_u32(plc_f32_bits(0.5f), PLC_ORDER_LO_HI, tol);
    cmd(PLC_C_HOME);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_BUSY);
    plc_map_t m0 = M;
    assert_int_equal(plc_fsm_write(&F, PLC_R_TOLERANCE, 2, tol, 0, &act), PLC_EX_BUSY);
    assert_int_equal(plc_fsm_write(&F, PLC_R_PART_NUMBER, 2, part, 0, &act), PLC_EX_BUSY);
    assert_int_equal(plc_fsm_write(&F, PLC_R_WATCHDOG_MS, 1, &wd, 0, &act), PLC_EX_BUSY);
    assert_int_equal(plc_fsm_write(&F, PLC_R_WORD_ORDER, 1, &order, 0, &act), PLC_EX_BUSY);
    /* command, sequence, heartbeat and watchdog: WATCHDOG_MS is not
     * writable while busy, so the whole request is refused */
    uint16_t four[4] = {PLC_C_ABORT, (uint16_t)(SEQ + 1), 9, 100};
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 4, four, 0, &act), PLC_EX_BUSY);
    assert_memory_equal(&M, &m0, sizeof M);
    /* the parameter block with PART_ID: refused */
    uint16_t id[16] = {'A' << 8};
    assert_int_equal(plc_fsm_write(&F, PLC_R_PART_ID, 16, id, 0, &act), PLC_EX_BUSY);
    assert_memory_equal(&M, &m0, sizeof M);
    /* Read-only and range errors keep their own exceptions. */
    assert_int_equal(plc_fsm_write(&F, PLC_R_MAGIC, 1, &hb, 0, &act), PLC_EX_ADDRESS);
    assert_int_equal(plc_fsm_write(&F, PLC_R_PLC_HEARTBEAT, 1, &hb, 0, &act), 0);
    /* The heartbeat changed, but WATCHDOG_MS is 0 (off): WD_ARMED stays
     * clear, as nothing can trip (issue 15). */
    assert_true(F.wd_armed);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_WD_ARMED);
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_NONE); /* the 1xx refusal, not an exception */
    assert_int_equal(F.cmd_result, PLC_E_BUSY);
    /* COMMAND + sequence + heartbeat in one request, as PLC programs write
     * them: each register is writable while busy, so the ABORT is taken. */
    uint16_t three[3] = {PLC_C_ABORT, ++SEQ, 10};
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 3, three, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_ABORT);
    assert_int_equal(F.state, PLC_S_ABORTING);
    assert_int_equal(M.reg[PLC_R_ACK_SEQ], SEQ);
    assert_int_equal(M.reg[PLC_R_PLC_HEARTBEAT], 10);
    assert_int_equal(plc_fsm_write(&F, PLC_R_TOLERANCE, 2, tol, 0, &act), PLC_EX_BUSY);
    plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL);
    assert_int_equal(plc_fsm_write(&F, PLC_R_TOLERANCE, 2, tol, 0, &act), 0); /* idle again */
    assert_true(plc_map_f32(&M, PLC_R_TOLERANCE) == 0.5f);
}

/* The sequence rules a PLC programmer is given (docs: the handshake). */
static void test_sequence_rules(void **state)
{
    (void)state;
    fresh(1);
    plc_action_t act;
    uint16_t v[2] = {PLC_C_RESET, 0};
    /* 0: refused 112 whatever the command, again and again. */
    for (int k = 0; k < 2; k++) {
        assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
        assert_int_equal(M.reg[PLC_R_CMD_RESULT], PLC_E_SEQ_ZERO);
        assert_int_equal(M.reg[PLC_R_ACK_SEQ], 0);
        assert_int_equal(plc_map_u32(&M, PLC_R_CMD_REFUSED), (uint32_t)k + 1);
    }
    /* HOME 1 taken; HOME 1 again is a retransmission (nothing at all). */
    assert_int_equal(cmd(PLC_C_HOME), PLC_ACT_START);
    plc_fsm_t f0 = F;
    plc_map_t m0 = M;
    v[0] = PLC_C_HOME, v[1] = SEQ;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_NONE);
    assert_memory_equal(&F, &f0, sizeof F);
    assert_memory_equal(&M, &m0, sizeof M);
    /* ABORT with sequence 1: refused 113, the job runs on. */
    v[0] = PLC_C_ABORT;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_NONE);
    assert_int_equal(F.state, PLC_S_HOMING);
    assert_int_equal(M.reg[PLC_R_CMD_RESULT], PLC_E_SEQ_REUSED);
    assert_int_equal(M.reg[PLC_R_ACK_SEQ], SEQ);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_REJECTED);
    assert_int_equal(F.last_cmd, PLC_C_ABORT);
    assert_int_equal(F.ack_cmd, PLC_C_HOME);
    /* The next sequence works as ever. */
    assert_int_equal(cmd(PLC_C_ABORT), PLC_ACT_ABORT);
    assert_int_equal(M.reg[PLC_R_CMD_RESULT], 0);
    /* Wrapping from 65535 to 1 (0 skipped) is a new sequence each time. */
    SEQ = 65534;
    plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL);
    cmd(PLC_C_ACK_RESULTS); /* 65535: refused 105, but taken as a command */
    assert_int_equal(M.reg[PLC_R_CMD_RESULT], PLC_E_NO_RESULTS);
    v[0] = PLC_C_HOME, v[1] = 1;
    assert_int_equal(plc_fsm_write(&F, PLC_R_COMMAND, 2, v, 0, &act), 0);
    assert_int_equal(act, PLC_ACT_START);
}

/* Version 2: the job's new parameters, JOB_TIME and FIT_STATUS, the
 * counters. */
static void test_map_v2(void **state)
{
    (void)state;
    fresh(1);
    plc_action_t act;
    /* Defaults: no loop, 100 %, auto refinement (the shell's, map version 3). */
    assert_true(plc_map_f32(&M, PLC_R_FIT_TOL) == 0.0f);
    assert_true(plc_map_f32(&M, PLC_R_FIT_WITHIN) == 100.0f);
    assert_int_equal(M.reg[PLC_R_FIT_REFINE], PLC_REFINE_AUTO);
    /* The block 82-91 and PART_ID in two requests; a FIT copies them. */
    uint16_t blk[10];
    plc_pack_u32(plc_f32_bits(0.01f), M.order, blk);
    plc_pack_u32(plc_f32_bits(99.5f), M.order, blk + 2);
    plc_pack_u32(2500, M.order, blk + 4);
    blk[6] = PLC_REFINE_UNIFORM, blk[7] = 1, blk[8] = 2, blk[9] = 3;
    assert_int_equal(plc_fsm_write(&F, PLC_R_FIT_TOL, 10, blk, 0, &act), 0);
    uint16_t id[16] = {('S' << 8) | 'N', ('-' << 8) | '7', '7' << 8};
    assert_int_equal(plc_fsm_write(&F, PLC_R_PART_ID, 16, id, 0, &act), 0);
    assert_int_equal(cmd(PLC_C_FIT), PLC_ACT_START);
    const plc_params_t *p = &F.job_params;
    assert_true(p->fit_tol == 0.01f && p->fit_within == 99.5f);
    assert_int_equal(p->fit_max_cp, 2500);
    assert_int_equal(p->fit_refine, PLC_REFINE_UNIFORM);
    assert_int_equal(p->fit_robust, 1);
    assert_int_equal(p->fit_reparam, 2);
    assert_int_equal(p->recipe, 3);
    assert_string_equal(p->part_id, "SN-77");
    /* The server stamps the job; the results carry it and the fit status. */
    F.job_params.utc = 1796000000u;
    plc_fsm_event(&F, PLC_EV_OK, 0, &RES);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOB_TIME), 1796000000u);
    assert_int_equal(M.reg[PLC_R_FIT_STATUS], PLC_FIT_NOT_MET_MAX_CP);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_OK), 1);
    cmd(PLC_C_ACK_RESULTS);
    for (unsigned a = PLC_R_RMS; a < PLC_R_RESULTS_END; a++)
        assert_int_equal(M.reg[a], 0);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_OK), 1); /* counters stay */
    char out[40];
    plc_map_get_str(&M, PLC_R_PART_ID, out, sizeof out);
    assert_string_equal(out, "SN-77");
    plc_map_get_str(&M, PLC_R_PART_ID, out, 4);
    assert_string_equal(out, "SN-");
    /* Failed, aborted, refused: each its counter; LAST_ERROR survives RESET. */
    cmd(PLC_C_FIT);
    plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_FIT, NULL);
    cmd(PLC_C_RESET);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], 0);
    assert_int_equal(M.reg[PLC_R_LAST_ERROR], PLC_E_FIT);
    cmd(PLC_C_FIT);
    cmd(PLC_C_ABORT);
    plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL);
    cmd(PLC_C_RESET); /* 109 */
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_OK), 1);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_FAILED), 1);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_ABORTED), 1);
    assert_int_equal(plc_map_u32(&M, PLC_R_CMD_REFUSED), 1);
    /* Counters re-pack with the word order like every 32-bit value. */
    uint16_t one = PLC_ORDER_HI_LO;
    assert_int_equal(plc_fsm_write(&F, PLC_R_WORD_ORDER, 1, &one, 0, &act), 0);
    assert_int_equal(M.reg[PLC_R_JOBS_OK], 0);
    assert_int_equal(M.reg[PLC_R_JOBS_OK + 1], 1);
    assert_int_equal(plc_map_u32(&M, PLC_R_JOBS_FAILED), 1);
}

/* A fault outside the handshake (the rig's process ended). */
static void test_fault(void **state)
{
    (void)state;
    fresh(1);
    cmd(PLC_C_HOME);
    plc_fsm_event(&F, PLC_EV_OK, 0, NULL);
    cmd(PLC_C_SCAN);
    uint16_t job = SEQ;
    assert_int_equal(plc_fsm_fault(&F, PLC_E_RIG_GONE, 1), PLC_ACT_ABORT);
    assert_int_equal(F.state, PLC_S_ABORTING);
    assert_false(M.reg[PLC_R_STATUS] & (PLC_ST_RIG | PLC_ST_HOMED));
    /* Shown at once, while the job still stops (issue 15: not only when
     * the scan's driver gives up seconds later). */
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_RIG_GONE);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_ERROR);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_RIG_LINK, NULL), PLC_S_ERROR);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_RIG_GONE); /* the fault, not the scan's */
    assert_int_equal(M.reg[PLC_R_DONE_SEQ], job);
    cmd(PLC_C_RESET);
    assert_int_equal(F.state, PLC_S_IDLE);
    cmd(PLC_C_HOME);
    assert_int_equal(F.cmd_result, PLC_E_NO_RIG); /* the rig is gone for good */
    /* Idle: straight to ERROR; an earlier error stays shown. */
    fresh(1);
    assert_int_equal(plc_fsm_fault(&F, PLC_E_RIG_GONE, 0), PLC_ACT_ABORT);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_RIG_GONE);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_RIG);
    assert_int_equal(plc_fsm_fault(&F, PLC_E_WATCHDOG, 0), PLC_ACT_NONE);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_RIG_GONE);
    /* A stage fault or e-stop during a scan loses the reference. */
    for (int k = 0; k < 3; k++) {
        static const uint16_t codes[3] = {PLC_E_STAGE, PLC_E_ESTOP, PLC_E_PROBE};
        fresh(1);
        cmd(PLC_C_HOME);
        plc_fsm_event(&F, PLC_EV_OK, 0, NULL);
        cmd(PLC_C_SCAN);
        plc_fsm_event(&F, PLC_EV_FAIL, codes[k], NULL);
        assert_int_equal(M.reg[PLC_R_ERROR_CODE], codes[k]);
        assert_int_equal(!!(M.reg[PLC_R_STATUS] & PLC_ST_HOMED), k == 2);
    }
}

/* The rig's errors as a PLC sees them (the table in the docs). */
static void test_rig_codes(void **state)
{
    (void)state;
    static const struct {
        int rc, where, want;
    } t[] = {
        {RIG_OK, SCAN_AT_NONE, 0},
        {RIG_EABORTED, SCAN_AT_STOP, CF_PLC_ABORTED},
        {RIG_EABORTED, SCAN_AT_STAGE, CF_PLC_ABORTED},
        {RIG_ETIMEOUT, SCAN_AT_PROBE, PLC_E_RIG_LINK},
        {RIG_EDISCONNECT, SCAN_AT_STAGE, PLC_E_RIG_LINK},
        {RIG_ECRC, SCAN_AT_STAGE, PLC_E_RIG_LINK},
        {RIG_EESTOP, SCAN_AT_STAGE, PLC_E_ESTOP},
        {RIG_EFAULT, SCAN_AT_STAGE, PLC_E_STAGE},
        {RIG_ELIMIT, SCAN_AT_STAGE, PLC_E_STAGE},
        {RIG_ENOTHOMED, SCAN_AT_STAGE, PLC_E_STAGE},
        {RIG_EEXCEPTION, SCAN_AT_PROBE, PLC_E_PROBE},
        {RIG_EPROTO, SCAN_AT_PROBE, PLC_E_PROBE},
        {RIG_EFULL, SCAN_AT_JOURNAL, PLC_E_RIG},
        {RIG_EIO, SCAN_AT_JOURNAL, PLC_E_RIG},
    };
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++)
        assert_int_equal(cf_plcrun_rig_code(t[i].rc, t[i].where), t[i].want);
}

static void heartbeat(uint16_t hb, uint32_t t)
{
    plc_action_t act;
    assert_int_equal(plc_fsm_write(&F, PLC_R_PLC_HEARTBEAT, 1, &hb, t, &act), 0);
}

static void test_watchdog(void **state)
{
    (void)state;
    fresh(1);
    uint16_t wd = 300;
    plc_action_t act;
    assert_int_equal(plc_fsm_write(&F, PLC_R_WATCHDOG_MS, 1, &wd, 0, &act), 0);
    /* Not armed before the PLC's first heartbeat: no trip, however long. */
    assert_int_equal(plc_fsm_tick(&F, 100000), PLC_ACT_NONE);
    assert_int_equal(F.state, PLC_S_IDLE);
    heartbeat(1, 100000);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_WD_ARMED);
    assert_int_equal(plc_fsm_tick(&F, 100300), PLC_ACT_NONE); /* exactly T: still fine */
    heartbeat(1, 100250);                                     /* unchanged: does not count */
    heartbeat(2, 100290);
    assert_int_equal(plc_fsm_tick(&F, 100590), PLC_ACT_NONE);
    cmd(PLC_C_FIT);
    assert_int_equal(plc_fsm_tick(&F, 100591), PLC_ACT_ABORT); /* trip mid-job */
    assert_int_equal(F.state, PLC_S_ABORTING);
    assert_false(M.reg[PLC_R_STATUS] & PLC_ST_WD_ARMED);
    assert_int_equal(plc_fsm_event(&F, PLC_EV_ABORTED, 0, NULL), PLC_S_ERROR);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_WATCHDOG);
    assert_true(M.reg[PLC_R_STATUS] & PLC_ST_ABORTED);
    assert_int_equal(plc_fsm_tick(&F, 200000), PLC_ACT_NONE); /* disarmed */
    /* A timeout set long after the last heartbeat counts from the write. */
    cmd(PLC_C_RESET);
    wd = 0;
    plc_fsm_write(&F, PLC_R_WATCHDOG_MS, 1, &wd, 200000, &act);
    heartbeat(9, 200000);
    assert_int_equal(plc_fsm_tick(&F, 300000), PLC_ACT_NONE); /* off */
    wd = 300;
    plc_fsm_write(&F, PLC_R_WATCHDOG_MS, 1, &wd, 300000, &act);
    assert_int_equal(plc_fsm_tick(&F, 300300), PLC_ACT_NONE);
    assert_int_equal(plc_fsm_tick(&F, 300301), PLC_ACT_ABORT);
    assert_int_equal(F.state, PLC_S_ERROR);
    cmd(PLC_C_RESET);
    assert_int_equal(F.state, PLC_S_IDLE);
    /* Idle trip, across the clock's wrap. */
    heartbeat(3, 0xFFFFFF00u);
    assert_int_equal(plc_fsm_tick(&F, 0x2Cu), PLC_ACT_NONE); /* 300 ms later */
    assert_int_equal(plc_fsm_tick(&F, 0x2Du), PLC_ACT_ABORT);
    assert_int_equal(F.state, PLC_S_ERROR);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_WATCHDOG);
    /* An earlier error stays the one shown. */
    cmd(PLC_C_RESET);
    cmd(PLC_C_FIT);
    plc_fsm_event(&F, PLC_EV_FAIL, PLC_E_NOMINAL, NULL);
    heartbeat(4, 1000);
    assert_int_equal(plc_fsm_tick(&F, 2000), PLC_ACT_NONE);
    assert_int_equal(M.reg[PLC_R_ERROR_CODE], PLC_E_NOMINAL);
    /* WATCHDOG_MS 0: off. */
    cmd(PLC_C_RESET);
    wd = 0;
    plc_fsm_write(&F, PLC_R_WATCHDOG_MS, 1, &wd, 0, &act);
    heartbeat(5, 3000);
    assert_int_equal(plc_fsm_tick(&F, 900000), PLC_ACT_NONE);
    assert_int_equal(F.state, PLC_S_IDLE);
}

static void test_cell_heartbeat(void **state)
{
    (void)state;
    fresh(0);
    uint16_t h0 = M.reg[PLC_R_CELL_HEARTBEAT];
    plc_fsm_tick(&F, 99);
    assert_int_equal(M.reg[PLC_R_CELL_HEARTBEAT], h0);
    plc_fsm_tick(&F, 100);
    assert_int_equal(M.reg[PLC_R_CELL_HEARTBEAT], (uint16_t)(h0 + 1));
    plc_fsm_tick(&F, 1050);
    assert_int_equal(M.reg[PLC_R_CELL_HEARTBEAT], (uint16_t)(h0 + 10));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_layout),
        cmocka_unit_test(test_docs_match),
        cmocka_unit_test(test_packing),
        cmocka_unit_test(test_write_validation),
        cmocka_unit_test(test_every_command_every_state),
        cmocka_unit_test(test_handshake),
        cmocka_unit_test(test_watchdog),
        cmocka_unit_test(test_cell_heartbeat),
        cmocka_unit_test(test_busy_writes),
        cmocka_unit_test(test_sequence_rules),
        cmocka_unit_test(test_map_v2),
        cmocka_unit_test(test_fault),
        cmocka_unit_test(test_rig_codes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
