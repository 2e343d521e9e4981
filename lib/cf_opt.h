/* SPDX-License-Identifier: MIT */
/* cf_opt.h: command-line options from one table per command: parsing
 * (--name VALUE, --name=VALUE, flags, positional arguments, "--"), the
 * usage that --help prints (every option with its default), error lines
 * that name the option and say what it takes, and the roff section of the
 * man pages (--help-man), all from the same table so they cannot drift. */
#ifndef CF_OPT_H
#define CF_OPT_H

#include <stdio.h>

#define CF_OPT_MAX 64 /* options in one table at most */

typedef enum cf_opt_kind {
    CF_OPT_FLAG,   /* int *: set to 1, takes no value */
    CF_OPT_STR,    /* const char **: the value as given */
    CF_OPT_DOUBLE, /* double *: a finite number in [lo, hi] */
    CF_OPT_LONG,   /* long *: an integer in [lo, hi] */
    CF_OPT_INT,    /* int *: an integer in [lo, hi] */
    CF_OPT_CHOICE, /* int *: the index of the value in choices */
    CF_OPT_FUNC    /* fn(value, dst) parses it: 0, or -1 with what in fn_what */
} cf_opt_kind_t;

typedef struct cf_opt {
    const char *name; /* "tol", given as --tol; NULL ends a table */
    cf_opt_kind_t kind;
    void *dst;
    const char *arg;            /* the value's placeholder in usage: "MM", "FILE" */
    const char *help;           /* one line */
    double lo, hi;              /* numeric range, inclusive; lo > hi: any value */
    const char *const *choices; /* CHOICE: NULL-terminated */
    int (*fn)(const char *v, void *dst);
    const char *fn_what; /* FUNC: what a value must be, for the error line */
    const char *def;     /* the default as shown; NULL: read from *dst */
    int req;             /* 1: must be given */
    int *given;          /* optional: set to 1 when the option is given */
} cf_opt_t;

typedef struct cf_cmd {
    const char *prog;    /* "cellfit", "cellsim" */
    const char *name;    /* "fit", "journal fit"; NULL for a program without commands */
    const char *args;    /* positional synopsis, e.g. "SURF POINTS"; NULL: none */
    const char *summary; /* one line */
    const char *descr;   /* a paragraph for --help and the man page; NULL: none */
    const cf_opt_t *opts;
    int min_pos, max_pos;
} cf_cmd_t;

/* Parses argv[1..argc-1] (argv[0] is the command's name). Positional
 * arguments go to pos[] in order (at most c->max_pos), their count to
 * *npos (both may be NULL when max_pos is 0). Returns 0 to go on; -1 when
 * --help (usage on stdout) or --help-man (roff) was answered, and the
 * command should exit 0; CLI_USAGE (2) after one line on stderr naming
 * the option and what it takes. */
int cf_opt_parse(const cf_cmd_t *c, int argc, char **argv, const char **pos, int *npos);

/* The exit code for a non-zero cf_opt_parse result. */
static inline int cf_opt_exit(int rc)
{
    return rc < 0 ? 0 : rc;
}

/* Usage: synopsis, summary, description, one line per option with its
 * default, and the exit codes. */
void cf_opt_usage(const cf_cmd_t *c, FILE *f);

/* The same as a man-page section (roff): .SS name, synopsis, .TP per option. */
void cf_opt_man(const cf_cmd_t *c, FILE *f);

#endif
