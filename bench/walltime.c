/* SPDX-License-Identifier: MIT */
/* walltime.c: a command's wall time for the benchmark, without the timer's
 * own cost: `walltime FILE CMD [ARG...]` runs CMD (its stdin, stdout and
 * stderr the caller's), writes the seconds from before its fork to after
 * its wait (CLOCK_MONOTONIC) to FILE and exits with CMD's status. Timing
 * with `date +%s%N` around the command counts the second date's fork and
 * exec (about 5 ms in this project's VMs) as the command's. SIGINT and
 * SIGTERM are passed on to CMD. */
#define _POSIX_C_SOURCE 200809L
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t child;

static void pass_on(int sig)
{
    if (child > 0)
        kill((pid_t)child, sig);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: walltime FILE CMD [ARG...]: CMD's wall seconds to FILE\n");
        return 2;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = pass_on;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    const double t0 = now();
    pid_t p = fork();
    if (p < 0) {
        perror("walltime: fork");
        return 2;
    }
    if (p == 0) {
        execvp(argv[2], argv + 2);
        perror("walltime: exec");
        _exit(127);
    }
    child = p;
    int st = 0;
    while (waitpid(p, &st, 0) < 0)
        ; /* EINTR: a signal passed on; wait again */
    const double t1 = now();
    FILE *f = fopen(argv[1], "w");
    if (!f || fprintf(f, "%.6f\n", t1 - t0) < 0 || fclose(f)) {
        perror("walltime: the time file");
        return 2;
    }
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}
