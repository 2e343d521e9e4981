/* SPDX-License-Identifier: MIT */
/* cf_opt.c: option tables (cf_opt.h). */
#include "cf_opt.h"
#include "cf_cli.h"
#include <math.h>
#include <stdarg.h>
#include <string.h>

static int fail(const cf_cmd_t *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail(const cf_cmd_t *c, const char *fmt, ...)
{
    va_list ap;
    if (c->name)
        fprintf(stderr, "%s %s: ", c->prog, c->name);
    else
        fprintf(stderr, "%s: ", c->prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (%s%s%s --help lists the options)\n", c->prog, c->name ? " " : "",
            c->name ? c->name : "");
    return CLI_USAGE;
}

static const cf_opt_t *find(const cf_cmd_t *c, const char *name, size_t len)
{
    for (const cf_opt_t *o = c->opts; o && o->name; o++)
        if (strlen(o->name) == len && !strncmp(o->name, name, len))
            return o;
    return NULL;
}

/* lo > hi, or both 0 (a table that left them out), mean any value. */
static int ranged(const cf_opt_t *o)
{
    return o->lo <= o->hi && !(o->lo == 0 && o->hi == 0);
}

/* "a number in [0, 100]", "an integer >= 1", ... for error lines. */
static void what(const cf_opt_t *o, char *b, size_t n)
{
    const char *noun = o->kind == CF_OPT_DOUBLE ? "a number" : "an integer";
    switch (o->kind) {
    case CF_OPT_DOUBLE:
    case CF_OPT_LONG:
    case CF_OPT_INT:
        if (!ranged(o))
            snprintf(b, n, "%s", noun);
        else if (o->hi >= 1e300)
            snprintf(b, n, "%s >= %.15g", noun, o->lo);
        else if (o->lo <= -1e300)
            snprintf(b, n, "%s <= %.15g", noun, o->hi);
        else
            snprintf(b, n, "%s in [%.15g, %.15g]", noun, o->lo, o->hi);
        break;
    case CF_OPT_CHOICE: {
        size_t k = (size_t)snprintf(b, n, "one of");
        for (const char *const *ch = o->choices; *ch && k < n; ch++)
            k += (size_t)snprintf(b + k, n - k, "%s %s", ch == o->choices ? "" : ",", *ch);
        break;
    }
    case CF_OPT_FUNC: snprintf(b, n, "%s", o->fn_what ? o->fn_what : "a valid value"); break;
    default: snprintf(b, n, "a value");
    }
}

static int set(const cf_cmd_t *c, const cf_opt_t *o, const char *v)
{
    char w[160];
    double d;
    long l;
    switch (o->kind) {
    case CF_OPT_FLAG: *(int *)o->dst = 1; return 0;
    case CF_OPT_STR: *(const char **)o->dst = v; return 0;
    case CF_OPT_DOUBLE:
        if (cli_double(v, &d) || (ranged(o) && (d < o->lo || d > o->hi)))
            break;
        *(double *)o->dst = d;
        return 0;
    case CF_OPT_LONG:
    case CF_OPT_INT:
        if (cli_int(v, ranged(o) ? (long)fmax(o->lo, -9.2e18) : -2147483647L - 1,
                    ranged(o) ? (long)fmin(o->hi, 9.2e18) : 2147483647L, &l))
            break;
        if (o->kind == CF_OPT_LONG)
            *(long *)o->dst = l;
        else
            *(int *)o->dst = (int)l;
        return 0;
    case CF_OPT_CHOICE:
        for (int i = 0; o->choices[i]; i++)
            if (!strcmp(o->choices[i], v)) {
                *(int *)o->dst = i;
                return 0;
            }
        break;
    case CF_OPT_FUNC:
        if (!o->fn(v, o->dst))
            return 0;
        break;
    }
    what(o, w, sizeof w);
    return fail(c, "--%s '%s': need %s", o->name, v, w);
}

int cf_opt_parse(const cf_cmd_t *c, int argc, char **argv, const char **pos, int *npos)
{
    int np = 0, only_pos = 0;
    unsigned char seen[CF_OPT_MAX] = {0};
    int nopt = 0;
    while (c->opts && c->opts[nopt].name)
        nopt++;
    if (nopt > CF_OPT_MAX)
        return fail(c, "has %d options, more than CF_OPT_MAX (a bug)", nopt);
    /* --help anywhere answers before anything is parsed, so the usage shows
     * the defaults, not values given beside it. */
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--"))
            break;
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            cf_opt_usage(c, stdout);
            return -1;
        }
        if (!strcmp(argv[i], "--help-man")) {
            cf_opt_man(c, stdout);
            return -1;
        }
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!only_pos && !strcmp(a, "--")) {
            only_pos = 1;
            continue;
        }
        /* "-" is standard input and "-5" a negative number: positional. */
        int is_opt =
            !only_pos && a[0] == '-' && a[1] && !(a[1] >= '0' && a[1] <= '9') && a[1] != '.';
        if (!is_opt) {
            if (np >= c->max_pos)
                return c->max_pos ? fail(c, "unexpected argument '%s'", a)
                                  : fail(c, "takes no argument, got '%s'", a);
            pos[np++] = a;
            continue;
        }
        if (a[1] != '-')
            return fail(c, "unknown option '%s'", a);
        const char *name = a + 2, *eq = strchr(name, '=');
        size_t len = eq ? (size_t)(eq - name) : strlen(name);
        const cf_opt_t *o = find(c, name, len);
        if (!o)
            return fail(c, "unknown option '--%.*s'", (int)len, name);
        const char *v = NULL;
        if (o->kind == CF_OPT_FLAG) {
            if (eq)
                return fail(c, "--%s takes no value", o->name);
        } else if (eq) {
            v = eq + 1;
        } else if (i + 1 < argc && !(argv[i + 1][0] == '-' && argv[i + 1][1] == '-')) {
            v = argv[++i];
        } else {
            return fail(c, "--%s needs a value (%s)", o->name, o->arg ? o->arg : "VALUE");
        }
        int rc = set(c, o, v);
        if (rc)
            return rc;
        seen[o - c->opts] = 1;
        if (o->given)
            *o->given = 1;
    }
    for (int k = 0; k < nopt; k++)
        if (c->opts[k].req && !seen[k])
            return fail(c, "--%s %s is required", c->opts[k].name,
                        c->opts[k].arg ? c->opts[k].arg : "VALUE");
    if (np < c->min_pos)
        return fail(c, "needs %s", c->args ? c->args : "more arguments");
    if (npos)
        *npos = np;
    return 0;
}

