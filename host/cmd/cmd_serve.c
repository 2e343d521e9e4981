/* SPDX-License-Identifier: MIT */
/* cmd_serve.c: `cellfit serve`: the cell headless, driven by a PLC over
 * Modbus TCP (docs/plc-register-map.md). Options (one table, cf_opt)
 * override the config file (key = value, cf_conf.h; keys are the long
 * options without "--", '-' as '_'), fit settings included (tolerance loop,
 * robust, reprojection: the fit job's); logs with levels to stderr or syslog; the rig from --stage and
 * --probe URIs (hal_rig.h), or cellsim started as a child with --sim;
 * SIGTERM or SIGINT stops it cleanly (a running job is aborted, the
 * simulator stopped). */
#include "cf_cli.h"
#include "cf_conf.h"
#include "cf_err.h"
#include "cf_log.h"
#include "cf_opt.h"
#include "cf_plant.h"
#include "cf_plcdoc.h"
#include "cf_plcrun.h"
#include "cf_plcsrv.h"
#include "cf_plcstats.h"
#include "cf_portfile.h"
#include "cf_scanfast.h"
#include "cf_simchild.h"
#include "cmd.h"
#include "hal_rig.h"
#include <arpa/inet.h>
#include <errno.h>
#include <malloc.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define SERVE_MAX_STRS 32
#define CF_SERVE_SIM_ARGS "--speed 5000 --seed 1" /* --sim without sim_args */

typedef struct serve_conf {
    char addr[64];
    long port, watchdog_ms, max_clients, idle_ms;
    double max_rate;
    const char *sim_args;
    cf_plcsrv_opts_t so; /* the allow-list lands here */
    int order, use_syslog, sim;
    cf_log_level_t level;
    double tol, alpha, beta;
    const char *port_file, *stage, *probe, *board;
    cf_plcrun_t run;
    cf_plant_t plant;           /* results.db and the plant (cf_plant.h) */
    char *strs[SERVE_MAX_STRS]; /* copies of string values, freed at the end */
    int nstrs, lost;
} serve_conf_t;

static const char *keep(serve_conf_t *c, const char *v)
{
    char *s = c->nstrs < SERVE_MAX_STRS ? strdup(v) : NULL;
    if (s)
        c->strs[c->nstrs++] = s;
    c->lost |= !s; /* apply refuses: a setting must not silently become none */
    return s;
}

static int yesno(const char *v, int *out)
{
    if (!strcmp(v, "yes") || !strcmp(v, "1") || !strcmp(v, "true"))
        return *out = 1, 0;
    if (!strcmp(v, "no") || !strcmp(v, "0") || !strcmp(v, "false"))
        return *out = 0, 0;
    return -1;
}

/* "tcp:ADDR:PORT", ADDR an IPv4 address. */
static int parse_plc(serve_conf_t *c, const char *v)
{
    const char *colon = strrchr(v, ':');
    if (strncmp(v, "tcp:", 4) || !colon || colon < v + 4)
        return -1;
    size_t n = (size_t)(colon - (v + 4));
    if (n == 0 || n >= sizeof c->addr)
        return -1;
    memcpy(c->addr, v + 4, n);
    c->addr[n] = 0;
    struct in_addr ia;
    if (inet_pton(AF_INET, c->addr, &ia) != 1)
        return -1;
    return cli_int(colon + 1, 0, 65535, &c->port);
}

/* "a.b.c.d[/bits],..." into the allow-list. */
static int parse_allow(cf_plcsrv_opts_t *o, const char *v)
{
    char buf[512];
    if (strlen(v) >= sizeof buf)
        return -1;
    strcpy(buf, v);
    o->nallow = 0;
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        long bits = 32;
        char *sl = strchr(t, '/');
        if (sl) {
            *sl = 0;
            if (cli_int(sl + 1, 0, 32, &bits))
                return -1;
        }
        struct in_addr ia;
        if (o->nallow >= CF_PLC_MAX_ALLOW || inet_pton(AF_INET, t, &ia) != 1)
            return -1;
        uint32_t mask = bits ? 0xFFFFFFFFu << (32 - bits) : 0;
        o->allow_mask[o->nallow] = mask;
        o->allow_net[o->nallow++] = ntohl(ia.s_addr) & mask;
    }
    return o->nallow ? 0 : -1;
}

