/* SPDX-License-Identifier: MIT */
/* cmd_ports.c: `cellfit ports`: the serial ports this machine has (with
 * their USB ids), and two checks of devices behind them: the laser probe
 * on a serial port (M0 readings, libserialport) and the USB trigger box
 * (identity, encoder packets, libusb). */
#include "cf_cli.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cmd.h"
#include "hal.h"
#include "hal_serial.h"
#include "hal_trig.h"
#include "hal_usb.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_PORTS 64

static int list_ports(int json)
{
    static hal_serial_port_t p[MAX_PORTS];
    size_t n = 0;
    char msg[256] = "";
    int rc = hal_serial_list(p, MAX_PORTS, &n, msg, sizeof msg);
    if (rc)
        return cli_error("ports", CLI_FAIL, "%s", msg);
    if (n > MAX_PORTS)
        n = MAX_PORTS;
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_int(&j, "count", (long)n);
        cf_json_arr(&j, "ports");
        for (size_t i = 0; i < n; i++) {
            char id[16] = "";
            if (p[i].usb)
                snprintf(id, sizeof id, "%04x:%04x", p[i].vid, p[i].pid);
            cf_json_obj(&j, NULL);
            cf_json_str(&j, "name", p[i].name);
            cf_json_str(&j, "usb", id);
            cf_json_str(&j, "serial", p[i].serial);
            cf_json_str(&j, "description", p[i].description);
            cf_json_close(&j);
        }
        cf_json_end(&j);
        return CLI_OK;
    }
    for (size_t i = 0; i < n; i++) {
        if (p[i].usb)
            printf("%s usb %04x:%04x serial %s (%s)\n", p[i].name, p[i].vid, p[i].pid,
                   p[i].serial[0] ? p[i].serial : "-", p[i].description);
        else
            printf("%s (%s)\n", p[i].name, p[i].description);
    }
    return CLI_OK;
}

/* One probe reply line: "M0,+01.234" (mm), "M0,FFFFFFF" (no surface in
 * range) or "ER,M0,nn" (the probe's error code). */
static int parse_m0(const char *line, double *mm, int *code)
{
    if (!strcmp(line, "M0,FFFFFFF"))
        return RIG_ENOSURF;
    if (!strncmp(line, "ER,M0,", 6) && line[6] >= '0' && line[6] <= '9' && line[7] >= '0' &&
        line[7] <= '9' && !line[8]) {
        *code = (line[6] - '0') * 10 + (line[7] - '0');
        return RIG_EEXCEPTION;
    }
    const char *p = line + 3;
    if (strncmp(line, "M0,", 3) || (*p != '+' && *p != '-'))
        return RIG_EPROTO;
    int digits = 0, dot = 0;
    for (const char *q = p + 1; *q; q++) {
        if (*q == '.' && !dot)
            dot = 1;
        else if (*q >= '0' && *q <= '9')
            digits++;
        else
            return RIG_EPROTO;
    }
    if (!dot || digits < 2)
        return RIG_EPROTO;
    *mm = strtod(p, NULL);
    return RIG_OK;
}

/* Ask once: M0, then a reply line within the timeout. */
static int probe_once(hal_t *h, double *mm, int *code, char *line, size_t cap)
{
    size_t n = 0;
    line[0] = 0;
    int rc = h->ops->flush(h);
    if (!rc)
        rc = h->ops->write(h, "M0\r\n", 4);
    double end = cli_now() + h->opts.timeout_ms / 1e3;
    while (!rc) {
        char c;
        size_t got = 0;
        int left = (int)((end - cli_now()) * 1e3);
        if (left <= 0) {
            snprintf(h->err, sizeof h->err, "no reply line in %d ms (got %zu bytes)",
                     h->opts.timeout_ms, n);
            return RIG_ETIMEOUT;
        }
        rc = h->ops->read(h, &c, 1, left, &got);
        if (rc || !got)
            continue;
        if (c == '\n' && n && line[n - 1] == '\r') {
            line[n - 1] = 0;
            rc = parse_m0(line, mm, code);
            if (rc == RIG_EPROTO)
                snprintf(h->err, sizeof h->err, "reply \"%.60s\" is not M0,+dd.ddd", line);
            return rc;
        }
        if (n + 1 >= cap)
            return RIG_EPROTO;
        line[n++] = c;
        line[n] = 0;
    }
    return rc;
}

