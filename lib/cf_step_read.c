/* SPDX-License-Identifier: MIT */
/* cf_step_read.c: the B-spline surface of a STEP file (ISO 10303-21): the
 * DATA section indexed by instance number, then the surface's instance
 * (B_SPLINE_SURFACE_WITH_KNOTS, or the rational complex entity) parsed with
 * its CARTESIAN_POINTs, knot multiplicities expanded, the file's length unit
 * applied. The whole file is held in memory while reading. */
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_step.h"
#include "cf_surf.h"
#include "nf_err.h"
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct sr_rec {
    long id;
    size_t at, end; /* the text after '=' up to (not including) the ';' */
} sr_rec_t;

typedef struct sr {
    const char *path;
    char *buf;
    size_t len;
    sr_rec_t *ix;
    size_t nix;
    char *msg;
    size_t msglen;
} sr_t;

/* A growable array of doubles or of instance numbers. */
typedef struct sr_vec {
    double *d;
    size_t n, cap;
} sr_vec_t;

static int vec_push(sr_vec_t *v, double x)
{
    if (v->n == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 64;
        double *d = realloc(v->d, cap * sizeof *d);
        if (!d)
            return CF_ENOMEM;
        v->d = d;
        v->cap = cap;
    }
    v->d[v->n++] = x;
    return CF_OK;
}

static long line_at(const sr_t *r, size_t pos)
{
    long line = 1;
    for (size_t i = 0; i < pos && i < r->len; i++)
        line += r->buf[i] == '\n';
    return line;
}

