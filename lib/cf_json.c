/* SPDX-License-Identifier: MIT */
/* cf_json.c: the nesting JSON writer (cf_json.h). */
#include "cf_json.h"
#include "cf_fmt.h"
#include <math.h>

void cf_json_begin(cf_json_t *j, FILE *f)
{
    j->f = f;
    j->depth = 1;
    j->n[0] = 0;
    j->arr[0] = 0;
    fputc('{', f);
}

/* The separator and, inside an object, the key of the next value. */
static void next(cf_json_t *j, const char *key)
{
    int d = j->depth - 1;
    if (d < 0)
        return;
    if (j->n[d])
        fputs(", ", j->f);
    if (j->n[d] < 255)
        j->n[d]++;
    if (!j->arr[d]) {
        cf_json_quote(j->f, key ? key : "");
        fputs(": ", j->f);
    }
}

void cf_json_quote(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

void cf_json_num(cf_json_t *j, const char *key, double v)
{
    char b[40];
    next(j, key);
    if (isfinite(v)) {
        cf_fmt17(v, b, sizeof b);
        fputs(b, j->f);
    } else {
        fputs("null", j->f);
    }
}

void cf_json_int(cf_json_t *j, const char *key, long v)
{
    next(j, key);
    fprintf(j->f, "%ld", v);
}

void cf_json_str(cf_json_t *j, const char *key, const char *v)
{
    next(j, key);
    if (v)
        cf_json_quote(j->f, v);
    else
        fputs("null", j->f);
}

void cf_json_bool(cf_json_t *j, const char *key, int v)
{
    next(j, key);
    fputs(v ? "true" : "false", j->f);
}

void cf_json_null(cf_json_t *j, const char *key)
{
    next(j, key);
    fputs("null", j->f);
}

static void open_c(cf_json_t *j, const char *key, int arr)
{
    next(j, key);
    fputc(arr ? '[' : '{', j->f);
    if (j->depth < CF_JSON_DEPTH) {
        j->n[j->depth] = 0;
        j->arr[j->depth] = (unsigned char)arr;
        j->depth++;
    }
}

void cf_json_obj(cf_json_t *j, const char *key)
{
    open_c(j, key, 0);
}

void cf_json_arr(cf_json_t *j, const char *key)
{
    open_c(j, key, 1);
}

void cf_json_close(cf_json_t *j)
{
    if (j->depth <= 1)
        return;
    j->depth--;
    fputc(j->arr[j->depth] ? ']' : '}', j->f);
}

void cf_json_end(cf_json_t *j)
{
    while (j->depth > 1)
        cf_json_close(j);
    j->depth = 0;
    fputs("}\n", j->f);
}
