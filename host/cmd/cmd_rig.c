/* SPDX-License-Identifier: MIT */
/* cmd_rig.c: `cellfit rig`: talk to the stage and the probe by hand or from
 * tests: status, home, move X Y, probe readings, fault reset, stop, on the
 * devices the --stage and --probe URIs name (hal.h). */
#include "cf_cli.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cmd.h"
#include "hal_rig.h"
#include <stdio.h>
#include <string.h>

/* One line: the driver's detail (it names the device), the code's name. */
static int rig_fail(int rc, const char *detail)
{
    return cli_error("rig", CLI_FAIL, "%s [%s, %d]", detail, rig_strerror(rc), rc);
}

static int do_probe(hal_rig_t *r, long count, int json)
{
    long ok = 0, nosurf = 0;
    double sum = 0, last = 0;
    for (long i = 0; i < count; i++) {
        double d;
        int rc = r->probe.ops->read(r->probe.ctx, &d);
        if (rc == RIG_ENOSURF) {
            nosurf++;
            if (!json)
                printf("nosurf\n");
            continue;
        }
        if (rc)
            return rig_fail(rc, hal_probe_error(r->probe.ctx));
        ok++;
        sum += d;
        last = d;
        if (!json)
            printf("%.4f\n", d);
    }
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_int(&j, "readings", ok);
        cf_json_int(&j, "nosurf", nosurf);
        cf_json_num(&j, "last_mm", last);
        cf_json_num(&j, "mean_mm", ok ? sum / ok : 0);
        cf_json_int(&j, "retries", (long)r->pr.h->retries);
        cf_json_int(&j, "reconnects", (long)r->pr.h->reconnects);
        cf_json_end(&j);
    }
    /* Out of range is a reading, not a failure of the line, but a run
     * that saw nothing else did not measure. */
    return ok || !nosurf ? CLI_OK : rig_fail(RIG_ENOSURF, hal_probe_error(r->probe.ctx));
}

static int do_status(hal_rig_t *r, int json)
{
    uint32_t bits = 0;
    double x = 0, y = 0, lo[2] = {0, 0}, hi[2] = {0, 0}, plo = 0, phi = 0;
    int rc;
    if (r->stage.ops) {
        if ((rc = r->stage.ops->status(r->stage.ctx, &bits)) ||
            (rc = r->stage.ops->position(r->stage.ctx, &x, &y)))
            return rig_fail(rc, hal_stage_error(r->stage.ctx));
        r->stage.ops->limits(r->stage.ctx, lo, hi);
    }
    if (r->probe.ops)
        r->probe.ops->range(r->probe.ctx, &plo, &phi);
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        if (r->stage.ops) {
            cf_json_int(&j, "status", (long)bits);
            cf_json_int(&j, "homed", !!(bits & RIG_ST_HOMED));
            cf_json_int(&j, "busy", !!(bits & RIG_ST_BUSY));
            cf_json_int(&j, "inpos", !!(bits & RIG_ST_INPOS));
            cf_json_int(&j, "fault", !!(bits & RIG_ST_FAULT));
            cf_json_int(&j, "estop", !!(bits & RIG_ST_ESTOP));
            cf_json_int(&j, "limit", !!(bits & RIG_ST_LIMIT));
            cf_json_num(&j, "x", x);
            cf_json_num(&j, "y", y);
            cf_json_num(&j, "x_lo", lo[0]);
            cf_json_num(&j, "x_hi", hi[0]);
            cf_json_num(&j, "y_lo", lo[1]);
            cf_json_num(&j, "y_hi", hi[1]);
        }
        if (r->probe.ops) {
            cf_json_num(&j, "range_lo", plo);
            cf_json_num(&j, "range_hi", phi);
        }
        cf_json_end(&j);
        return CLI_OK;
    }
    if (r->stage.ops)
        printf("stage: status 0x%02x%s%s%s%s%s%s, at (%.3f, %.3f) mm, limits [%g, %g] x [%g, %g]\n",
               (unsigned)bits, bits & RIG_ST_HOMED ? " homed" : "",
               bits & RIG_ST_BUSY ? " busy" : "", bits & RIG_ST_INPOS ? " in-position" : "",
               bits & RIG_ST_FAULT ? " FAULT" : "", bits & RIG_ST_ESTOP ? " E-STOP" : "",
               bits & RIG_ST_LIMIT ? " limit" : "", x, y, lo[0], hi[0], lo[1], hi[1]);
    if (r->probe.ops)
        printf("probe: range [%g, %g] mm\n", plo, phi);
    return CLI_OK;
}