static int read_probe(const char *port, long baud, long count, const hal_opts_t *o, int json)
{
    hal_uri_t u = {
        .kind = HAL_SERIAL, .baud = (int)baud, .data_bits = 8, .parity = 'N', .stop_bits = 1};
    snprintf(u.path, sizeof u.path, "%s", port);
    hal_t *h = NULL;
    char msg[256];
    int rc = hal_serial_open(&u, o, &h, msg, sizeof msg);
    if (rc)
        return cli_error("ports", CLI_FAIL, "%s: %s (%s)", port, rig_strerror(rc), msg);
    long ok = 0, nosurf = 0, failed = 0, last_err = 0;
    double sum = 0, first = 0;
    char why[300] = "";
    for (long i = 1; i <= count; i++) {
        double mm = 0;
        int code = 0;
        char line[128];
        rc = RIG_ETIMEOUT;
        /* A timeout or a garbled line is asked again, with backoff. */
        for (int a = 0, wait = o->backoff_ms; a <= o->retries; a++, wait *= 2) {
            if (a) {
                h->retries++;
                struct timespec ts = {wait / 1000, (long)(wait % 1000) * 1000000L};
                nanosleep(&ts, NULL);
            }
            rc = probe_once(h, &mm, &code, line, sizeof line);
            if (rc != RIG_ETIMEOUT && rc != RIG_EPROTO)
                break;
            last_err = rc;
        }
        if (rc == RIG_OK) {
            ok++;
            sum += mm;
            if (ok == 1)
                first = mm;
            if (!json)
                printf("reading %ld: %.3f mm\n", i, mm);
        } else if (rc == RIG_ENOSURF) {
            nosurf++;
            if (!json)
                printf("reading %ld: out of range\n", i);
        } else {
            failed++;
            last_err = rc;
            if (rc == RIG_EEXCEPTION)
                snprintf(h->err, sizeof h->err, "probe error %02d", code);
            snprintf(why, sizeof why, "reading %ld: %s (%.200s)", i, rig_strerror(rc), h->err);
            if (!json)
                printf("reading %ld: error %d: %s\n", i, rc, rig_strerror(rc));
            if (rc == RIG_EDISCONNECT)
                break;
        }
    }
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "port", port);
        cf_json_int(&j, "readings", ok);
        cf_json_int(&j, "out_of_range", nosurf);
        cf_json_int(&j, "failed", failed);
        cf_json_num(&j, "first_mm", first);
        cf_json_num(&j, "mean_mm", ok ? sum / ok : 0);
        cf_json_int(&j, "retries", (long)h->retries);
        cf_json_int(&j, "reconnects", (long)h->reconnects);
        cf_json_int(&j, "last_error", last_err);
        cf_json_end(&j);
    }
    h->ops->close(h);
    if (failed)
        return cli_error("ports", CLI_FAIL, "%s: %s", port, why);
    return CLI_OK;
}

static int parse_usb(const char *s, hal_uri_t *u)
{
    unsigned vid, pid;
    int n = 0;
    memset(u, 0, sizeof *u);
    u->kind = HAL_USB;
    if (sscanf(s, "%4x:%4x%n", &vid, &pid, &n) != 2)
        return -1;
    if (s[n] == ':' && s[n + 1])
        snprintf(u->serial, sizeof u->serial, "%s", s + n + 1);
    else if (s[n])
        return -1;
    u->vid = (uint16_t)vid;
    u->pid = (uint16_t)pid;
    return 0;
}

