/* SPDX-License-Identifier: MIT */
/* sim_umock.c: sim-umock, the simulated USB devices for tests: builds a
 * umockdev testbed with an FTDI serial adapter (the laser probe behind it)
 * and the USB trigger box, runs the program under test as its child inside
 * it (LD_PRELOAD=libumockdev-preload.so.0, UMOCKDEV_DIR), plays the devices
 * while it runs and exits with the child's status.
 *   sim-umock [options] -- PROGRAM [ARGS...]   (options: sim-umock --help) */
#include "sim_umock.h"
#include <errno.h>
#include <glib-unix.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

int sim_verbose;

void sim_log(const char *fmt, ...)
{
    va_list ap;
    if (!sim_verbose)
        return;
    va_start(ap, fmt);
    fprintf(stderr, "sim-umock: ");
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

double sim_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int usage(FILE *f, int code)
{
    fprintf(f, "usage: sim-umock [options] -- PROGRAM [ARGS...]\n"
               "  --no-serial | --no-usb      leave a device out (both by default)\n"
               "serial adapter 0403:6001 at /dev/ttyUSB0, laser probe (M0 -> M0,+01.234):\n"
               "  --table D1,D2,...           distances in mm, cycled ('oor': out of range)\n"
               "  --garble N                  reply N (1-based) garbled (repeatable)\n"
               "  --error N:CODE              reply N is ER,M0,CODE (repeatable)\n"
               "  --serial-unplug N           pull the adapter after N replies\n"

               "trigger box 1209:cf01 (docs/rig-usb.md):\n"
               "  --usb-silent N              bulk IN never answered after N packets\n"
               "  --usb-unplug N              pull the box after N packets\n"
               "  --usb-replug MS             and plug it back MS later\n"
               "  --usb-badcrc N | --usb-skip N   packet N sent with a bad CRC / never sent\n"
               "  -v                          log device traffic on stderr\n"
               "exit status: the program's (128+signal if killed); 2 bad usage; 1 setup failed\n");
    return code;
}

static int num(const char *s, int *out)
{
    char *end;
    long v = strtol(s ? s : "", &end, 10);
    if (!s || !*s || *end || v < 0 || v > 1000000000L)
        return -1;
    *out = (int)v;
    return 0;
}

static int push(int *arr, int *n, const char *s)
{
    if (*n >= SIM_MAX_FAULTS || num(s, &arr[*n]) || arr[*n] < 1)
        return -1;
    (*n)++;
    return 0;
}

static int parse_table(sim_serial_cfg_t *c, const char *s)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", s);
    c->ntable = 0;
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        if (c->ntable >= SIM_MAX_TABLE)
            return -1;
        char *end;
        double v = strtod(t, &end);
        if (!strcmp(t, "oor"))
            v = NAN;
        else if (*end || !(fabs(v) < 100))
            return -1;
        c->table[c->ntable++] = v;
    }
    return c->ntable ? 0 : -1;
}

static GMainLoop *loop;
static pid_t child;
static int child_status = -1;

static void on_child(GPid pid, gint status, gpointer data)
{
    (void)pid;
    (void)data;
    child_status = status;
    g_main_loop_quit(loop);
}

static gboolean on_tick(gpointer data)
{
    (void)data;
    sim_serial_tick();
    sim_usb_tick();
    return G_SOURCE_CONTINUE;
}

static gboolean on_term(gpointer data)
{
    (void)data;
    if (child > 0)
        kill(child, SIGTERM);
    return G_SOURCE_CONTINUE;
}

