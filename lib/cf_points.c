/* SPDX-License-Identifier: MIT */
/* cf_points.c: streaming point-file reader (ASCII lines; PLY ascii and
 * binary_little_endian). One fixed buffer refilled with fread; a line is
 * parsed in place, after moving its start to the front of the buffer when it
 * straddles a refill. Numbers take Clinger's fast path when that is exact,
 * then Eisel-Lemire's (cf_points_el.c) when it decides, and strtod
 * otherwise, so every value equals strtod's. */
#include "cf_points.h"
#include "cf_bigmem.h"
#include "cf_err.h"
#include "cf_points_el.h"
#include "cf_points_mt.h"
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The read buffer: about 2 MiB; the fuzz build takes a small one
 * (mk/fuzz.mk), so that lines cross refills often and an open costs little. */
#ifndef CF_POINTS_BUF
/* One huge page with cf_bigmem's header, the NUL and the pad: its first
 * touch is one fault, not 512 (about 3 ms in this project's VMs). */
#define CF_POINTS_BUF ((2L << 20) - 4096)
#endif
#define CP_BUF ((long)CF_POINTS_BUF)
_Static_assert(CF_POINTS_BUF >= 2 * CF_POINTS_MAX_LINE + 2,
               "the buffer holds a longest line twice");
#define CP_PAD 8 /* bytes after the buffer's NUL: cf_pel_digits8 loads 8 at a time */
/* Points a raw read must ask for to bypass the buffer (fewer: one fread
 * each would cost more than the copy it saves). */
#define CP_RAW_DIRECT_MIN 512
#define CP_MAX_PROPS 32
#define CP_MAX_ELEMS 16
/* The parse thread's ring (cf_points_thread): 4 blocks of 8,192 rows, 1.5
 * MiB at 5 columns; a block changes hands about every millisecond. */
#define CP_MT_BLOCK 8192
#define CP_MT_NBLK 4

enum { CP_ASCII, CP_PLY_ASCII, CP_PLY_BIN, CP_RAW };
enum { CP_NUM_OK, CP_NUM_JUNK, CP_NUM_NONFINITE, CP_NUM_RANGE };
enum { CP_T_I8 = 1, CP_T_U8, CP_T_I16, CP_T_U16, CP_T_I32, CP_T_U32, CP_T_F32, CP_T_F64 };

typedef struct cp_prop {
    int type;  /* scalar type, or item type of a list */
    int ltype; /* count type of a list; 0 for a scalar */
    int slot;  /* output column, -1 when not wanted */
} cp_prop_t;

typedef struct cp_elem {
    long long count;
    int nprop, vertex;
    cp_prop_t prop[CP_MAX_PROPS];
} cp_elem_t;

struct cf_points {
    FILE *f;
    int is_stdin;
    char name[256];
    char *buf;  /* cap + 1 + CP_PAD bytes: a NUL after a final unterminated line, and
                * room for cf_pel_digits8's 8-byte loads past it */
    size_t cap; /* CP_BUF, or less for a small regular file (cp_cap) */
    size_t len, pos;
    long bound;         /* points at most (cf_points_bound), -1: not known */
    long long boff;     /* file offset of buf[0] */
    long long data_off; /* offset of the first point (after a PLY header) */
    int eof;
    int want, cols, fmt;
    long line, last, data_line;
    int pending; /* the line [ps, pe) was looked at by open, not yet returned */
    char *ps, *pe;
    int err;
    long errline;     /* the error's line, counted from this reader's first (0: none) */
    char errtxt[400]; /* the error without "name:line: " (a rebase words it again) */
    char errmsg[720];
    /* Two halves (cf_points_split): path to open the file again; the first
     * half reads no byte at or past end (-1: to the end of the file); the
     * second starts lbase lines (raw: points) into the file. */
    char *path;
    long long end;
    long lbase;
    int part2;       /* 1: a second half (reads on its caller's thread) */
    cf_points_t *r2; /* the first half's second (closed with it) */
    /* PLY */
    cp_elem_t elem[CP_MAX_ELEMS];
    int nelem, velem, ply_ready;
    long long vdone;
    /* CSV with a header line: the file's columns, and which of them go to
     * each output column. */
    int hdr, hcols;
    int map[CF_POINTS_MAX_COLS];
    /* The parse thread, when on: it alone touches everything above. */
    cf_pmt_t *mt;
    /* 1 after a read since the open or the last rewind: without one, a
     * rewind keeps the thread's work (its ring starts at the first point). */
    int used;
};

static int cp_err(cf_points_t *r, int code, long line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* The kept error in words, its line counted from the file's start. */
static void cp_errword(cf_points_t *r)
{
    if (r->errline > 0)
        snprintf(r->errmsg, sizeof r->errmsg, "%s:%ld: %s", r->name, r->lbase + r->errline,
                 r->errtxt);
    else
        snprintf(r->errmsg, sizeof r->errmsg, "%s: %s", r->name, r->errtxt);
}

/* "name:line: text", kept so that later reads repeat it. */
static int cp_err(cf_points_t *r, int code, long line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->errtxt, sizeof r->errtxt, fmt, ap);
    va_end(ap);
    r->errline = line;
    cp_errword(r);
    r->err = code;
    return code;
}

/* ------------------------------------------------------------ buffering */

/* The buffer for a file of size bytes (-1: not a regular file, or not
 * known): CP_BUF, or for a smaller file the file and a page (a fresh huge
 * page costs 0.4 ms to clear, its 2 MiB more than a small file's pages),
 * never less than a longest line twice. A file that grows after open
 * still streams through it. */
static size_t cp_cap(long long size)
{
    const long long least = 2 * CF_POINTS_MAX_LINE + 2;
    if (size < 0 || size >= CP_BUF - 4096)
        return (size_t)CP_BUF;
    long long c = (size + 4096 + 4095) / 4096 * 4096 - (1 + CP_PAD);
    c = c > CP_BUF ? CP_BUF : c;
    return (size_t)(c < least ? least : c);
}

/* Keep the unread bytes, append what fread gives; sets eof at the end. */
static int cp_fill(cf_points_t *r)
{
    size_t keep = r->len - r->pos;
    if (r->pos) {
        memmove(r->buf, r->buf + r->pos, keep);
        r->boff += (long long)r->pos;
        r->pos = 0;
        r->len = keep;
    }
    size_t room = r->cap - r->len;
    if (r->end >= 0 && (long long)room > r->end - (r->boff + (long long)r->len))
        room = (size_t)(r->end - (r->boff + (long long)r->len)); /* a first half ends there */
    size_t got = room ? fread(r->buf + r->len, 1, room, r->f) : 0;
    r->len += got;
    if (got == 0) {
        if (ferror(r->f))
            return cp_err(r, CF_EIO, r->line + 1, "read error: %s", strerror(errno));
        r->eof = 1;
    }
    return CF_OK;
}

