/* SPDX-License-Identifier: MIT */
/* cf_conf.c: "key = value" configuration files (cf_conf.h). */
#include "cf_conf.h"
#include "cf_err.h"
#include <errno.h>
#include <stdio.h>
#include <string.h>

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r' || s[n - 1] == '\n'))
        s[--n] = 0;
    return s;
}

int cf_conf_read(const char *path, cf_conf_fn fn, void *ctx, char *msg, size_t ml)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot open: %s", path, strerror(errno));
    char line[4096], sub[512];
    int rc = CF_OK;
    for (long ln = 1; !rc && fgets(line, sizeof line, f); ln++) {
        if (!strchr(line, '\n') && !feof(f)) {
            rc = cf_fail(msg, ml, CF_EPARSE, "%s:%ld: line longer than %zu bytes", path, ln,
                         sizeof line - 2);
            break;
        }
        char *s = trim(line);
        if (!*s || *s == '#')
            continue;
        char *eq = strchr(s, '=');
        if (!eq) {
            rc = cf_fail(msg, ml, CF_EPARSE, "%s:%ld: expected key = value", path, ln);
            break;
        }
        *eq = 0;
        char *k = trim(s), *v = trim(eq + 1);
        if (!*k) {
            rc = cf_fail(msg, ml, CF_EPARSE, "%s:%ld: empty key", path, ln);
            break;
        }
        rc = fn(ctx, k, v, sub, sizeof sub);
        if (rc)
            cf_fail(msg, ml, rc, "%s:%ld: %s", path, ln, sub);
    }
    if (!rc && ferror(f))
        rc = cf_fail(msg, ml, CF_EIO, "%s: read error", path);
    fclose(f);
    return rc;
}