static int sr_fail(const sr_t *r, size_t pos, int err, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int sr_fail(const sr_t *r, size_t pos, int err, const char *fmt, ...)
{
    char what[300];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return cf_fail(r->msg, r->msglen, err, "%s:%ld: %s", r->path, line_at(r, pos), what);
}

/* ---- lexing ---------------------------------------------------------------- */

/* Past white space and comments. An unterminated comment runs to the end. */
static size_t skip_ws(const sr_t *r, size_t p)
{
    for (;;) {
        while (p < r->len && isspace((unsigned char)r->buf[p]))
            p++;
        if (p + 1 < r->len && r->buf[p] == '/' && r->buf[p + 1] == '*') {
            const char *e = strstr(r->buf + p + 2, "*/");
            p = e ? (size_t)(e - r->buf) + 2 : r->len;
            continue;
        }
        return p;
    }
}

/* Past a string literal starting at p ('...', '' inside); 0 if unterminated. */
static size_t skip_string(const sr_t *r, size_t p)
{
    for (p++; p < r->len; p++)
        if (r->buf[p] == '\'') {
            if (p + 1 < r->len && r->buf[p + 1] == '\'')
                p++;
            else
                return p + 1;
        }
    return 0;
}

/* The end of the statement starting at p: the ';' outside strings and
 * comments. r->len if there is none. */
static size_t stmt_end(const sr_t *r, size_t p)
{
    while (p < r->len) {
        char c = r->buf[p];
        if (c == '\'') {
            p = skip_string(r, p);
            if (!p)
                return r->len;
        } else if (c == '/' && p + 1 < r->len && r->buf[p + 1] == '*') {
            const char *e = strstr(r->buf + p + 2, "*/");
            p = e ? (size_t)(e - r->buf) + 2 : r->len;
        } else if (c == ';')
            return p;
        else
            p++;
    }
    return r->len;
}

static int is_kw(char c)
{
    return isupper((unsigned char)c) || isdigit((unsigned char)c) || c == '_' ||
           islower((unsigned char)c);
}

/* The keyword at p (upper-cased into kw, up to kl - 1 characters); the
 * position after it, or p when there is none. */
static size_t keyword(const sr_t *r, size_t p, char *kw, size_t kl)
{
    size_t n = 0, q = p;
    if (q < r->len && (isalpha((unsigned char)r->buf[q]) || r->buf[q] == '_'))
        while (q < r->len && is_kw(r->buf[q])) {
            if (n + 1 < kl)
                kw[n++] = (char)toupper((unsigned char)r->buf[q]);
            q++;
        }
    kw[n] = '\0';
    return q;
}

static int rec_cmp(const void *a, const void *b)
{
    long x = ((const sr_rec_t *)a)->id, y = ((const sr_rec_t *)b)->id;
    return x < y ? -1 : x > y;
}

/* Index the DATA section: every "#n = ...;" instance. */
static int sr_index(sr_t *r)
{
    size_t p = skip_ws(r, 0);
    if (r->len - p < 13 || memcmp(r->buf + p, "ISO-10303-21", 12))
        return sr_fail(r, p, CF_EPARSE, "not a STEP file (no ISO-10303-21 header)");
    /* Statements up to and including DATA. */
    int data = 0;
    while (!data) {
        p = skip_ws(r, p);
        if (p >= r->len)
            return sr_fail(r, p, CF_EPARSE, "no DATA section");
        char kw[32];
        keyword(r, p, kw, sizeof kw);
        data = !strcmp(kw, "DATA");
        size_t e = stmt_end(r, p);
        if (e >= r->len)
            return sr_fail(r, p, CF_EPARSE, "statement without ';'");
        p = e + 1;
    }
    size_t cap = 1024;
    r->ix = malloc(cap * sizeof *r->ix);
    if (!r->ix)
        return cf_fail(r->msg, r->msglen, CF_ENOMEM, "%s: out of memory", r->path);
    for (;;) {
        p = skip_ws(r, p);
        if (p >= r->len)
            return sr_fail(r, p, CF_EPARSE, "DATA section without ENDSEC");
        if (r->buf[p] != '#') {
            char kw[32];
            keyword(r, p, kw, sizeof kw);
            if (!strcmp(kw, "ENDSEC"))
                break;
            return sr_fail(r, p, CF_EPARSE, "expected an instance '#n = ...;' or ENDSEC");
        }
        char *end;
        errno = 0;
        long id = strtol(r->buf + p + 1, &end, 10);
        if (end == r->buf + p + 1 || id < 1 || errno)
            return sr_fail(r, p, CF_EPARSE, "bad instance number");
        size_t q = skip_ws(r, (size_t)(end - r->buf));
        if (q >= r->len || r->buf[q] != '=')
            return sr_fail(r, q, CF_EPARSE, "expected '=' after #%ld", id);
        size_t e = stmt_end(r, q + 1);
        if (e >= r->len)
            return sr_fail(r, p, CF_EPARSE, "instance #%ld without ';'", id);
        if (r->nix == cap) {
            sr_rec_t *ix = realloc(r->ix, 2 * cap * sizeof *ix);
            if (!ix)
                return cf_fail(r->msg, r->msglen, CF_ENOMEM, "%s: out of memory", r->path);
            r->ix = ix;
            cap *= 2;
        }
        r->ix[r->nix++] = (sr_rec_t){id, q + 1, e};
        p = e + 1;
    }
    qsort(r->ix, r->nix, sizeof *r->ix, rec_cmp);
    for (size_t i = 1; i < r->nix; i++)
        if (r->ix[i].id == r->ix[i - 1].id)
            return sr_fail(r, r->ix[i].at, CF_EPARSE, "instance #%ld defined twice", r->ix[i].id);
    return CF_OK;
}

static const sr_rec_t *sr_find(const sr_t *r, long id)
{
    sr_rec_t key = {id, 0, 0};
    return bsearch(&key, r->ix, r->nix, sizeof *r->ix, rec_cmp);
}

/* ---- parameters -------------------------------------------------------------- */

/* A cursor inside one instance. */
typedef struct sc {
    const sr_t *r;
    size_t p, end;
} sc_t;

static int sc_peek(sc_t *c)
{
    c->p = skip_ws(c->r, c->p);
    return c->p < c->end ? (unsigned char)c->r->buf[c->p] : -1;
}

static int sc_expect(sc_t *c, char ch)
{
    if (sc_peek(c) != ch)
        return sr_fail(c->r, c->p, CF_EPARSE, "expected '%c'", ch);
    c->p++;
    return CF_OK;
}

/* ',' between parameters, or ')' at the end of a list: 1 for ',', 0 for
 * ')' (consumed both). */
static int sc_sep(sc_t *c, int *more)
{
    int ch = sc_peek(c);
    if (ch == ',' || ch == ')') {
        c->p++;
        *more = ch == ',';
        return CF_OK;
    }
    return sr_fail(c->r, c->p, CF_EPARSE, "expected ',' or ')'");
}

static int sc_real(sc_t *c, double *v)
{
    int ch = sc_peek(c);
    if (!(ch == '-' || ch == '+' || ch == '.' || (ch >= '0' && ch <= '9')))
        return sr_fail(c->r, c->p, CF_EPARSE, "expected a number");
    char *end;
    *v = strtod(c->r->buf + c->p, &end);
    if (end == c->r->buf + c->p || (size_t)(end - c->r->buf) > c->end || !isfinite(*v))
        return sr_fail(c->r, c->p, CF_EPARSE, "bad number");
    c->p = (size_t)(end - c->r->buf);
    return CF_OK;
}

static int sc_int(sc_t *c, long *v)
{
    double d;
    size_t at = c->p;
    int rc = sc_real(c, &d);
    if (rc)
        return rc;
    if (d != floor(d) || fabs(d) > 1e9)
        return sr_fail(c->r, at, CF_EPARSE, "expected an integer");
    *v = (long)d;
    return CF_OK;
}

static int sc_ref(sc_t *c, long *id)
{
    if (sc_peek(c) != '#')
        return sr_fail(c->r, c->p, CF_EPARSE, "expected a reference '#n'");
    char *end;
    errno = 0;
    *id = strtol(c->r->buf + c->p + 1, &end, 10);
    if (end == c->r->buf + c->p + 1 || *id < 1 || errno)
        return sr_fail(c->r, c->p, CF_EPARSE, "bad reference");
    c->p = (size_t)(end - c->r->buf);
    return CF_OK;
}

/* Past one parameter of any kind. */
static int sc_skip(sc_t *c)
{
    int ch = sc_peek(c);
    if (ch == '\'') {
        size_t e = skip_string(c->r, c->p);
        if (!e || e > c->end)
            return sr_fail(c->r, c->p, CF_EPARSE, "unterminated string");
        c->p = e;
        return CF_OK;
    }
    if (ch == '(') {
        c->p++;
        if (sc_peek(c) == ')') {
            c->p++;
            return CF_OK;
        }
        for (int more = 1; more;) {
            int rc = sc_skip(c);
            if (rc || (rc = sc_sep(c, &more)))
                return rc;
        }
        return CF_OK;
    }
    if (ch == '$' || ch == '*') {
        c->p++;
        return CF_OK;
    }
    if (ch == '#') {
        long id;
        return sc_ref(c, &id);
    }
    if (ch == '.') { /* an enumeration .X. (or a number like .5) */
        size_t q = c->p + 1;
        while (q < c->end && is_kw(c->r->buf[q]))
            q++;
        if (q < c->end && c->r->buf[q] == '.' && q > c->p + 1 &&
            !isdigit((unsigned char)c->r->buf[c->p + 1])) {
            c->p = q + 1;
            return CF_OK;
        }
    }
    if (ch == '"') { /* binary */
        const char *e = memchr(c->r->buf + c->p + 1, '"', c->end - c->p - 1);
        if (!e)
            return sr_fail(c->r, c->p, CF_EPARSE, "unterminated binary");
        c->p = (size_t)(e - c->r->buf) + 1;
        return CF_OK;
    }
    if (ch >= 0 && (isalpha(ch) || ch == '_')) { /* typed parameter KEYWORD(...) */
        char kw[64];
        c->p = keyword(c->r, c->p, kw, sizeof kw);
        if (sc_peek(c) != '(')
            return sr_fail(c->r, c->p, CF_EPARSE, "expected '(' after %s", kw);
        return sc_skip(c);
    }
    double d;
    return sc_real(c, &d);
}

/* A list "(a, b, ...)" of numbers appended to v. */
static int sc_reals(sc_t *c, sr_vec_t *v, size_t *n)
{
    int rc = sc_expect(c, '(');
    size_t n0 = v->n;
    for (int more = 1; !rc && more;) {
        double x;
        if ((rc = sc_real(c, &x)) || (rc = vec_push(v, x)))
            break;
        rc = sc_sep(c, &more);
    }
    if (rc == CF_ENOMEM)
        return cf_fail(c->r->msg, c->r->msglen, rc, "%s: out of memory", c->r->path);
    *n = v->n - n0;
    return rc;
}

/* A list of lists: each inner list of numbers (refs when refs) appended to
 * v, all inner lists of one length (*cols), *rows of them. */
static int sc_grid(sc_t *c, sr_vec_t *v, int refs, size_t *rows, size_t *cols)
{
    int rc = sc_expect(c, '(');
    *rows = *cols = 0;
    for (int more = 1; !rc && more;) {
        size_t at = c->p, n0 = v->n;
        if ((rc = sc_expect(c, '(')))
            return rc;
        for (int in = 1; !rc && in;) {
            double x;
            long id = 0;
            if (refs) {
                rc = sc_ref(c, &id);
                x = (double)id;
            } else
                rc = sc_real(c, &x);
            if (rc || (rc = vec_push(v, x)))
                break;
            rc = sc_sep(c, &in);
        }
        if (rc == CF_ENOMEM)
            return cf_fail(c->r->msg, c->r->msglen, rc, "%s: out of memory", c->r->path);
        if (rc)
            return rc;
        size_t n = v->n - n0;
        if (*rows && n != *cols)
            return sr_fail(c->r, at, CF_EPARSE, "rows of %zu and %zu entries in one net", *cols, n);
        *cols = n;
        (*rows)++;
        rc = sc_sep(c, &more);
    }
    return rc;
}

/* For a complex instance "(A(...) B(...) ...)": the cursor on the '(' of
 * partial entity name's parameters; CF_ENOTFOUND if it has none such. For
 * a simple instance "NAME(...)": the same when NAME matches. */
static int sc_part(const sr_t *r, const sr_rec_t *rec, const char *name, sc_t *c)
{
    char kw[64];
    c->r = r;
    c->p = rec->at;
    c->end = rec->end;
    int complex = sc_peek(c) == '(';
    if (complex)
        c->p++;
    for (;;) {
        if (sc_peek(c) < 0)
            return CF_ENOTFOUND;
        size_t q = keyword(r, c->p, kw, sizeof kw);
        if (q == c->p)
            return complex && sc_peek(c) == ')' ? CF_ENOTFOUND
                                                : sr_fail(r, c->p, CF_EPARSE, "expected a type");
        c->p = q;
        if (sc_peek(c) != '(')
            return sr_fail(r, c->p, CF_EPARSE, "expected '(' after %s", kw);
        if (!strcmp(kw, name))
            return CF_OK;
        if (!complex)
            return CF_ENOTFOUND;
        int rc = sc_skip(c);
        if (rc)
            return rc;
    }
}

/* The type of a simple instance, or the first partial type of a complex one. */
static void rec_type(const sr_t *r, const sr_rec_t *rec, char *kw, size_t kl)
{
    size_t p = skip_ws(r, rec->at);
    if (p < rec->end && r->buf[p] == '(')
        p = skip_ws(r, p + 1);
    keyword(r, p, kw, kl);
}

/* ---- units ---------------------------------------------------------------------- */

/* Millimetres per length unit of the file: the lowest-numbered instance with a
 * LENGTH_UNIT part decides (SI_UNIT(prefix, .METRE.)); 1 when there is none. */
static int sr_unit(const sr_t *r, double *mm)
{
    static const struct {
        const char *name;
        double f;
    } pre[] = {{"EXA", 1e21},  {"PETA", 1e18}, {"TERA", 1e15},   {"GIGA", 1e12},
               {"MEGA", 1e9},  {"KILO", 1e6},  {"HECTO", 1e5},   {"DECA", 1e4},
               {"DECI", 1e2},  {"CENTI", 1e1}, {"MILLI", 1.0},   {"MICRO", 1e-3},
               {"NANO", 1e-6}, {"PICO", 1e-9}, {"FEMTO", 1e-12}, {"ATTO", 1e-15}};
    *mm = 1.0;
    for (size_t i = 0; i < r->nix; i++) {
        const sr_rec_t *rec = &r->ix[i];
        sc_t c;
        if (sc_part(r, rec, "LENGTH_UNIT", &c) != CF_OK)
            continue;
        if (sc_part(r, rec, "SI_UNIT", &c) != CF_OK)
            return sr_fail(r, rec->at, CF_EUNSUPPORTED,
                           "#%ld: a length unit other than an SI unit (e.g. the inch) is not "
                           "supported",
                           rec->id);
        char kw[32] = "";
        c.p++; /* '(' */
        int ch = sc_peek(&c);
        if (ch == '.') {
            size_t q = keyword(r, c.p + 1, kw, sizeof kw);
            c.p = q + 1;
        } else if (ch == '$')
            c.p++;
        else
            return sr_fail(r, c.p, CF_EPARSE, "#%ld: bad SI_UNIT prefix", rec->id);
        double f = 1000.0; /* no prefix: metres */
        if (*kw) {
            size_t k = 0;
            while (k < sizeof pre / sizeof pre[0] && strcmp(pre[k].name, kw))
                k++;
            if (k == sizeof pre / sizeof pre[0])
                return sr_fail(r, c.p, CF_EPARSE, "#%ld: unknown SI prefix .%s.", rec->id, kw);
            f = pre[k].f;
        }
        int more;
        char nm[32];
        if (sc_sep(&c, &more) || !more)
            return sr_fail(r, c.p, CF_EPARSE, "#%ld: SI_UNIT needs a name", rec->id);
        if (sc_peek(&c) != '.')
            return sr_fail(r, c.p, CF_EPARSE, "#%ld: SI_UNIT name is not an enumeration", rec->id);
        keyword(r, c.p + 1, nm, sizeof nm);
        if (strcmp(nm, "METRE"))
            return sr_fail(r, c.p, CF_EUNSUPPORTED, "#%ld: length unit .%s.", rec->id, nm);
        *mm = f;
        return CF_OK;
    }
    return CF_OK;
}

/* ---- the surface ------------------------------------------------------------------ */

static int sr_point(const sr_t *r, long id, size_t from, double xyz[3], sr_vec_t *tmp)
{
    const sr_rec_t *rec = sr_find(r, id);
    if (!rec)
        return sr_fail(r, from, CF_EPARSE, "control point #%ld is not in the file", id);
    sc_t c;
    int rc = sc_part(r, rec, "CARTESIAN_POINT", &c);
    if (rc == CF_ENOTFOUND)
        return sr_fail(r, rec->at, CF_EPARSE, "#%ld is not a CARTESIAN_POINT", id);
    if (rc)
        return rc;
    int more;
    size_t n;
    c.p++;
    tmp->n = 0;
    if ((rc = sc_skip(&c)) || (rc = sc_sep(&c, &more)) || (rc = sc_reals(&c, tmp, &n)))
        return rc;
    if (n != 3)
        return sr_fail(r, rec->at, CF_EPARSE, "#%ld: a point with %zu coordinates, not 3", id, n);
    memcpy(xyz, tmp->d, 3 * sizeof(double));
    return CF_OK;
}

/* Knots from distinct values and multiplicities: exactly m of them. */
static int expand(const sr_t *r, size_t at, const char *dir, const sr_vec_t *mult, size_t m0,
                  const sr_vec_t *kn, size_t k0, size_t nd, double *U, long m)
{
    long k = 0;
    for (size_t i = 0; i < nd; i++) {
        double mu = mult->d[m0 + i];
        if (mu < 1 || mu > m || mu != floor(mu))
            return sr_fail(r, at, CF_EPARSE, "%s knot multiplicity %g", dir, mu);
        if (i && !(kn->d[k0 + i] > kn->d[k0 + i - 1]))
            return sr_fail(r, at, CF_EPARSE, "%s knots not increasing", dir);
        for (long j = 0; j < (long)mu; j++) {
            if (k >= m)
                return sr_fail(r, at, CF_EPARSE, "%s: more knots than %ld", dir, m);
            U[k++] = kn->d[k0 + i];
        }
    }
    if (k != m)
        return sr_fail(r, at, CF_EPARSE, "%s: %ld knots, a B-spline of this size needs %ld", dir, k,
                       m);
    return CF_OK;
}

static int sr_surface(const sr_t *r, const sr_rec_t *rec, nf_surf_t *s)
{
    sr_vec_t net = {0}, mult = {0}, kn = {0}, wts = {0}, tmp = {0};
    sc_t c;
    int rc, more, complex;
    long p = 0, q = 0;
    size_t nu = 0, nv = 0, wr = 0, wc = 0;
    size_t n[4];
    /* Simple: (name, p, q, net, form, closed, closed, self, mults, knots, spec);
     * complex: B_SPLINE_SURFACE(p, q, net, ...) and
     * B_SPLINE_SURFACE_WITH_KNOTS(mults, knots, spec). */
    complex = sc_peek(&(sc_t){r, rec->at, rec->end}) == '(';
    rc = sc_part(r, rec, complex ? "B_SPLINE_SURFACE" : "B_SPLINE_SURFACE_WITH_KNOTS", &c);
    if (rc == CF_ENOTFOUND)
        rc = sr_fail(r, rec->at, CF_EPARSE, "#%ld: no B_SPLINE_SURFACE part", rec->id);
    if (rc)
        goto out;
    c.p++;
    if (!complex && ((rc = sc_skip(&c)) || (rc = sc_sep(&c, &more))))
        goto out;
    if ((rc = sc_int(&c, &p)) || (rc = sc_sep(&c, &more)) || (rc = sc_int(&c, &q)) ||
        (rc = sc_sep(&c, &more)) || (rc = sc_grid(&c, &net, 1, &nu, &nv)))
        goto out;
    if (p < 1 || q < 1 || p > NF_MAX_DEGREE || q > NF_MAX_DEGREE) {
        rc = sr_fail(r, rec->at, NF_EDEGREE, "#%ld: degrees %ld, %ld (1..%d supported)", rec->id, p,
                     q, NF_MAX_DEGREE);
        goto out;
    }
    for (int k = 0; k < 4; k++) /* form, u_closed, v_closed, self_intersect */
        if ((rc = sc_sep(&c, &more)) || (rc = sc_skip(&c)))
            goto out;
    if (complex) {
        rc = sc_part(r, rec, "B_SPLINE_SURFACE_WITH_KNOTS", &c);
        if (rc == CF_ENOTFOUND)
            rc = sr_fail(r, rec->at, CF_EPARSE, "#%ld: no B_SPLINE_SURFACE_WITH_KNOTS part",
                         rec->id);
        if (rc)
            goto out;
        c.p++;
    } else if ((rc = sc_sep(&c, &more)))
        goto out;
    size_t at = c.p;
    if ((rc = sc_reals(&c, &mult, &n[0])) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_reals(&c, &mult, &n[1])) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_reals(&c, &kn, &n[2])) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_reals(&c, &kn, &n[3])))
        goto out;
    if (n[0] != n[2] || n[1] != n[3]) {
        rc = sr_fail(r, at, CF_EPARSE, "#%ld: %zu/%zu multiplicities for %zu/%zu knots", rec->id,
                     n[0], n[1], n[2], n[3]);
        goto out;
    }
    if (complex) {
        rc = sc_part(r, rec, "RATIONAL_B_SPLINE_SURFACE", &c);
        if (rc == CF_OK) {
            c.p++;
            if ((rc = sc_grid(&c, &wts, 0, &wr, &wc)))
                goto out;
            if (wr != nu || wc != nv) {
                rc = sr_fail(r, c.p, CF_EPARSE, "#%ld: %zu x %zu weights for %zu x %zu points",
                             rec->id, wr, wc, nu, nv);
                goto out;
            }
        } else if (rc != CF_ENOTFOUND)
            goto out;
    }
    if (nu > (size_t)NF_MAX_CP || nv > (size_t)NF_MAX_CP || nu * nv > (size_t)NF_MAX_CP) {
        rc = sr_fail(r, rec->at, NF_EBUDGET, "#%ld: %zu x %zu control points exceed %ld", rec->id,
                     nu, nv, (long)NF_MAX_CP);
        goto out;
    }
    if ((rc = cf_surf_alloc(s, (int)p, (int)q, (int)nu, (int)nv))) {
        rc = cf_fail(r->msg, r->msglen, rc, "%s: out of memory", r->path);
        goto out;
    }
    if ((rc = expand(r, at, "u", &mult, 0, &kn, 0, n[0], s->U, (long)nu + p + 1)) ||
        (rc = expand(r, at, "v", &mult, n[0], &kn, n[2], n[1], s->V, (long)nv + q + 1)))
        goto out;
    double mm;
    if ((rc = sr_unit(r, &mm)))
        goto out;
    /* STEP's net is indexed [u][v]; ours u fastest. */
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nv; j++) {
            size_t k = i + j * nu;
            if ((rc = sr_point(r, (long)net.d[i * nv + j], rec->at, s->cp + 3 * k, &tmp)))
                goto out;
            if (mm != 1.0)
                for (int d = 0; d < 3; d++)
                    s->cp[3 * k + d] *= mm;
            if (wts.n)
                s->w[k] = wts.d[i * nv + j];
        }
    rc = nf_surf_check(s);
    if (rc)
        rc = sr_fail(r, rec->at, rc, "#%ld: invalid surface: %s", rec->id, nf_strerror(rc));