enum { OP_STATUS, OP_HOME, OP_MOVE, OP_PROBE, OP_RESET, OP_STOP, NOPS };

typedef struct rig_op {
    const char *name, *args, *summary;
    int stage, probe; /* 2: required, 1: optional, 0: not taken */
} rig_op_t;

static const rig_op_t ops[NOPS] = {
    {"status", NULL, "the stage's status bits, position and limits, the probe's range", 1, 1},
    {"home", NULL, "home the stage", 2, 0},
    {"move", "X Y", "move the stage to (X, Y) mm", 2, 0},
    {"probe", NULL, "--count readings of the probe (mm; \"nosurf\" out of range)", 0, 2},
    {"reset", NULL, "reset the stage's fault", 2, 0},
    {"stop", NULL, "stop the stage", 2, 0},
};

typedef struct rig_args {
    const char *stage, *probe;
    long count;
    int json;
    hal_opts_t ho;
} rig_args_t;

/* The options of operation k, from one table; pos gets X Y for move. */
static int rig_parse(int k, int argc, char **argv, rig_args_t *a, const char **pos)
{
    const rig_op_t *op = &ops[k];
    cf_opt_t opts[12];
    int n = 0;
    if (op->stage)
        opts[n++] = (cf_opt_t){.name = "stage",
                               .kind = CF_OPT_STR,
                               .dst = &a->stage,
                               .arg = "URI",
                               .help = "the stage's URI (hal.h: rtu:..., tcp:HOST:PORT[:UNIT])",
                               .req = op->stage == 2};
    if (op->probe)
        opts[n++] = (cf_opt_t){.name = "probe",
                               .kind = CF_OPT_STR,
                               .dst = &a->probe,
                               .arg = "URI",
                               .help = "the probe's URI (hal.h: serial:..., tty:..., tcp:...)",
                               .req = op->probe == 2};
    if (k == OP_PROBE)
        opts[n++] = (cf_opt_t){.name = "count",
                               .kind = CF_OPT_LONG,
                               .dst = &a->count,
                               .arg = "N",
                               .help = "readings to take",
                               .lo = 1,
                               .hi = 100000000};
    opts[n++] = (cf_opt_t){.name = "timeout",
                           .kind = CF_OPT_INT,
                           .dst = &a->ho.timeout_ms,
                           .arg = "MS",
                           .help = "one request or read",
                           .lo = 1,
                           .hi = 600000};
    opts[n++] = (cf_opt_t){.name = "retries",
                           .kind = CF_OPT_INT,
                           .dst = &a->ho.retries,
                           .arg = "N",
                           .help = "extra attempts after a timeout or a bad frame",
                           .lo = 0,
                           .hi = 600000};
    opts[n++] = (cf_opt_t){.name = "late",
                           .kind = CF_OPT_INT,
                           .dst = &a->ho.late_ms,
                           .arg = "MS",
                           .help = "a device's worst-case reply delay: later replies are dropped",
                           .lo = 1,
                           .hi = 600000,
                           .def = "the --timeout"};
    opts[n++] = (cf_opt_t){.name = "reconnect",
                           .kind = CF_OPT_INT,
                           .dst = &a->ho.reconnect_ms,
                           .arg = "MS",
                           .help = "how long to keep reopening a lost line",
                           .lo = 1,
                           .hi = 600000};
    opts[n++] = (cf_opt_t){
        .name = "json", .kind = CF_OPT_FLAG, .dst = &a->json, .help = "one JSON object on stdout"};
    opts[n] = (cf_opt_t){0};
    char name[16];
    snprintf(name, sizeof name, "rig %s", op->name);
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = name,
                          .args = op->args,
                          .summary = op->summary,
                          .descr = op->stage == 1 ? "Give --stage, --probe or both." : NULL,
                          .opts = opts,
                          .min_pos = k == OP_MOVE ? 2 : 0,
                          .max_pos = k == OP_MOVE ? 2 : 0};
    return cf_opt_parse(&cmd, argc, argv, pos, NULL);
}

