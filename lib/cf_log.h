/* SPDX-License-Identifier: MIT */
/* cf_log.h: levelled log lines for the cell's daemon (`cellfit serve`):
 * to stderr ("2026-12-01T17:00:00.123Z info plc: ...") or to syslog
 * (facility daemon, ident "cellfit"). Safe from several threads: one
 * write per line. */
#ifndef CF_LOG_H
#define CF_LOG_H

typedef enum cf_log_level { CF_LOG_ERROR, CF_LOG_WARN, CF_LOG_INFO, CF_LOG_DEBUG } cf_log_level_t;

/* Lines above level are dropped; use_syslog: 1 syslog, 0 stderr. */
void cf_log_open(cf_log_level_t level, int use_syslog);
void cf_log_close(void);

/* "error", "warn", "info", "debug" into *out; -1 for anything else. */
int cf_log_parse_level(const char *s, cf_log_level_t *out);

void cf_log(cf_log_level_t level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
