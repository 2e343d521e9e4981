/* SPDX-License-Identifier: MIT */
/* cf_cli.c: shared helpers of the cellfit subcommands. */
#include "cf_cli.h"
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int cli_error(const char *cmd, int code, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "cellfit %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

int cli_double(const char *s, double *out)
{
    char *end;
    if (!s || !*s)
        return -1;
    errno = 0;
    double v = strtod(s, &end);
    if (*end || errno == ERANGE || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

int cli_int(const char *s, long lo, long hi, long *out)
{
    char *end;
    if (!s || !*s)
        return -1;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end || errno == ERANGE || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int cli_solver(const char *s, nf_solver_t *out)
{
    static const nf_solver_t all[] = {NF_SOLVER_AUTO, NF_SOLVER_GS, NF_SOLVER_CHOL, NF_SOLVER_PCG};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        if (s && !strcmp(s, nf_solver_name(all[i]))) {
            *out = all[i];
            return 0;
        }
    return -1;
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double cli_utc_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void cli_iso8601(double utc, char *b, size_t n)
{
    if (!(utc > 0) || n < 32) {
        if (n)
            b[0] = '\0';
        return;
    }
    time_t t = (time_t)floor(utc);
    int ms = (int)floor((utc - (double)t) * 1000.0);
    struct tm tm;
    gmtime_r(&t, &tm);
    size_t k = strftime(b, n, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(b + k, n - k, ".%03dZ", ms > 999 ? 999 : ms);
}