/* One setting, from the config file or an option. */
static int apply(void *ctx, const char *k, const char *v, char *msg, size_t ml)
{
    serve_conf_t *c = ctx;
    cf_plcrun_t *r = &c->run;
    long idx;
    int pr = cf_plant_apply(&c->plant, k, v, msg, ml); /* results and plant keys */
    if (pr <= 0)
        return pr ? CF_EARG : 0;
    if (!strcmp(k, "plc")) {
        if (parse_plc(c, v))
            return cf_fail(msg, ml, CF_EARG, "plc '%s': need tcp:ADDR:PORT (IPv4, port 0..65535)",
                           v);
    } else if (!strcmp(k, "word_order")) {
        if (!strcmp(v, "lo-hi"))
            c->order = PLC_ORDER_LO_HI;
        else if (!strcmp(v, "hi-lo"))
            c->order = PLC_ORDER_HI_LO;
        else
            return cf_fail(msg, ml, CF_EARG, "word_order '%s': lo-hi or hi-lo", v);
    } else if (!strcmp(k, "watchdog_ms")) {
        if (cli_int(v, 0, 60000, &c->watchdog_ms))
            return cf_fail(msg, ml, CF_EARG, "watchdog_ms '%s': need 0 (off) .. 60000", v);
    } else if (!strcmp(k, "max_clients")) {
        if (cli_int(v, 1, 64, &c->max_clients))
            return cf_fail(msg, ml, CF_EARG, "max_clients '%s': need 1 .. 64", v);
    } else if (!strcmp(k, "log_level")) {
        if (cf_log_parse_level(v, &c->level))
            return cf_fail(msg, ml, CF_EARG, "log_level '%s': error, warn, info or debug", v);
    } else if (!strcmp(k, "syslog")) {
        if (yesno(v, &c->use_syslog))
            return cf_fail(msg, ml, CF_EARG, "syslog '%s': yes or no", v);
    } else if (!strcmp(k, "sim")) {
        if (yesno(v, &c->sim))
            return cf_fail(msg, ml, CF_EARG, "sim '%s': yes or no", v);
    } else if (!strcmp(k, "max_rate")) {
        if (cli_double(v, &c->max_rate) || c->max_rate < 0 || c->max_rate > 1e6)
            return cf_fail(msg, ml, CF_EARG, "max_rate '%s': need 0 (off) .. 1e6 requests/s", v);
    } else if (!strcmp(k, "allow")) {
        if (parse_allow(&c->so, v))
            return cf_fail(msg, ml, CF_EARG,
                           "allow '%s': need IPv4 addresses or ADDR/BITS, comma-separated (at "
                           "most %d)",
                           v, CF_PLC_MAX_ALLOW);
    } else if (!strcmp(k, "z0")) {
        if (cli_double(v, &r->z0))
            return cf_fail(msg, ml, CF_EARG, "z0 '%s': need a height (mm)", v);
    } else if (!strcmp(k, "cal")) {
        char *e1, *e2, *e3;
        r->cal[0] = strtod(v, &e1);
        r->cal[1] = *e1 == ',' ? strtod(e1 + 1, &e2) : (e2 = e1, 0);
        r->cal[2] = *e2 == ',' ? strtod(e2 + 1, &e3) : (e3 = e2, 0);
        if (e1 == v || *e1 != ',' || *e2 != ',' || *e3)
            return cf_fail(msg, ml, CF_EARG, "cal '%s': need CX,CY,CZ (mm)", v);
    } else if (!strcmp(k, "tol") || !strcmp(k, "alpha") || !strcmp(k, "beta")) {
        double x;
        int tol = k[0] == 't';
        if (cli_double(v, &x) || x < (tol ? 0.0001 : 0) || x > (tol ? 100 : 1e6))
            return cf_fail(msg, ml, CF_EARG, "%s '%s': need %s", k, v,
                           tol ? "0.0001 .. 100 (mm)" : "0 .. 1e6");
        *(tol ? &c->tol : k[0] == 'a' ? &c->alpha : &c->beta) = x;
    } else if (!strcmp(k, "fit_to_tol")) {
        if (yesno(v, &r->fit.loop))
            return cf_fail(msg, ml, CF_EARG, "fit_to_tol '%s': yes or no", v);
    } else if (!strcmp(k, "robust")) {
        if (yesno(v, &r->fit.robust))
            return cf_fail(msg, ml, CF_EARG, "robust '%s': yes or no", v);
    } else if (!strcmp(k, "within")) {
        if (cli_double(v, &r->fit.within) || !(r->fit.within > 0) || r->fit.within > 100)
            return cf_fail(msg, ml, CF_EARG, "within '%s': need a percentage in (0, 100]", v);
    } else if (!strcmp(k, "max_cp")) {
        if (cli_int(v, 4, NF_MAX_CP, &r->fit.max_cp))
            return cf_fail(msg, ml, CF_EARG, "max_cp '%s': need 4 .. %ld (board %s)", v,
                           (long)NF_MAX_CP, BOARD_NAME);
    } else if (!strcmp(k, "max_rounds")) {
        if (cli_int(v, 1, CF_FITJOB_MAX_ROUNDS, &r->fit.max_rounds))
            return cf_fail(msg, ml, CF_EARG, "max_rounds '%s': need 1 .. %d", v,
                           CF_FITJOB_MAX_ROUNDS);
    } else if (!strcmp(k, "prune")) {
        if (cli_int(v, 0, CF_FITJOB_MAX_ROUNDS, &r->fit.prune))
            return cf_fail(msg, ml, CF_EARG, "prune '%s': need 0 (none) .. %d", v,
                           CF_FITJOB_MAX_ROUNDS);
    } else if (!strcmp(k, "min_gain")) {
        if (cli_double(v, &r->fit.min_gain) || !(r->fit.min_gain >= 1e-12) || r->fit.min_gain > 100)
            return cf_fail(msg, ml, CF_EARG, "min_gain '%s': need 1e-12 .. 100 (points of %%)", v);
    } else if (!strcmp(k, "robust_iters")) {
        if (cli_int(v, 1, 100, &r->fit.robust_iters))
            return cf_fail(msg, ml, CF_EARG, "robust_iters '%s': need 1 .. 100", v);
    } else if (!strcmp(k, "reparam")) {
        if (cli_int(v, 0, 100, &r->fit.reparam))
            return cf_fail(msg, ml, CF_EARG, "reparam '%s': need 0 .. 100", v);
    } else if (!strcmp(k, "refine")) {
        if (!strcmp(v, "uniform") || !strcmp(v, "residual") || !strcmp(v, "auto"))
            r->fit.refine = v[0] == 'u'   ? CF_REFINE_UNIFORM
                            : v[0] == 'r' ? CF_REFINE_RESIDUAL
                                          : CF_REFINE_AUTO;
        else
            return cf_fail(msg, ml, CF_EARG, "refine '%s': auto, uniform or residual", v);
    } else if (!strncmp(k, "results_dir", 11)) {
        idx = 0;
        if (k[11] && (k[11] != '.' || cli_int(k + 12, 0, PLC_MAX_FOLDERS - 1, &idx)))
            return cf_fail(msg, ml, CF_EARG, "%s: results_dir or results_dir.N, N 0 .. %d", k,
                           PLC_MAX_FOLDERS - 1);
        r->results_dir[idx] = keep(c, v);
    } else if (!strncmp(k, "nominal.", 8)) {
        if (cli_int(k + 8, 1, CF_PLCRUN_RECIPES - 1, &idx))
            return cf_fail(msg, ml, CF_EARG, "%s: nominal.N, N 1 .. %d (RECIPE)", k,
                           CF_PLCRUN_RECIPES - 1);
        r->recipe[idx] = keep(c, v);
    } else if (!strcmp(k, "idle_ms")) {
        if (cli_int(v, 1000, 3600000, &c->idle_ms))
            return cf_fail(msg, ml, CF_EARG, "idle_ms '%s': need 1000 .. 3600000", v);
    } else if (!strcmp(k, "nominal"))
        r->nominal = keep(c, v);
    else if (!strcmp(k, "points"))
        r->points = keep(c, v);
    else if (!strcmp(k, "checks"))
        r->checks = keep(c, v);
    else if (!strcmp(k, "port_file"))
        c->port_file = keep(c, v);
    else if (!strcmp(k, "stage"))
        c->stage = keep(c, v);
    else if (!strcmp(k, "probe"))
        c->probe = keep(c, v);
    else if (!strcmp(k, "sim_args"))
        c->sim_args = keep(c, v);
    else if (!strcmp(k, "scan_method")) { /* issue 19: cf_scanfast.h */
        r->scan_method = cf_scanfast_method(v);
        if (r->scan_method < 0)
            return cf_fail(msg, ml, CF_EARG, "scan_method '%s': stop, otf or profiler", v);
    } else if (!strcmp(k, "scan_period_us")) {
        if (cli_double(v, &r->scan_period_us) || !(r->scan_period_us >= 20) ||
            r->scan_period_us > 1e6)
            return cf_fail(msg, ml, CF_EARG, "scan_period_us '%s': need 20 .. 1000000", v);
    } else if (!strcmp(k, "min_free_mb")) {
        double mb;
        if (cli_double(v, &mb) || !(mb >= 0) || mb > 1e9)
            return cf_fail(msg, ml, CF_EARG, "min_free_mb '%s': need 0 .. 1e9 (MiB)", v);
        r->min_free = mb > 0 ? mb * 1024.0 * 1024.0 : 1.0; /* 0: only the job's own bytes */
    } else if (!strcmp(k, "journal_dir"))
        r->journal_dir = keep(c, v);
    else if (!strcmp(k, "board"))
        c->board = keep(c, v);
    else
        return cf_fail(msg, ml, CF_EARG, "unknown setting '%s'", k);
    if (c->lost)
        return cf_fail(msg, ml, CF_EARG, "%s: more than %d file, directory and device settings", k,
                       SERVE_MAX_STRS);
    return 0;
}

