/* SPDX-License-Identifier: MIT */
/* cf_log.c: levelled log lines to stderr or syslog (cf_log.h). */
#define _DEFAULT_SOURCE /* syslog's LOG_* names, vsyslog */
#include "cf_log.h"
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <syslog.h>
#include <time.h>

static cf_log_level_t log_level = CF_LOG_INFO;
static int log_syslog;

static const char *const level_names[] = {"error", "warn", "info", "debug"};

void cf_log_open(cf_log_level_t level, int use_syslog)
{
    log_level = level;
    log_syslog = use_syslog;
    if (use_syslog)
        openlog("cellfit", LOG_PID, LOG_DAEMON);
}

void cf_log_close(void)
{
    if (log_syslog)
        closelog();
    log_syslog = 0;
}

int cf_log_parse_level(const char *s, cf_log_level_t *out)
{
    for (int i = 0; i <= CF_LOG_DEBUG; i++)
        if (!strcmp(s, level_names[i])) {
            *out = (cf_log_level_t)i;
            return 0;
        }
    return -1;
}

void cf_log(cf_log_level_t level, const char *fmt, ...)
{
    if (level > log_level)
        return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (log_syslog) {
        static const int prio[] = {LOG_ERR, LOG_WARNING, LOG_INFO, LOG_DEBUG};
        syslog(prio[level], "%s", line);
        return;
    }
    struct timespec ts;
    struct tm tm;
    char stamp[32] = "";
    clock_gettime(CLOCK_REALTIME, &ts);
    if (gmtime_r(&ts.tv_sec, &tm))
        strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%S", &tm);
    /* One fprintf per line: stdio locks the stream, lines do not interleave. */
    fprintf(stderr, "%s.%03ldZ %s %s\n", stamp, ts.tv_nsec / 1000000L, level_names[level], line);
}
