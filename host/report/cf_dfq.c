/* SPDX-License-Identifier: MIT */
/* cf_dfq.c: Q-DAS ASCII transfer format (cf_dfq.h). */
#include "cf_dfq.h"
#include "cf_atomic.h"
#include "cf_err.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Printable ASCII of s, at most max characters ("" for NULL). */
static void clean(char *dst, const char *s, size_t max)
{
    size_t n = 0;
    for (; s && s[n] && n < max; n++)
        dst[n] = (s[n] >= 0x20 && s[n] < 0x7F) ? s[n] : '_';
    dst[n] = '\0';
}

/* The shortest decimal that reads back to v (0.05, not 0.050000000000000003):
 * SPC systems show limits as written. */
static void num(FILE *f, const char *key, int c, double v)
{
    char b[40];
    for (int d = 1; d <= 17; d++) {
        snprintf(b, sizeof b, "%.*g", d, v);
        if (strtod(b, NULL) == v)
            break;
    }
    fprintf(f, "%s/%d %s\n", key, c, b);
}

int cf_dfq_write(const char *path, const cf_dfq_part_t *part, const cf_dfq_char_t *c, int n,
                 char *msg, size_t ml)
{
    if (!path || !part || (!c && n) || n < 1 || n > 9999)
        return cf_fail(msg, ml, CF_EARG, "cf_dfq_write: bad arguments");
    char t[81], when[32];
    time_t tt = (time_t)part->utc;
    struct tm tm;
    if (!gmtime_r(&tt, &tm))
        return cf_fail(msg, ml, CF_EARG, "cf_dfq_write: bad time");
    /* AQDEF date/time: DD.MM.YYYY/HH:MM:SS. */
    strftime(when, sizeof when, "%d.%m.%Y/%H:%M:%S", &tm);
    cf_atomic_t a;
    int rc = cf_atomic_open(&a, path, msg, ml);
    if (rc)
        return rc;
    FILE *f = a.f;
    fprintf(f, "K0100 %d\n", n);
    clean(t, part->number, 30);
    fprintf(f, "K1001/1 %s\n", t);
    clean(t, part->name, 80);
    fprintf(f, "K1002/1 %s\n", t);
    for (int i = 0; i < n; i++) {
        int k = i + 1;
        fprintf(f, "K2001/%d %d\n", k, k);
        clean(t, c[i].name, 80);
        fprintf(f, "K2002/%d %s\n", k, t);
        fprintf(f, "K2004/%d 0\n", k); /* variable characteristic */
        if (isfinite(c[i].nominal))
            num(f, "K2101", k, c[i].nominal);
        if (isfinite(c[i].lo))
            num(f, "K2110", k, c[i].lo);
        if (isfinite(c[i].hi))
            num(f, "K2111", k, c[i].hi);
        clean(t, c[i].unit, 20);
        fprintf(f, "K2142/%d %s\n", k, t);
        fprintf(f, "K2022/%d %d\n", k, c[i].decimals);
    }
    /* The values: one part, one value per characteristic. */
    for (int i = 0; i < n; i++) {
        int k = i + 1;
        if (isfinite(c[i].value)) {
            num(f, "K0001", k, c[i].value);
        } else {
            fprintf(f, "K0001/%d 0\n", k);
            fprintf(f, "K0002/%d 255\n", k); /* value not measured */
        }
        fprintf(f, "K0004/%d %s\n", k, when);
        if (part->ident && part->ident[0]) {
            clean(t, part->ident, 40);
            fprintf(f, "K0014/%d %s\n", k, t);
        }
    }
    return cf_atomic_commit(&a, 1, msg, ml);
}