out:
    free(net.d);
    free(mult.d);
    free(kn.d);
    free(wts.d);
    free(tmp.d);
    if (rc)
        cf_surf_free(s);
    return rc;
}

/* The file into r->buf and its instances indexed; r->ix and r->buf are the
 * caller's to free, also on failure. */
static int sr_load(sr_t *r)
{
    const char *path = r->path;
    FILE *f = fopen(path, "rb");
    if (!f)
        return cf_fail(r->msg, r->msglen, CF_EIO, "%s: cannot open: %s", path, strerror(errno));
    long len = -1;
    if (fseek(f, 0, SEEK_END) == 0)
        len = ftell(f);
    if (len < 0 || fseek(f, 0, SEEK_SET)) {
        fclose(f);
        return cf_fail(r->msg, r->msglen, CF_EIO, "%s: cannot read: %s", path, strerror(errno));
    }
    r->buf = malloc((size_t)len + 1);
    if (!r->buf) {
        fclose(f);
        return cf_fail(r->msg, r->msglen, CF_ENOMEM, "%s: out of memory for %ld bytes", path, len);
    }
    r->len = fread(r->buf, 1, (size_t)len, f);
    int bad = ferror(f);
    fclose(f);
    r->buf[r->len] = '\0';
    if (bad || r->len != (size_t)len)
        return cf_fail(r->msg, r->msglen, CF_EIO, "%s: read error", path);
    if (memchr(r->buf, '\0', r->len))
        return cf_fail(r->msg, r->msglen, CF_EPARSE, "%s: binary data (a NUL byte) in a STEP file",
                       path);
    return sr_index(r);
}