/* Next line, NUL-terminated in place: 1, 0 at the end, or an error. */
static int cp_line(cf_points_t *r, char **s, char **e)
{
    for (;;) {
        char *p = r->buf + r->pos;
        size_t avail = r->len - r->pos;
        char *nl = memchr(p, '\n', avail);
        if (nl) {
            if (nl - p > CF_POINTS_MAX_LINE)
                break;
            *nl = '\0';
            r->pos = (size_t)(nl + 1 - r->buf);
            r->line++;
            *s = p;
            *e = nl;
            return 1;
        }
        if (avail > CF_POINTS_MAX_LINE)
            break;
        if (r->eof) {
            if (!avail)
                return 0;
            p[avail] = '\0';
            r->pos = r->len;
            r->line++;
            *s = p;
            *e = p + avail;
            return 1;
        }
        int rc = cp_fill(r);
        if (rc)
            return rc;
    }
    return cp_err(r, CF_EPARSE, r->line + 1, "line longer than %d bytes (not a point file?)",
                  CF_POINTS_MAX_LINE);
}

/* ------------------------------------------------------------- numbers */

static int cp_digit(char c)
{
    return (unsigned)(c - '0') < 10u;
}

static int cp_lower(char c)
{
    return (c >= 'A' && c <= 'Z') ? c + ('a' - 'A') : c;
}

/* s starts with lit, ignoring case (s is NUL-terminated, lit lower case). */
static int cp_prefix(const char *s, const char *lit)
{
    for (; *lit; s++, lit++)
        if (cp_lower(*s) != *lit)
            return 0;
    return 1;
}

static int cp_sep(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == ',' || c == '#' || c == '\0' || c == '\v' ||
           c == '\f';
}

static int cp_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* The slow path: strtod on a NUL-terminated copy (the line may go on). */
static __attribute__((noinline)) double cp_strtod(const char *s, size_t n)
{
    char tmp[CF_POINTS_MAX_LINE + 1];
    memcpy(tmp, s, n);
    tmp[n] = '\0';
    return strtod(tmp, NULL);
}

/* Decimal number at p: [+-] digits [. digits] [e [+-] digits]. *end is set
 * after it; the caller checks that a separator follows. */
static int cp_num(const char *p, const char **end, double *out)
{
    const char *s = p;
    int neg = 0, nd = 0, drop = 0, any = 0;
    uint64_t m = 0;
    long e10;
    if (*p == '-' || *p == '+')
        neg = *p++ == '-';
    while (*p == '0') {
        p++;
        any = 1;
    }
#if CF_PEL_SWAR
    for (int n = 8; n == 8 && nd <= 11 && cp_digit(*p);) { /* nd + 8 <= 19: nothing dropped here */
        uint64_t v;
        if (!(n = cf_pel_digits8(p, &v)))
            break;
        m = m * cf_pel_p10u[n] + v;
        nd += n;
        p += n;
        any = 1;
    }
#endif
    for (; cp_digit(*p); p++, any = 1) {
        if (nd < 19) {
            m = m * 10 + (uint64_t)(*p - '0');
            nd++;
        } else {
            drop++;
        }
    }
    e10 = drop;
    if (*p == '.') {
        p++;
        if (!nd)
            for (; *p == '0'; p++, any = 1)
                e10--;
#if CF_PEL_SWAR
        for (int n = 8; n == 8 && nd <= 11 && cp_digit(*p);) {
            uint64_t v;
            if (!(n = cf_pel_digits8(p, &v)))
                break;
            m = m * cf_pel_p10u[n] + v;
            nd += n;
            e10 -= n;
            p += n;
            any = 1;
        }
#endif
        for (; cp_digit(*p); p++, any = 1) {
            if (nd < 19) {
                m = m * 10 + (uint64_t)(*p - '0');
                nd++;
                e10--;
            } else {
                drop++;
            }
        }
    }
    if (!any) {
        /* inf, infinity, nan, nan(chars): parsed only to be refused by name;
         * "information" stays junk. */
        const char *q = p;
        if (cp_prefix(q, "inf")) {
            q += cp_prefix(q, "infinity") ? 8 : 3;
        } else if (cp_prefix(q, "nan")) {
            q += 3;
            if (*q == '(') {
                const char *c = q + 1;
                while ((cp_lower(*c) >= 'a' && cp_lower(*c) <= 'z') || cp_digit(*c) || *c == '_')
                    c++;
                q = *c == ')' ? c + 1 : q;
            }
        }
        if (q != p && cp_sep(*q)) {
            *end = q;
            return CP_NUM_NONFINITE;
        }
        *end = p;
        return CP_NUM_JUNK;
    }
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        int en = 0;
        long ex = 0;
        if (*q == '-' || *q == '+')
            en = *q++ == '-';
        if (!cp_digit(*q)) {
            *end = p;
            return CP_NUM_JUNK;
        }
        for (; cp_digit(*q); q++)
            if (ex < 100000)
                ex = ex * 10 + (*q - '0');
        e10 += en ? -ex : ex;
        p = q;
    }
    *end = p;
    if (m == 0) { /* drop is 0 too: only leading zeros were seen */
        *out = neg ? -0.0 : 0.0;
        return CP_NUM_OK;
    }
    /* The exact shortcuts (cf_points_el.h), else strtod. */
    {
        double d;
        if (cf_pel_fast(m, e10, drop, &d)) {
            *out = neg ? -d : d;
            return CP_NUM_OK;
        }
    }
    *out = cp_strtod(s, (size_t)(p - s));
    return isinf(*out) ? CP_NUM_RANGE : CP_NUM_OK;
}

/* Error for the token at p (st: what cp_num said, bad: first offending byte). */
static int cp_bad_token(cf_points_t *r, const char *p, const char *bad, int st)
{
    char tok[28];
    int n = 0;
    unsigned char b = (unsigned char)*bad;
    if (st == CP_NUM_JUNK || st == CP_NUM_OK) {
        if (b == 0)
            return cp_err(r, CF_EPARSE, r->line, "NUL byte: binary data, not a point file");
        if (b < 0x20 || b >= 0x7F)
            return cp_err(r, CF_EPARSE, r->line, "byte 0x%02x: binary data, not a point file", b);
    }
    for (; p[n] && !cp_sep(p[n]) && n < (int)sizeof tok - 4; n++)
        tok[n] = (p[n] >= 0x20 && p[n] < 0x7F) ? p[n] : '?';
    if (p[n] && !cp_sep(p[n]))
        tok[n++] = '.', tok[n++] = '.', tok[n++] = '.';
    tok[n] = '\0';
    if (st == CP_NUM_NONFINITE)
        return cp_err(r, CF_EPARSE, r->line, "non-finite coordinate '%s'", tok);
    if (st == CP_NUM_RANGE)
        return cp_err(r, CF_EPARSE, r->line, "number '%s' out of double range", tok);
    return cp_err(r, CF_EPARSE, r->line, "'%s' is not a number", tok);
}

