/* sim_main.c: cellsim, the simulated rig on the real wire protocols:
 * options, the part, the stage and probe models, the servers, the control
 * file, and the "ready" lines tests wait for. */
#include "cf_cli.h"
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

static int usage(FILE *f, int code)
{
    fprintf(
        f,
        "usage: cellsim [options]   the simulated rig (docs/rig-devices.md)\n"
        "servers (at least one):\n"
        "  --tcp PORT          Modbus TCP on 127.0.0.1:PORT (0: a free port, printed)\n"
        "  --rtu PATH          Modbus RTU on the tty PATH (e.g. one end of a socat pty pair)\n"
        "  --ascii PATH        the probe's ASCII protocol on the tty PATH\n"
        "                      (each may be given up to 8 times in all)\n"
        "  --gev SERIAL        the laser line profiler: Aravis's fake GigE Vision camera on\n"
        "                      127.0.0.1 (port 3956: one per machine), serial SERIAL, open it as\n"
        "                      gev:127.0.0.1:SERIAL (docs/rig-profiler.md); with it:\n"
        "    --gev-loss R      GVSP packet loss ratio 0..1 (0)\n"
        "    --gev-width W     points per profile (1024)   --gev-height H  profiles a frame (64)\n"
        "    --gev-profiles P  profiles over one pass of the part (256)\n"
        "    --gev-scale MM    mm per range count (0.001)  --gev-flank DEG  no reading on flanks\n"
        "                      steeper than DEG degrees (60); z0, range and noise are the probe's\n"
        "  Every Modbus server carries the stage (holding registers, --stage-unit, default 1;\n"
        "  on TCP also units 0 and 255) and the probe (input registers, --probe-unit, default 2).\n"
        "the part under the probe:\n"
        "  --part FILE.igs     nominal surface (first entity 128); default: the built-in panel\n"
        "                      (cellfit gen's nominal: 200 x 150 mm, 40 x 30 bicubic)\n"
        "  --dent-depth MM     depth of the dent (0.4; 0: none)   --warp MM  twist (0.3; 0: none)\n"
        "  The real part is the nominal plus the dent and warp of host/cf_part.h.\n"
        "the probe (kinematic model: a point is (sx + ox, sy + oy, z0 - d)):\n"
        "  --z0 MM             height of the beam origin (50)\n"
        "  --offset OX,OY      beam offset from the stage position (0,0)\n"
        "  --range LO,HI       measuring range (30,60): out of range outside it or off the part\n"
        "  --noise SIGMA       Gaussian noise on the distance, mm (0.002)\n"
        "  --seed S            seeds noise and fault probabilities (1)\n"
        "the stage:\n"
        "  --speed MM/S        both axes (200)   --settle-ms MS   after each move (0)\n"
        "  --limits XLO,XHI,YLO,YHI  soft limits (-10,210,-10,160); home is (0,0)\n"
        "  --homed             start homed, at home (default: unreferenced at 37.5,12.25)\n"
        "faults (repeatable): --fault KIND[@WIRE]:WHEN[:MS]\n"
        "  KIND   crc     RTU: CRC bit flipped; TCP: transaction id flipped; ASCII: garble\n"
        "         garble  one reply byte changed       drop    one reply byte left out\n"
        "         slow    reply held back MS ms          silent  no reply\n"
        "         disconnect  the line or server closed for MS ms\n"
        "         busy    Modbus exception 06\n"
        "         nosurf  probe reads out of range       proberr probe error (ER,M0,01)\n"
        "         stagefault  the move faults half-way (drive fault latched)\n"
        "  WIRE   tcp | rtu | ascii: count and hit only requests on that wire\n"
        "  WHEN   nK: at the K-th event only; eK: every K-th; pP: with probability P\n"
        "         events: wire faults count requests, nosurf/proberr probe readings,\n"
        "         stagefault accepted moves; each fault counts its own\n"
        "  e.g. --fault crc@rtu:n3 --fault slow:n5:800 --fault disconnect@tcp:n10:500\n"
        "  --control FILE      polled every 100 ms; when it exists its lines are obeyed and it\n"
        "                      is removed: 'fault SPEC' (counting from now), 'estop on|off',\n"
        "                      'stagefault' (latch a drive fault now)\n"
        "  Holding registers 100 (E-stop 1/0) and 101 (write 1: drive fault) do the same.\n"
        "  --verbose           log faults and line events on stderr\n"
        "start-up: prints 'cellsim: tcp 127.0.0.1 PORT', 'cellsim: rtu PATH', 'cellsim: ascii\n"
        "  PATH', 'cellsim: gev 127.0.0.1 SERIAL width W height H profiles P x0 X dx DX y0 Y\n"
        "  dy DY z0 Z lo LO scale S' and last 'cellsim: ready pid PID' on stdout; --pidfile FILE "
        "writes the PID.\n"
        "  SIGTERM or SIGINT stops it. Exit status: 0 stopped, 1 failed, 2 bad usage.\n");
    return code;
}

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
    static sim_net_t net;
    static sim_faults_t faults;
    static sim_stage_t stage;
    static sim_probe_t probe;
    static sim_part_t part;
    sim_rig_t rig = {&stage, &probe, HAL_STAGE_UNIT, HAL_PROBE_UNIT};
    const char *part_path = NULL, *pidfile = NULL, *ctl = NULL;
    double dent = -1, warp = 0, z0 = 50, off[2] = {0, 0}, range[2] = {30, 60}, noise = 0.002;
    double speed = 200, settle = 0, lim[4] = {-10, 210, -10, 160};
    long seed = 1, unit;
    int homed = 0, verbose = 0, warp_set = 0;
    sim_gev_cfg_t gev = {
        .width = 1024, .height = 64, .profiles = 256, .scale = 0.001, .flank_deg = 60};
    sim_gev_t *gevs = NULL;
    long gl;
    sim_stage_init(&stage, &faults);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h"))
            return usage(stdout, 0);
        if (!strcmp(a, "--homed")) {
            homed = 1;
            continue;
        }
        if (!strcmp(a, "--verbose")) {
            verbose = 1;
            continue;
        }
        const char *v = i + 1 < argc ? argv[++i] : NULL;
        if (!v) {
            fprintf(stderr, "cellsim: option %s needs a value\n", a);
            return 2;
        }
        int bad = 0;
        if (!strcmp(a, "--tcp") || !strcmp(a, "--rtu") || !strcmp(a, "--ascii")) {
            if (net.nports == SIM_MAX_PORTS) {
                fprintf(stderr, "cellsim: at most %d servers\n", SIM_MAX_PORTS);
                return 2;
            }
            sim_port_t *p = &net.port[net.nports];
            long port = 0;
            p->wire = a[2] == 't' ? SIM_W_TCP : a[2] == 'r' ? SIM_W_RTU : SIM_W_ASCII;
            if (p->wire == SIM_W_TCP)
                bad = cli_int(v, 0, 65535, &port);
            else
                bad = strlen(v) >= sizeof p->path || !v[0];
            p->tcp_port = (int)port;
            if (!bad && p->wire != SIM_W_TCP)
                strcpy(p->path, v);
            p->fd = -1;
            net.nports++;
        } else if (!strcmp(a, "--stage-unit") || !strcmp(a, "--probe-unit")) {
            bad = cli_int(v, 1, 247, &unit);
            if (a[2] == 's')
                rig.stage_unit = (int)unit;
            else
                rig.probe_unit = (int)unit;
        } else if (!strcmp(a, "--gev"))
            bad = !v[0] || strlen(v) > 15 || !(gev.serial = v);
        else if (!strcmp(a, "--gev-loss"))
            bad = cli_double(v, &gev.loss) || gev.loss < 0 || gev.loss > 1;
        else if (!strcmp(a, "--gev-width")) {
            bad = cli_int(v, 2, 2048, &gl);
            gev.width = (int)gl;
        } else if (!strcmp(a, "--gev-height")) {
            bad = cli_int(v, 1, 2048, &gl);
            gev.height = (int)gl;
        } else if (!strcmp(a, "--gev-profiles"))
            bad = cli_int(v, 2, 100000, &gev.profiles);
        else if (!strcmp(a, "--gev-scale"))
            bad = cli_double(v, &gev.scale) || !(gev.scale > 0);
        else if (!strcmp(a, "--gev-flank"))
            bad = cli_double(v, &gev.flank_deg) || !(gev.flank_deg > 0);
        else if (!strcmp(a, "--part"))
            part_path = v;
        else if (!strcmp(a, "--dent-depth"))
            bad = cli_double(v, &dent) || dent < 0;
        else if (!strcmp(a, "--warp")) {
            bad = cli_double(v, &warp);
            warp_set = 1;
        } else if (!strcmp(a, "--z0"))
            bad = cli_double(v, &z0);
        else if (!strcmp(a, "--offset"))
            bad = pair(v, 2, off);
        else if (!strcmp(a, "--range"))
            bad = pair(v, 2, range) || !(range[0] < range[1]);
        else if (!strcmp(a, "--noise"))
            bad = cli_double(v, &noise) || noise < 0;
        else if (!strcmp(a, "--seed"))
            bad = cli_int(v, 0, 1L << 62, &seed);
        else if (!strcmp(a, "--speed"))
            bad = cli_double(v, &speed) || !(speed > 0);
        else if (!strcmp(a, "--settle-ms"))
            bad = cli_double(v, &settle) || settle < 0;
        else if (!strcmp(a, "--limits"))
            bad = pair(v, 4, lim) || !(lim[0] < lim[1] && lim[2] < lim[3]);
        else if (!strcmp(a, "--fault")) {
            if (add_fault(&faults, v))
                return 2;
        } else if (!strcmp(a, "--control"))
            ctl = v;
        else if (!strcmp(a, "--pidfile"))
            pidfile = v;
        else {
            fprintf(stderr, "cellsim: unknown option '%s' (cellsim --help)\n", a);
            return 2;
        }
        if (bad) {
            fprintf(stderr, "cellsim: %s '%s': bad value (cellsim --help)\n", a, v);
            return 2;
        }
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
        if (net.nports)
            sim_net_poll(&net, 100);
        else {
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
