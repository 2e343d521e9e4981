/* SPDX-License-Identifier: MIT */
/* cf_json.h: the JSON writer every `--json` output and report file goes
 * through: objects, arrays, numbers (%.17g, null when not finite),
 * integers, strings (escaped), booleans and null, nested to a fixed depth.
 * Keys are given inside objects and NULL inside arrays. */
#ifndef CF_JSON_H
#define CF_JSON_H

#include <stdio.h>

#define CF_JSON_DEPTH 16

typedef struct cf_json {
    FILE *f;
    int depth;                        /* open containers, the top object included */
    unsigned char n[CF_JSON_DEPTH];   /* items written in each open container */
    unsigned char arr[CF_JSON_DEPTH]; /* 1 where the container is an array */
} cf_json_t;

/* Opens the top-level object ("{"). */
void cf_json_begin(cf_json_t *j, FILE *f);
/* Closes every open container and ends the line ("}\n"). */
void cf_json_end(cf_json_t *j);

void cf_json_num(cf_json_t *j, const char *key, double v);
void cf_json_int(cf_json_t *j, const char *key, long v);
void cf_json_str(cf_json_t *j, const char *key, const char *v); /* NULL: null */
void cf_json_bool(cf_json_t *j, const char *key, int v);
void cf_json_null(cf_json_t *j, const char *key);

/* A nested object or array as the next value; cf_json_close ends it. */
void cf_json_obj(cf_json_t *j, const char *key);
void cf_json_arr(cf_json_t *j, const char *key);
void cf_json_close(cf_json_t *j);

/* s as a JSON string literal (quotes included) on f. */
void cf_json_quote(FILE *f, const char *s);

#endif