/* Numbers of the line [s, e) (NUL at e): the first lim into row. Returns how
 * many there are, or an error. */
static int cp_parse(cf_points_t *r, const char *s, const char *e, double *row, int lim)
{
    const char *p = s;
    int n = 0;
    double dummy;
    for (;;) {
        while (cp_space(*p))
            p++;
        if (*p == ',') {
            if (n == 0)
                return cp_err(r, CF_EPARSE, r->line, "empty field before ','");
            p++;
            while (cp_space(*p))
                p++;
            if ((*p == '\0' && p == e) || *p == '#' || *p == ',')
                return cp_err(r, CF_EPARSE, r->line, "empty field after ','");
        }
        if (*p == '\0') {
            if (p != e)
                return cp_bad_token(r, p, p, CP_NUM_JUNK);
            return n;
        }
        if (*p == '#') {
            if (memchr(p, '\0', (size_t)(e - p)))
                return cp_err(r, CF_EPARSE, r->line, "NUL byte: binary data, not a point file");
            return n;
        }
        const char *q;
        int st = cp_num(p, &q, n < lim ? &row[n] : &dummy);
        if (st != CP_NUM_OK || !cp_sep(*q) || (*q == '\0' && q != e))
            return cp_bad_token(r, p, q, st);
        n++;
        p = q;
    }
}

/* --------------------------------------------------------------- ASCII */

static int cp_ascii_point(cf_points_t *r, double *row)
{
    for (;;) {
        char *s, *e;
        int rc = 1;
        if (r->pending) {
            r->pending = 0;
            s = r->ps;
            e = r->pe;
        } else {
            rc = cp_line(r, &s, &e);
        }
        if (rc <= 0)
            return rc;
        if (r->hdr) {
            double all[CP_MAX_PROPS];
            int n = cp_parse(r, s, e, all, r->hcols);
            if (n < 0)
                return n;
            if (n == 0)
                continue;
            if (n != r->hcols)
                return cp_err(r, CF_EPARSE, r->line, "%d value%s, the header names %d", n,
                              n == 1 ? "" : "s", r->hcols);
            for (int k = 0; k < r->cols; k++)
                row[k] = all[r->map[k]];
            r->last = r->line;
            return 1;
        }
        int n = cp_parse(r, s, e, row, r->cols);
        if (n < 0)
            return n;
        if (n == 0)
            continue;
        if (n != r->cols)
            return cp_err(r, CF_EPARSE, r->line, "%d value%s, expected %d", n, n == 1 ? "" : "s",
                          r->cols);
        r->last = r->line;
        return 1;
    }
}

/* want_cols = 0: the first data line decides; it is kept for the first read. */
static int cp_first_cols(cf_points_t *r)
{
    double row[CF_POINTS_MAX_COLS];
    for (;;) {
        char *s, *e;
        int rc = 1;
        if (r->pending) { /* the line cp_csv_header looked at */
            r->pending = 0;
            s = r->ps;
            e = r->pe;
        } else {
            rc = cp_line(r, &s, &e);
        }
        if (rc <= 0)
            return rc; /* empty file: cols stays 0, reads return 0 */
        int n = cp_parse(r, s, e, row, CF_POINTS_MAX_COLS);
        if (n < 0)
            return n;
        if (n == 0)
            continue;
        if (n != 3 && n != 5)
            return cp_err(r, CF_EPARSE, r->line,
                          "%d values; a point line has 3 (x y z) or 5 (u v x y z)", n);
        r->cols = n;
        r->pending = 1;
        r->ps = s;
        r->pe = e;
        return CF_OK;
    }
}

/* CSV with a header line ("x,y,z", "u,v,x,y,z", in any order, other
 * columns ignored): when the first line that is not blank or a comment
 * starts with a letter or a quote, its names choose the columns. Without a
 * header nothing is consumed (the line stays pending for the reads). */
static int cp_csv_header(cf_points_t *r)
{
    char *s, *e;
    for (;;) {
        int rc = cp_line(r, &s, &e);
        if (rc <= 0)
            return rc;
        const char *p = s;
        while (cp_space(*p))
            p++;
        /* Blank or a comment; a NUL before the line's end is data (the
         * reader names it), as on every later read. */
        if ((*p == '\0' && p == e) || *p == '#')
            continue;
        int words = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || *p == '"';
        /* A header holds names only ("information 2 3" is a bad data line)
         * and names at least one of u v x y z ("hello world" is junk). */
        int named = 0;
        for (const char *t = p; words && t < e;) {
            double d;
            const char *q;
            if (cp_num(t, &q, &d) == CP_NUM_OK && (cp_sep(*q) || *q == ';'))
                words = 0;
            const char *w0 = t + (*t == '"');
            while (t < e && !cp_space(*t) && *t != ',' && *t != ';')
                t++;
            size_t wl = (size_t)(t - w0) - (t > w0 && t[-1] == '"');
            if (wl == 1 && strchr("uvxyzUVXYZ", *w0))
                named = 1;
            while (t < e && (cp_space(*t) || *t == ',' || *t == ';'))
                t++;
        }
        words = words && named;
        if (!words) {
            r->pending = 1; /* a data line, read first */
            r->ps = s;
            r->pe = e;
            return 1;
        }
        break;
    }
    /* The names, split at commas, semicolons or blanks, quotes dropped. */
    int idx[5] = {-1, -1, -1, -1, -1}; /* u v x y z */
    int n = 0;
    char *p = s;
    while (p < e) {
        while (p < e && (cp_space(*p) || *p == ',' || *p == ';'))
            p++;
        if (p >= e)
            break;
        char name[32];
        size_t k = 0;
        while (p < e && !cp_space(*p) && *p != ',' && *p != ';') {
            if (*p != '"' && k + 1 < sizeof name)
                name[k++] = (char)cp_lower(*p);
            p++;
        }
        name[k] = '\0';
        if (n >= CP_MAX_PROPS)
            return cp_err(r, CF_EUNSUPPORTED, r->line, "header with more than %d columns",
                          CP_MAX_PROPS);
        static const char *const want[5] = {"u", "v", "x", "y", "z"};
        for (int w = 0; w < 5; w++)
            if (!strcmp(name, want[w])) {
                if (idx[w] >= 0)
                    return cp_err(r, CF_EPARSE, r->line, "header names column '%s' twice", want[w]);
                idx[w] = n;
            }
        n++;
    }
    int has_uv = idx[0] >= 0 && idx[1] >= 0, has_xyz = idx[2] >= 0 && idx[3] >= 0 && idx[4] >= 0;
    int cols = r->want ? r->want : has_uv && has_xyz ? 5 : 3;
    const int *from = cols == 2 ? idx : cols == 3 ? idx + 2 : idx;
    if (cols != 2 && cols != 3 && cols != 5)
        return cp_err(r, CF_EUNSUPPORTED, r->line, "a header for %d columns", cols);
    for (int k = 0; k < cols; k++) {
        if (from[k] < 0) {
            static const char *const what[5] = {"u", "v", "x", "y", "z"};
            int w = (int)(from - idx) + k;
            return cp_err(r, CF_EPARSE, r->line,
                          "the header names no '%s' column (need %s; names are u v x y z)", what[w],
                          cols == 2   ? "u,v"
                          : cols == 3 ? "x,y,z"
                                      : "u,v,x,y,z");
        }
        r->map[k] = from[k];
    }
    r->hdr = 1;
    r->hcols = n;
    r->cols = cols;
    r->data_off = r->boff + (long long)r->pos;
    r->data_line = r->line;
    return 1;
}