/* The surface instance: #id, or the first B_SPLINE_SURFACE_WITH_KNOTS in the file. */
static int sr_pick(sr_t *r, long id, const sr_rec_t **out)
{
    const sr_rec_t *rec = NULL;
    sc_t c;
    if (id) {
        rec = sr_find(r, id);
        if (!rec)
            return cf_fail(r->msg, r->msglen, CF_ENOTFOUND, "%s: no instance #%ld", r->path, id);
        if (sc_part(r, rec, "B_SPLINE_SURFACE_WITH_KNOTS", &c) != CF_OK) {
            char kw[64];
            rec_type(r, rec, kw, sizeof kw);
            return sr_fail(r, rec->at, CF_EUNSUPPORTED,
                           "#%ld is %s, not a B_SPLINE_SURFACE_WITH_KNOTS", id, kw);
        }
    } else {
        /* The first in the file, not the lowest number. */
        for (size_t i = 0; i < r->nix; i++)
            if (sc_part(r, &r->ix[i], "B_SPLINE_SURFACE_WITH_KNOTS", &c) == CF_OK &&
                (!rec || r->ix[i].at < rec->at))
                rec = &r->ix[i];
        if (!rec)
            return cf_fail(r->msg, r->msglen, CF_ENOTFOUND,
                           "%s: no B_SPLINE_SURFACE_WITH_KNOTS in the file", r->path);
    }
    *out = rec;
    return CF_OK;
}

