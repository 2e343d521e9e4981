/* SPDX-License-Identifier: MIT */
/* plc_map.c: the register table, 32-bit packing and write validation. */
#include "plc_map.h"
#include <string.h>

const plc_reg_t plc_regs[PLC_NENTRIES] = {
#define PLC_X_ROW(n, a, t, acc, l, h, u, d) {#n, a, PLC_T_##t, PLC_##acc, l, h, u, d},
    PLC_REGS(PLC_X_ROW)
#undef PLC_X_ROW
};

int plc_type_words(int type)
{
    switch (type) {
    case PLC_T_U32:
    case PLC_T_F32:
    case PLC_T_CMD: return 2;
    case PLC_T_STR16: return 8;
    case PLC_T_STR32: return 16;
    default: return 1;
    }
}

const char *plc_type_name(int type)
{
    switch (type) {
    case PLC_T_U16: return "u16";
    case PLC_T_BITS: return "bits16";
    case PLC_T_U32: return "u32";
    case PLC_T_F32: return "float32";
    case PLC_T_STR16: return "char[16]";
    case PLC_T_CMD: return "u16 + u16";
    case PLC_T_STR32: return "char[32]";
    default: return "?";
    }
}

const plc_reg_t *plc_map_entry(unsigned a)
{
    for (int i = 0; i < PLC_NENTRIES; i++) {
        const plc_reg_t *r = &plc_regs[i];
        if (a >= r->addr && a < r->addr + (unsigned)plc_type_words(r->type))
            return r;
    }
    return NULL;
}

void plc_pack_u32(uint32_t v, int order, uint16_t w[2])
{
    uint16_t lo = (uint16_t)(v & 0xFFFFu), hi = (uint16_t)(v >> 16);
    w[0] = order == PLC_ORDER_HI_LO ? hi : lo;
    w[1] = order == PLC_ORDER_HI_LO ? lo : hi;
}

uint32_t plc_unpack_u32(const uint16_t w[2], int order)
{
    uint32_t a = w[0], b = w[1];
    return order == PLC_ORDER_HI_LO ? (a << 16) | b : (b << 16) | a;
}

/* IEEE 754 single bits by memcpy: no aliasing tricks, no libmodbus helpers
 * (3.1.6's float functions are broken, HARDWARE-TESTING.md). */
uint32_t plc_f32_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