/* ----------------------------------------------------------------- PLY */

static int cp_type(const char *t)
{
    static const struct {
        const char *name;
        int type;
    } map[] = {
        {"char", CP_T_I8},   {"int8", CP_T_I8},     {"uchar", CP_T_U8},   {"uint8", CP_T_U8},
        {"short", CP_T_I16}, {"int16", CP_T_I16},   {"ushort", CP_T_U16}, {"uint16", CP_T_U16},
        {"int", CP_T_I32},   {"int32", CP_T_I32},   {"uint", CP_T_U32},   {"uint32", CP_T_U32},
        {"float", CP_T_F32}, {"float32", CP_T_F32}, {"double", CP_T_F64}, {"float64", CP_T_F64}};
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcmp(t, map[i].name))
            return map[i].type;
    return 0;
}

static size_t cp_tsize(int t)
{
    static const size_t sz[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return sz[t];
}

/* Little-endian value of type t at b, as a double. */
static double cp_le(const unsigned char *b, int t)
{
    uint64_t u = 0;
    size_t n = cp_tsize(t);
    for (size_t i = 0; i < n; i++)
        u |= (uint64_t)b[i] << (8 * i);
    switch (t) {
    case CP_T_I8: return (double)(int8_t)u;
    case CP_T_U8: return (double)u;
    case CP_T_I16: return (double)(int16_t)u;
    case CP_T_U16: return (double)u;
    case CP_T_I32: return (double)(int32_t)u;
    case CP_T_U32: return (double)u;
    case CP_T_F32: {
        float f;
        uint32_t w = (uint32_t)u;
        memcpy(&f, &w, sizeof f);
        return (double)f;
    }
    default: {
        double d;
        memcpy(&d, &u, sizeof d);
        return d;
    }
    }
}

/* Split a header line into at most max words. */
static int cp_words(char *s, char **w, int max)
{
    int n = 0;
    for (;;) {
        while (cp_space(*s))
            s++;
        if (!*s || n == max)
            return n;
        w[n++] = s;
        while (*s && !cp_space(*s))
            s++;
        if (*s)
            *s++ = '\0';
    }
}

static int cp_ply_slots(cf_points_t *r, cp_elem_t *v, char (*names)[32])
{
    int at[5] = {-1, -1, -1, -1, -1}; /* x y z u v */
    static const char *nm[7] = {"x", "y", "z", "u", "v", "s", "t"};
    for (int i = 0; i < v->nprop; i++) {
        v->prop[i].slot = -1;
        for (int k = 0; k < 7; k++)
            if (!v->prop[i].ltype && !strcmp(names[i], nm[k]) && at[k < 5 ? k : k - 2] < 0)
                at[k < 5 ? k : k - 2] = i;
    }
    if (at[0] < 0 || at[1] < 0 || at[2] < 0)
        return cp_err(r, CF_EPARSE, r->line, "PLY vertex element lacks scalar x, y and z");
    int uv = at[3] >= 0 && at[4] >= 0;
    int cols = r->want ? r->want : (uv ? 5 : 3);
    if (cols == 5 && !uv)
        return cp_err(r, CF_EPARSE, r->line,
                      "PLY vertices have no u v (or s t) properties, 5 columns wanted");
    if (cols != 3 && cols != 5)
        return cp_err(r, CF_EUNSUPPORTED, r->line, "PLY input gives 3 or 5 columns, not %d", cols);
    for (int k = 0; k < 3; k++)
        v->prop[at[k]].slot = k + (cols == 5 ? 2 : 0);
    if (cols == 5) {
        v->prop[at[3]].slot = 0;
        v->prop[at[4]].slot = 1;
    }
    r->cols = cols;
    return CF_OK;
}

static int cp_ply_header(cf_points_t *r)
{
    char names[CP_MAX_PROPS][32];
    int have_format = 0, after = 0; /* after: elements past the vertices, never read */
    r->velem = -1;
    for (;;) {
        char *s, *e, *w[6];
        int rc = cp_line(r, &s, &e);
        if (rc < 0)
            return rc;
        if (rc == 0)
            return cp_err(r, CF_EPARSE, r->line, "PLY header without end_header");
        if ((size_t)(e - s) != strlen(s))
            return cp_err(r, CF_EPARSE, r->line, "NUL byte in the PLY header");
        int n = cp_words(s, w, 6);
        if (r->line == 1) {
            if (n != 1 || strcmp(w[0], "ply"))
                return cp_err(r, CF_EPARSE, r->line, "not a PLY header");
            continue;
        }
        if (n == 0 || !strcmp(w[0], "comment") || !strcmp(w[0], "obj_info"))
            continue;
        if (!strcmp(w[0], "end_header") && n == 1)
            break;
        if (!strcmp(w[0], "element") && r->velem >= 0)
            after = 1;
        if (after)
            continue;
        if (!strcmp(w[0], "format") && n == 3) {
            if (!strcmp(w[1], "ascii"))
                r->fmt = CP_PLY_ASCII;
            else if (!strcmp(w[1], "binary_little_endian"))
                r->fmt = CP_PLY_BIN;
            else
                return cp_err(r, CF_EUNSUPPORTED, r->line, "PLY format %s is not supported", w[1]);
            if (strcmp(w[2], "1.0"))
                return cp_err(r, CF_EUNSUPPORTED, r->line, "PLY version %s", w[2]);
            have_format = 1;
        } else if (!strcmp(w[0], "element") && n == 3) {
            char *end;
            long long cnt = strtoll(w[2], &end, 10);
            if (*end || cnt < 0)
                return cp_err(r, CF_EPARSE, r->line, "element count '%s'", w[2]);
            if (r->nelem == CP_MAX_ELEMS)
                return cp_err(r, CF_EUNSUPPORTED, r->line, "more than %d PLY elements",
                              CP_MAX_ELEMS);
            cp_elem_t *el = &r->elem[r->nelem++];
            memset(el, 0, sizeof *el);
            el->count = cnt;
            el->vertex = !strcmp(w[1], "vertex");
            if (el->vertex)
                r->velem = r->nelem - 1;
        } else if (!strcmp(w[0], "property") && (n == 3 || n == 5)) {
            if (!r->nelem)
                return cp_err(r, CF_EPARSE, r->line, "PLY property before any element");
            cp_elem_t *el = &r->elem[r->nelem - 1];
            if (el->nprop == CP_MAX_PROPS)
                return cp_err(r, CF_EUNSUPPORTED, r->line, "more than %d properties", CP_MAX_PROPS);
            cp_prop_t *pr = &el->prop[el->nprop];
            int list = n == 5 && !strcmp(w[1], "list");
            pr->ltype = list ? cp_type(w[2]) : 0;
            pr->type = cp_type(w[list ? 3 : 1]);
            pr->slot = -1;
            if (!pr->type || (list && (!pr->ltype || pr->ltype >= CP_T_F32)) || (n == 5 && !list))
                return cp_err(r, CF_EPARSE, r->line, "PLY property type not understood");
            if (el->vertex)
                snprintf(names[el->nprop], sizeof names[0], "%s", w[n - 1]);
            el->nprop++;
        } else {
            return cp_err(r, CF_EPARSE, r->line, "PLY header line '%.40s' not understood", w[0]);
        }
    }
    if (!have_format)
        return cp_err(r, CF_EPARSE, r->line, "PLY header without a format line");
    if (r->velem < 0)
        return cp_err(r, CF_EPARSE, r->line, "PLY file without a vertex element");
    int rc = cp_ply_slots(r, &r->elem[r->velem], names);
    if (rc)
        return rc;
    r->data_off = r->boff + (long long)r->pos;
    r->data_line = r->line;
    return CF_OK;
}

/* Make n bytes readable at pos: 0, 1 at a clean end of file, -1 mid-value. */
static int cp_need(cf_points_t *r, size_t n)
{
    while (r->len - r->pos < n) {
        if (r->eof)
            return r->len == r->pos ? 1 : -1;
        int rc = cp_fill(r);
        if (rc)
            return rc;
    }
    return 0;
}

/* One binary element instance; wanted values into row. */
static int cp_bin_one(cf_points_t *r, const cp_elem_t *el, double *row, long long idx)
{
    for (int i = 0; i < el->nprop; i++) {
        const cp_prop_t *pr = &el->prop[i];
        size_t sz = cp_tsize(pr->ltype ? pr->ltype : pr->type);
        int rc = cp_need(r, sz);
        if (rc > 0 && i == 0)
            return 1;
        if (rc)
            return rc < -1 ? rc
                           : cp_err(r, CF_EPARSE, 0, "file ends inside element %lld of %lld",
                                    idx + 1, el->count);
        double v = cp_le((unsigned char *)r->buf + r->pos, pr->ltype ? pr->ltype : pr->type);
        r->pos += sz;
        if (!pr->ltype) {
            if (pr->slot >= 0) {
                if (!isfinite(v))
                    return cp_err(r, CF_EPARSE, 0, "vertex %lld: non-finite coordinate", idx + 1);
                row[pr->slot] = v;
            }
            continue;
        }
        /* A list: skip count items, a buffer's worth at a time. */
        if (v < 0)
            return cp_err(r, CF_EPARSE, 0, "element %lld: negative list length", idx + 1);
        long long skip = (long long)v * (long long)cp_tsize(pr->type);
        while (skip > 0) {
            rc = cp_need(r, 1);
            if (rc)
                return rc < -1 ? rc
                               : cp_err(r, CF_EPARSE, 0, "file ends inside element %lld", idx + 1);
            size_t take = r->len - r->pos;
            if ((long long)take > skip)
                take = (size_t)skip;
            r->pos += take;
            skip -= (long long)take;
        }
    }
    return 0;
}

/* One ASCII element instance (one line): wanted values into row. */
static int cp_asc_one(cf_points_t *r, const cp_elem_t *el, double *row, long long idx)
{
    char *s, *e;
    int rc;
    do {
        rc = cp_line(r, &s, &e);
        if (rc < 0)
            return rc;
        if (rc == 0)
            return cp_err(r, CF_EPARSE, r->line, "file ends after %lld of %lld elements", idx,
                          el->count);
        while (cp_space(*s))
            s++;
    } while (s == e);
    const char *p = s;
    for (int i = 0; i < el->nprop; i++) {
        const cp_prop_t *pr = &el->prop[i];
        long long items = 1;
        int list = pr->ltype != 0;
        for (long long k = 0; k < items + list; k++) {
            const char *q;
            double v;
            while (cp_space(*p))
                p++;
            if (*p == '\0' && p == e)
                return cp_err(r, CF_EPARSE, r->line, "too few values for the PLY element");
            int st = cp_num(p, &q, &v);
            if (st != CP_NUM_OK || !cp_sep(*q) || *q == ',' || *q == '#' || (*q == '\0' && q != e))
                return cp_bad_token(r, p, q, st);
            if (list && k == 0) {
                if (v < 0 || v > CF_POINTS_MAX_LINE || v != floor(v))
                    return cp_err(r, CF_EPARSE, r->line, "bad PLY list length");
                items = (long long)v;
            } else if (pr->slot >= 0) {
                row[pr->slot] = v;
            }
            p = q;
        }
    }
    while (cp_space(*p))
        p++;
    if (p != e)
        return cp_err(r, CF_EPARSE, r->line, "more values than the PLY element has properties");
    return 0;
}

static int cp_ply_point(cf_points_t *r, double *row)
{
    double scratch[CF_POINTS_MAX_COLS];
    if (!r->ply_ready) { /* elements before the vertices: read and dropped */
        for (int k = 0; k < r->velem; k++)
            /* A binary element without properties has no bytes: 10^12 of
             * them are nothing to read, not 10^12 turns of a loop. */
            for (long long i = 0;
                 i < r->elem[k].count && (r->fmt != CP_PLY_BIN || r->elem[k].nprop); i++) {
                int rc = r->fmt == CP_PLY_BIN ? cp_bin_one(r, &r->elem[k], scratch, i)
                                              : cp_asc_one(r, &r->elem[k], scratch, i);
                if (rc > 0)
                    return cp_err(r, CF_EPARSE, 0, "file ends in element %d", k);
                if (rc)
                    return rc;
            }
        r->ply_ready = 1;
    }
    const cp_elem_t *v = &r->elem[r->velem];
    if (r->vdone == v->count)
        return 0;
    int rc =
        r->fmt == CP_PLY_BIN ? cp_bin_one(r, v, row, r->vdone) : cp_asc_one(r, v, row, r->vdone);
    if (rc > 0)
        return cp_err(r, CF_EPARSE, 0, "file ends after %lld of %lld vertices", r->vdone, v->count);
    if (rc)
        return rc;
    r->vdone++;
    r->last = r->fmt == CP_PLY_BIN ? (long)r->vdone : r->line;
    return 1;
}

/* ------------------------------------------- raw float64 (.xyz.bin) */

/* Columns of a raw little-endian float64 file named by its extension:
 * 5 for .uvxyz.bin, 3 for .xyz.bin, 0 for anything else (docs/formats.md). */
static int cp_raw_cols(const char *path)
{
    size_t n = strlen(path);
    if (n >= 10 && !strcmp(path + n - 10, ".uvxyz.bin"))
        return 5;
    if (n >= 8 && !strcmp(path + n - 8, ".xyz.bin"))
        return 3;
    return 0;
}

/* Values of points [k0, k0 + n) of out all finite, else the error. Branch
 * free over blocks of 4 values first: an exponent of all ones (inf, NaN)
 * plus one carries into the sign bit, OR-ed over all; the search only on a
 * find. The check at memory speed (issue 20). */
static int cp_raw_finite(cf_points_t *r, const double *out, long k0, long n)
{
    const size_t nv = (size_t)n * (size_t)r->cols;
    const double *o = out + k0 * r->cols;
    const uint64_t E = UINT64_C(0x7ff0000000000000), ONE = UINT64_C(1) << 52;
    uint64_t bad = 0;
    size_t i = 0;
    for (; i + 4 <= nv; i += 4) {
        uint64_t a, b, c, d;
        memcpy(&a, o + i, 8);
        memcpy(&b, o + i + 1, 8);
        memcpy(&c, o + i + 2, 8);
        memcpy(&d, o + i + 3, 8);
        bad |= ((a & E) + ONE) | ((b & E) + ONE) | ((c & E) + ONE) | ((d & E) + ONE);
    }
    for (; i < nv; i++) {
        uint64_t b;
        memcpy(&b, o + i, sizeof b);
        bad |= (b & E) + ONE;
    }
    for (i = 0; bad >> 63 && i < nv; i++)
        if (!isfinite(o[i]))
            return cp_err(r, CF_EPARSE, 0, "point %lld: non-finite value",
                          r->lbase + r->vdone + 1 + (long long)(i / (size_t)r->cols));
    return CF_OK;
}

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
/* With the buffer empty, whole records straight from the file into out
 * (at most max, up to a first half's end): one copy fewer (40 MB a pass
 * for 10^6 u v x y z points, issue 20). Bytes of a record cut by the file's end
 * go to the buffer, where the caller's loop reports them. The count read,
 * 0 when direct reading does not apply, or an error. */
static long cp_raw_direct(cf_points_t *r, double *out, long max)
{
    const size_t rec = sizeof(double) * (size_t)r->cols;
    long long want = (long long)max * (long long)rec, at = r->boff + (long long)r->len;
    if (r->end >= 0 && want > r->end - at)
        want = r->end - at;
    if (r->eof || r->pos != r->len || want < CP_RAW_DIRECT_MIN * (long long)rec)
        return 0;
    size_t got = fread(out, 1, (size_t)want, r->f);
    if (got < (size_t)want && ferror(r->f))
        return cp_err(r, CF_EIO, 0, "read error: %s", strerror(errno));
    if (got < (size_t)want)
        r->eof = 1;
    const long n = (long)(got / rec);
    const size_t stray = got % rec;
    memcpy(r->buf, (const char *)out + got - stray, stray);
    r->boff = at + (long long)(got - stray);
    r->len = stray;
    r->pos = 0;
    int rc = cp_raw_finite(r, out, 0, n);
    if (rc)
        return rc;
    r->vdone += n;
    return n;
}
#endif

/* Whole records into out: straight from the file when the buffer is empty
 * (cp_raw_direct), else a memcpy from the buffer on a little-endian host
 * (the file's order), so the reader runs at memory speed; every value
 * checked finite, like the text formats. */
static long cp_raw_read(cf_points_t *r, double *out, long max)
{
    size_t rec = sizeof(double) * (size_t)r->cols;
    long k = 0;
    while (k < max) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
        long d = cp_raw_direct(r, out + k * r->cols, max - k);
        if (d < 0)
            return d;
        if (d > 0) {
            k += d;
            continue;
        }
#endif
        size_t avail = r->len - r->pos; /* after a direct read: the bytes it cut */
        if (avail < rec) {
            if (r->eof) {
                if (avail && !k) /* the whole points first, the error next call */
                    return cp_err(r, CF_EPARSE, 0,
                                  "file ends inside point %lld (%zu stray bytes; %zu per point)",
                                  r->lbase + r->vdone + 1, avail, rec);
                break;
            }
            int rc = cp_fill(r);
            if (rc)
                return rc;
            continue;
        }
        long take = (long)(avail / rec);
        take = take > max - k ? max - k : take;
        const unsigned char *b = (const unsigned char *)r->buf + r->pos;
        double *o = out + k * r->cols;
        size_t nv = (size_t)take * (size_t)r->cols;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
        memcpy(o, b, nv * sizeof(double));
#else
        for (size_t i = 0; i < nv; i++)
            o[i] = cp_le(b + 8 * i, CP_T_F64);
#endif
        int rc = cp_raw_finite(r, out, k, take);
        if (rc)
            return rc;
        r->pos += nv * sizeof(double);
        r->vdone += take;
        k += take;
    }
    r->last = (long)r->vdone;
    return k;
}

