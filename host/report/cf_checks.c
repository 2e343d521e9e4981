/* SPDX-License-Identifier: MIT */
/* cf_checks.c: named check points and zones (cf_checks.h). */
#include "cf_checks.h"
#include "cf_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One line's check into c: 1 done, 0 a blank or comment line, -1 bad. */
static int parse_line(char *line, cf_check_t *c)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    char *save = NULL, *tok[5];
    int n = 0;
    for (char *t = strtok_r(line, " \t\r\n", &save); t; t = strtok_r(NULL, " \t\r\n", &save)) {
        if (n == 5) /* NAME X Y Z RADIUS at most */
            return -1;
        tok[n++] = t;
    }
    if (n == 0)
        return 0;
    if (n < 4 || strlen(tok[0]) > CF_CHECKS_NAME)
        return -1;
    memset(c, 0, sizeof *c);
    strcpy(c->name, tok[0]);
    double v[4] = {0, 0, 0, NAN};
    for (int i = 1; i < n; i++) {
        char *e;
        v[i - 1] = strtod(tok[i], &e);
        if (e == tok[i] || *e || !isfinite(v[i - 1]))
            return -1;
    }
    if (n == 5 && !(v[3] > 0))
        return -1;
    memcpy(c->p, v, sizeof c->p);
    c->radius = v[3];
    return 1;
}

int cf_checks_read(cf_checks_t *cs, const char *path, char *msg, size_t ml)
{
    memset(cs, 0, sizeof *cs);
    FILE *f = fopen(path, "r");
    if (!f)
        return cf_fail(msg, ml, CF_EIO, "%s: cannot open", path);
    char line[1024];
    int cap = 0, rc = CF_OK;
    long no = 0;
    while (!rc && fgets(line, sizeof line, f)) {
        no++;
        cf_check_t c;
        int got = strchr(line, '\n') || feof(f) ? parse_line(line, &c) : -1;
        if (got < 0) {
            rc = cf_fail(msg, ml, CF_EPARSE,
                         "%s:%ld: need NAME X Y Z [RADIUS] (mm, RADIUS > 0, NAME at most %d "
                         "characters)",
                         path, no, CF_CHECKS_NAME);
            break;
        }
        if (!got)
            continue;
        for (int i = 0; i < cs->n; i++)
            if (!strcmp(cs->c[i].name, c.name))
                rc =
                    cf_fail(msg, ml, CF_EPARSE, "%s:%ld: check '%s' named twice", path, no, c.name);
        if (!rc && cs->n >= CF_CHECKS_MAX)
            rc =
                cf_fail(msg, ml, CF_EPARSE, "%s:%ld: more than %d checks", path, no, CF_CHECKS_MAX);
        if (!rc && cs->n == cap) {
            int nc = cap ? 2 * cap : 16;
            cf_check_t *p = realloc(cs->c, sizeof *p * (size_t)nc);
            if (!p)
                rc = cf_fail(msg, ml, CF_ENOMEM, "%s: out of memory", path);
            else
                cs->c = p, cap = nc;
        }
        if (!rc)
            cs->c[cs->n++] = c;
    }
    if (!rc && ferror(f))
        rc = cf_fail(msg, ml, CF_EIO, "%s: read error", path);
    fclose(f);
    if (rc)
        cf_checks_free(cs);
    else
        cf_checks_reset(cs);
    return rc;
}

void cf_checks_reset(cf_checks_t *cs)
{
    for (int i = 0; i < cs->n; i++) {
        cs->c[i].points = 0;
        cs->c[i].sum = 0;
        cs->c[i].best2 = INFINITY;
        cs->c[i].best = NAN;
    }
}

void cf_checks_add(cf_checks_t *cs, const double Q[3], double dev)
{
    for (int i = 0; i < cs->n; i++) {
        cf_check_t *c = &cs->c[i];
        const double dx = Q[0] - c->p[0], dy = Q[1] - c->p[1], dz = Q[2] - c->p[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (isnan(c->radius)) {
            c->points++;
            if (d2 < c->best2) /* strictly: the first of equals stays */
                c->best2 = d2, c->best = dev;
        } else if (d2 <= c->radius * c->radius) {
            c->points++;
            c->sum += dev;
        }
    }
}

double cf_checks_value(const cf_checks_t *cs, int i)
{
    const cf_check_t *c = &cs->c[i];
    if (!c->points)
        return NAN;
    return isnan(c->radius) ? c->best : c->sum / (double)c->points;
}

const char *cf_checks_missing(const cf_checks_t *cs, int i, char *buf, size_t n)
{
    const cf_check_t *c = &cs->c[i];
    if (c->points)
        return NULL;
    if (isnan(c->radius)) /* only when there were no points at all */
        snprintf(buf, n, "check %s: no points measured: no value", c->name);
    else
        snprintf(buf, n, "check %s: no point within %g mm of (%g, %g, %g): no value", c->name,
                 c->radius, c->p[0], c->p[1], c->p[2]);
    return buf;
}

int cf_checks_warn(const cf_checks_t *cs, FILE *f, const char *who)
{
    char why[256];
    int n = 0;
    for (int i = 0; i < cs->n; i++)
        if (cf_checks_missing(cs, i, why, sizeof why)) {
            fprintf(f, "%s: warning: %s\n", who, why);
            n++;
        }
    return n;
}

void cf_checks_json(const cf_checks_t *cs, cf_json_t *j)
{
    cf_json_arr(j, "checks");
    for (int i = 0; i < cs->n; i++) {
        const cf_check_t *c = &cs->c[i];
        cf_json_obj(j, NULL);
        cf_json_str(j, "name", c->name);
        cf_json_num(j, "x", c->p[0]);
        cf_json_num(j, "y", c->p[1]);
        cf_json_num(j, "z", c->p[2]);
        cf_json_num(j, "radius", c->radius);
        cf_json_int(j, "points", isnan(c->radius) ? (c->points > 0) : c->points);
        cf_json_num(j, "deviation", cf_checks_value(cs, i));
        cf_json_close(j);
    }
    cf_json_close(j);
}

void cf_checks_free(cf_checks_t *cs)
{
    free(cs->c);
    memset(cs, 0, sizeof *cs);
}