/* dir and its missing parents, as `mkdir -p`: 0, or -1 with errno. */
static int mkdir_p(const char *dir)
{
    char buf[4096];
    if (strlen(dir) >= sizeof buf)
        return errno = ENAMETOOLONG, -1;
    strcpy(buf, dir);
    for (char *q = buf + 1; *q; q++)
        if (*q == '/') {
            *q = 0;
            if (mkdir(buf, 0775) && errno != EEXIST)
                return -1;
            *q = '/';
        }
    return mkdir(buf, 0775) && errno != EEXIST ? -1 : 0;
}

/* The results and journal folders made at start when missing (the first
 * job must not fail on a folder nobody created). One that cannot be made
 * is a warning: it may appear later (a share mounted after boot); a job
 * that needs it is refused when accepted (108) while it is missing. */
static void make_folders(const cf_plcrun_t *r)
{
    const char *dirs[PLC_MAX_FOLDERS + 1];
    int n = 0;
    for (int i = 0; i < PLC_MAX_FOLDERS; i++)
        if (r->results_dir[i])
            dirs[n++] = r->results_dir[i];
    if (r->journal_dir)
        dirs[n++] = r->journal_dir;
    for (int i = 0; i < n; i++) {
        struct stat st;
        if (!stat(dirs[i], &st) && S_ISDIR(st.st_mode))
            continue;
        if (mkdir_p(dirs[i]))
            cf_log(CF_LOG_WARN, "cannot create the folder %s: %s (jobs that need it are refused)",
                   dirs[i], strerror(errno));
        else
            cf_log(CF_LOG_INFO, "created the folder %s", dirs[i]);
    }
}

