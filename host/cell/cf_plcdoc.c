/* SPDX-License-Identifier: MIT */
/* cf_plcdoc.c: Markdown rows of the register map and the state table. */
#include "cf_plcdoc.h"
#include "plc_fsm.h"
#include <string.h>

void cf_plcdoc_reg_row(int i, char *buf, size_t n)
{
    const plc_reg_t *r = &plc_regs[i];
    unsigned a = r->addr, w = (unsigned)plc_type_words(r->type);
    char addr[32], four[32], range[64] = "";
    if (w > 1) {
        snprintf(addr, sizeof addr, "%u-%u", a, a + w - 1);
        snprintf(four, sizeof four, "%u-%u", 40001u + a, 40001u + a + w - 1);
    } else {
        snprintf(addr, sizeof addr, "%u", a);
        snprintf(four, sizeof four, "%u", 40001u + a);
    }
    if (r->access == PLC_RW)
        snprintf(range, sizeof range, "%.10g .. %.10g", r->lo, r->hi);
    snprintf(buf, n, "| %s | %s | %s | %s | %s | %s | %s | %s |", addr, four, r->name,
             plc_type_name(r->type), r->access == PLC_RW ? "R/W" : "R", range, r->units, r->desc);
}

void cf_plcdoc_state_row(int s, char *buf, size_t n)
{
    size_t k = (size_t)snprintf(buf, n, "| %d %s |", s, plc_state_name(s));
    for (int c = PLC_C_HOME; c < PLC_C_COUNT && k < n; c++) {
        plc_rule_t r = plc_cmd_rules[s][c];
        char cell[48];
        switch (r.kind) {
        case PLC_K_REJECT: snprintf(cell, sizeof cell, "refused %u", r.code); break;
        case PLC_K_START:
            snprintf(cell, sizeof cell, "-> %s", plc_state_name(plc_job_phases[c][0]));
            break;
        case PLC_K_ABORT: snprintf(cell, sizeof cell, "-> ABORTING"); break;
        case PLC_K_NOOP: snprintf(cell, sizeof cell, "stop motion"); break;
        case PLC_K_RESET: snprintf(cell, sizeof cell, "-> IDLE"); break;
        case PLC_K_ACK: snprintf(cell, sizeof cell, "clear results"); break;
        default: snprintf(cell, sizeof cell, "?");
        }
        k += (size_t)snprintf(buf + k, n - k, " %s |", cell);
    }
}

void cf_plcdoc_print(FILE *f)
{
    char row[512];
    fprintf(f, "| Address | 4xxxx | Name | Type | Access | Range | Units | Description |\n");
    fprintf(f, "|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < PLC_NENTRIES; i++) {
        cf_plcdoc_reg_row(i, row, sizeof row);
        fprintf(f, "%s\n", row);
    }
    fprintf(f, "\n| State |");
    for (int c = PLC_C_HOME; c < PLC_C_COUNT; c++)
        fprintf(f, " %d %s |", c, plc_cmd_name(c));
    fprintf(f, "\n|---|");
    for (int c = PLC_C_HOME; c < PLC_C_COUNT; c++)
        fprintf(f, "---|");
    fprintf(f, "\n");
    for (int s = 0; s < PLC_S_COUNT; s++) {
        cf_plcdoc_state_row(s, row, sizeof row);
        fprintf(f, "%s\n", row);
    }
}