int cf_step_read(const char *path, long id, nf_surf_t *out, char *msg, size_t msglen)
{
    if (!path || !out || id < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_step_read: bad arguments");
    memset(out, 0, sizeof *out);
    sr_t r = {path, NULL, 0, NULL, 0, msg, msglen};
    const sr_rec_t *rec = NULL;
    int rc = sr_load(&r);
    if (!rc)
        rc = sr_pick(&r, id, &rec);
    if (!rc)
        rc = sr_surface(&r, rec, out);
    free(r.ix);
    free(r.buf);
    return rc;
}

/* ---- the face's bounds (trim) --------------------------------------------------- */

/* An enumeration ".X." into kw. */
static int sc_enum(sc_t *c, char *kw, size_t kl)
{
    if (sc_peek(c) != '.')
        return sr_fail(c->r, c->p, CF_EPARSE, "expected an enumeration");
    size_t q = keyword(c->r, c->p + 1, kw, kl);
    if (q >= c->end || c->r->buf[q] != '.')
        return sr_fail(c->r, c->p, CF_EPARSE, "bad enumeration");
    c->p = q + 1;
    return CF_OK;
}

/* The cursor just inside instance id's NAME( , past its first k parameters. */
static int sr_args(const sr_t *r, long id, const char *name, int k, sc_t *c)
{
    const sr_rec_t *rec = sr_find(r, id);
    if (!rec)
        return cf_fail(r->msg, r->msglen, CF_EPARSE, "%s: #%ld is not in the file", r->path, id);
    int rc = sc_part(r, rec, name, c);
    if (rc == CF_ENOTFOUND) {
        char kw[64];
        rec_type(r, rec, kw, sizeof kw);
        return sr_fail(r, rec->at, CF_EUNSUPPORTED, "#%ld is %s, not %s (in a face's bounds)", id,
                       kw, name);
    }
    if (rc)
        return rc;
    c->p++;
    int more;
    for (int i = 0; i < k && !rc; i++)
        if (!(rc = sc_skip(c)))
            rc = sc_sep(c, &more);
    return rc;
}

/* A list "(#a, #b, ...)" of references appended to v. */
static int sc_refs(sc_t *c, sr_vec_t *v)
{
    int rc = sc_expect(c, '(');
    for (int more = 1; !rc && more;) {
        long id;
        if ((rc = sc_ref(c, &id)) || (rc = vec_push(v, (double)id)))
            break;
        rc = sc_sep(c, &more);
    }
    if (rc == CF_ENOMEM)
        return cf_fail(c->r->msg, c->r->msglen, rc, "%s: out of memory", c->r->path);
    return rc;
}

/* A 2-D B-spline curve (B_SPLINE_CURVE_WITH_KNOTS, or the rational complex
 * instance) into out as (u, v, 0) points. */
static int sr_curve2d(const sr_t *r, long id, nf_curve_t *out)
{
    const sr_rec_t *rec = sr_find(r, id);
    sr_vec_t pts = {0}, mult = {0}, kn = {0}, wts = {0}, tmp = {0};
    sc_t c;
    long p = 0;
    size_t nm, nk, nw;
    int rc, more;
    if (!rec)
        return cf_fail(r->msg, r->msglen, CF_EPARSE, "%s: #%ld is not in the file", r->path, id);
    int complex = sc_peek(&(sc_t){r, rec->at, rec->end}) == '(';
    rc = sc_part(r, rec, complex ? "B_SPLINE_CURVE" : "B_SPLINE_CURVE_WITH_KNOTS", &c);
    if (rc == CF_ENOTFOUND) {
        char kw[64];
        rec_type(r, rec, kw, sizeof kw);
        return sr_fail(r, rec->at, CF_ENOTFOUND,
                       "#%ld: a parameter-space curve of type %s (only B-splines are read)", id,
                       kw);
    }
    if (rc)
        return rc;
    c.p++;
    if (!complex && ((rc = sc_skip(&c)) || (rc = sc_sep(&c, &more))))
        goto out;
    if ((rc = sc_int(&c, &p)) || (rc = sc_sep(&c, &more)) || (rc = sc_refs(&c, &pts)))
        goto out;
    for (int k = 0; k < 3; k++) /* form, closed, self_intersect */
        if ((rc = sc_sep(&c, &more)) || (rc = sc_skip(&c)))
            goto out;
    if (complex) {
        if ((rc = sc_part(r, rec, "B_SPLINE_CURVE_WITH_KNOTS", &c)))
            goto out;
        c.p++;
    } else if ((rc = sc_sep(&c, &more)))
        goto out;
    if ((rc = sc_reals(&c, &mult, &nm)) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_reals(&c, &kn, &nk)))
        goto out;
    if (complex && (rc = sc_part(r, rec, "RATIONAL_B_SPLINE_CURVE", &c)) == CF_OK) {
        c.p++;
        if ((rc = sc_reals(&c, &wts, &nw)))
            goto out;
    } else if (rc == CF_ENOTFOUND)
        rc = CF_OK;
    if (rc)
        goto out;
    const int n = (int)pts.n;
    if (p < 1 || p > NF_MAX_DEGREE || n < p + 1 || n > NF_MAX_CP || nm != nk ||
        (wts.n && (int)wts.n != n)) {
        rc = sr_fail(r, rec->at, CF_EPARSE, "#%ld: a degree %ld curve of %d points, %zu weights",
                     id, p, n, wts.n);
        goto out;
    }
    if ((rc = cf_curve_alloc(out, (int)p, n))) {
        rc = cf_fail(r->msg, r->msglen, rc, "%s: out of memory", r->path);
        goto out;
    }
    if ((rc = expand(r, rec->at, "curve", &mult, 0, &kn, 0, nm, out->U, (long)n + p + 1)))
        goto out;
    for (int i = 0; i < n && !rc; i++) {
        sc_t pc;
        size_t got;
        int m2;
        tmp.n = 0;
        if ((rc = sr_args(r, (long)pts.d[i], "CARTESIAN_POINT", 1, &pc)) ||
            (rc = sc_reals(&pc, &tmp, &got)))
            break;
        (void)m2;
        if (got != 2) {
            rc = sr_fail(r, rec->at, CF_EPARSE,
                         "#%ld: a parameter-space point with %zu coordinates", id, got);
            break;
        }
        out->cp[3 * i] = tmp.d[0];
        out->cp[3 * i + 1] = tmp.d[1];
        out->cp[3 * i + 2] = 0.0;
        out->w[i] = wts.n ? wts.d[i] : 1.0;
    }
    if (!rc && (rc = nf_curve_check(out)))
        rc = sr_fail(r, rec->at, rc, "#%ld: invalid curve: %s", id, nf_strerror(rc));
out:
    free(pts.d);
    free(mult.d);
    free(kn.d);
    free(wts.d);
    free(tmp.d);
    if (rc)
        cf_curve_free(out);
    return rc;
}

