/* cf_cli.h: what the cellfit subcommands share: exit codes, one-line error
 * reports, option value parsing, timing and a small JSON writer. */
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

/* Minimal JSON object writer: cli_json_begin, fields, cli_json_end. */
typedef struct cli_json {
    FILE *f;
    int n;
} cli_json_t;
void cli_json_begin(cli_json_t *j, FILE *f);
void cli_json_num(cli_json_t *j, const char *key, double v);
void cli_json_int(cli_json_t *j, const char *key, long v);
void cli_json_str(cli_json_t *j, const char *key, const char *v);
void cli_json_end(cli_json_t *j);

int cmd_fit(int argc, char **argv);
int cmd_eval(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_gen(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_report(int argc, char **argv);
int cmd_project(int argc, char **argv);
int cmd_base(int argc, char **argv);
int cmd_journal(int argc, char **argv);
int cmd_scan(int argc, char **argv);
int cmd_rig(int argc, char **argv);
int cmd_ports(int argc, char **argv);
int cmd_thin(int argc, char **argv);
int cmd_serve(int argc, char **argv);

#endif
