/* SPDX-License-Identifier: MIT */
/* cf_simchild.c: cellsim as serve's child (cf_simchild.h). */
#define _DEFAULT_SOURCE /* prctl's PR_SET_PDEATHSIG, kill */
#include "cf_simchild.h"
#include "cf_err.h"
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define SIM_MAX_ARGS 48

static double mono_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

/* cellsim beside /proc/self/exe. */
static int sim_path(char *buf, size_t n)
{
    char self[PATH_MAX];
    ssize_t k = readlink("/proc/self/exe", self, sizeof self - 1);
    if (k <= 0)
        return -1;
    self[k] = 0;
    char *slash = strrchr(self, '/');
    if (!slash)
        return -1;
    *slash = 0;
    if ((size_t)snprintf(buf, n, "%s/cellsim", self) >= n)
        return -1;
    return access(buf, X_OK);
}

static void describe(int st, char *msg, size_t ml)
{
    if (WIFSIGNALED(st))
        snprintf(msg, ml, "killed by signal %d", WTERMSIG(st));
    else
        snprintf(msg, ml, "exited with status %d", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
}

int cf_simchild_start(cf_simchild_t *c, const char *extra, int timeout_ms, char *msg, size_t ml)
{
    memset(c, 0, sizeof *c);
    c->out_fd = -1;
    char path[PATH_MAX + 16], args[1024];
    if (sim_path(path, sizeof path))
        return cf_fail(msg, ml, CF_EIO, "--sim: no cellsim beside this cellfit (%s)", path);
    char *argv[SIM_MAX_ARGS + 1];
    int argc = 0;
    argv[argc++] = path;
    argv[argc++] = "--tcp";
    argv[argc++] = "0";
    snprintf(args, sizeof args, "%s", extra ? extra : "");
    for (char *t = strtok(args, " \t"); t; t = strtok(NULL, " \t")) {
        if (argc >= SIM_MAX_ARGS)
            return cf_fail(msg, ml, CF_EARG, "sim_args: more than %d arguments", SIM_MAX_ARGS - 3);
        argv[argc++] = t;
    }
    argv[argc] = NULL;
    int fds[2];
    if (pipe(fds))
        return cf_fail(msg, ml, CF_EIO, "--sim: pipe: %s", strerror(errno));
    pid_t parent = getpid(), pid = fork();
    if (pid < 0) {
        close(fds[0]);
        close(fds[1]);
        return cf_fail(msg, ml, CF_EIO, "--sim: fork: %s", strerror(errno));
    }
    if (pid == 0) {
        /* The child: stdout into the pipe, stderr shared (cellsim's own
         * lines go to serve's log stream), gone with its parent. */
        prctl(PR_SET_PDEATHSIG, SIGTERM);
        if (getppid() != parent)
            _exit(127);
        dup2(fds[1], 1);
        close(fds[0]);
        close(fds[1]);
        sigset_t none;
        sigemptyset(&none);
        sigprocmask(SIG_SETMASK, &none, NULL);
        execv(path, argv);
        _exit(127);
    }
    close(fds[1]);
    fcntl(fds[0], F_SETFD, FD_CLOEXEC);
    c->pid = pid;
    c->out_fd = fds[0];
    snprintf(msg, ml, "cellsim gave no ready line in %d ms", timeout_ms);
    /* Read its start-up lines: "cellsim: tcp 127.0.0.1 PORT", then ready. */
    char buf[2048];
    size_t have = 0;
    double t_end = mono_ms() + timeout_ms;
    while (mono_ms() < t_end) {
        struct pollfd p = {fds[0], POLLIN, 0};
        if (poll(&p, 1, 50) <= 0)
            continue;
        ssize_t k = read(fds[0], buf + have, sizeof buf - 1 - have);
        if (k <= 0) {
            snprintf(msg, ml, "cellsim ended before it was ready");
            break;
        }
        have += (size_t)k;
        buf[have] = 0;
        char *t = strstr(buf, "cellsim: tcp 127.0.0.1 ");
        if (t)
            c->port = atoi(t + 23);
        /* "cellsim: gev 127.0.0.1 SERIAL width W ...": the profiler's line. */
        const char *g = strstr(buf, "cellsim: gev 127.0.0.1 ");
        const char *nl = g ? strchr(g, '\n') : NULL;
        if (nl && !c->gev_uri[0]) {
            char ser[32] = "";
            snprintf(c->gev_geom, sizeof c->gev_geom, "%.*s", (int)(nl - g), g);
            if (sscanf(g + 23, "%31s", ser) == 1)
                snprintf(c->gev_uri, sizeof c->gev_uri, "gev:127.0.0.1:%s", ser);
        }
        if (strstr(buf, "cellsim: ready") && c->port > 0) {
            snprintf(c->stage, sizeof c->stage, "tcp:127.0.0.1:%d:1", c->port);
            snprintf(c->probe, sizeof c->probe, "tcp:127.0.0.1:%d:2", c->port);
            return 0;
        }
        if (have >= sizeof buf - 1)
            break;
    }
    char why[128];
    snprintf(why, sizeof why, "%s", msg);
    cf_simchild_stop(c);
    return cf_fail(msg, ml, CF_EIO, "--sim: %s (%s)", why, path);
}

int cf_simchild_ended(cf_simchild_t *c, char *msg, size_t ml)
{
    if (c->pid <= 0 || c->ended)
        return 0;
    int st;
    if (waitpid(c->pid, &st, WNOHANG) != c->pid)
        return 0;
    c->ended = 1;
    c->status = st;
    describe(st, msg, ml);
    return 1;
}

void cf_simchild_stop(cf_simchild_t *c)
{
    if (c->pid > 0 && !c->ended) {
        kill(c->pid, SIGTERM);
        double t_end = mono_ms() + 2000;
        int st = 0;
        pid_t r;
        while ((r = waitpid(c->pid, &st, WNOHANG)) == 0 && mono_ms() < t_end) {
            struct timespec d = {0, 20000000};
            nanosleep(&d, NULL);
        }
        if (r == 0) {
            kill(c->pid, SIGKILL);
            waitpid(c->pid, &st, 0);
        }
        c->ended = 1;
        c->status = st;
    }
    if (c->out_fd >= 0)
        close(c->out_fd);
    c->out_fd = -1;
}