/* ----------------------------------------------------------------- API */

int cf_points_open(cf_points_t **rp, const char *path, int want_cols, char *msg, size_t msglen)
{
    if (rp)
        *rp = NULL;
    if (!rp || !path || want_cols < 0 || want_cols > CF_POINTS_MAX_COLS)
        return cf_fail(msg, msglen, CF_EARG, "cf_points_open: bad arguments");
    cf_points_t *r = calloc(1, sizeof *r);
    if (!r)
        return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", path);
    r->is_stdin = !strcmp(path, "-");
    struct stat st;
    const long long size =
        !r->is_stdin && !stat(path, &st) && S_ISREG(st.st_mode) ? (long long)st.st_size : -1;
    r->cap = cp_cap(size);
    r->bound = -1;
    r->buf = cf_bigmem_alloc(r->cap + 1 + CP_PAD);
    /* Touch every page now (not with zeros: malloc+memset 0 may become a lazy
     * calloc) so the footprint is fixed at open, whatever the file size. */
    if (r->buf)
        memset(r->buf, ' ', r->cap + 1 + CP_PAD);
    snprintf(r->name, sizeof r->name, "%s", r->is_stdin ? "<stdin>" : path);
    r->want = r->cols = want_cols;
    r->end = -1;
    r->path = strdup(path);
    if (!r->buf || !r->path) {
        cf_points_close(r);
        return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", path);
    }
    r->f = r->is_stdin ? stdin : fopen(path, "rb");
    if (!r->f) {
        int e = errno;
        cf_points_close(r);
        return cf_fail(msg, msglen, CF_EIO, "%s: cannot open: %s", path, strerror(e));
    }
    /* A file is read once from end to end (twice with a residual pass):
     * let the kernel read ahead further (no effect on a pipe). */
    if (!r->is_stdin)
        (void)posix_fadvise(fileno(r->f), 0, 0, POSIX_FADV_SEQUENTIAL);
    int rc = cp_fill(r);
    while (!rc && !r->eof && r->len < 4)
        rc = cp_fill(r);
    const unsigned char *b = (const unsigned char *)r->buf;
    int raw = r->is_stdin ? 0 : cp_raw_cols(path);
    /* The whole file read: its lines, counted before parsing marks them
     * (a bound for the text formats only: binary PLY's bytes are not lines). */
    long lines = -1;
    if (!rc && !raw && size >= 0 && (long long)r->len == size) {
        lines = 1;
        for (const char *p = r->buf, *e = r->buf + r->len; (p = memchr(p, '\n', (size_t)(e - p)));
             p++)
            lines++;
    }
    if (rc) {
        /* message already in r->errmsg */
    } else if (raw) {
        r->fmt = CP_RAW;
        if (want_cols && want_cols != raw)
            rc = cp_err(r, CF_EPARSE, 0, "raw float64 file with %d values per point, %d wanted",
                        raw, want_cols);
        r->cols = raw;
    } else if (r->len >= 2 && b[0] == 0x1F && b[1] == 0x8B) {
        rc = cp_err(r, CF_EUNSUPPORTED, 0, "gzip-compressed: gunzip it first");
    } else if (r->len >= 4 && !memcmp(b, "ply", 3) && (b[3] == '\n' || b[3] == '\r')) {
        rc = cp_ply_header(r);
    } else {
        r->fmt = CP_ASCII;
        rc = cp_csv_header(r);
        /* No header: read from the start again, so the first pass is the
         * very reading every rewind gives (standard input keeps its line). */
        if (rc >= 0 && !r->hdr && !r->is_stdin)
            rc = cf_points_rewind(r) ? CF_EIO : rc;
        if (rc > 0 && !r->hdr && !want_cols)
            rc = cp_first_cols(r); /* no header: the first data line decides */
        else if (rc > 0)
            rc = CF_OK;
    }
    if (rc) {
        cf_fail(msg, msglen, rc, "%s", r->errmsg);
        cf_points_close(r);
        return rc;
    }
    if (r->fmt == CP_RAW && size >= 0)
        r->bound = (long)(size / (long long)(sizeof(double) * (size_t)r->cols));
    else if (r->fmt == CP_ASCII || r->fmt == CP_PLY_ASCII)
        r->bound = lines;
    *rp = r;
    return CF_OK;
}

