/* SPDX-License-Identifier: MIT */
/* cf_cli.h: what the command-line programs (cellfit, cellsim) share: exit
 * codes, one-line error reports, strict number parsing, a monotonic clock.
 * Option tables and usage: cf_opt.h; JSON output: cf_json.h. */
#ifndef CF_CLI_H
#define CF_CLI_H

#include "nf_budget.h"
#include <stdio.h>

enum { CLI_OK = 0, CLI_FAIL = 1, CLI_USAGE = 2 }; /* exit codes (DESIGN.md) */

/* "cellfit <cmd>: <message>" on stderr, one line; returns code. */
int cli_error(const char *cmd, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Strict numeric option values: the whole string must parse, finite. */
int cli_double(const char *s, double *out);
int cli_int(const char *s, long lo, long hi, long *out);

/* "auto", "gs", "chol", "pcg" into *out; -1 for anything else. */
int cli_solver(const char *s, nf_solver_t *out);

double cli_now(void); /* monotonic seconds */

/* Wall-clock UTC, seconds since 1970 (the Linux cell controller's clock). */
double cli_utc_now(void);

/* utc as ISO 8601 with milliseconds, "2026-12-02T04:45:01.123Z" (n >= 32);
 * "" for utc <= 0 (no wall clock). */
void cli_iso8601(double utc, char *b, size_t n);

#endif
