/* SPDX-License-Identifier: MIT */
/* cmd_fitopts.h: the fit job's options that `cellfit fit`, `journal fit`
 * and `scan --fit` share, with one meaning each: --reparam, --tol,
 * --within, --max-cp, --max-rounds, --refine, --min-gain, --noise,
 * --robust, --robust-iters
 * (rows of a cf_opt table), their checks after parsing, and the JSON
 * fields of the tolerance loop and the robust passes in the summaries. */
#ifndef CMD_FITOPTS_H
#define CMD_FITOPTS_H

#include "cf_fitjob.h"
#include "cf_json.h"
#include "cf_opt.h"

#define CMD_FITOPTS_N 11 /* rows cmd_fitopts_table writes */

/* What was given, for the checks. */
typedef struct cmd_fitopts {
    int refine;             /* cf_refine_t: uniform, residual, auto */
    int loop_opt;           /* --within, --max-cp, --max-rounds or --refine given */
    int robust_iters_given; /* --robust-iters implies --robust */
    int any;                /* --tol, --reparam or --robust given */
} cmd_fitopts_t;

/* The CMD_FITOPTS_N rows into t (o's defaults shown); reparam_help says
 * what --reparam projects for this command. Returns CMD_FITOPTS_N. */
int cmd_fitopts_table(cf_opt_t *t, cf_fitjob_opts_t *o, cmd_fitopts_t *a, const char *reparam_help);

/* After parsing: --refine and --robust-iters into o, the loop on with
 * --tol. CLI_OK, or CLI_USAGE after one line on stderr when loop options
 * come without --tol. */
int cmd_fitopts_check(const char *cmd, cf_fitjob_opts_t *o, const cmd_fitopts_t *a);

/* 1 when any of these options was given (a command that fits only on
 * request refuses them without it). */
int cmd_fitopts_given(const cmd_fitopts_t *a);

/* The loop's fields (tol, within, within_tol_pct, tol_met, refine,
 * stopped, rounds) when it ran, the robust passes' (robust_iters,
 * robust_sigma, outliers) when asked, into an open JSON object. */
void cmd_fitopts_json(cf_json_t *j, const cf_fitjob_opts_t *o, const cf_fitjob_result_t *r);

/* A tolerance not met is a failure of the work: CLI_FAIL after one line
 * (the share within, why the loop stopped, the best fit written to out);
 * CLI_OK when it was met or no loop ran. */
int cmd_fitopts_verdict(const char *cmd, const cf_fitjob_opts_t *o, const cf_fitjob_result_t *r,
                        const char *out);

#endif
