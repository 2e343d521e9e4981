/* SPDX-License-Identifier: MIT */
/* cf_conf.h: the cell's configuration file: one "key = value" a line,
 * blanks around both trimmed, '#' starts a comment line, blank lines
 * skipped; values run to the end of the line (no quoting). Each pair goes
 * to a callback, which refuses unknown keys and bad values; errors say
 * "file:line: ...". */
#ifndef CF_CONF_H
#define CF_CONF_H

#include <stddef.h>

/* 0 from the callback to go on; anything else stops the read with its
 * message. */
typedef int (*cf_conf_fn)(void *ctx, const char *key, const char *val, char *msg, size_t ml);

/* CF_OK, CF_EIO (cannot open), CF_EPARSE (no '=' or a line too long), or
 * the callback's code; msg says file:line. */
int cf_conf_read(const char *path, cf_conf_fn fn, void *ctx, char *msg, size_t ml);

#endif