static volatile sig_atomic_t stop_flag;

static void on_signal(int sig)
{
    (void)sig;
    stop_flag = 1;
}

/* The settings that are also options: --name for key name ('_' as '-'),
 * in the order of docs/plc-register-map.md's table. */
typedef struct serve_key {
    const char *key, *arg, *help, *def;
} serve_key_t;

static const serve_key_t keys[] = {
    {"plc", "tcp:ADDR:PORT", "the Modbus TCP server's address (IPv4; port 0: a free one)",
     "(required)"},
    {"port_file", "FILE", "write the port actually bound here", NULL},
    {"word_order", "ORDER", "lo-hi or hi-lo (WORD_ORDER at start)", "lo-hi"},
    {"watchdog_ms", "MS", "WATCHDOG_MS at start, 0 off", "0"},
    {"max_clients", "N", "Modbus connections at once (1 .. 64)", "8"},
    {"idle_ms", "MS", "a connection without a request for this long is closed (1000 .. 3600000)",
     "60000"},
    {"nominal", "FILE", "the nominal surface (FIT, SCAN_FIT), IGES entity 128", NULL},
    {"points", "FILE", "the points file FIT fits: x y z or u v x y z", NULL},
    {"checks", "FILE",
     "check points and zones (NAME X Y Z [RADIUS] a line): EXPORT's report.dfq and report.json "
     "carry their deviations",
     NULL},
    {"results_dir", "DIR", "results folder 0 (config: results_dir.N for choice N)", NULL},
    {"tol", "MM", "TOLERANCE at start: the deviation tolerance", "0.05"},
    {"alpha", "A", "ALPHA at start (Eq. 7)", "0.1"},
    {"beta", "B", "BETA at start (Eq. 7)", "0.001"},
    {"within", "PCT", "with fit_to_tol: the share of points within tol (FIT_WITHIN)", "100"},
    {"max_cp", "N", "with fit_to_tol: control points the loop may reach at most", "the board's"},
    {"max_rounds", "N", "with fit_to_tol: rounds of the loop at most", "12"},
    {"min_gain", "PTS",
     "with fit_to_tol, refine auto: stop after two rounds in a row gaining less than this many "
     "points of the share within tol",
     "0.1"},
    {"prune", "N",
     "with fit_to_tol, refine auto, once met: trial fits each with one inserted knot line taken "
     "out again, kept while within holds (0: none)",
     "4"},
    {"refine", "HOW",
     "with fit_to_tol: auto (knot lines scored per control point added), uniform or residual "
     "knot insertion (FIT_REFINE 2, 0, 1)",
     "auto"},
    {"robust_iters", "N", "with robust: Tukey passes", "3"},
    {"reparam", "K", "reprojection passes onto the fit, each refitted", "0"},
    {"log_level", "LEVEL", "error, warn, info or debug", "info"},
    {"board", "NAME", "must name the board this cellfit is built for", NULL},
    {"stage", "URI", "the rig's stage (docs/rig-devices.md)", NULL},
    {"probe", "URI", "the rig's probe", NULL},
    {"sim_args", "ARGS", "extra cellsim arguments, space-separated",
     "--speed 5000 --seed 1 --part NOMINAL"},
    {"scan_method", "M",
     "SCAN's method: stop (stop-and-go), otf (on the fly) or profiler (--sim: cellsim's GigE "
     "Vision line profiler)",
     "stop"},
    {"scan_period_us", "US",
     "scan_method otf: the trigger period; the stage runs at SCAN_STEP / it", "50"},
    {"journal_dir", "DIR", "folder of the scans' journals", "the results folder"},
    {"min_free_mb", "MB",
     "MiB a scan's journal folder and an export's results folder keep free beyond the job's own "
     "bytes (checked when the job is accepted: 108)",
     "1"},
    {"z0", "MM", "the probe's beam height", "50"},
    {"cal", "CX,CY,CZ", "the probe's calibration offset, mm", "0,0,0"},
    {"allow", "ADDR[/BITS],...", "client addresses allowed (IPv4, up to 16)", "any"},
    {"max_rate", "R", "requests a second per client, 0 no limit", "1000"},
    {"results_db", "FILE", "the cell's SQLite database of every job (docs/plant.md)",
     "results.db in results folder 0"},
    {"cell_id", "NAME", "this cell's name in the results, topics and plant database",
     "the host's name"},
    {"plant_db", "URL",
     "forward every job to PostgreSQL: postgresql://USER@HOST:PORT/DB (the "
     "password from the config's plant_db_password or PGPASSWORD)",
     NULL},
    {"mqtt", "URL",
     "publish every job and the cell's state: mqtt://HOST:PORT/PREFIX (the "
     "password from the config's mqtt_password)",
     NULL},
    {"mqtt_username", "USER", "the MQTT user", NULL},
    {"mqtt_cafile", "FILE", "MQTT over TLS: the CA certificate", NULL},
    {"mqtt_certfile", "FILE", "MQTT over TLS: the client certificate", NULL},
    {"mqtt_keyfile", "FILE", "MQTT over TLS: the client key", NULL},
    {"outbox_max", "N", "outbox entries kept at most (the oldest dropped and counted)", NULL},
    {"forward_backoff_max", "S", "longest wait between forwarding retries, seconds", NULL},
};
#define NKEYS ((int)(sizeof keys / sizeof keys[0]))