/* The parameter-space curve of EDGE_CURVE ec on surface surf: the PCURVE
 * (of a SURFACE_CURVE or SEAM_CURVE) over surf; *same its same_sense. */
static int sr_edge_pcurve(const sr_t *r, long ec, long surf, nf_curve_t *out, int *same)
{
    sc_t c;
    long v0, v1, geom;
    char kw[16];
    int more;
    int rc = sr_args(r, ec, "EDGE_CURVE", 1, &c);
    if (rc || (rc = sc_ref(&c, &v0)) || (rc = sc_sep(&c, &more)) || (rc = sc_ref(&c, &v1)) ||
        (rc = sc_sep(&c, &more)) || (rc = sc_ref(&c, &geom)) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_enum(&c, kw, sizeof kw)))
        return rc;
    *same = !strcmp(kw, "T");
    const sr_rec_t *g = sr_find(r, geom);
    sc_t gc;
    if (!g)
        return cf_fail(r->msg, r->msglen, CF_EPARSE, "%s: #%ld is not in the file", r->path, geom);
    const char *kind = sc_part(r, g, "SURFACE_CURVE", &gc) == CF_OK ? "SURFACE_CURVE"
                       : sc_part(r, g, "SEAM_CURVE", &gc) == CF_OK  ? "SEAM_CURVE"
                                                                    : NULL;
    if (!kind)
        return sr_fail(r, g->at, CF_ENOTFOUND,
                       "#%ld: edge #%ld has no curve in parameter space (a 3-D curve only)", geom,
                       ec);
    sr_vec_t pcs = {0};
    if ((rc = sr_args(r, geom, kind, 2, &gc)) || (rc = sc_refs(&gc, &pcs))) {
        free(pcs.d);
        return rc;
    }
    rc = sr_fail(r, g->at, CF_ENOTFOUND, "#%ld: no PCURVE on surface #%ld", geom, surf);
    for (size_t i = 0; i < pcs.n; i++) {
        sc_t pc;
        long basis, defrep, item;
        sr_vec_t items = {0};
        if (sr_args(r, (long)pcs.d[i], "PCURVE", 1, &pc) || sc_ref(&pc, &basis) || basis != surf)
            continue;
        if ((rc = sc_sep(&pc, &more)) || (rc = sc_ref(&pc, &defrep)) ||
            (rc = sr_args(r, defrep, "DEFINITIONAL_REPRESENTATION", 1, &pc)) ||
            (rc = sc_refs(&pc, &items))) {
            free(items.d);
            break;
        }
        item = items.n ? (long)items.d[0] : 0;
        free(items.d);
        rc = sr_curve2d(r, item, out);
        break;
    }
    free(pcs.d);
    return rc;
}