static int read_trig(const char *id, long count, long period, const hal_opts_t *o, int json)
{
    hal_uri_t u;
    if (parse_usb(id, &u))
        return cli_error("ports", CLI_USAGE, "--trig wants VID:PID[:SERIAL] in hex, not '%s'", id);
    hal_t *h = NULL;
    char msg[256];
    int rc = hal_usb_open(&u, o, &h, msg, sizeof msg);
    if (rc)
        return cli_error("ports", CLI_FAIL, "usb %s: %s (%s)", id, rig_strerror(rc), msg);
    hal_trig_ident_t ident = {0};
    hal_trig_seq_t seq = {0};
    long got = 0, crc = 0, first = -1, last = -1;
    const char *step = "identity";
    rc = hal_trig_ident(h, &ident);
    int have_ident = rc == RIG_OK;
    if (have_ident && !json)
        printf("trigger box %s: protocol %d, firmware %d.%d.%d, serial %u, %d axes\n", id,
               ident.proto, ident.fw_major, ident.fw_minor, ident.fw_patch, ident.serial,
               ident.axes);
    if (!rc) {
        step = "set period";
        rc = hal_trig_set_period(h, (uint32_t)period);
    }
    if (!rc) {
        step = "arm";
        rc = hal_trig_arm(h, 1);
    }
    if (!rc)
        step = "read packets";
    long rearmed = 0;
    while (!rc && got < count) {
        hal_trig_pkt_t p[3];
        size_t n = 0;
        unsigned long before = h->reconnects;
        rc = hal_trig_read(h, &seq, p, 3, &n);
        if (rc == RIG_ECRC) {
            crc++;
            rc = RIG_OK; /* that packet is lost (a gap), the stream goes on */
        } else if (rc == RIG_EDISCONNECT && h->reconnects > before && rearmed < 3) {
            /* Plugged back: a restarted box, set up again; its trigger
             * numbers start over. */
            rearmed++;
            memset(&seq, 0, sizeof seq);
            rc = hal_trig_set_period(h, (uint32_t)period);
            if (!rc)
                rc = hal_trig_arm(h, 1);
            continue;
        }
        for (size_t k = 0; !rc && k < n && got < count; k++, got++) {
            if (first < 0)
                first = p[k].seq;
            last = p[k].seq;
            if (!json)
                printf("trigger %u t %u us enc %d %d\n", (unsigned)p[k].seq, (unsigned)p[k].t_us,
                       (int)p[k].enc[0], (int)p[k].enc[1]);
        }
    }
    char why[300] = "";
    if (rc)
        snprintf(why, sizeof why, "%s: %s (%.200s)", step, rig_strerror(rc), h->err);
    else
        hal_trig_arm(h, 0);
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_str(&j, "device", id);
        cf_json_int(&j, "serial", have_ident ? (long)ident.serial : 0);
        cf_json_int(&j, "packets", got);
        cf_json_int(&j, "lost", (long)seq.lost);
        cf_json_int(&j, "crc_errors", crc);
        cf_json_int(&j, "first_seq", first);
        cf_json_int(&j, "last_seq", last);
        cf_json_int(&j, "reconnects", (long)h->reconnects);
        cf_json_int(&j, "rearmed", rearmed);
        cf_json_int(&j, "error", rc);
        cf_json_end(&j);
    }
    h->ops->close(h);
    if (rc)
        return cli_error("ports", CLI_FAIL, "usb %s: %s", id, why);
    return CLI_OK;
}

int cmd_ports(int argc, char **argv)
{
    const char *probe = NULL, *trig = NULL;
    long baud = 115200, count = 1, period = 10000;
    int json = 0;
    hal_opts_t o = HAL_OPTS_DEFAULT;
    const cf_opt_t opts[] = {
        {.name = "probe",
         .kind = CF_OPT_STR,
         .dst = &probe,
         .arg = "PORT",
         .help = "read the laser probe on this serial port (M0 readings)"},
        {.name = "trig",
         .kind = CF_OPT_STR,
         .dst = &trig,
         .arg = "VID:PID[:SERIAL]",
         .help = "read the USB trigger box (hex ids): identity, encoder packets"},
        {.name = "baud",
         .kind = CF_OPT_LONG,
         .dst = &baud,
         .arg = "BAUD",
         .help = "--probe: the line's speed",
         .lo = 50,
         .hi = 4000000},
        {.name = "count",
         .kind = CF_OPT_LONG,
         .dst = &count,
         .arg = "N",
         .help = "readings (--probe) or packets (--trig) to take",
         .lo = 1,
         .hi = 1000000},
        {.name = "period",
         .kind = CF_OPT_LONG,
         .dst = &period,
         .arg = "US",
         .help = "--trig: the trigger period",
         .lo = TRIG_MIN_PERIOD,
         .hi = TRIG_MAX_PERIOD},
        {.name = "timeout",
         .kind = CF_OPT_INT,
         .dst = &o.timeout_ms,
         .arg = "MS",
         .help = "one request or read",
         .lo = 1,
         .hi = 600000},
        {.name = "retries",
         .kind = CF_OPT_INT,
         .dst = &o.retries,
         .arg = "N",
         .help = "extra attempts after a timeout or a bad reply",
         .lo = 0,
         .hi = 100},
        {.name = "reconnect",
         .kind = CF_OPT_INT,
         .dst = &o.reconnect_ms,
         .arg = "MS",
         .help = "how long to keep reopening a lost line",
         .lo = 0,
         .hi = 600000},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "one JSON object on stdout"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "ports",
                          .summary = "the serial ports (with their USB ids); with --probe or "
                                     "--trig, a check of the device behind one",
                          .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return cf_opt_exit(rc);
    if (probe && trig)
        return cli_error("ports", CLI_USAGE, "--probe and --trig: one at a time");
    if (probe)
        return read_probe(probe, baud, count, &o, json);
    if (trig)
        return read_trig(trig, count, period, &o, json);
    return list_ports(json);
}