int cf_points_cols(const cf_points_t *r)
{
    return r ? r->cols : 0;
}

long cf_points_bound(const cf_points_t *r)
{
    return r ? r->bound : -1;
}

/* The parse thread's fill (cf_points_mt.h): the text formats' point loop of
 * cf_points_read, the line of every point kept. */
static long cp_fill_block(void *ctx, double *rows, long *lines, long max, int *err, char *msg,
                          size_t ml)
{
    cf_points_t *r = ctx;
    long k = 0;
    *err = r->err;
    while (!*err && k < max && r->cols > 0) {
        int rc = r->fmt == CP_ASCII ? cp_ascii_point(r, rows + k * r->cols)
                                    : cp_ply_point(r, rows + k * r->cols);
        if (rc == 0)
            break;
        if (rc < 0)
            *err = rc;
        else
            lines[k++] = r->last;
    }
    if (*err)
        snprintf(msg, ml, "%s", r->errmsg);
    return k;
}

int cf_points_thread(cf_points_t *r)
{
    if (!r)
        return CF_EARG;
    if (r->mt)
        return CF_OK; /* on already (r is the thread's now: not even r->last) */
    if (r->last)
        return CF_EARG;
    if (r->fmt == CP_RAW || r->fmt == CP_PLY_BIN || r->cols <= 0 || r->err || r->part2 ||
        r->end >= 0)
        return CF_OK; /* memory speed already, nothing to read, or a half (its own thread) */
    /* A file of few points: blocks of a quarter of them (the ring on the
     * heap's pages, not a huge page to clear). */
    const long quarter = r->bound > 0 ? r->bound / CP_MT_NBLK + 1 : CP_MT_BLOCK;
    const long block = quarter >= CP_MT_BLOCK ? CP_MT_BLOCK : quarter < 256 ? 256 : quarter;
    return cf_pmt_start(&r->mt, r->cols, block, CP_MT_NBLK, cp_fill_block, r);
}

