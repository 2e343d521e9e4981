/* SPDX-License-Identifier: MIT */
/* cmd_fitopts.c: the fit job's shared options (cmd_fitopts.h): one table
 * fragment, one check and one set of JSON fields for every command that
 * fits, so --tol and its companions mean the same everywhere. */
#include "cmd_fitopts.h"
#include "cf_cli.h"
#include <string.h>

/* In the order of cf_refine_t. */
static const char *const refines[] = {"uniform", "residual", "auto", NULL};

int cmd_fitopts_table(cf_opt_t *t, cf_fitjob_opts_t *o, cmd_fitopts_t *a, const char *reparam_help)
{
    memset(a, 0, sizeof *a);
    a->refine = (int)o->refine;
    const cf_opt_t rows[CMD_FITOPTS_N] = {
        {.name = "reparam",
         .kind = CF_OPT_LONG,
         .dst = &o->reparam,
         .arg = "K",
         .help = reparam_help,
         .lo = 0,
         .hi = 100,
         .given = &a->any},
        {.name = "tol",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->tol,
         .arg = "MM",
         .help = "deviation tolerance: fit, check, insert knots until --within % of the points "
                 "are within it (0: one fit)",
         .lo = 1e-300,
         .hi = 1e300,
         .def = "0",
         .given = &a->any},
        {.name = "within",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->within,
         .arg = "PCT",
         .help = "share of the points that must be within --tol",
         .lo = 1e-9,
         .hi = 100,
         .given = &a->loop_opt},
        {.name = "max-cp",
         .kind = CF_OPT_LONG,
         .dst = &o->max_cp,
         .arg = "N",
         .help = "control points the loop may reach at most",
         .lo = 4,
         .hi = NF_MAX_CP,
         .given = &a->loop_opt},
        {.name = "max-rounds",
         .kind = CF_OPT_LONG,
         .dst = &o->max_rounds,
         .arg = "N",
         .help = "rounds of the loop at most",
         .lo = 1,
         .hi = CF_FITJOB_MAX_ROUNDS,
         .given = &a->loop_opt},
        {.name = "refine",
         .kind = CF_OPT_CHOICE,
         .dst = &a->refine,
         .arg = "HOW",
         .help = "where the loop inserts knots: auto (knot lines scored per control point added, "
                 "only where data lie on both sides, at most half the points), residual or "
                 "uniform",
         .choices = refines,
         .given = &a->loop_opt},
        {.name = "min-gain",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->min_gain,
         .arg = "PTS",
         .help = "--refine auto: stop (not_met_no_progress) after two rounds in a row gaining "
                 "less than this many points of the percentage within",
         .lo = 1e-12,
         .hi = 100,
         .given = &a->loop_opt},
        {.name = "prune",
         .kind = CF_OPT_LONG,
         .dst = &o->prune,
         .arg = "N",
         .help = "--refine auto, once met: at most N trial fits each with one inserted knot "
                 "line taken out again, kept while --within is still met (0: none)",
         .lo = 0,
         .hi = CF_FITJOB_MAX_ROUNDS,
         .given = &a->loop_opt},
        {.name = "noise",
         .kind = CF_OPT_DOUBLE,
         .dst = &o->noise,
         .arg = "MM",
         .help = "the probe's noise: a floor under the robust scale (with --tol at least a "
                 "quarter of it)",
         .lo = 1e-12,
         .hi = 1e300,
         .def = "0"},
        {.name = "robust",
         .kind = CF_OPT_FLAG,
         .dst = &o->robust,
         .help = "Tukey-reweighted passes against outliers (scale from the MAD)",
         .given = &a->any},
        {.name = "robust-iters",
         .kind = CF_OPT_LONG,
         .dst = &o->robust_iters,
         .arg = "N",
         .help = "robust passes (implies --robust)",
         .lo = 1,
         .hi = 100,
         .given = &a->robust_iters_given},
    };
    memcpy(t, rows, sizeof rows);
    return CMD_FITOPTS_N;
}

int cmd_fitopts_check(const char *cmd, cf_fitjob_opts_t *o, const cmd_fitopts_t *a)
{
    o->refine = (cf_refine_t)a->refine;
    o->robust |= a->robust_iters_given;
    o->loop = o->tol > 0;
    if (a->loop_opt && !o->loop)
        return cli_error(cmd, CLI_USAGE,
                         "--within, --max-cp, --max-rounds and --refine need --tol T");
    return CLI_OK;
}

int cmd_fitopts_given(const cmd_fitopts_t *a)
{
    return a->any || a->loop_opt || a->robust_iters_given;
}

void cmd_fitopts_json(cf_json_t *j, const cf_fitjob_opts_t *o, const cf_fitjob_result_t *r)
{
    if (o->loop) {
        cf_json_num(j, "tol", o->tol);
        cf_json_num(j, "within", o->within);
        cf_json_num(j, "within_tol_pct", r->within_pct);
        cf_json_bool(j, "tol_met", r->status == CF_FITJOB_MET);
        cf_json_str(j, "refine", cf_refine_name(o->refine));
        cf_json_str(j, "stopped", r->why);
        if (r->fp_cells > 0) {
            cf_json_obj(j, "footprint");
            cf_json_int(j, "cells", r->fp_cells);
            cf_json_int(j, "filled", r->fp_filled);
            cf_json_int(j, "empty", r->fp_empty);
            cf_json_int(j, "outline", r->fp_outline);
            cf_json_close(j);
        }
        if (o->refine == CF_REFINE_AUTO)
            cf_json_int(j, "pruned", r->pruned);
        cf_rounds_json(j, r->rounds, r->nrounds, o->robust);
    }
    /* The last round the result came from: a pruning trial undone is not it. */
    int last = r->nrounds - 1;
    while (last > 0 && r->rounds[last].prune < 0)
        last--;
    if (o->robust && r->nrounds > 0) {
        cf_json_int(j, "robust_iters", o->robust_iters);
        cf_json_num(j, "robust_sigma", r->rounds[last].sigma);
        cf_json_int(j, "outliers", r->rounds[last].rejected);
        cf_json_num(j, "robust_floor", r->robust_floor);
    }
}

int cmd_fitopts_verdict(const char *cmd, const cf_fitjob_opts_t *o, const cf_fitjob_result_t *r,
                        const char *out)
{
    if (!o->loop || r->status == CF_FITJOB_MET)
        return CLI_OK;
    return cli_error(cmd, CLI_FAIL,
                     "tolerance %g mm not met: %.3f %% of the points within, need %g %%; "
                     "stopped: %s; wrote the best fit (%d x %d) to %s",
                     o->tol, r->within_pct, o->within, r->why, r->surf.nu, r->surf.nv, out);
}
