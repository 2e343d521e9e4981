/* SPDX-License-Identifier: MIT */
/* cf_plcdoc.h: the register map and the state table as Markdown rows, from
 * the firmware's tables (plc_map.h, plc_fsm.h): `cellfit serve --print-map`
 * prints them, docs/plc-register-map.md holds them, tests/test_plc.c checks
 * that every row is in the docs verbatim. */
#ifndef CF_PLCDOC_H
#define CF_PLCDOC_H

#include <stddef.h>
#include <stdio.h>

/* Row of register entry i (0 .. PLC_NENTRIES - 1):
 * "| 2-3 | 40003-40004 | TEST_F32 | float32 | R | | | 123.456 ... |" */
void cf_plcdoc_reg_row(int i, char *buf, size_t n);

/* Row of state s: what each command does there ("-> HOMING", "refused 102"). */
void cf_plcdoc_state_row(int s, char *buf, size_t n);

/* Both tables with their headers. */
void cf_plcdoc_print(FILE *f);

#endif