/* One bound (FACE_OUTER_BOUND or FACE_BOUND) as a loop of curves in the
 * order and direction the face runs them. */
static int sr_bound(const sr_t *r, long b, long surf, cf_trim_t *t, int *outer)
{
    sc_t c;
    long loop;
    char kw[16];
    int more, rc;
    const sr_rec_t *rec = sr_find(r, b);
    *outer = rec && sc_part(r, rec, "FACE_OUTER_BOUND", &c) == CF_OK;
    rc = sr_args(r, b, *outer ? "FACE_OUTER_BOUND" : "FACE_BOUND", 1, &c);
    if (rc || (rc = sc_ref(&c, &loop)) || (rc = sc_sep(&c, &more)) ||
        (rc = sc_enum(&c, kw, sizeof kw)))
        return rc;
    int bsense = !strcmp(kw, "T");
    sr_vec_t oes = {0};
    if ((rc = sr_args(r, loop, "EDGE_LOOP", 1, &c)) || (rc = sc_refs(&c, &oes))) {
        free(oes.d);
        return rc;
    }
    const int n = (int)oes.n;
    nf_curve_t *cv = n > 0 && n <= CF_TRIM_MAX_CURVES ? calloc((size_t)n, sizeof *cv) : NULL;
    if (!cv) {
        free(oes.d);
        return sr_fail(r, rec ? rec->at : 0, n ? CF_ENOMEM : CF_EPARSE, "#%ld: %d edges", loop, n);
    }
    for (int i = 0; i < n && !rc; i++) {
        long ec;
        int same;
        if ((rc = sr_args(r, (long)oes.d[i], "ORIENTED_EDGE", 3, &c)) || (rc = sc_ref(&c, &ec)) ||
            (rc = sc_sep(&c, &more)) || (rc = sc_enum(&c, kw, sizeof kw)))
            break;
        int osense = !strcmp(kw, "T");
        /* The bound's sense, the oriented edge's and the edge's own: their
         * parity says whether the curve runs the way the face goes. */
        int k = bsense ? i : n - 1 - i;
        if ((rc = sr_edge_pcurve(r, ec, surf, &cv[k], &same)))
            break;
        if ((osense == same) != bsense)
            nf_curve_reverse(&cv[k]);
    }
    free(oes.d);
    if (rc) {
        for (int i = 0; i < n; i++)
            cf_curve_free(&cv[i]);
        free(cv);
        return rc;
    }
    if ((rc = cf_trim_add_loop(t, cv, n)))
        return cf_fail(r->msg, r->msglen, rc, "%s: too many bounds", r->path);
    return CF_OK;
}