/* Yes/no settings, given as flags. */
enum { F_SYSLOG, F_SIM, F_FIT_TO_TOL, F_ROBUST, NFLAGS };
static const serve_key_t flag_keys[NFLAGS] = {
    {"syslog", NULL, "log to syslog (facility daemon) instead of stderr", NULL},
    {"sim", NULL, "the simulated rig: cellsim started as a child on 127.0.0.1", NULL},
    {"fit_to_tol", NULL,
     "FIT and SCAN_FIT run the tolerance loop (fit, check, insert knots) to tol (FIT_TOL at "
     "start)",
     NULL},
    {"robust", NULL, "FIT and SCAN_FIT fit robustly (Tukey passes against outliers)", NULL},
};

/* The config file first (--config), then the options over it. */
static int parse(int argc, char **argv, serve_conf_t *c, int *print_map)
{
    char msg[1024], names[NKEYS + NFLAGS][32];
    const char *val[NKEYS] = {0}, *config = NULL;
    int flag[NFLAGS] = {0};
    cf_opt_t opts[NKEYS + NFLAGS + 3];
    int n = 0;
    opts[n++] = (cf_opt_t){.name = "config",
                           .kind = CF_OPT_STR,
                           .dst = &config,
                           .arg = "FILE",
                           .help = "settings, key = value a line (options override them)"};
    for (int i = 0; i < NKEYS + NFLAGS; i++) {
        const serve_key_t *k = i < NKEYS ? &keys[i] : &flag_keys[i - NKEYS];
        snprintf(names[i], sizeof names[i], "%s",
                 !strcmp(k->key, "results_dir") ? "results" : k->key);
        for (char *p = names[i]; *p; p++)
            *p = *p == '_' ? '-' : *p;
        opts[n++] = (cf_opt_t){.name = names[i],
                               .kind = i < NKEYS ? CF_OPT_STR : CF_OPT_FLAG,
                               .dst = i < NKEYS ? (void *)&val[i] : (void *)&flag[i - NKEYS],
                               .arg = k->arg,
                               .help = k->help,
                               .def = k->def};
    }
    opts[n++] = (cf_opt_t){.name = "print-map",
                           .kind = CF_OPT_FLAG,
                           .dst = print_map,
                           .help = "print the register map (docs/plc-register-map.md) and exit"};
    opts[n] = (cf_opt_t){0};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "serve",
                          .summary = "the cell headless, driven by a PLC over Modbus TCP "
                                     "(docs/plc-register-map.md)",
                          .descr = "Every option is also a config key: its name without the "
                                   "dashes, '-' as '_' (--results is results_dir).",
                          .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return rc;
    if (config && cf_conf_read(config, apply, c, msg, sizeof msg))
        return cli_error("serve", CLI_USAGE, "%s", msg);
    for (int i = 0; i < NKEYS; i++)
        if (val[i] && apply(c, keys[i].key, val[i], msg, sizeof msg))
            return cli_error("serve", CLI_USAGE, "--%s: %s", names[i], msg);
    for (int i = 0; i < NFLAGS; i++)
        if (flag[i])
            apply(c, flag_keys[i].key, "yes", msg, sizeof msg);
    return CLI_OK;
}

