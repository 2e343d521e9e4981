/* SPDX-License-Identifier: MIT */
/* sim_main.c: cellsim, the simulated rig on the real wire protocols:
 * options, the part, the stage and probe models, the servers, the control
 * file, and the "ready" lines tests wait for. */
#include "cf_cli.h"
#include "cf_cpu.h"
#include "cf_opt.h"
#include "hal_regmap.h"
#include "sim.h"
#include "sim_gev.h"
#include "sim_net.h"
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t g_stop;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

/* What --help says beyond the option lines: the wires, the part, the
 * fault language and the start-up lines tests wait for. */
static const char descr[] =
    "Servers: at least one of --tcp, --rtu, --ascii (up to 8 in all) or --gev. Every Modbus server "
    "carries the stage (holding registers, --stage-unit; on TCP also units 0 and 255) and the "
    "probe (input registers, --probe-unit). docs/rig-devices.md has the register map.\n"
    "The part: the nominal (--part, or the built-in panel: cellfit gen's nominal, 200 x 150 mm, "
    "40 x 30 bicubic) plus the dent and warp of lib/cf_part.h. The probe's kinematic model: a "
    "point is (sx + ox, sy + oy, z0 - d); out of range outside --range or off the part.\n"
    "Faults (--fault, repeatable): KIND[@WIRE]:WHEN[:MS]\n"
    "  KIND   crc     RTU: CRC bit flipped; TCP: transaction id flipped; ASCII: garble\n"
    "         garble  one reply byte changed       drop    one reply byte left out\n"
    "         slow    reply held back MS ms          silent  no reply\n"
    "         disconnect  the line or server closed for MS ms\n"
    "         busy    Modbus exception 06\n"
    "         nosurf  probe reads out of range       proberr probe error (ER,M0,01)\n"
    "         stagefault  the move faults half-way (drive fault latched)\n"
    "  WIRE   tcp | rtu | ascii: count and hit only requests on that wire\n"
    "  WHEN   nK: at the K-th event only; eK: every K-th; pP: with probability P;\n"
    "         sK (reply faults, Modbus): the reply carrying stream entry K of each arming\n"
    "         events: wire faults count requests, nosurf/proberr probe readings,\n"
    "         stagefault accepted moves; each fault counts its own\n"
    "  e.g. --fault crc@rtu:n3 --fault slow:n5:800 --fault disconnect@tcp:n10:500\n"
    "The control file (--control) is polled every 100 ms; when it exists its lines are obeyed "
    "and it is removed: 'fault SPEC' (counting from now), 'estop on|off', 'stagefault' (latch "
    "a drive fault now). Holding registers 100 (E-stop 1/0) and 101 (write 1: drive fault) do "
    "the same.\n"
    "Start-up: prints 'cellsim: tcp 127.0.0.1 PORT', 'cellsim: rtu PATH', 'cellsim: ascii "
    "PATH' and last 'cellsim: ready pid PID' on stdout. SIGTERM or SIGINT stops it (exit 0).";

/* "a,b[,c,d]": exactly n comma-separated finite numbers. */
static int pair(const char *s, int n, double *out)
{
    char buf[128];
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    char *p = buf;
    for (int i = 0; i < n; i++) {
        char *c = strchr(p, ',');
        if ((i < n - 1) != (c != NULL))
            return -1;
        if (c)
            *c = '\0';
        if (cli_double(p, &out[i]))
            return -1;
        p = c ? c + 1 : p;
    }
    return 0;
}

static int offset_arg(const char *v, void *dst)
{
    return pair(v, 2, dst);
}

static int range_arg(const char *v, void *dst)
{
    double r[2];
    if (pair(v, 2, r) || !(r[0] < r[1]))
        return -1;
    memcpy(dst, r, sizeof r);
    return 0;
}

static int limits_arg(const char *v, void *dst)
{
    double l[4];
    if (pair(v, 4, l) || !(l[0] < l[1] && l[2] < l[3]))
        return -1;
    memcpy(dst, l, sizeof l);
    return 0;
}

static int positive(const char *v, void *dst)
{
    double d;
    if (cli_double(v, &d) || !(d > 0))
        return -1;
    *(double *)dst = d;
    return 0;
}