int main(int argc, char **argv)
{
    static sim_serial_cfg_t sc = {.enabled = 1, .table = {1.234, 2.5, -0.75, 12.0}, .ntable = 4};
    static sim_usb_cfg_t uc = {.enabled = 1};
    int i = 1;
    for (; i < argc && strcmp(argv[i], "--"); i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0, takes = 1;
        if (!strcmp(a, "--no-serial"))
            sc.enabled = 0, takes = 0;
        else if (!strcmp(a, "--no-usb"))
            uc.enabled = 0, takes = 0;
        else if (!strcmp(a, "-v"))
            sim_verbose = 1, takes = 0;
        else if (!strcmp(a, "-h") || !strcmp(a, "--help"))
            return usage(stdout, 0);
        else if (!strcmp(a, "--table"))
            bad = !v || parse_table(&sc, v);
        else if (!strcmp(a, "--garble"))
            bad = push(sc.garble, &sc.ngarble, v);
        else if (!strcmp(a, "--error")) {
            const char *colon = v ? strchr(v, ':') : NULL;
            char n[32];
            bad = !colon || sc.nerr >= SIM_MAX_FAULTS || colon - v >= (long)sizeof n;
            if (!bad) {
                snprintf(n, sizeof n, "%.*s", (int)(colon - v), v);
                bad = num(n, &sc.errat[sc.nerr]) || num(colon + 1, &sc.errcode[sc.nerr]) ||
                      sc.errcode[sc.nerr] > 99;
                sc.nerr += !bad;
            }
        } else if (!strcmp(a, "--serial-unplug"))
            bad = num(v, &sc.unplug_after);
        else if (!strcmp(a, "--usb-silent"))
            bad = num(v, &uc.silent_after);
        else if (!strcmp(a, "--usb-unplug"))
            bad = num(v, &uc.unplug_after);
        else if (!strcmp(a, "--usb-replug"))
            bad = num(v, &uc.replug_ms);
        else if (!strcmp(a, "--usb-badcrc"))
            bad = push(uc.badcrc, &uc.nbadcrc, v);
        else if (!strcmp(a, "--usb-skip"))
            bad = push(uc.skip, &uc.nskip, v);
        else {
            fprintf(stderr, "sim-umock: unknown option '%s'\n", a);
            return usage(stderr, 2);
        }
        if (bad) {
            fprintf(stderr, "sim-umock: bad value for %s: '%s'\n", a, v ? v : "");
            return 2;
        }
        i += takes;
    }
    if (i + 1 >= argc) {
        fprintf(stderr, "sim-umock: no program to run after --\n");
        return usage(stderr, 2);
    }
    char **prog = argv + i + 1;

    UMockdevTestbed *tb = umockdev_testbed_new();
    char msg[512] = "";
    if ((sc.enabled && sim_serial_start(tb, &sc, msg, sizeof msg)) ||
        (uc.enabled && sim_usb_start(tb, &uc, msg, sizeof msg))) {
        fprintf(stderr, "sim-umock: %s\n", msg);
        g_object_unref(tb);
        return 1;
    }
    gchar *root = umockdev_testbed_get_root_dir(tb);
    loop = g_main_loop_new(NULL, FALSE);
    fflush(NULL);
    child = fork();
    if (child < 0) {
        fprintf(stderr, "sim-umock: fork: %s\n", strerror(errno));
        return 1;
    }
    if (child == 0) {
        /* umockdev-wrapper's environment: the preload library first. */
        const char *old = getenv("LD_PRELOAD");
        char pre[1024];
        snprintf(pre, sizeof pre, "libumockdev-preload.so.0%s%s", old && *old ? ":" : "",
                 old ? old : "");
        setenv("LD_PRELOAD", pre, 1);
        setenv("UMOCKDEV_DIR", root, 1);
        execvp(prog[0], prog);
        fprintf(stderr, "sim-umock: cannot run %s: %s\n", prog[0], strerror(errno));
        _exit(127);
    }
    sim_log("testbed %s, child %ld", root, (long)child);
    g_child_watch_add(child, on_child, NULL);
    g_timeout_add(5, on_tick, NULL);
    g_unix_signal_add(SIGTERM, on_term, NULL);
    g_unix_signal_add(SIGINT, on_term, NULL);
    g_main_loop_run(loop);
    g_main_loop_unref(loop);
    g_free(root);
    g_object_unref(tb);
    if (WIFEXITED(child_status))
        return WEXITSTATUS(child_status);
    if (WIFSIGNALED(child_status))
        return 128 + WTERMSIG(child_status);
    return 1;
}