float plc_bits_f32(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

void plc_map_put_u16(plc_map_t *m, unsigned a, uint16_t v)
{
    if (a < PLC_NREGS)
        m->reg[a] = v;
}

void plc_map_put_u32(plc_map_t *m, unsigned a, uint32_t v)
{
    if (a + 1 < PLC_NREGS)
        plc_pack_u32(v, m->order, &m->reg[a]);
}

void plc_map_put_f32(plc_map_t *m, unsigned a, float v)
{
    plc_map_put_u32(m, a, plc_f32_bits(v));
}

uint16_t plc_map_u16(const plc_map_t *m, unsigned a)
{
    return a < PLC_NREGS ? m->reg[a] : 0;
}

uint32_t plc_map_u32(const plc_map_t *m, unsigned a)
{
    return a + 1 < PLC_NREGS ? plc_unpack_u32(&m->reg[a], m->order) : 0;
}

float plc_map_f32(const plc_map_t *m, unsigned a)
{
    return plc_bits_f32(plc_map_u32(m, a));
}

void plc_map_inc_u32(plc_map_t *m, unsigned a)
{
    plc_map_put_u32(m, a, plc_map_u32(m, a) + 1u);
}

void plc_map_get_str(const plc_map_t *m, unsigned a, char *out, unsigned n)
{
    const plc_reg_t *r = plc_map_entry(a);
    unsigned len = r ? 2u * (unsigned)plc_type_words(r->type) : 0, k = 0;
    for (; k + 1 < n && k < len; k++) {
        uint16_t w = m->reg[r->addr + k / 2];
        char c = (char)(k % 2 ? w & 0xFFu : w >> 8);
        if (!c)
            break;
        out[k] = c;
    }
    if (n)
        out[k] = 0;
}

void plc_map_init(plc_map_t *m, int order, const char *board)
{
    memset(m, 0, sizeof *m);
    m->order = order == PLC_ORDER_HI_LO ? PLC_ORDER_HI_LO : PLC_ORDER_LO_HI;
    m->reg[PLC_R_MAGIC] = PLC_MAGIC;
    m->reg[PLC_R_MAP_VERSION] = PLC_MAP_VERSION;
    plc_map_put_f32(m, PLC_R_TEST_F32, PLC_TEST_F32);
    plc_map_put_u32(m, PLC_R_TEST_U32, PLC_TEST_U32);
    m->reg[PLC_R_FW_VERSION] = PLC_FW_VERSION;
    m->reg[PLC_R_WORD_ORDER] = (uint16_t)m->order;
    /* Two characters a register, the first in the high byte (as most PLCs
     * lay out STRING data in holding registers). */
    for (int i = 0; board && i < 16 && board[i]; i++) {
        unsigned a = PLC_R_BOARD_NAME + (unsigned)i / 2;
        uint16_t c = (uint16_t)(unsigned char)board[i];
        m->reg[a] = (uint16_t)(m->reg[a] | (i % 2 ? c : (uint16_t)(c << 8)));
    }
}

void plc_map_set_order(plc_map_t *m, int order)
{
    order = order == PLC_ORDER_HI_LO ? PLC_ORDER_HI_LO : PLC_ORDER_LO_HI;
    if (order != m->order)
        for (int i = 0; i < PLC_NENTRIES; i++)
            if (plc_regs[i].type == PLC_T_U32 || plc_regs[i].type == PLC_T_F32) {
                uint16_t *w = &m->reg[plc_regs[i].addr], t = w[0];
                w[0] = w[1];
                w[1] = t;
            }
    m->order = order;
    m->reg[PLC_R_WORD_ORDER] = (uint16_t)order;
}

int plc_map_read(const plc_map_t *m, unsigned a, unsigned n, uint16_t *out)
{
    if (n < 1 || n > PLC_MAX_READ)
        return PLC_EX_VALUE;
    if (a >= PLC_NREGS || a + n > PLC_NREGS)
        return PLC_EX_ADDRESS;
    memcpy(out, &m->reg[a], n * sizeof *out);
    return 0;
}

/* One entry's new value against its range; w points at its first word. */
static int check_value(const plc_map_t *m, const plc_reg_t *r, const uint16_t *w)
{
    double x;
    switch (r->type) {
    case PLC_T_U32: x = (double)plc_unpack_u32(w, m->order); break;
    case PLC_T_F32: {
        float f = plc_bits_f32(plc_unpack_u32(w, m->order));
        /* Compared in float: a PLC writing 0.0001f means the limit 0.0001. */
        if (!(f >= (float)r->lo && f <= (float)r->hi)) /* NaN fails too */
            return PLC_EX_VALUE;
        return 0;
    }
    case PLC_T_STR32: {
        /* Printable ASCII, then only 0s: what a report and a file name can hold. */
        int end = 0;
        for (int k = 0; k < 2 * plc_type_words(r->type); k++) {
            unsigned c = k % 2 ? w[k / 2] & 0xFFu : (unsigned)w[k / 2] >> 8;
            if (c == 0)
                end = 1;
            else if (end || c < r->lo || c > r->hi)
                return PLC_EX_VALUE;
        }
        return 0;
    }
    default: x = w[0]; /* U16; CMD: the code word (any sequence goes) */
    }
    return x >= r->lo && x <= r->hi ? 0 : PLC_EX_VALUE;
}

int plc_map_check_write(const plc_map_t *m, unsigned a, unsigned n, const uint16_t *v)
{
    if (n < 1 || n > PLC_MAX_WRITE)
        return PLC_EX_VALUE;
    if (a >= PLC_NREGS || a + n > PLC_NREGS)
        return PLC_EX_ADDRESS;
    /* Every register must be writable and every entry covered whole, so
     * nothing is ever half-written (a 32-bit value, command + sequence). */
    for (unsigned k = a; k < a + n;) {
        const plc_reg_t *r = plc_map_entry(k);
        if (!r || r->access != PLC_RW)
            return PLC_EX_ADDRESS;
        unsigned w = (unsigned)plc_type_words(r->type);
        if (r->addr < a || r->addr + w > a + n)
            return PLC_EX_ADDRESS;
        k = r->addr + w;
    }
    for (unsigned k = a; k < a + n;) {
        const plc_reg_t *r = plc_map_entry(k);
        int ex = check_value(m, r, v + (k - a));
        if (ex)
            return ex;
        k = r->addr + (unsigned)plc_type_words(r->type);
    }
    return 0;
}

void plc_map_store(plc_map_t *m, unsigned a, unsigned n, const uint16_t *v)
{
    if (a < PLC_NREGS && a + n <= PLC_NREGS)
        memcpy(&m->reg[a], v, n * sizeof *v);
}
