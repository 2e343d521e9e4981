/* cmd_rig.c: `cellfit rig`: talk to the stage and the probe by hand or from
 * tests: status, home, move X Y, probe readings, fault reset, stop, on the
 * devices the --stage and --probe URIs name (hal.h). */
#include "cf_cli.h"
#include "cf_json.h"
#include "cmd.h"
#include "hal_rig.h"
#include <stdio.h>
#include <string.h>

#define RIG_USAGE                                                                                  \
    "usage: cellfit rig status|home|move X Y|probe|reset|stop [--stage URI] [--probe URI]\n"       \
    "       [--count N] [--timeout MS] [--retries N] [--late MS] [--reconnect MS] [--json]"

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

int cmd_rig(int argc, char **argv)
{
    const char *stage = NULL, *probe = NULL, *op = NULL;
    double mx = 0, my = 0;
    long count = 1, v;
    int json = 0, npos = 0;
    hal_opts_t o = HAL_OPTS_DEFAULT;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--json")) {
            json = 1;
            continue;
        }
        if (a[0] != '-' || (a[1] >= '0' && a[1] <= '9') || a[1] == '.') {
            if (!op)
                op = a;
            else if (!strcmp(op, "move") && npos < 2) {
                if (cli_double(a, npos ? &my : &mx))
                    return cli_error("rig", CLI_USAGE, "move: '%s' is not a number (mm)", a);
                npos++;
            } else
                return cli_error("rig", CLI_USAGE, "unexpected argument '%s'", a);
            continue;
        }
        const char *val = i + 1 < argc ? argv[++i] : NULL;
        if (!val)
            return cli_error("rig", CLI_USAGE, "option %s needs a value", a);
        if (!strcmp(a, "--stage"))
            stage = val;
        else if (!strcmp(a, "--probe"))
            probe = val;
        else if (!strcmp(a, "--count")) {
            if (cli_int(val, 1, 100000000L, &count))
                return cli_error("rig", CLI_USAGE, "--count '%s'", val);
        } else if (!strcmp(a, "--timeout") || !strcmp(a, "--retries") || !strcmp(a, "--late") ||
                   !strcmp(a, "--reconnect")) {
            int retries = !strcmp(a, "--retries");
            if (cli_int(val, retries ? 0 : 1, 600000, &v))
                return cli_error("rig", CLI_USAGE, "%s '%s'", a, val);
            if (retries)
                o.retries = (int)v;
            else if (!strcmp(a, "--timeout"))
                o.timeout_ms = (int)v;
            else if (!strcmp(a, "--late"))
                o.late_ms = (int)v;
            else
                o.reconnect_ms = (int)v;
        } else
            return cli_error("rig", CLI_USAGE, "unknown option '%s'", a);
    }
    if (!op)
        return cli_error("rig", CLI_USAGE, "%s", RIG_USAGE);
    int need_stage = strcmp(op, "probe") && strcmp(op, "status");
    int need_probe = !strcmp(op, "probe");
    if (strcmp(op, "status") && strcmp(op, "home") && strcmp(op, "move") && strcmp(op, "probe") &&
        strcmp(op, "reset") && strcmp(op, "stop"))
        return cli_error("rig", CLI_USAGE, "unknown operation '%s' (%s)", op,
                         "status, home, move, probe, reset, stop");
    if (!strcmp(op, "move") && npos != 2)
        return cli_error("rig", CLI_USAGE, "move needs X and Y (mm)");
    if ((need_stage && !stage) || (need_probe && !probe) || (!stage && !probe))
        return cli_error("rig", CLI_USAGE, "%s needs %s", op,
                         need_probe ? "--probe URI" : "--stage URI");
    hal_rig_t *r;
    char msg[512];
    int rc = hal_rig_open(stage, probe, &o, &r, msg, sizeof msg);
    if (rc)
        return cli_error("rig", rc == RIG_EARG ? CLI_USAGE : CLI_FAIL, "%s [%s, %d]", msg,
                         rig_strerror(rc), rc);
    int code = CLI_OK;
    if (!strcmp(op, "status"))
        code = do_status(r, json);
    else if (!strcmp(op, "probe"))
        code = do_probe(r, count, json);
    else {
        void *c = r->stage.ctx;
        rc = !strcmp(op, "home")    ? r->stage.ops->home(c)
             : !strcmp(op, "move")  ? r->stage.ops->move_to(c, mx, my)
             : !strcmp(op, "reset") ? r->stage.ops->reset_fault(c)
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