long cf_points_read(cf_points_t *r, double *buf, long max_points, char *msg, size_t msglen)
{
    if (!r || (!buf && max_points > 0) || max_points < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_points_read: bad arguments");
    r->used = 1;
    if (r->mt)
        return cf_pmt_read(r->mt, buf, max_points, msg, msglen);
    if (r->err)
        return cf_fail(msg, msglen, r->err, "%s", r->errmsg);
    if (r->fmt == CP_RAW) {
        long n = cp_raw_read(r, buf, max_points);
        return n < 0 ? cf_fail(msg, msglen, (int)n, "%s", r->errmsg) : n;
    }
    long k = 0;
    while (k < max_points && r->cols > 0) {
        double *row = buf + k * r->cols;
        int rc = r->fmt == CP_ASCII ? cp_ascii_point(r, row) : cp_ply_point(r, row);
        if (rc == 0)
            break;
        if (rc < 0)
            return cf_fail(msg, msglen, rc, "%s", r->errmsg);
        k++;
    }
    return k;
}

long cf_points_line(const cf_points_t *r)
{
    return !r ? 0 : r->mt ? cf_pmt_line(r->mt) : r->last ? r->lbase + r->last : 0;
}

long cf_points_lines(const cf_points_t *r)
{
    return !r ? 0 : r->lbase + (r->fmt == CP_RAW ? (long)r->vdone : r->line);
}

static int cp_rewind(cf_points_t *r);

/* The first line start at or after the middle of the data (the end of the
 * file when none follows), by pread: the reader's position stays. A
 * middle inside a line longer than any point line: CF_EUNSUPPORTED (one
 * reader names it). */
static int cp_split_text(cf_points_t *r, long long size, long long *at)
{
    const long long d = r->data_off;
    *at = size;
    if (size - d < 2)
        return CF_OK;
    const long long mid = d + (size - d) / 2; /* > d: mid - 1 is data */
    char b[CF_POINTS_MAX_LINE + 2];
    ssize_t n = pread(fileno(r->f), b, sizeof b, (off_t)(mid - 1));
    if (n <= 0)
        return CF_EIO;
    const char *nl = memchr(b, '\n', (size_t)n);
    if (nl)
        *at = mid + (nl - b);
    else if (mid - 1 + n < size)
        return CF_EUNSUPPORTED;
    return CF_OK;
}

int cf_points_split(cf_points_t *r, cf_points_t **r2p, char *msg, size_t msglen)
{
    if (!r || !r2p)
        return cf_fail(msg, msglen, CF_EARG, "cf_points_split: bad arguments");
    *r2p = NULL;
    struct stat st;
    if (r->is_stdin || r->part2 || (r->fmt != CP_ASCII && r->fmt != CP_RAW) || r->cols <= 0 ||
        fstat(fileno(r->f), &st) || !S_ISREG(st.st_mode))
        return cf_fail(msg, msglen, CF_EUNSUPPORTED, "%s: not a file of ASCII or raw points",
                       r->name);
    if (!r->r2) {
        long long at = st.st_size;
        long base = 0;
        if (r->fmt == CP_RAW) { /* a record boundary; stray bytes stay at the end */
            long long rec = 8LL * r->cols, n = (st.st_size - r->data_off) / rec;
            n = n > 0 ? n : 0;
            at = r->data_off + n / 2 * rec;
            base = (long)(n / 2);
        } else {
            int rc = cp_split_text(r, (long long)st.st_size, &at);
            if (rc)
                return cf_fail(msg, msglen, rc, "%s: no line start near the middle", r->name);
        }
        cf_points_t *b = calloc(1, sizeof *b);
        if (!b)
            return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", r->name);
        /* What open settled, fixed since (r's parse thread may run):
         * format, columns, the CSV header's map, the name. */
        b->want = r->want;
        b->cols = r->cols;
        b->fmt = r->fmt;
        b->hdr = r->hdr;
        b->hcols = r->hcols;
        memcpy(b->map, r->map, sizeof b->map);
        memcpy(b->name, r->name, sizeof b->name);
        b->cap = r->cap;
        b->bound = -1;
        b->buf = cf_bigmem_alloc(b->cap + 1 + CP_PAD);
        b->path = strdup(r->path);
        b->f = b->buf && b->path ? fopen(r->path, "rb") : NULL;
        if (!b->f) {
            cf_bigmem_free(b->buf);
            free(b->path);
            free(b);
            return cf_fail(msg, msglen, CF_EIO, "%s: cannot open a second time", r->name);
        }
        memset(b->buf, ' ', b->cap + 1 + CP_PAD); /* resident now, as at open */
        (void)posix_fadvise(fileno(b->f), 0, 0, POSIX_FADV_SEQUENTIAL);
        b->part2 = 1;
        b->data_off = at;
        b->data_line = 0;
        b->lbase = base;
        b->end = -1;
        r->r2 = b;
    }
    cf_pmt_stop(r->mt); /* the halves read on their callers' threads */
    r->mt = NULL;
    r->end = r->r2->data_off;
    if (cp_rewind(r) || cp_rewind(r->r2))
        return cf_fail(msg, msglen, CF_EIO, "%s: cannot seek", r->name);
    *r2p = r->r2;
    return CF_OK;
}

int cf_points_whole(cf_points_t *r)
{
    if (!r)
        return CF_EARG;
    r->end = -1;
    return cf_points_rewind(r);
}

void cf_points_rebase(cf_points_t *r2, long lines)
{
    if (!r2 || !r2->part2 || r2->fmt == CP_RAW)
        return; /* raw: known at the split */
    r2->lbase = lines;
    if (r2->err)
        cp_errword(r2);
}

static int cp_rewind(cf_points_t *r)
{
    clearerr(r->f);
    if (fseeko(r->f, (off_t)r->data_off, SEEK_SET))
        return CF_EIO;
    r->len = r->pos = 0;
    r->boff = r->data_off;
    r->eof = 0;
    r->line = r->data_line;
    r->last = 0;
    r->pending = 0;
    r->used = 0;
    r->err = 0;
    r->errline = 0;
    r->errmsg[0] = '\0';
    r->ply_ready = 0;
    r->vdone = 0;
    return CF_OK;
}

int cf_points_rewind(cf_points_t *r)
{
    if (!r)
        return CF_EARG;
    if (r->is_stdin)
        return CF_EUNSUPPORTED;
    /* Nothing read yet: the thread parsed ahead from the first point (a
     * caller that starts it at the open, before its own set-up, keeps that
     * work). */
    if (r->mt && !r->used && r->end < 0)
        return CF_OK;
    /* The thread stops before the file moves, and starts again after, on
     * the same ring. Without a thread it reads alike on this one. */
    if (r->mt)
        cf_pmt_pause(r->mt);
    int rc = cp_rewind(r);
    if (r->mt && (rc || cf_pmt_resume(r->mt))) {
        cf_pmt_stop(r->mt);
        r->mt = NULL;
    }
    return rc;
}

void cf_points_close(cf_points_t *r)
{
    if (!r)
        return;
    cf_pmt_stop(r->mt);
    cf_points_close(r->r2);
    if (r->f && !r->is_stdin)
        fclose(r->f);
    cf_bigmem_free(r->buf);
    free(r->path);
    free(r);
}