int cf_step_read_trim(const char *path, long id, cf_trim_t *out, char *msg, size_t msglen)
{
    if (!path || !out || id < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_step_read_trim: bad arguments");
    memset(out, 0, sizeof *out);
    sr_t r = {path, NULL, 0, NULL, 0, msg, msglen};
    const sr_rec_t *srec = NULL;
    int rc = sr_load(&r);
    if (!rc)
        rc = sr_pick(&r, id, &srec);
    for (size_t i = 0; !rc && i < r.nix; i++) {
        sc_t c;
        long surf;
        int more;
        sr_vec_t bounds = {0};
        if (sc_part(&r, &r.ix[i], "ADVANCED_FACE", &c) != CF_OK)
            continue;
        c.p++;
        if ((rc = sc_skip(&c)) || (rc = sc_sep(&c, &more)) || (rc = sc_refs(&c, &bounds)) ||
            (rc = sc_sep(&c, &more)) || (rc = sc_ref(&c, &surf))) {
            free(bounds.d);
            break;
        }
        if (surf != srec->id) {
            free(bounds.d);
            continue;
        }
        int outer_at = -1;
        for (size_t k = 0; k < bounds.n && !rc; k++) {
            int outer;
            rc = sr_bound(&r, (long)bounds.d[k], surf, out, &outer);
            if (!rc && outer && outer_at < 0)
                outer_at = (int)k;
        }
        free(bounds.d);
        if (!rc && outer_at > 0) { /* the outer bound first */
            cf_trim_loop_t o = out->loop[outer_at];
            memmove(out->loop + 1, out->loop, sizeof o * (size_t)outer_at);
            out->loop[0] = o;
        }
        break;
    }
    free(r.ix);
    free(r.buf);
    if (rc)
        cf_trim_free(out);
    /* Edges with 3-D curves only (cellfit's own untrimmed faces: the four
     * sides of the net) or with PCURVEs other than B-splines (OCCT writes a
     * face's straight sides as LINEs, whose extent only the vertices give):
     * the face is taken whole, as before trims were read. */
    return rc == CF_ENOTFOUND ? CF_OK : rc;
}