/* The default of o as text into b ("" when there is none to show). */
static void deflt(const cf_opt_t *o, char *b, size_t n)
{
    b[0] = '\0';
    if (o->def) {
        snprintf(b, n, "%s", o->def);
        return;
    }
    switch (o->kind) {
    case CF_OPT_STR:
        if (*(const char *const *)o->dst)
            snprintf(b, n, "%s", *(const char *const *)o->dst);
        break;
    case CF_OPT_DOUBLE: snprintf(b, n, "%g", *(const double *)o->dst); break;
    case CF_OPT_LONG: snprintf(b, n, "%ld", *(const long *)o->dst); break;
    case CF_OPT_INT: snprintf(b, n, "%d", *(const int *)o->dst); break;
    case CF_OPT_CHOICE: snprintf(b, n, "%s", o->choices[*(const int *)o->dst]); break;
    default: break;
    }
}

static void synopsis(const cf_cmd_t *c, FILE *f)
{
    fprintf(f, "%s%s%s [options]%s%s", c->prog, c->name ? " " : "", c->name ? c->name : "",
            c->args ? " " : "", c->args ? c->args : "");
}

void cf_opt_usage(const cf_cmd_t *c, FILE *f)
{
    fputs("usage: ", f);
    synopsis(c, f);
    fprintf(f, "\n%s\n", c->summary);
    if (c->descr)
        fprintf(f, "\n%s\n", c->descr);
    fputs("\noptions:\n", f);
    for (const cf_opt_t *o = c->opts; o && o->name; o++) {
        char head[96], d[96], w[160];
        snprintf(head, sizeof head, "--%s%s%s", o->name, o->kind == CF_OPT_FLAG ? "" : " ",
                 o->kind == CF_OPT_FLAG ? "" : (o->arg ? o->arg : "VALUE"));
        deflt(o, d, sizeof d);
        fprintf(f, "  %-24s %s", head, o->help);
        if (o->kind == CF_OPT_CHOICE) {
            what(o, w, sizeof w);
            fprintf(f, " (%s)", w);
        }
        if (o->req)
            fputs(" [required]", f);
        else if (d[0])
            fprintf(f, " [default: %s]", d);
        fputc('\n', f);
    }
    fprintf(f, "  %-24s %s\n", "--help", "print this help and exit");
    fputs("exit status: 0 success, 1 the work failed, 2 bad usage or input\n", f);
}

/* Text for roff: a leading dot or quote escaped, backslashes and dashes. */
static void roff(FILE *f, const char *s)
{
    if (*s == '.' || *s == '\'')
        fputs("\\&", f);
    for (; *s; s++) {
        if (*s == '\\')
            fputs("\\e", f);
        else if (*s == '-')
            fputs("\\-", f);
        else
            fputc(*s, f);
        if (*s == '\n' && (s[1] == '.' || s[1] == '\''))
            fputs("\\&", f);
    }
}

void cf_opt_man(const cf_cmd_t *c, FILE *f)
{
    fputs(".SS \"", f);
    roff(f, c->name ? c->name : c->prog);
    fputs("\"\n.B ", f);
    char syn[256];
    snprintf(syn, sizeof syn, "%s%s%s [options]%s%s", c->prog, c->name ? " " : "",
             c->name ? c->name : "", c->args ? " " : "", c->args ? c->args : "");
    roff(f, syn);
    fputs("\n.br\n", f);
    roff(f, c->summary);
    fputc('\n', f);
    if (c->descr) {
        fputs(".PP\n", f);
        roff(f, c->descr);
        fputc('\n', f);
    }
    for (const cf_opt_t *o = c->opts; o && o->name; o++) {
        char d[96], w[160];
        fputs(".TP\n.B \\-\\-", f);
        roff(f, o->name);
        if (o->kind != CF_OPT_FLAG) {
            fputs(" \\fI", f);
            roff(f, o->arg ? o->arg : "VALUE");
            fputs("\\fR", f);
        }
        fputc('\n', f);
        roff(f, o->help);
        size_t hl = strlen(o->help);
        if (hl && o->help[hl - 1] != '.')
            fputc('.', f);
        if (o->kind == CF_OPT_CHOICE) {
            what(o, w, sizeof w);
            fputs(" (", f);
            roff(f, w);
            fputc(')', f);
        }
        deflt(o, d, sizeof d);
        if (o->req)
            fputs(" Required.", f);
        else if (d[0]) {
            fputs(" Default: ", f);
            roff(f, d);
            fputc('.', f);
        }
        fputc('\n', f);
    }
}