/* --tcp PORT, --rtu PATH, --ascii PATH: one more server each time. */
static int add_port(sim_net_t *net, int wire, const char *v)
{
    long port = 0;
    if (net->nports == SIM_MAX_PORTS)
        return -1;
    sim_port_t *p = &net->port[net->nports];
    if (wire == SIM_W_TCP ? cli_int(v, 0, 65535, &port) : strlen(v) >= sizeof p->path || !v[0])
        return -1;
    p->wire = wire;
    p->tcp_port = (int)port;
    if (wire != SIM_W_TCP)
        strcpy(p->path, v);
    p->fd = -1;
    net->nports++;
    return 0;
}

static int tcp_arg(const char *v, void *dst)
{
    return add_port(dst, SIM_W_TCP, v);
}

static int rtu_arg(const char *v, void *dst)
{
    return add_port(dst, SIM_W_RTU, v);
}

static int ascii_arg(const char *v, void *dst)
{
    return add_port(dst, SIM_W_ASCII, v);
}

/* --fault SPEC, repeatable: the specs are kept and parsed after the
 * options, so a bad one is reported with sim_fault_parse's reason. */
typedef struct fault_specs {
    const char *v[SIM_MAX_FAULTS];
    int n;
} fault_specs_t;

static int fault_arg(const char *v, void *dst)
{
    fault_specs_t *fs = dst;
    if (fs->n == SIM_MAX_FAULTS)
        return -1;
    fs->v[fs->n++] = v;
    return 0;
}

static int add_fault(sim_faults_t *fs, const char *spec)
{
    char msg[256];
    if (fs->n == SIM_MAX_FAULTS) {
        fprintf(stderr, "cellsim: more than %d faults\n", SIM_MAX_FAULTS);
        return -1;
    }
    if (sim_fault_parse(spec, &fs->f[fs->n], msg, sizeof msg)) {
        fprintf(stderr, "cellsim: %s\n", msg);
        return -1;
    }
    fs->n++;
    return 0;
}

/* The control file: obeyed line by line, then removed. */
static void control(const char *path, sim_faults_t *fs, sim_stage_t *st)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    char line[256];
    int ln = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        line[strcspn(line, "\r\n")] = '\0';
        if (!line[0] || line[0] == '#')
            continue;
        if (!strncmp(line, "fault ", 6))
            add_fault(fs, line + 6);
        else if (!strcmp(line, "estop on") || !strcmp(line, "estop off"))
            sim_stage_set_estop(st, sim_now_ms(), line[7] == 'n');
        else if (!strcmp(line, "stagefault"))
            sim_stage_latch_fault(st, sim_now_ms());
        else
            fprintf(stderr, "cellsim: %s:%d: unknown control '%s'\n", path, ln, line);
    }
    fclose(f);
    unlink(path);
}

