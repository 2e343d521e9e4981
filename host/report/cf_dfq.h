/* SPDX-License-Identifier: MIT */
/* cf_dfq.h: a job's results as a Q-DAS ASCII transfer file (AQDEF, .dfq),
 * the format SPC systems import: the part (K1001 number, K1002 name), per
 * characteristic its number, name, nominal, lower and upper limits and unit
 * (K2001, K2002, K2101, K2110, K2111, K2142), and one measured value per
 * characteristic with its date and time and the part's ident (K0001,
 * K0004, K0014). One K-field a line, "Kxxxx/c value"; the field profile is
 * in docs/formats.md. */
#ifndef CF_DFQ_H
#define CF_DFQ_H

#include <stddef.h>

typedef struct cf_dfq_char {
    const char *name; /* K2002, e.g. "RMS deviation" (at most 80 characters) */
    double nominal;   /* K2101; NaN: none written */
    double lo, hi;    /* K2110, K2111; NaN: that limit is open */
    const char *unit; /* K2142, e.g. "mm", "%" */
    double value;     /* K0001; NaN: not measured (K0002 attribute 255) */
    int decimals;     /* K2022: places shown by the SPC system */
} cf_dfq_char_t;

typedef struct cf_dfq_part {
    const char *number; /* K1001 part number */
    const char *name;   /* K1002 part name */
    const char *ident;  /* K0014 the part's serial/ident from the PLC; NULL or "": none */
    long long utc;      /* K0004 the job's end, seconds since 1970 (written in UTC) */
} cf_dfq_part_t;

/* Write n characteristics (numbered 1..n, K0100 n) to path, atomically.
 * Texts are cleaned to printable ASCII (a DFQ line ends at a line break).
 * CF_OK, CF_EARG, or CF_EIO with msg. */
int cf_dfq_write(const char *path, const cf_dfq_part_t *part, const cf_dfq_char_t *c, int n,
                 char *msg, size_t ml);

#endif