int cmd_serve(int argc, char **argv)
{
    serve_conf_t c;
    memset(&c, 0, sizeof c);
    cf_plant_init(&c.plant);
    c.port = -1;
    c.max_clients = 8;
    c.level = CF_LOG_INFO;
    c.tol = 0.05;
    c.alpha = NF_ALPHA_DEFAULT;
    c.beta = NF_BETA_DEFAULT;
    c.max_rate = 1000;
    c.run.z0 = 50.0; /* cellsim's beam height */
    cf_fitjob_defaults(&c.run.fit);
    /* FIT's passes on two cores where there are two (as cellfit fit's) */
    c.run.fit.cores = sysconf(_SC_NPROCESSORS_ONLN) >= 2 ? 2 : 1;
    int print_map = 0, ec = parse(argc, argv, &c, &print_map);
    if (ec) {
        ec = cf_opt_exit(ec);
        goto done;
    }
    if (print_map) {
        cf_plcdoc_print(stdout);
        goto done;
    }
    if (c.port < 0) {
        ec = cli_error("serve", CLI_USAGE, "need --plc tcp:ADDR:PORT (or plc = in --config)");
        goto done;
    }
    if (c.board && strcmp(c.board, BOARD_NAME)) {
        ec = cli_error("serve", CLI_USAGE, "--board %s: this cellfit is built for board %s",
                       c.board, BOARD_NAME);
        goto done;
    }
    if (c.run.scan_method == CF_SCAN_PROFILER && !c.sim) {
        /* No configured gev: probe yet: the simulated profiler only. */
        ec = cli_error("serve", CLI_USAGE, "scan_method profiler needs --sim (cellsim --gev)");
        goto done;
    }
    if (c.sim && (c.stage || c.probe)) {
        ec = cli_error("serve", CLI_USAGE, "--sim or --stage/--probe, not both");
        goto done;
    }
    if (!c.sim && (!c.stage) != (!c.probe)) {
        ec = cli_error("serve", CLI_USAGE, "%s: the rig needs both --stage URI and --probe URI",
                       c.stage ? "--stage" : "--probe");
        goto done;
    }
    cf_log_open(c.level, c.use_syslog);
#ifdef M_MMAP_THRESHOLD
    /* A fixed threshold: glibc raises it after the first large free, and a
     * job's large buffers then stay resident in the heap after the job;
     * mapped, they go back to the system between jobs (plc_rig's soak: RSS
     * +2.3 MB after the first jobs without this, +0.2 MB with it). */
    mallopt(M_MMAP_THRESHOLD, 128 * 1024);
#endif
    /* The port file first: a live serve's is never taken over (nothing
     * started), a stale one (its serve killed) is replaced (cf_portfile.h). */
    cf_portfile_t pf = {-1, ""};
    char msg[512];
    if (c.port_file && cf_portfile_claim(&pf, c.port_file, msg, sizeof msg)) {
        ec = cli_error("serve", CLI_FAIL, "%s", msg);
        goto done_log;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal; /* no SA_RESTART: select returns EINTR */
    sigemptyset(&sa.sa_mask);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);
    /* The simulator first (fork before any thread), then the rig on it. */
    cf_simchild_t sim;
    memset(&sim, 0, sizeof sim);
    if (c.sim) {
        /* Without sim_args the simulator runs at the doc's speed with the
         * nominal as its part (cellsim's own default stage is a slow
         * real-time 200 mm/s). */
        char simdef[4200];
        if (!c.sim_args) {
            const char *nom = c.run.nominal;
            int part = nom && !strpbrk(nom, " \t") && strlen(nom) < 4096;
            snprintf(simdef, sizeof simdef, "%s%s%s", CF_SERVE_SIM_ARGS, part ? " --part " : "",
                     part ? nom : "");
            c.sim_args = simdef;
            cf_log(CF_LOG_INFO, "rig: cellsim with the default sim_args \"%s\"", simdef);
        }
        /* The profiler: cellsim's fake GigE Vision camera (port 3956). */
        char simgev[4300];
        if (c.run.scan_method == CF_SCAN_PROFILER) {
            snprintf(simgev, sizeof simgev, "%s --gev cfserve", c.sim_args);
            c.sim_args = simgev;
        }
        if (cf_simchild_start(&sim, c.sim_args, 10000, msg, sizeof msg)) {
            ec = cli_error("serve", CLI_FAIL, "%s", msg);
            goto done_log;
        }
        if (c.run.scan_method == CF_SCAN_PROFILER) {
            if (!sim.gev_uri[0] || cf_scanfast_geom_parse(sim.gev_geom, &c.run.gev_geom)) {
                ec = cli_error("serve", CLI_FAIL, "--sim: cellsim gave no profiler line");
                goto done_sim;
            }
            c.run.gev_uri = sim.gev_uri;
            cf_log(CF_LOG_INFO, "rig: profiler %s, %s", sim.gev_uri, sim.gev_geom);
        }
        c.stage = sim.stage;
        c.probe = sim.probe;
        c.run.sim = &sim;
        cf_log(CF_LOG_INFO, "rig: cellsim pid %ld on 127.0.0.1:%d", (long)sim.pid, sim.port);
    }
    if (c.stage) {
        hal_opts_t ho = HAL_OPTS_DEFAULT;
        int rc = hal_rig_open(c.stage, c.probe, &ho, &c.run.rig, msg, sizeof msg);
        if (rc) {
            ec = cli_error("serve", rc == RIG_EARG ? CLI_USAGE : CLI_FAIL, "rig: %s", msg);
            goto done_sim;
        }
        cf_log(CF_LOG_INFO, "rig: stage %s, probe %s", c.stage, c.probe);
    }
    make_folders(&c.run);
    cf_runner_t runner;
    cf_plcrun_init(&c.run, &runner);
    if (cf_plant_start(&c.plant, &c.run, c.run.results_dir[0], &runner, &runner, msg, sizeof msg)) {
        ec = cli_error("serve", CLI_FAIL, "results: %s", msg);
        cf_plcrun_free(&c.run);
        goto done_rig;
    }
    cf_plcsrv_opts_t so = c.so;
    so.addr = c.addr;
    so.port = (int)c.port;
    so.max_clients = (int)c.max_clients;
    so.word_order = c.order;
    so.watchdog_ms = (unsigned)c.watchdog_ms;
    so.port_file = c.port_file;
    so.portfile = c.port_file ? &pf : NULL;
    so.tol = (float)c.tol;
    so.alpha = (float)c.alpha;
    so.beta = (float)c.beta;
    so.max_rate = c.max_rate;
    so.idle_ms = (unsigned)c.idle_ms;
    /* The config's fit settings are the registers' defaults (FIT_TOL ..
     * FIT_REPARAM): fit_to_tol loops to TOLERANCE. */
    so.fit_tol = c.run.fit.loop ? (float)c.tol : 0.0f;
    so.fit_within = (float)c.run.fit.within;
    so.fit_max_cp = c.run.fit.max_cp >= NF_MAX_CP ? 0u : (uint32_t)c.run.fit.max_cp;
    so.fit_refine = c.run.fit.refine == CF_REFINE_UNIFORM    ? PLC_REFINE_UNIFORM
                    : c.run.fit.refine == CF_REFINE_RESIDUAL ? PLC_REFINE_RESIDUAL
                                                             : PLC_REFINE_AUTO;
    /* Map version 3: the outbox (results.db, when jobs are recorded) and
     * the last scan's counts as registers. */
    cf_plcstats_t stats;
    cf_plcstats_start(&stats, &c.run, c.plant.started ? c.plant.db_path : NULL);
    so.stats = cf_plcstats_read;
    so.stats_ctx = &stats;
    so.fit_robust = (uint16_t)(c.run.fit.robust != 0);
    so.fit_reparam = (uint16_t)c.run.fit.reparam;
    cf_log(CF_LOG_INFO, "cellfit serve: board %s, nominal %s, points %s, results %s", BOARD_NAME,
           c.run.nominal ? c.run.nominal : "(none)", c.run.points ? c.run.points : "(none)",
           c.run.results_dir[0] ? c.run.results_dir[0] : "(none)");
    const cf_fitjob_opts_t *fo = &c.run.fit;
    cf_log(CF_LOG_INFO,
           "fit defaults (FIT_TOL .. FIT_REPARAM): %s%g mm%s, within %g %%, robust %s, reparam %ld",
           fo->loop ? "loop to " : "plain (FIT_TOL 0; tol ", c.tol,
           fo->loop ? (fo->refine == CF_REFINE_UNIFORM    ? " (uniform)"
                       : fo->refine == CF_REFINE_RESIDUAL ? " (residual)"
                                                          : " (auto)")
                    : ")",
           fo->within, fo->robust ? "yes" : "no", fo->reparam);
    ec = cf_plcsrv_run(&so, &runner, &stop_flag) ? CLI_FAIL : CLI_OK;
    cf_plcstats_close(&stats);
    cf_plant_stop(&c.plant);
    cf_plcrun_free(&c.run);
done_rig:
    if (c.run.rig)
        hal_rig_close(c.run.rig);
done_sim:
    if (c.sim) {
        int lost = sim.ended;
        cf_simchild_stop(&sim);
        if (!lost)
            cf_log(CF_LOG_INFO, "rig: cellsim pid %ld stopped", (long)sim.pid);
    }
done_log:
    cf_portfile_release(&pf, 1); /* ours (fd -1 when not claimed) */
    cf_log_close();
done:
    cf_plant_stop(&c.plant);
    for (int i = 0; i < c.nstrs; i++)
        free(c.strs[i]);
    return ec;
}