int main(int argc, char **argv)
{
    cf_cpu_from_env();
    static sim_net_t net;
    static sim_faults_t faults;
    static sim_stage_t stage;
    static sim_probe_t probe;
    static sim_part_t part;
    sim_rig_t rig = {&stage, &probe, HAL_STAGE_UNIT, HAL_PROBE_UNIT};
    const char *part_path = NULL, *pidfile = NULL, *ctl = NULL;
    double dent = -1, warp = 0, z0 = 50, off[2] = {0, 0}, range[2] = {30, 60}, noise = 0.002;
    double speed = 200, settle = 0, lim[4] = {-10, 210, -10, 160};
    long seed = 1;
    long fifo = 0;
    int homed = 0, verbose = 0, warp_set = 0;
    int stage_unit = HAL_STAGE_UNIT, probe_unit = HAL_PROBE_UNIT;
    fault_specs_t specs = {{0}, 0};
    sim_gev_cfg_t gev = {
        .width = 1024, .height = 64, .profiles = 256, .scale = 0.001, .flank_deg = 60};
    sim_gev_t *gevs = NULL;
    sim_stage_init(&stage, &faults);
    const cf_opt_t opts[] = {
        {.name = "tcp",
         .kind = CF_OPT_FUNC,
         .dst = &net,
         .arg = "PORT",
         .help = "a Modbus TCP server on 127.0.0.1:PORT (0: a free port, printed)",
         .fn = tcp_arg,
         .fn_what = "a port 0..65535 (8 servers at most)"},
        {.name = "rtu",
         .kind = CF_OPT_FUNC,
         .dst = &net,
         .arg = "PATH",
         .help = "a Modbus RTU server on the tty PATH (e.g. one end of a socat pty pair)",
         .fn = rtu_arg,
         .fn_what = "a tty path (8 servers at most)"},
        {.name = "ascii",
         .kind = CF_OPT_FUNC,
         .dst = &net,
         .arg = "PATH",
         .help = "the probe's ASCII protocol on the tty PATH",
         .fn = ascii_arg,
         .fn_what = "a tty path (8 servers at most)"},
        {.name = "stage-unit",
         .kind = CF_OPT_INT,
         .dst = &stage_unit,
         .arg = "UNIT",
         .help = "the stage's Modbus unit",
         .lo = 1,
         .hi = 247},
        {.name = "probe-unit",
         .kind = CF_OPT_INT,
         .dst = &probe_unit,
         .arg = "UNIT",
         .help = "the probe's Modbus unit",
         .lo = 1,
         .hi = 247},
        {.name = "gev",
         .kind = CF_OPT_STR,
         .dst = &gev.serial,
         .arg = "SERIAL",
         .help = "the laser line profiler: Aravis's fake GigE Vision camera on 127.0.0.1 (port "
                 "3956: one per machine), opened as gev:127.0.0.1:SERIAL (docs/rig-profiler.md)"},
        {.name = "gev-loss",
         .kind = CF_OPT_DOUBLE,
         .dst = &gev.loss,
         .arg = "R",
         .help = "the profiler's GVSP packet loss ratio",
         .lo = 0,
         .hi = 1},
        {.name = "gev-width",
         .kind = CF_OPT_INT,
         .dst = &gev.width,
         .arg = "W",
         .help = "points per profile",
         .lo = 2,
         .hi = 2048},
        {.name = "gev-height",
         .kind = CF_OPT_INT,
         .dst = &gev.height,
         .arg = "H",
         .help = "profiles a frame",
         .lo = 1,
         .hi = 2048},
        {.name = "gev-profiles",
         .kind = CF_OPT_LONG,
         .dst = &gev.profiles,
         .arg = "P",
         .help = "profiles over one pass of the part",
         .lo = 2,
         .hi = 100000},
        {.name = "fifo",
         .kind = CF_OPT_LONG,
         .dst = &fifo,
         .arg = "N",
         .help = "entries the probe's streaming FIFO holds (a small one overflows: the overrun "
                 "fault of tests/cli/scan_fast.sh)",
         .lo = 1,
         .hi = 65536,
         .def = "65536"},
        {.name = "gev-scale",
         .kind = CF_OPT_DOUBLE,
         .dst = &gev.scale,
         .arg = "MM",
         .help = "mm per range count",
         .lo = 1e-9,
         .hi = 1e3},
        {.name = "gev-flank",
         .kind = CF_OPT_DOUBLE,
         .dst = &gev.flank_deg,
         .arg = "DEG",
         .help = "no reading on flanks steeper than DEG degrees",
         .lo = 1e-6,
         .hi = 90},
        {.name = "part",
         .kind = CF_OPT_STR,
         .dst = &part_path,
         .arg = "FILE.igs",
         .help = "the nominal surface (first entity 128)",
         .def = "the built-in panel"},
        {.name = "dent-depth",
         .kind = CF_OPT_DOUBLE,
         .dst = &dent,
         .arg = "MM",
         .help = "depth of the dent (0: none)",
         .lo = 0,
         .hi = 1e308,
         .def = "0.4"},
        {.name = "warp",
         .kind = CF_OPT_DOUBLE,
         .dst = &warp,
         .arg = "MM",
         .help = "twist of the part (0: none)",
         .lo = 1,
         .hi = 0,
         .def = "0.3",
         .given = &warp_set},
        {.name = "z0",
         .kind = CF_OPT_DOUBLE,
         .dst = &z0,
         .arg = "MM",
         .help = "height of the probe's beam origin",
         .lo = 1,
         .hi = 0},
        {.name = "offset",
         .kind = CF_OPT_FUNC,
         .dst = off,
         .arg = "OX,OY",
         .help = "the beam's offset from the stage position",
         .fn = offset_arg,
         .fn_what = "two numbers OX,OY (mm)",
         .def = "0,0"},
        {.name = "range",
         .kind = CF_OPT_FUNC,
         .dst = range,
         .arg = "LO,HI",
         .help = "the probe's measuring range",
         .fn = range_arg,
         .fn_what = "two numbers LO,HI with LO < HI (mm)",
         .def = "30,60"},
        {.name = "noise",
         .kind = CF_OPT_DOUBLE,
         .dst = &noise,
         .arg = "SIGMA",
         .help = "Gaussian noise on the distance, mm",
         .lo = 0,
         .hi = 1e308},
        {.name = "seed",
         .kind = CF_OPT_LONG,
         .dst = &seed,
         .arg = "S",
         .help = "seeds the noise and the fault probabilities",
         .lo = 0,
         .hi = 4611686018427387904.0},
        {.name = "speed",
         .kind = CF_OPT_FUNC,
         .dst = &speed,
         .arg = "MM/S",
         .help = "the stage's speed, both axes",
         .fn = positive,
         .fn_what = "a number > 0",
         .def = "200"},
        {.name = "settle-ms",
         .kind = CF_OPT_DOUBLE,
         .dst = &settle,
         .arg = "MS",
         .help = "the stage's settling time after each move",
         .lo = 0,
         .hi = 1e308},
        {.name = "limits",
         .kind = CF_OPT_FUNC,
         .dst = lim,
         .arg = "XLO,XHI,YLO,YHI",
         .help = "the stage's soft limits; home is (0,0)",
         .fn = limits_arg,
         .fn_what = "four numbers XLO,XHI,YLO,YHI with XLO < XHI, YLO < YHI (mm)",
         .def = "-10,210,-10,160"},
        {.name = "homed",
         .kind = CF_OPT_FLAG,
         .dst = &homed,
         .help = "start homed, at home (else unreferenced at 37.5,12.25)"},
        {.name = "fault",
         .kind = CF_OPT_FUNC,
         .dst = &specs,
         .arg = "KIND[@WIRE]:WHEN[:MS]",
         .help = "inject a fault (repeatable; the language below)",
         .fn = fault_arg,
         .fn_what = "a fault spec (32 at most)",
         .def = "none"},
        {.name = "control",
         .kind = CF_OPT_STR,
         .dst = &ctl,
         .arg = "FILE",
         .help = "a control file, polled every 100 ms (below)"},
        {.name = "pidfile",
         .kind = CF_OPT_STR,
         .dst = &pidfile,
         .arg = "FILE",
         .help = "write the PID to FILE (removed at exit)"},
        {.name = "verbose",
         .kind = CF_OPT_FLAG,
         .dst = &verbose,
         .help = "log faults and line events on stderr"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellsim",
                          .summary = "the simulated rig on the real wire protocols "
                                     "(docs/rig-devices.md)",
                          .descr = descr,
                          .opts = opts};
    int prc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (prc)
        return cf_opt_exit(prc);
    for (int k = 0; k < specs.n; k++)
        if (add_fault(&faults, specs.v[k]))
            return 2;
    rig.stage_unit = stage_unit;
    rig.probe_unit = probe_unit;
    if (gev.serial && (!gev.serial[0] || strlen(gev.serial) > 15)) {
        fprintf(stderr, "cellsim: --gev '%s': a serial of 1 to 15 characters\n", gev.serial);
        return 2;
    }
    if (!net.nports && !gev.serial) {
        fprintf(stderr,
                "cellsim: no server asked (--tcp, --rtu, --ascii or --gev; cellsim --help)\n");
        return 2;
    }
    if (rig.stage_unit == rig.probe_unit) {
        fprintf(stderr, "cellsim: --stage-unit and --probe-unit must differ\n");
        return 2;
    }
    char msg[512];
    if (part_path ? sim_part_iges(&part, part_path, msg, sizeof msg)
                  : sim_part_builtin(&part, msg, sizeof msg)) {
        fprintf(stderr, "cellsim: %s\n", msg);
        return 1;
    }
    if (dent >= 0)
        part.pt.dent_depth = dent;
    if (warp_set)
        part.pt.warp = warp;
    faults.verbose = verbose;
    sim_rng_seed(&faults.rng, (uint64_t)seed, 1);
    stage.speed = speed;
    stage.settle_ms = settle;
    stage.lo[0] = lim[0];
    stage.hi[0] = lim[1];
    stage.lo[1] = lim[2];
    stage.hi[1] = lim[3];
    if (homed) {
        stage.homed = stage.inpos = 1;
        stage.p0[0] = stage.p1[0] = stage.home[0];
        stage.p0[1] = stage.p1[1] = stage.home[1];
    }
    probe.part = &part;
    probe.stage = &stage;
    probe.z0 = z0;
    probe.off[0] = off[0];
    probe.off[1] = off[1];
    probe.lo = range[0];
    probe.hi = range[1];
    probe.noise = noise;
    probe.faults = &faults;
    probe.stream.cap = (size_t)fifo;
    sim_rng_seed(&probe.rng, (uint64_t)seed, 2);
    net.rig = &rig;
    net.faults = &faults;
    net.gap_ms = 20;
    net.verbose = verbose;
    signal(SIGPIPE, SIG_IGN);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    if (net.nports && sim_net_start(&net, msg, sizeof msg)) {
        fprintf(stderr, "cellsim: %s\n", msg);
        sim_part_free(&part);
        return 1;
    }
    if (gev.serial) {
        gev.part = &part;
        gev.z0 = z0;
        gev.lo = range[0];
        gev.hi = range[1];
        gev.noise = noise;
        gev.seed = (uint64_t)seed;
        if (sim_gev_start(&gevs, &gev, msg, sizeof msg)) {
            fprintf(stderr, "cellsim: %s\n", msg);
            if (net.nports)
                sim_net_stop(&net);
            sim_part_free(&part);
            return 1;
        }
        printf("cellsim: gev 127.0.0.1 %s width %d height %d profiles %ld x0 %.17g dx %.17g y0 "
               "%.17g dy %.17g z0 %.17g lo %.17g scale %.17g\n",
               gev.serial, gev.width, gev.height, gev.profiles, gev.x0, gev.dx, gev.y0, gev.dy,
               gev.z0, gev.lo, gev.scale);
    }
    for (int i = 0; i < net.nports; i++) {
        const sim_port_t *p = &net.port[i];
        if (p->wire == SIM_W_TCP)
            printf("cellsim: tcp 127.0.0.1 %d\n", p->tcp_port);
        else
            printf("cellsim: %s %s\n", p->wire == SIM_W_RTU ? "rtu" : "ascii", p->path);
    }
    if (pidfile) {
        FILE *f = fopen(pidfile, "w");
        if (!f || fprintf(f, "%ld\n", (long)getpid()) < 0 || fclose(f)) {
            fprintf(stderr, "cellsim: %s: cannot write the PID file\n", pidfile);
            sim_gev_stop(gevs);
            if (net.nports)
                sim_net_stop(&net);
            sim_part_free(&part);
            return 1;
        }
    }
    printf("cellsim: ready pid %ld\n", (long)getpid());
    fflush(stdout);
    double next_ctl = 0;
    while (!g_stop) {
        if (ctl && sim_now_ms() >= next_ctl) {
            control(ctl, &faults, &stage);
            next_ctl = sim_now_ms() + 100;
        }
        if (net.nports) {
            sim_net_poll(&net, 100);
        } else {
            struct timespec ts = {0, 100000000L};
            nanosleep(&ts, NULL);
        }
    }
    sim_gev_stop(gevs);
    if (net.nports)
        sim_net_stop(&net);
    sim_stream_free(&probe);
    sim_part_free(&part);
    if (pidfile)
        unlink(pidfile);
    return 0;
}