/* `cellfit rig` without an operation: its own table (no options), whose
 * description lists the operations; --help-man adds every operation's
 * section. */
static int rig_top(int argc, char **argv)
{
    char list[1024];
    size_t n = (size_t)snprintf(list, sizeof list,
                                "The devices the --stage and --probe URIs name (hal.h). "
                                "Operations (cellfit rig OPERATION --help lists its options):");
    for (int k = 0; k < NOPS && n < sizeof list; k++)
        n +=
            (size_t)snprintf(list + n, sizeof list - n, "\n  %-7s %s", ops[k].name, ops[k].summary);
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "rig",
                          .args = "OPERATION",
                          .summary = "the stage and the probe by hand: status, home, move, probe, "
                                     "reset, stop",
                          .descr = list,
                          .min_pos = 1};
    int rc = cf_opt_parse(&cmd, argc < 2 ? 1 : 2, argv, NULL, NULL);
    if (rc < 0 && !strcmp(argv[1], "--help-man")) {
        rig_args_t ra = {.count = 1, .ho = HAL_OPTS_DEFAULT};
        const char *pos[2];
        for (int k = 0; k < NOPS; k++)
            rig_parse(k, 2, argv, &ra, pos);
    }
    return rc ? cf_opt_exit(rc) : CLI_USAGE;
}

int cmd_rig(int argc, char **argv)
{
    if (argc < 2 || argv[1][0] == '-')
        return rig_top(argc, argv);
    rig_args_t ra = {.count = 1, .ho = HAL_OPTS_DEFAULT};
    const char *pos[2];
    int k = 0;
    while (k < NOPS && strcmp(argv[1], ops[k].name))
        k++;
    if (k == NOPS)
        return cli_error("rig", CLI_USAGE,
                         "unknown operation '%s' (status, home, move, probe, reset, stop; "
                         "cellfit rig --help)",
                         argv[1]);
    int prc = rig_parse(k, argc - 1, argv + 1, &ra, pos);
    if (prc)
        return cf_opt_exit(prc);
    double xy[2] = {0, 0};
    for (int i = 0; k == OP_MOVE && i < 2; i++)
        if (cli_double(pos[i], &xy[i]))
            return cli_error("rig", CLI_USAGE, "move: '%s' is not a number (mm)", pos[i]);
    const double mx = xy[0], my = xy[1];
    if (!ra.stage && !ra.probe)
        return cli_error("rig", CLI_USAGE, "%s needs --stage URI, --probe URI or both",
                         ops[k].name);
    const char *stage = ra.stage, *probe = ra.probe, *op = ops[k].name;
    hal_opts_t o = ra.ho;
    long count = ra.count;
    int json = ra.json;
    hal_rig_t *r;
    char msg[512];
    int rc = hal_rig_open(stage, probe, &o, &r, msg, sizeof msg);
    if (rc)
        return cli_error("rig", rc == RIG_EARG ? CLI_USAGE : CLI_FAIL, "%s [%s, %d]", msg,
                         rig_strerror(rc), rc);
    int code = CLI_OK;
    if (k == OP_STATUS)
        code = do_status(r, json);
    else if (k == OP_PROBE)
        code = do_probe(r, count, json);
    else {
        void *c = r->stage.ctx;
        rc = k == OP_HOME    ? r->stage.ops->home(c)
             : k == OP_MOVE  ? r->stage.ops->move_to(c, mx, my)
             : k == OP_RESET ? r->stage.ops->reset_fault(c)
                             : r->stage.ops->stop(c);
        if (rc)
            code = rig_fail(rc, hal_stage_error(c));
        else {
            double x = 0, y = 0;
            r->stage.ops->position(c, &x, &y);
            if (json) {
                cf_json_t j;
                cf_json_begin(&j, stdout);
                cf_json_str(&j, "done", op);
                cf_json_num(&j, "x", x);
                cf_json_num(&j, "y", y);
                cf_json_int(&j, "retries", (long)r->st.h->retries);
                cf_json_int(&j, "reconnects", (long)r->st.h->reconnects);
                cf_json_end(&j);
            } else
                printf("stage: %s done, at (%.3f, %.3f) mm\n", op, x, y);
        }
    }
    hal_rig_close(r);
    return code;
}
