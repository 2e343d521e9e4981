/* SPDX-License-Identifier: MIT */
/* cf_iges_read.c: IGES 5.3 entities 128 (rational B-spline surface) and
 * 126 (rational B-spline curve), read (cf_iges.h; the writer is
 * cf_iges_write.c). The reader makes one pass: Start (skipped), Global (delimiters), Directory
 * (every entry, a few integers each), Parameter (only the lines of the wanted
 * 128 and of its transformation matrices), Terminate (counts checked).
 * Nothing is allocated from a count in the file before the values behind it
 * have been read, so a lying header cannot make it allocate much. */
#include "cf_bigmem.h"
#include "cf_err.h"
#include "cf_fmt.h"
#include "cf_iges.h"
#include "cf_points_el.h"
#include "cf_surf.h"
#include "cf_trim.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define IG_INBUF 65536
#define IG_PCOLS 64 /* data columns of a P line */
#define IG_GCOLS 72 /* data columns of an S or G line */
#define IG_MAX_GLINES 10000L
#define IG_MAX_CHAIN 8 /* transformation matrices followed per entity */
#define IG_MAX_SEQ 9999999L
#define IG_PAD 8 /* NUL bytes after the parameter data: cf_pel_digits8 loads 8 at a time */

/* ---------------------------------------------------------------- input */

typedef struct ig_in {
    FILE *f;
    unsigned char buf[IG_INBUF];
    size_t len, pos;
    int eof, ioerr;
    long line; /* physical line of the next byte */
} ig_in_t;

/* One 80-column record: columns 1..80 blank-padded, section letter, sequence.
 * t is the line in the input buffer when it is a whole printable 80-column
 * line there (no copy), else store. */
typedef struct ig_rec {
    const char *t;
    char store[81];
    char sect;
    long seq; /* -1 when the sequence columns are blank */
    long line;
} ig_rec_t;

typedef struct ig_de {
    int type, form;
    long pptr, pcount, matrix;
    long line; /* physical line of its first D record */
} ig_de_t;

/* Parameter data of one entity we want: columns 1-64 of its P lines, then
 * IG_PAD NUL bytes once read (ig_scan). */
typedef struct ig_par {
    long de, pptr, pcount;
    int type;
    char *data;
    size_t len, cap;
    long *lines; /* physical line of each collected P record */
    long got, lcap;
} ig_par_t;

typedef struct ig_rd {
    ig_in_t *in;
    const char *path;
    char *msg;
    size_t ml;
    char pd, rd;    /* parameter and record delimiters */
    double unit_mm; /* Global fields 14/15: millimetres per model unit */
    char *g;
    size_t glen;
    ig_de_t *de;
    long nde, decap;
    long count[4]; /* S G D P lines */
    char d1[81];   /* first line of a D entry waiting for its second */
    long d1line;
    long target;   /* index into de of the wanted entity, -1 none */
    int want_type; /* 128 (surface) or 126 (curve) */
    long nth;      /* entity_de = 0: take the nth (0-based) of want_type */
    int notfound;  /* CF_ENOTFOUND with msg already written */
    int dir_only;  /* stop at the P section: the Directory is all we want */
    ig_par_t want[1 + IG_MAX_CHAIN];
    int nwant;
    int fast; /* ig_real_at may run: no tab delimiter (blanks around numbers are skipped) */
} ig_rd_t;

static int ig_getc(ig_in_t *in)
{
    if (in->pos == in->len) {
        if (in->eof)
            return EOF;
        in->len = fread(in->buf, 1, sizeof in->buf, in->f);
        in->pos = 0;
        if (in->len == 0) {
            in->eof = 1;
            in->ioerr = ferror(in->f) != 0;
            return EOF;
        }
    }
    return in->buf[in->pos++];
}

static int ig_fail(ig_rd_t *c, int err, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* "path: " + message. */
static int ig_fail(ig_rd_t *c, int err, const char *fmt, ...)
{
    char tmp[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    return cf_fail(c->msg, c->ml, err, "%s: %s", c->path, tmp);
}

static int is_blank(int ch)
{
    return ch == ' ' || ch == '\t';
}

/* Sequence columns 74-80: digits, possibly padded either side; -1 if blank. */
static int ig_seq(const char *t, long *seq)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    /* The usual right-justified number at once: columns 73-80 as eight
     * bytes, column 73 and the leading blanks made '0's, eight digits
     * summed as in cf_pel_digits8. Blanks elsewhere, or all blank: the loop. */
    uint64_t x, y;
    memcpy(&x, t + 72, 8);
    y = x ^ UINT64_C(0x2020202020202020);
    const uint64_t lo7 = UINT64_C(0x7F7F7F7F7F7F7F7F);
    const uint64_t sp = (~(((y & lo7) + lo7) | y) & ~lo7) >> 7 & ~UINT64_C(0xFF); /* 1 a blank */
    const uint64_t spm = sp * 0xFF >> 8; /* 0xFF a blank, columns 74-80 in bytes 0-6 */
    if ((spm & (spm + 1)) == 0 && spm != UINT64_C(0x00FFFFFFFFFFFFFF)) {
        x = ((x & ~UINT64_C(0xFF)) | 0x30) + (sp << 4); /* ' ' + 0x10 = '0' */
        if ((((x + UINT64_C(0x4646464646464646)) | (x - UINT64_C(0x3030303030303030))) &
             UINT64_C(0x8080808080808080)) == 0) {
            x -= UINT64_C(0x3030303030303030);
            x = x * 10 + (x >> 8);
            x = (((x & UINT64_C(0x000000FF000000FF)) * (100 + (UINT64_C(1000000) << 32))) +
                 (((x >> 16) & UINT64_C(0x000000FF000000FF)) * (1 + (UINT64_C(10000) << 32)))) >>
                32;
            *seq = (long)(x & 0xFFFFFFFFu);
            return 0;
        }
    }
#endif
    long v = 0;
    int i = 73, any = 0;
    while (i < 80 && t[i] == ' ')
        i++;
    for (; i < 80 && t[i] >= '0' && t[i] <= '9'; i++, any = 1)
        v = v * 10 + (t[i] - '0');
    while (i < 80 && t[i] == ' ')
        i++;
    if (i < 80)
        return -1;
    *seq = any ? v : -1;
    return 0;
}

/* 0..4 for the section letters S G D P T, -1 for anything else. */
static int ig_sect(int ch)
{
    switch (ch) {
    case 'S': return 0;
    case 'G': return 1;
    case 'D': return 2;
    case 'P': return 3;
    case 'T': return 4;
    default: return -1;
    }
}

/* The 80 bytes at b are all 0x20..0x7E: eight at a time, one test. */
static int ig_printable80(const unsigned char *b)
{
    uint64_t bad = 0;
    for (int k = 0; k < 80; k += 8) {
        uint64_t x;
        memcpy(&x, b + k, 8);
        bad |= ((x - UINT64_C(0x2020202020202020)) & ~x) | (x + UINT64_C(0x0101010101010101)) | x;
    }
    return (bad & UINT64_C(0x8080808080808080)) == 0;
}

/* Next non-blank record. Lines end at LF, CRLF or CR; a line without an end
 * longer than 80 columns is split into 80-column records when column 73 holds
 * a section letter (files written as fixed records without newlines).
 * Returns 1 with a record, 0 at the end of the file, or an error. */
static int ig_record(ig_rd_t *c, ig_rec_t *r)
{
    ig_in_t *in = c->in;
    /* The common line, 80 printable columns and LF or CR LF, whole in the
     * buffer: used where it is (what the loop below makes of it too). */
    if (in->len - in->pos >= 82) {
        const unsigned char *b = in->buf + in->pos;
        const int eol = b[80] == '\n' ? 1 : b[80] == '\r' && b[81] == '\n' ? 2 : 0;
        if (eol && ig_sect(b[72]) >= 0 && ig_printable80(b)) {
            r->t = (const char *)b;
            r->line = in->line++;
            r->sect = (char)b[72];
            in->pos += 80 + (size_t)eol;
            if (ig_seq(r->t, &r->seq))
                return ig_fail(c, CF_EPARSE, "line %ld: sequence number '%.7s' is not a number",
                               r->line, r->t + 73);
            return 1;
        }
    }
    r->t = r->store;
    for (;;) {
        int n = 0, blank = 1, ch;
        r->line = in->line;
        for (;;) {
            /* The run of plain printable bytes in the buffer, at once: every
             * byte but the ends and the refused ones (a line's 80 at most). */
            const unsigned char *b = in->buf + in->pos;
            size_t k = 0, lim = in->len - in->pos;
            if (lim > (size_t)(80 - n))
                lim = (size_t)(80 - n);
            for (; k + 8 <= lim; k += 8) { /* 8 at a time: none below 0x20, none 0x7F */
                uint64_t x, y;
                memcpy(&x, b + k, 8);
                y = x ^ UINT64_C(0x7F7F7F7F7F7F7F7F);
                if (((x - UINT64_C(0x2020202020202020)) & ~x & UINT64_C(0x8080808080808080)) |
                    ((y - UINT64_C(0x0101010101010101)) & ~y & UINT64_C(0x8080808080808080)))
                    break;
                blank &= x == UINT64_C(0x2020202020202020);
            }
            while (k < lim && b[k] >= 0x20 && b[k] != 0x7F) {
                blank &= b[k] == ' ';
                k++;
            }
            memcpy(r->store + n, b, k);
            n += (int)k;
            in->pos += k;
            ch = ig_getc(in);
            if (ch == EOF)
                break;
            if (ch == 0x1A) { /* DOS end-of-file mark: nothing after it counts */
                in->eof = 1;
                in->pos = in->len;
                ch = EOF;
                break;
            }
            if (ch == '\n') {
                in->line++;
                break;
            }
            if (ch == '\r') {
                int nx = ig_getc(in);
                if (nx != '\n' && nx != EOF)
                    in->pos--;
                in->line++;
                break;
            }
            if ((ch < 0x20 && ch != '\t') || ch == 0x7F)
                return ig_fail(c, CF_EPARSE,
                               "line %ld: binary data (byte 0x%02x): not an ASCII IGES file",
                               in->line, ch);
            if (n == 80) {
                in->pos--; /* the 81st byte starts the next record */
                if (ig_sect(r->store[72]) < 0)
                    return ig_fail(c, CF_EPARSE, "line %ld: longer than 80 columns", r->line);
                break;
            }
            r->store[n++] = (char)ch;
            if (!is_blank(ch))
                blank = 0;
        }
        if (in->ioerr)
            return ig_fail(c, CF_EIO, "read error: %s", strerror(errno));
        if (blank) {
            if (ch == EOF)
                return 0;
            continue;
        }
        if (n < 73)
            return ig_fail(c, CF_EPARSE,
                           "line %ld: only %d columns; an IGES line has its section letter in "
                           "column 73 (truncated or not an IGES file?)",
                           r->line, n);
        memset(r->store + n, ' ', (size_t)(80 - n));
        r->store[80] = '\0';
        r->sect = r->store[72];
        if (ig_sect(r->sect) < 0)
            return ig_fail(c, CF_EPARSE,
                           "line %ld: column 73 holds '%c', not a section letter (S G D P T)",
                           r->line, r->sect);
        if (ig_seq(r->t, &r->seq))
            return ig_fail(c, CF_EPARSE, "line %ld: sequence number '%.7s' is not a number",
                           r->line, r->t + 73);
        return 1;
    }
}

/* Integer in an 8-column D field (blank is 0). */
static int ig_field8(const char *t, int i, long *v)
{
    const char *p = t + 8 * i, *e = p + 8;
    long x = 0;
    int neg = 0, any = 0;
    while (p < e && *p == ' ')
        p++;
    if (p < e && (*p == '-' || *p == '+'))
        neg = *p++ == '-';
    for (; p < e && *p >= '0' && *p <= '9'; p++, any = 1)
        x = x * 10 + (*p - '0');
    while (p < e && *p == ' ')
        p++;
    if (p < e || (neg && !any))
        return -1;
    *v = neg ? -x : x;
    return 0;
}

/* The Global field after the delimiter at g[*i] into buf (Hollerith
 * strings unwrapped); *i moves to the delimiter that ends it. 0, or -1 at
 * the end of the section or for a string running past it. */
static int ig_gnext(const ig_rd_t *c, size_t *i, char *buf, size_t bl)
{
    const char *g = c->g;
    size_t n = c->glen, k = *i, o = 0;
    if (k >= n || g[k] == c->rd)
        return -1;
    k++;
    while (k < n && g[k] == ' ')
        k++;
    size_t j = k;
    long len = 0;
    while (j < n && g[j] >= '0' && g[j] <= '9' && len < 100000)
        len = len * 10 + (g[j++] - '0');
    if (j > k && j < n && (g[j] == 'H' || g[j] == 'h')) {
        if (j + 1 + (size_t)len > n)
            return -1;
        for (long t = 0; t < len; t++)
            if (o + 1 < bl)
                buf[o++] = g[j + 1 + t];
        k = j + 1 + (size_t)len;
    } else {
        while (k < n && g[k] != c->pd && g[k] != c->rd) {
            if (o + 1 < bl && g[k] != ' ')
                buf[o++] = g[k];
            k++;
        }
    }
    while (k < n && g[k] == ' ')
        k++;
    buf[o] = 0;
    *i = k;
    return 0;
}

/* Millimetres per unit for the Global unit flag (field 14), or for the
 * unit name (field 15) when the flag is 3; 0 when unknown. */
static double ig_unit_mm(long flag, const char *name)
{
    static const struct {
        long flag;
        const char *name;
        double mm;
    } u[] = {{1, "IN", 25.4},    {1, "INCH", 25.4}, {2, "MM", 1.0},      {4, "FT", 304.8},
             {5, "MI", 1609344}, {6, "M", 1000.0},  {7, "KM", 1.0e6},    {8, "MIL", 0.0254},
             {9, "UM", 0.001},   {10, "CM", 10.0},  {11, "UIN", 2.54e-5}};
    for (size_t k = 0; k < sizeof u / sizeof u[0]; k++)
        if ((flag != 3 && flag == u[k].flag) || (flag == 3 && !strcmp(name, u[k].name)))
            return u[k].mm;
    return 0.0;
}

static int ig_global(ig_rd_t *c, long line)
{
    const char *g = c->g;
    size_t n = c->glen, i = 0;
    if (!g)
        return ig_fail(c, CF_EPARSE, "line %ld: no Global (G) section before the Directory", line);
    while (i < n && g[i] == ' ')
        i++;
    /* Field 1 is "1Hx" or defaulted (empty, so the text starts with ','). */
    if (i < n && g[i] == ',') {
        c->pd = ',';
        i++;
    } else if (i + 3 < n && g[i] == '1' && (g[i + 1] == 'H' || g[i + 1] == 'h')) {
        c->pd = g[i + 2];
        i += 3;
        while (i < n && g[i] == ' ')
            i++;
        if (i >= n || g[i] != c->pd)
            return ig_fail(c, CF_EPARSE,
                           "Global section: parameter delimiter '%c' does not follow 1H%c", c->pd,
                           c->pd);
        i++;
    } else {
        return ig_fail(c, CF_EPARSE,
                       "Global section does not start with the parameter delimiter (1H, or ,)");
    }
    while (i < n && g[i] == ' ')
        i++;
    if (i < n && g[i] == c->pd) {
        c->rd = ';';
    } else if (i + 3 < n && g[i] == '1' && (g[i + 1] == 'H' || g[i + 1] == 'h')) {
        c->rd = g[i + 2];
        i += 3;
        while (i < n && g[i] == ' ')
            i++;
        if (i >= n || (g[i] != c->pd && g[i] != c->rd))
            return ig_fail(c, CF_EPARSE,
                           "Global section: no delimiter after the record delimiter 1H%c", c->rd);
    } else {
        return ig_fail(c, CF_EPARSE,
                       "Global section: second field is not the record delimiter (1H; or empty)");
    }
    /* Characters that can occur in numbers cannot delimit them. */
    const char *bad = " 0123456789+-.EeDdHh";
    if (c->pd == c->rd || strchr(bad, c->pd) || strchr(bad, c->rd) || !c->pd || !c->rd)
        return ig_fail(c, CF_EPARSE, "Global section: unusable delimiters '%c' and '%c'", c->pd,
                       c->rd);
    /* Fields 3..15: the unit flag (14) and unit name (15) say what a model
     * unit is; cellfit works in millimetres, as CAD kernels convert. */
    char f14[64] = "", f15[64] = "";
    c->unit_mm = 1.0;
    for (int field = 3; field <= 15; field++) {
        char buf[64];
        if (ig_gnext(c, &i, buf, sizeof buf))
            return CF_OK; /* a short Global section defaults the rest: mm */
        if (field == 14)
            memcpy(f14, buf, sizeof f14);
        if (field == 15)
            memcpy(f15, buf, sizeof f15);
    }
    for (char *p = f15; *p; p++)
        *p = (char)(*p >= 'a' && *p <= 'z' ? *p - 32 : *p);
    char *end;
    long flag = f14[0] ? strtol(f14, &end, 10) : 2;
    if (f14[0] && *end)
        return ig_fail(c, CF_EPARSE, "Global section: unit flag (field 14) '%s' is not an integer",
                       f14);
    c->unit_mm = ig_unit_mm(flag, f15);
    if (c->unit_mm == 0.0)
        return ig_fail(c, CF_EUNSUPPORTED, "Global section: unknown unit (flag %ld, name '%s')",
                       flag, f15);
    return CF_OK;
}

static int ig_add_want(ig_rd_t *c, long idx)
{
    const ig_de_t *d = &c->de[idx];
    long de = 2 * idx + 1;
    if (d->pptr < 1 || d->pcount < 1 || d->pptr > IG_MAX_SEQ || d->pcount > IG_MAX_SEQ)
        return ig_fail(c, CF_EPARSE,
                       "line %ld (DE %ld): parameter data pointer %ld and line count %ld are "
                       "not usable",
                       d->line, de, d->pptr, d->pcount);
    ig_par_t *w = &c->want[c->nwant++];
    memset(w, 0, sizeof *w);
    w->de = de;
    w->pptr = d->pptr;
    w->pcount = d->pcount;
    w->type = d->type;
    return CF_OK;
}

static const char *ig_tname(int type)
{
    switch (type) {
    case 126: return "rational B-spline curve";
    case 144: return "trimmed surface";
    case 142: return "curve on a parametric surface";
    case 102: return "composite curve";
    default: return "rational B-spline surface";
    }
}

/* At the start of the P section: find the wanted entity and its matrices. */
static int ig_pick(ig_rd_t *c, int entity_de, long line)
{
    const int ty = c->want_type;
    if (c->nde == 0)
        return ig_fail(c, CF_EPARSE, "line %ld: no Directory Entry (D) section", line);
    if (c->d1line)
        return ig_fail(c, CF_EPARSE,
                       "line %ld: Directory Entry at line %ld has only one of its two lines", line,
                       c->d1line);
    c->target = -1;
    if (entity_de == 0) {
        long seen = 0;
        for (long k = 0; k < c->nde && c->target < 0; k++)
            if (c->de[k].type == ty && seen++ == c->nth)
                c->target = k;
        if (c->target < 0) {
            if (c->nth == 0)
                c->notfound = ig_fail(c, CF_ENOTFOUND,
                                      "no %s (entity %d) among the %ld "
                                      "Directory Entries",
                                      ig_tname(ty), ty, c->nde);
            else
                c->notfound = ig_fail(c, CF_ENOTFOUND, "only %ld %s entities (%d), wanted %ld",
                                      seen, ig_tname(ty), ty, c->nth + 1);
            return CF_OK;
        }
    } else {
        if (entity_de % 2 == 0 || entity_de > 2 * c->nde - 1) {
            c->notfound =
                ig_fail(c, CF_ENOTFOUND, "no Directory Entry %d: DE numbers are odd, 1 to %ld here",
                        entity_de, 2 * c->nde - 1);
            return CF_OK;
        }
        c->target = (entity_de - 1) / 2;
        const ig_de_t *d = &c->de[c->target];
        if (d->type != ty) {
            c->notfound =
                ig_fail(c, CF_ENOTFOUND, "line %ld (DE %d): entity %d form %d, not a %s (%d)",
                        d->line, entity_de, d->type, d->form, ig_tname(ty), ty);
            c->target = -1;
            return CF_OK;
        }
    }
    int rc = ig_add_want(c, c->target);
    long k = c->target;
    while (!rc && c->de[k].matrix != 0) {
        long m = c->de[k].matrix;
        if (m < 0 || m % 2 == 0 || m > 2 * c->nde - 1)
            return ig_fail(c, CF_EPARSE,
                           "line %ld (DE %ld): transformation matrix pointer %ld is not a "
                           "Directory Entry of this file",
                           c->de[k].line, 2 * k + 1, m);
        if (c->nwant > IG_MAX_CHAIN)
            return ig_fail(c, CF_EPARSE,
                           "line %ld (DE %ld): more than %d chained transformation matrices "
                           "(a cycle?)",
                           c->de[k].line, 2 * k + 1, IG_MAX_CHAIN);
        long j = (m - 1) / 2;
        if (c->de[j].type != 124)
            return ig_fail(c, CF_EPARSE,
                           "line %ld (DE %ld): transformation matrix pointer %ld leads to entity "
                           "%d, not 124",
                           c->de[k].line, 2 * k + 1, m, c->de[j].type);
        rc = ig_add_want(c, j);
        k = j;
    }
    return rc;
}

static int ig_dline(ig_rd_t *c, const ig_rec_t *r)
{
    long k = ++c->count[2];
    if (r->seq >= 0 && r->seq != k)
        return ig_fail(c, CF_EPARSE,
                       "line %ld: D sequence number %ld, expected %ld (lines missing or out of "
                       "order)",
                       r->line, r->seq, k);
    if (k % 2 == 1) {
        memcpy(c->d1, r->t, 80);
        c->d1[80] = '\0';
        c->d1line = r->line;
        return CF_OK;
    }
    long type, pptr, matrix, type2, pcount, form;
    if (ig_field8(c->d1, 0, &type) || ig_field8(c->d1, 1, &pptr) || ig_field8(c->d1, 6, &matrix))
        return ig_fail(c, CF_EPARSE,
                       "line %ld (DE %ld): entity type, parameter pointer or matrix field is "
                       "not an integer",
                       c->d1line, k - 1);
    if (ig_field8(r->t, 0, &type2) || ig_field8(r->t, 3, &pcount) || ig_field8(r->t, 4, &form))
        return ig_fail(c, CF_EPARSE,
                       "line %ld (DE %ld): entity type, parameter line count or form field is "
                       "not an integer",
                       r->line, k - 1);
    if (type != type2)
        return ig_fail(c, CF_EPARSE,
                       "line %ld (DE %ld): entity type %ld on the first line, %ld on the second",
                       r->line, k - 1, type, type2);
    if (type < 0 || type > 99999 || form < -99 || form > 999)
        return ig_fail(c, CF_EPARSE, "line %ld (DE %ld): entity type %ld form %ld", c->d1line,
                       k - 1, type, form);
    if (c->nde == c->decap) {
        long cap = c->decap ? 2 * c->decap : 256;
        ig_de_t *nd = realloc(c->de, sizeof *nd * (size_t)cap);
        if (!nd)
            return ig_fail(c, CF_ENOMEM, "out of memory for %ld Directory Entries", cap);
        c->de = nd;
        c->decap = cap;
    }
    ig_de_t *d = &c->de[c->nde++];
    d->type = (int)type;
    d->form = (int)form;
    d->pptr = pptr;
    d->pcount = pcount;
    d->matrix = matrix;
    d->line = c->d1line;
    c->d1line = 0;
    return CF_OK;
}

/* Room for more of w's P lines: at first all pcount of them (no regrowth;
 * a large net's on huge pages, cf_bigmem), unless the file is too short
 * to hold them (a damaged count: then as the lines come, doubling). */
static int ig_par_grow(ig_rd_t *c, ig_par_t *w)
{
    struct stat st;
    long most = fstat(fileno(c->in->f), &st) ? 16 : (long)(st.st_size / 64) + 16;
    long n = w->lcap ? 2 * w->lcap : w->pcount;
    n = n > most && !w->lcap ? most : n;
    n = n > w->pcount ? w->pcount : n;
    n = n < w->got + 1 ? w->got + 1 : n;
    char *nd = cf_bigmem_alloc((size_t)n * IG_PCOLS + IG_PAD);
    long *nl = realloc(w->lines, sizeof *nl * (size_t)n);
    if (nl)
        w->lines = nl;
    if (!nd || !nl) {
        cf_bigmem_free(nd);
        return CF_ENOMEM;
    }
    if (w->len)
        memcpy(nd, w->data, w->len);
    cf_bigmem_free(w->data);
    w->data = nd;
    w->cap = (size_t)n * IG_PCOLS;
    w->lcap = n;
    return CF_OK;
}

static int ig_pline(ig_rd_t *c, const ig_rec_t *r)
{
    long k = ++c->count[3];
    if (r->seq >= 0 && r->seq != k)
        return ig_fail(c, CF_EPARSE,
                       "line %ld: P sequence number %ld, expected %ld (lines missing or out of "
                       "order)",
                       r->line, r->seq, k);
    for (int i = 0; i < c->nwant; i++) {
        ig_par_t *w = &c->want[i];
        if (k < w->pptr || k >= w->pptr + w->pcount)
            continue;
        if (w->got == w->lcap && ig_par_grow(c, w))
            return ig_fail(c, CF_ENOMEM, "out of memory for parameter data");
        memcpy(w->data + w->len, r->t, IG_PCOLS);
        w->len += IG_PCOLS;
        w->lines[w->got++] = r->line;
    }
    return CF_OK;
}

static int ig_tline(ig_rd_t *c, const ig_rec_t *r)
{
    static const char name[4] = {'S', 'G', 'D', 'P'};
    for (int i = 0; i < 4; i++) {
        long v;
        char f[9];
        memcpy(f, r->t + 8 * i, 8);
        f[8] = '\0';
        if (f[0] != name[i])
            return ig_fail(c, CF_EPARSE, "line %ld: Terminate section field %d is '%s'", r->line,
                           i + 1, f);
        f[0] = ' ';
        if (ig_field8(f, 0, &v))
            return ig_fail(c, CF_EPARSE, "line %ld: Terminate section field %d is '%c%s'", r->line,
                           i + 1, name[i], f + 1);
        if (v != c->count[i])
            return ig_fail(c, CF_EPARSE,
                           "line %ld: Terminate section counts %ld %c lines, the file has %ld "
                           "(truncated or damaged)",
                           r->line, v, name[i], c->count[i]);
    }
    return CF_OK;
}

/* Refuse what is not plain ASCII IGES before reading records. */
static int ig_sniff(ig_rd_t *c)
{
    ig_in_t *in = c->in;
    in->len = fread(in->buf, 1, sizeof in->buf, in->f);
    if (in->len == 0) {
        if (ferror(in->f))
            return ig_fail(c, CF_EIO, "read error: %s", strerror(errno));
        return ig_fail(c, CF_EPARSE, "line 1: empty file");
    }
    const unsigned char *b = in->buf;
    if (in->len >= 2 && b[0] == 0x1F && b[1] == 0x8B)
        return ig_fail(c, CF_EUNSUPPORTED, "gzip-compressed file: gunzip it first");
    if (in->len >= 4 && !memcmp(b, "PK\003\004", 4))
        return ig_fail(c, CF_EUNSUPPORTED, "zip archive: extract the .igs first");
    if (in->len >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF)
        in->pos = 3; /* UTF-8 byte order mark from some Windows editors */
    if (in->len >= in->pos + 73 && !memchr(b + in->pos, '\n', 72) &&
        !memchr(b + in->pos, '\r', 72)) {
        unsigned char f = b[in->pos + 72];
        if (f == 'B')
            return ig_fail(c, CF_EUNSUPPORTED,
                           "binary IGES (flag 'B' in column 73 of the first record): only the "
                           "fixed 80-column ASCII form is supported");
        if (f == 'C')
            return ig_fail(c, CF_EUNSUPPORTED,
                           "compressed ASCII IGES (flag 'C' in column 73 of the first record): "
                           "only the fixed 80-column ASCII form is supported");
    }
    return CF_OK;
}

/* Read all records; leaves the wanted parameter data in c->want. */
static int ig_scan(ig_rd_t *c, int entity_de)
{
    static const char order[] = "SGDPT";
    int sect = 0, seen_t = 0;
    long last_line = 1;
    ig_rec_t r;
    int rc;
    while ((rc = ig_record(c, &r)) == 1) {
        last_line = r.line;
        rc = CF_OK;
        int s = ig_sect(r.sect);
        if (s < sect)
            return ig_fail(c, CF_EPARSE, "line %ld: %c line after the %c section", r.line, r.sect,
                           order[sect]);
        if (s > sect || (s == 0 && c->count[0] == 0)) {
            /* Entering section s: what the earlier ones left must be complete. */
            if (s >= 2 && sect < 2 && (rc = ig_global(c, r.line)))
                return rc;
            if (s >= 3 && sect < 3 && (rc = ig_pick(c, entity_de, r.line)))
                return rc;
            if (s >= 3 && c->dir_only)
                return CF_OK;
            if (s == 4 && sect < 3)
                return ig_fail(c, CF_EPARSE, "line %ld: no Parameter Data (P) section", r.line);
            sect = s;
        }
        switch (r.sect) {
        case 'S': c->count[0]++; break;
        case 'G':
            if (++c->count[1] > IG_MAX_GLINES)
                return ig_fail(c, CF_EPARSE, "line %ld: Global section over %ld lines", r.line,
                               IG_MAX_GLINES);
            {
                char *ng = realloc(c->g, c->glen + IG_GCOLS);
                if (!ng)
                    return ig_fail(c, CF_ENOMEM, "out of memory");
                c->g = ng;
                memcpy(c->g + c->glen, r.t, IG_GCOLS);
                c->glen += IG_GCOLS;
            }
            break;
        case 'D': rc = ig_dline(c, &r); break;
        case 'P': rc = ig_pline(c, &r); break;
        default:
            rc = ig_tline(c, &r);
            seen_t = 1;
            break;
        }
        if (rc)
            return rc;
        if (seen_t)
            break; /* whatever follows the Terminate line is not IGES data */
    }
    if (rc < 0)
        return rc;
    if (!seen_t)
        return ig_fail(c, CF_EPARSE,
                       "line %ld: file ends in the %c section without a Terminate (T) line "
                       "(truncated?)",
                       last_line, order[sect]);
    for (int i = 0; i < c->nwant; i++) {
        const ig_par_t *w = &c->want[i];
        if (w->got < w->pcount)
            return ig_fail(c, CF_EPARSE,
                           "line %ld (DE %ld): parameter data on P lines %ld to %ld, but the P "
                           "section has %ld lines",
                           c->de[(w->de - 1) / 2].line, w->de, w->pptr, w->pptr + w->pcount - 1,
                           c->count[3]);
        memset(w->data + w->len, 0, IG_PAD); /* got >= pcount >= 1: allocated */
    }
    return CF_OK;
}

/* ------------------------------------------------------ parameter data */

typedef struct ig_fld {
    const char *s; /* trimmed text */
    size_t n;
    size_t at; /* offset in the data, for line numbers */
} ig_fld_t;

/* Next field from *pos: 1 when the parameter delimiter ends it, 2 when the
 * record delimiter does, 0 when the data runs out first, -1 when a Hollerith
 * string claims more characters than there are. */
static int ig_next(const ig_rd_t *c, const ig_par_t *p, size_t *pos, ig_fld_t *f)
{
    const char *d = p->data;
    size_t i = *pos, n = p->len;
    while (i < n && is_blank(d[i]))
        i++;
    size_t start = i, j = i;
    while (j < n && j - i < 9 && d[j] >= '0' && d[j] <= '9')
        j++;
    if (j > i && j < n && (d[j] == 'H' || d[j] == 'h')) {
        size_t len = (size_t)strtol(d + i, NULL, 10);
        if (len > n - j - 1)
            return -1;
        i = j + 1 + len;
    }
    while (i < n && d[i] != c->pd && d[i] != c->rd)
        i++;
    if (i >= n)
        return 0;
    size_t end = i;
    while (end > start && is_blank(d[end - 1]))
        end--;
    f->s = d + start;
    f->n = end - start;
    f->at = start < i ? start : i;
    *pos = i + 1;
    return d[i] == c->rd ? 2 : 1;
}

/* "path: line L (P record R): ..." for a field at offset at of p. */
static int ig_pfail(ig_rd_t *c, const ig_par_t *p, size_t at, int err, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

static int ig_pfail(ig_rd_t *c, const ig_par_t *p, size_t at, int err, const char *fmt, ...)
{
    char tmp[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    long k = (long)(at / IG_PCOLS);
    if (k >= p->got)
        k = p->got - 1;
    return cf_fail(c->msg, c->ml, err, "%s: line %ld (P record %ld, DE %ld): %s", c->path,
                   p->lines[k], p->pptr + k, p->de, tmp);
}

enum { IG_NUM_OK, IG_NUM_EMPTY, IG_NUM_BAD, IG_NUM_RANGE };

/* IGES real: [+-] digits [. digits] [E|D [+-] digits]; Fortran D exponents.
 * Correctly rounded as strtod: the exact shortcuts of cf_points_el.h
 * (Clinger, the x87 check, Eisel-Lemire), else strtod. */
static int ig_real(const ig_fld_t *f, double *v)
{
    const char *b = f->s;
    size_t i = 0, n = f->n, digits = 0, ex_at = 0;
    uint64_t m = 0;
    long e10 = 0, ex = 0;
    int nd = 0, drop = 0, neg = 0, eneg = 0;
    if (n == 0)
        return IG_NUM_EMPTY;
    if (n >= 72)
        return IG_NUM_BAD;
    if (b[i] == '+' || b[i] == '-')
        neg = b[i++] == '-';
    /* m: the first 19 significant digits; drop: those after, e10 the scale */
    for (; i < n && b[i] >= '0' && b[i] <= '9'; i++, digits++) {
        if (nd < 19) {
            m = m * 10 + (uint64_t)(b[i] - '0');
            nd += m != 0;
        } else {
            e10++;
            drop = 1;
        }
    }
    if (i < n && b[i] == '.')
        for (i++; i < n && b[i] >= '0' && b[i] <= '9'; i++, digits++) {
            if (nd < 19) {
                m = m * 10 + (uint64_t)(b[i] - '0');
                nd += m != 0;
                e10--;
            } else {
                drop = 1;
            }
        }
    if (!digits)
        return IG_NUM_BAD;
    if (i < n && (b[i] == 'E' || b[i] == 'e' || b[i] == 'D' || b[i] == 'd')) {
        ex_at = i++;
        if (i < n && (b[i] == '+' || b[i] == '-'))
            eneg = b[i++] == '-';
        if (!(i < n && b[i] >= '0' && b[i] <= '9'))
            return IG_NUM_BAD;
        for (; i < n && b[i] >= '0' && b[i] <= '9'; i++)
            if (ex < 100000)
                ex = ex * 10 + (b[i] - '0');
    }
    if (i != n)
        return IG_NUM_BAD;
    e10 += eneg ? -ex : ex;
    double d;
    if (m == 0) {
        d = 0.0;
    } else if (!cf_pel_fast(m, e10, drop, &d)) { /* the exact shortcuts, else strtod */
        char t[72];
        memcpy(t, b, n);
        t[n] = '\0';
        if (ex_at)
            t[ex_at] = 'E';
        char *end;
        d = strtod(t, &end);
        if (end != t + n)
            return IG_NUM_BAD;
        *v = d;
        return isfinite(d) ? IG_NUM_OK : IG_NUM_RANGE;
    }
    *v = neg ? -d : d;
    return IG_NUM_OK;
}

static int ig_isdigit(char ch)
{
    return (unsigned)(ch - '0') < 10u;
}

/* The field at *pos in one pass, when it is a plain number (blanks around
 * it) that a delimiter ends and that one of the exact shortcuts decides:
 * 1, the value in *v and *pos after the delimiter. Otherwise 0 and nothing
 * moved: ig_next and ig_real take it (Hollerith, garbled, empty, strtod).
 * The same grammar and the same correctly rounded value as ig_real. */
static int ig_real_at(const ig_rd_t *c, const ig_par_t *p, size_t *pos, double *v)
{
    const char *d = p->data, *q = d + *pos; /* NUL-padded: every scan stops by d + len */
    while (*q == ' ' || *q == '\t')
        q++;
    const char *start = q;
    int neg = 0, nd = 0, drop = 0, any = 0;
    uint64_t m = 0;
    long e10 = 0;
    if (*q == '+' || *q == '-')
        neg = *q++ == '-';
    while (*q == '0') {
        q++;
        any = 1;
    }
    /* Coordinates have a few integer digits: one at a time is cheaper. */
    for (; nd < 3 && ig_isdigit(*q); q++, nd++, any = 1)
        m = m * 10 + (uint64_t)(*q - '0');
#if CF_PEL_SWAR
    for (int n = 8; n == 8 && nd <= 11 && ig_isdigit(*q);) { /* nd + 8 <= 19: none dropped */
        uint64_t dv = 0;
        n = cf_pel_digits8(q, &dv);
        m = m * cf_pel_p10u[n] + dv;
        nd += n;
        q += n;
        any = 1;
    }
#endif
    for (; ig_isdigit(*q); q++, any = 1) { /* leading zeros skipped: every digit counts */
        if (nd < 19) {
            m = m * 10 + (uint64_t)(*q - '0');
            nd++;
        } else {
            e10++;
            drop = 1;
        }
    }
    if (*q == '.') {
        q++;
        if (!nd)
            for (; *q == '0'; q++, any = 1)
                e10--;
#if CF_PEL_SWAR
        for (int n = 8; n == 8 && nd <= 11 && ig_isdigit(*q);) {
            uint64_t dv = 0;
            n = cf_pel_digits8(q, &dv);
            m = m * cf_pel_p10u[n] + dv;
            nd += n;
            e10 -= n;
            q += n;
            any = 1;
        }
#endif
        for (; ig_isdigit(*q); q++, any = 1) {
            if (nd < 19) {
                m = m * 10 + (uint64_t)(*q - '0');
                nd++;
                e10--;
            } else {
                drop = 1;
            }
        }
    }
    if (!any)
        return 0;
    if (*q == 'E' || *q == 'e' || *q == 'D' || *q == 'd') {
        int eneg = 0;
        long ex = 0;
        q++;
        if (*q == '+' || *q == '-')
            eneg = *q++ == '-';
        if (!ig_isdigit(*q))
            return 0;
        for (; ig_isdigit(*q); q++)
            if (ex < 100000)
                ex = ex * 10 + (*q - '0');
        e10 += eneg ? -ex : ex;
    }
    const char *end = q;
    while (*q == ' ' || *q == '\t')
        q++;
    if (q >= d + p->len || (*q != c->pd && *q != c->rd) || end - start >= 72)
        return 0;
    double x = 0.0;
    if (m == 0) {
    } else if (!cf_pel_fast(m, e10, drop, &x)) { /* the exact shortcuts (cf_points_el.h) */
        return 0;
    }
    *v = neg ? -x : x;
    *pos = (size_t)(q - d) + 1;
    return 1;
}

static int ig_int(const ig_fld_t *f, long *v)
{
    size_t i = 0;
    long x = 0;
    int neg = 0;
    if (f->n == 0)
        return IG_NUM_EMPTY;
    if (f->s[0] == '+' || f->s[0] == '-')
        neg = f->s[i++] == '-';
    if (i == f->n || f->n - i > 9)
        return IG_NUM_BAD;
    for (; i < f->n; i++) {
        if (f->s[i] < '0' || f->s[i] > '9')
            return IG_NUM_BAD;
        x = x * 10 + (f->s[i] - '0');
    }
    *v = neg ? -x : x;
    return IG_NUM_OK;
}

static const char *ig_numwhy(int r)
{
    return r == IG_NUM_EMPTY ? "is empty" : r == IG_NUM_RANGE ? "is out of range" : "is garbled";
}

/* Parameter values of one record, read in order. */
typedef struct ig_it {
    ig_rd_t *c;
    const ig_par_t *p;
    size_t pos;
} ig_it_t;

/* How many bytes of d[0, n) are ch: eight at a time, a byte equal to ch
 * made 0x80 and the 0/1 bytes summed by one multiply. */
static long ig_countc(const char *d, size_t n, char ch)
{
    const uint64_t k = UINT64_C(0x0101010101010101) * (unsigned char)ch;
    const uint64_t lo7 = UINT64_C(0x7F7F7F7F7F7F7F7F);
    long cnt = 0;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t x;
        memcpy(&x, d + i, 8);
        x ^= k;
        const uint64_t z = ~(((x & lo7) + lo7) | x) & ~lo7;
        cnt += (long)(((z >> 7) * UINT64_C(0x0101010101010101)) >> 56);
    }
    for (; i < n; i++)
        cnt += d[i] == ch;
    return cnt;
}

static int ig_count(ig_rd_t *c, const ig_par_t *p, long *nf)
{
    /* Without an H before the record delimiter there is no Hollerith
     * string: the fields are the delimiters before it, plus one. */
    const char *rd = memchr(p->data, c->rd, p->len);
    if (rd) {
        const size_t n = (size_t)(rd - p->data);
        if (!memchr(p->data, 'H', n) && !memchr(p->data, 'h', n)) {
            *nf = ig_countc(p->data, n, c->pd) + 1;
            return CF_OK;
        }
    }
    size_t pos = 0;
    ig_fld_t f;
    long n = 0;
    for (;;) {
        int r = ig_next(c, p, &pos, &f);
        if (r < 0)
            return ig_pfail(c, p, pos, CF_EPARSE,
                            "a Hollerith string runs past the end of the entity's data");
        if (r == 0)
            return ig_pfail(c, p, p->len - 1, CF_EPARSE,
                            "no record delimiter '%c' within the %ld P lines of the entity", c->rd,
                            p->pcount);
        n++;
        if (r == 2)
            break;
    }
    *nf = n;
    return CF_OK;
}

enum { IG_KU, IG_KV, IG_W, IG_XYZ, IG_RANGE, IG_MAT };

/* Name of value idx of a kind, as the IGES specification writes it. */
static void ig_label(char *b, size_t bl, int kind, long idx, const nf_surf_t *s)
{
    static const char *range[4] = {"U(0)", "U(1)", "V(0)", "V(1)"};
    switch (kind) {
    case IG_KU: snprintf(b, bl, "u knot S(%ld)", idx - s->p); break;
    case IG_KV: snprintf(b, bl, "v knot T(%ld)", idx - s->q); break;
    case IG_W: snprintf(b, bl, "weight W(%ld,%ld)", idx % s->nu, idx / s->nu); break;
    case IG_XYZ:
        snprintf(b, bl, "%c(%ld,%ld)", "XYZ"[idx % 3], idx / 3 % s->nu, idx / 3 / s->nu);
        break;
    case IG_RANGE: snprintf(b, bl, "parameter range %s", range[idx & 3]); break;
    default: snprintf(b, bl, "matrix value %ld", idx + 1); break;
    }
}

static int ig_get_real_slow(ig_it_t *it, int kind, long idx, const nf_surf_t *s, double *v)
{
    ig_fld_t f;
    ig_next(it->c, it->p, &it->pos, &f); /* counted before: cannot fail */
    int r = ig_real(&f, v);
    if (r != IG_NUM_OK) {
        char what[64];
        ig_label(what, sizeof what, kind, idx, s);
        return ig_pfail(it->c, it->p, f.at, CF_EPARSE, "%s '%.*s' %s, not a number", what,
                        (int)(f.n > 40 ? 40 : f.n), f.s, ig_numwhy(r));
    }
    return CF_OK;
}

/* The value at it, in one pass when ig_real_at decides it (inlined into
 * the loops below: the call layer was a tenth of a value's read). */
static inline int ig_get_real(ig_it_t *it, int kind, long idx, const nf_surf_t *s, double *v)
{
    if (it->c->fast && ig_real_at(it->c, it->p, &it->pos, v))
        return CF_OK;
    return ig_get_real_slow(it, kind, idx, s, v);
}

static int ig_get_int(ig_it_t *it, const char *what, long *v, size_t *at)
{
    ig_fld_t f;
    ig_next(it->c, it->p, &it->pos, &f);
    *at = f.at;
    int r = ig_int(&f, v);
    if (r != IG_NUM_OK)
        return ig_pfail(it->c, it->p, f.at, CF_EPARSE, "%s '%.*s' %s, not an integer", what,
                        (int)(f.n > 40 ? 40 : f.n), f.s, ig_numwhy(r));
    return CF_OK;
}

/* Entity 124: x' = R x + T, parameters R11 R12 R13 T1 R21 ... T3. */
static int ig_matrix(ig_rd_t *c, const ig_par_t *p, double m[12])
{
    long nf, type;
    size_t at;
    int rc = ig_count(c, p, &nf);
    if (rc)
        return rc;
    ig_it_t it = {c, p, 0};
    if ((rc = ig_get_int(&it, "entity type", &type, &at)))
        return rc;
    if (type != 124)
        return ig_pfail(c, p, at, CF_EPARSE, "parameter data of entity %ld, D entry says 124",
                        type);
    if (nf < 13)
        return ig_pfail(c, p, at, CF_EPARSE, "%ld parameters, a transformation matrix needs 13",
                        nf);
    for (int i = 0; i < 12; i++)
        if ((rc = ig_get_real(&it, IG_MAT, i, NULL, &m[i])))
            return rc;
    return CF_OK;
}

/* Where a knot vector breaks nf_knots_check's rules: index and reason. */
static int ig_knot_diag(int n, int p, const double *U, const char **why)
{
    const int m = n + p + 1;
    for (int i = 0; i < m; i++)
        if (U[i + 1] < U[i]) {
            *why = "knot vector decreases";
            return i + 1;
        }
    for (int i = 1; i <= p; i++) {
        if (U[i] != U[0]) {
            *why = "knot vector not clamped at its start (first degree+1 knots differ)";
            return i;
        }
        if (U[m - i] != U[m]) {
            *why = "knot vector not clamped at its end (last degree+1 knots differ)";
            return m - i;
        }
    }
    if (!(U[p] < U[n + 1])) {
        *why = "knot vector has an empty parameter range";
        return n + 1;
    }
    int mult = 1;
    for (int i = p + 1; i <= n; i++) {
        mult = (U[i] == U[i - 1] && i - 1 > p) ? mult + 1 : 1;
        if (U[i] == U[p] || U[i] == U[n + 1]) {
            *why = "end knot repeated more than degree+1 times";
            return i;
        }
        if (mult > p) {
            *why = "interior knot repeated more than degree times";
            return i;
        }
    }
    *why = "knot vector invalid";
    return 0;
}

/* Offsets of every field, so a check failing later can name its line. */
static size_t ig_field_at(ig_rd_t *c, const ig_par_t *p, long idx)
{
    size_t pos = 0;
    ig_fld_t f = {NULL, 0, 0};
    for (long k = 0; k <= idx; k++)
        if (ig_next(c, p, &pos, &f) <= 0)
            break;
    return f.at;
}

/* x' = R x + T for every control point; NURBS are affine invariant. */
static void ig_transform(nf_surf_t *s, const double m[12])
{
    long n = (long)s->nu * s->nv;
    for (long i = 0; i < n; i++) {
        double *P = s->cp + 3 * i, x = P[0], y = P[1], z = P[2];
        for (int r = 0; r < 3; r++)
            P[r] = m[4 * r] * x + m[4 * r + 1] * y + m[4 * r + 2] * z + m[4 * r + 3];
    }
}

/* The 128 in p, with the nm matrices in m applied in order, checked. */
static int ig_surface(ig_rd_t *c, const ig_par_t *p, const double (*m)[12], int nm, nf_surf_t *s)
{
    long nf, h[10];
    size_t at[10];
    static const char *hname[10] = {"entity type", "K1",    "K2",    "M1",    "M2",
                                    "PROP1",       "PROP2", "PROP3", "PROP4", "PROP5"};
    int rc = ig_count(c, p, &nf);
    if (rc)
        return rc;
    if (nf < 10)
        return ig_pfail(c, p, 0, CF_EPARSE,
                        "%ld parameters; a rational B-spline surface needs at least 10", nf);
    ig_it_t it = {c, p, 0};
    for (int i = 0; i < 10; i++)
        if ((rc = ig_get_int(&it, hname[i], &h[i], &at[i])))
            return rc;
    long K1 = h[1], K2 = h[2], M1 = h[3], M2 = h[4];
    if (h[0] != 128)
        return ig_pfail(c, p, at[0], CF_EPARSE, "parameter data of entity %ld, D entry says 128",
                        h[0]);
    for (int i = 1; i <= 4; i++)
        if (h[i] < 0)
            return ig_pfail(c, p, at[i], CF_EPARSE, "%s = %ld is negative", hname[i], h[i]);
    if (M1 < 1 || M1 > NF_MAX_DEGREE || M2 < 1 || M2 > NF_MAX_DEGREE)
        return ig_pfail(c, p, at[M1 < 1 || M1 > NF_MAX_DEGREE ? 3 : 4], NF_EDEGREE,
                        "degrees M1 = %ld, M2 = %ld; this build (board %s) takes 1 to %d", M1, M2,
                        BOARD_NAME, NF_MAX_DEGREE);
    if (K1 < M1 || K2 < M2)
        return ig_pfail(c, p, at[K1 < M1 ? 1 : 2], NF_ESIZE,
                        "K1 = %ld, K2 = %ld give a %ld x %ld control net, too small for degrees "
                        "%ld x %ld",
                        K1, K2, K1 + 1, K2 + 1, M1, M2);
    long long ncp = (long long)(K1 + 1) * (K2 + 1);
    long long need = 10 + (K1 + M1 + 2) + (K2 + M2 + 2) + 4 * ncp;
    if (nf < need)
        return ig_pfail(c, p, at[1], CF_EPARSE,
                        "%ld parameters, but K1 = %ld, K2 = %ld, M1 = %ld, M2 = %ld need %lld "
                        "(truncated data or wrong counts)",
                        nf, K1, K2, M1, M2, need);
    if (ncp > NF_MAX_CP)
        return ig_pfail(c, p, at[1], NF_EBUDGET,
                        "%ld x %ld control points; this build (board %s) takes at most %ld", K1 + 1,
                        K2 + 1, BOARD_NAME, (long)NF_MAX_CP);
    int nu = (int)K1 + 1, nv = (int)K2 + 1, pu = (int)M1, pv = (int)M2;
    if (cf_surf_alloc(s, pu, pv, nu, nv))
        return ig_fail(c, CF_ENOMEM, "out of memory for a %d x %d surface", nu, nv);
    const long nk_u = nu + pu + 1, nk_v = nv + pv + 1, n = (long)nu * nv;
    for (long i = 0; i < nk_u && !rc; i++)
        rc = ig_get_real(&it, IG_KU, i, s, &s->U[i]);
    for (long i = 0; i < nk_v && !rc; i++)
        rc = ig_get_real(&it, IG_KV, i, s, &s->V[i]);
    for (long i = 0; i < n && !rc; i++)
        rc = ig_get_real(&it, IG_W, i, s, &s->w[i]);
    for (long i = 0; i < 3 * n && !rc; i++)
        rc = ig_get_real(&it, IG_XYZ, i, s, &s->cp[i]);
    /* Optional U0 U1 V0 V1: only checked to be numbers; pointers may follow. */
    if (!rc && nf >= need + 4) {
        double dom;
        for (int i = 0; i < 4 && !rc; i++)
            rc = ig_get_real(&it, IG_RANGE, i, s, &dom);
    }
    if (rc)
        return rc;
    for (int i = 0; i < nm; i++)
        ig_transform(s, m[i]);
    rc = nf_surf_check(s);
    if (rc == NF_EKNOTS) {
        const char *why;
        int iu = ig_knot_diag(nu - 1, pu, s->U, &why);
        if (nf_knots_check(nu - 1, pu, s->U))
            return ig_pfail(c, p, ig_field_at(c, p, 10 + iu), rc, "%s at S(%d) = %.17g (u)", why,
                            iu - pu, s->U[iu]);
        int iv = ig_knot_diag(nv - 1, pv, s->V, &why);
        return ig_pfail(c, p, ig_field_at(c, p, 10 + nk_u + iv), rc, "%s at T(%d) = %.17g (v)", why,
                        iv - pv, s->V[iv]);
    }
    if (rc == NF_EWEIGHT) {
        long i = 0;
        while (i < n - 1 && s->w[i] > 0.0)
            i++;
        return ig_pfail(c, p, ig_field_at(c, p, 10 + nk_u + nk_v + i), rc,
                        "weight W(%ld,%ld) = %.17g is not positive", i % nu, i / nu, s->w[i]);
    }
    if (rc == NF_ENONFINITE)
        return ig_pfail(c, p, 0, rc,
                        "a control point is not finite after the %d "
                        "transformation matrices",
                        nm);
    if (rc)
        return ig_pfail(c, p, 0, rc, "invalid surface: %s", nf_strerror(rc));
    return CF_OK;
}

static void ig_rd_free(ig_rd_t *c)
{
    if (c->in && c->in->f)
        fclose(c->in->f);
    free(c->in);
    free(c->g);
    free(c->de);
    for (int i = 0; i < c->nwant; i++) {
        cf_bigmem_free(c->want[i].data);
        free(c->want[i].lines);
    }
}

/* Read the file up to the wanted entity's parameter data and its
 * matrices (m, *nm), or (dir_only) up to the P section: the Directory and
 * which entry is wanted; c must be freed with ig_rd_free whatever happens. */
static int ig_load(ig_rd_t *c, const char *path, int type, int entity_de, long nth, int dir_only,
                   char *msg, size_t msglen, double (*m)[12], int *nm)
{
    memset(c, 0, sizeof *c);
    c->dir_only = dir_only;
    c->unit_mm = 1.0;
    c->path = path;
    c->msg = msg;
    c->ml = msglen;
    c->pd = ',';
    c->rd = ';';
    c->target = -1;
    c->want_type = type;
    c->nth = nth;
    c->in = calloc(1, sizeof *c->in);
    if (!c->in)
        return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", path);
    c->in->line = 1;
    c->in->f = fopen(path, "rb");
    if (!c->in->f) {
        int e = errno;
        return cf_fail(msg, msglen, CF_EIO, "%s: cannot open: %s", path, strerror(e));
    }
    int rc = ig_sniff(c);
    if (!rc)
        rc = ig_scan(c, entity_de);
    c->fast = c->pd != '\t' && c->rd != '\t';
    if (!rc && c->notfound)
        rc = c->notfound; /* its message is already in msg */
    for (int i = 1; !rc && !dir_only && i < c->nwant; i++)
        rc = ig_matrix(c, &c->want[i], m[i - 1]);
    *nm = c->nwant > 0 ? c->nwant - 1 : 0;
    return rc;
}

int cf_iges_read(const char *path, int entity_de, nf_surf_t *out, char *msg, size_t msglen)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out || entity_de < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_read: bad arguments");
    ig_rd_t c;
    double m[IG_MAX_CHAIN][12];
    int nm = 0;
    int rc = ig_load(&c, path, 128, entity_de, 0, 0, msg, msglen, m, &nm);
    if (!rc)
        rc = ig_surface(&c, &c.want[0], (const double(*)[12])m, nm, out);
    if (!rc && c.unit_mm != 1.0) /* model units to millimetres; knots are unitless */
        for (long k = 0; k < 3L * out->nu * out->nv; k++)
            out->cp[k] *= c.unit_mm;
    ig_rd_free(&c);
    if (rc)
        cf_surf_free(out);
    return rc;
}

/* ------------------------------------------------------ entity 126 */

enum { IGC_K, IGC_W, IGC_XYZ, IGC_RANGE };

static int ig_get_creal(ig_it_t *it, int kind, long idx, int p, double *v)
{
    if (it->c->fast && ig_real_at(it->c, it->p, &it->pos, v))
        return CF_OK;
    ig_fld_t f;
    ig_next(it->c, it->p, &it->pos, &f); /* counted before: cannot fail */
    int r = ig_real(&f, v);
    if (r != IG_NUM_OK) {
        char what[64];
        switch (kind) {
        case IGC_K: snprintf(what, sizeof what, "knot T(%ld)", idx - p); break;
        case IGC_W: snprintf(what, sizeof what, "weight W(%ld)", idx); break;
        case IGC_XYZ: snprintf(what, sizeof what, "%c(%ld)", "XYZ"[idx % 3], idx / 3); break;
        default: snprintf(what, sizeof what, "parameter range V(%ld)", idx); break;
        }
        return ig_pfail(it->c, it->p, f.at, CF_EPARSE, "%s '%.*s' %s, not a number", what,
                        (int)(f.n > 40 ? 40 : f.n), f.s, ig_numwhy(r));
    }
    return CF_OK;
}

void cf_curve_free(nf_curve_t *c)
{
    if (c && c->U)
        free(c->U);
    if (c)
        memset(c, 0, sizeof *c);
}

int cf_curve_alloc(nf_curve_t *c, int p, int n)
{
    memset(c, 0, sizeof *c);
    if (p < 1 || n < 1)
        return CF_EARG;
    double *mem = calloc((size_t)NF_CURVE_DOUBLES(n, p), sizeof(double));
    if (!mem)
        return CF_ENOMEM;
    nf_curve_wire(c, p, n, mem);
    return CF_OK;
}

/* The 126 in p: K, M, PROP1-4, knots, weights, points, V(0) V(1) [, normal]. */
static int ig_curve(ig_rd_t *c, const ig_par_t *p, const double (*m)[12], int nm, nf_curve_t *cv)
{
    long nf, h[7];
    size_t at[7];
    static const char *hname[7] = {"entity type", "K", "M", "PROP1", "PROP2", "PROP3", "PROP4"};
    int rc = ig_count(c, p, &nf);
    if (rc)
        return rc;
    if (nf < 7)
        return ig_pfail(c, p, 0, CF_EPARSE,
                        "%ld parameters; a rational B-spline curve needs at least 7", nf);
    ig_it_t it = {c, p, 0};
    for (int i = 0; i < 7; i++)
        if ((rc = ig_get_int(&it, hname[i], &h[i], &at[i])))
            return rc;
    long K = h[1], M = h[2];
    if (h[0] != 126)
        return ig_pfail(c, p, at[0], CF_EPARSE, "parameter data of entity %ld, D entry says 126",
                        h[0]);
    if (M < 1 || M > NF_MAX_DEGREE)
        return ig_pfail(c, p, at[2], NF_EDEGREE,
                        "degree M = %ld; this build (board %s) takes 1 to %d", M, BOARD_NAME,
                        NF_MAX_DEGREE);
    if (K < M)
        return ig_pfail(c, p, at[1], NF_ESIZE,
                        "K = %ld gives %ld control points, too few for degree %ld", K, K + 1, M);
    if (K + 1 > NF_MAX_CP)
        return ig_pfail(c, p, at[1], NF_EBUDGET, "%ld control points; this build takes at most %ld",
                        K + 1, (long)NF_MAX_CP);
    long need = 7 + (K + M + 2) + 4 * (K + 1) + 2;
    if (nf < need)
        return ig_pfail(c, p, at[1], CF_EPARSE,
                        "%ld parameters, but K = %ld, M = %ld need %ld (truncated data or wrong "
                        "counts)",
                        nf, K, M, need);
    const int n = (int)K + 1, pd = (int)M;
    if (cf_curve_alloc(cv, pd, n))
        return ig_fail(c, CF_ENOMEM, "out of memory for a curve of %d points", n);
    for (long i = 0; i < n + pd + 1 && !rc; i++)
        rc = ig_get_creal(&it, IGC_K, i, pd, &cv->U[i]);
    for (long i = 0; i < n && !rc; i++)
        rc = ig_get_creal(&it, IGC_W, i, pd, &cv->w[i]);
    for (long i = 0; i < 3L * n && !rc; i++)
        rc = ig_get_creal(&it, IGC_XYZ, i, pd, &cv->cp[i]);
    double range[2];
    for (int i = 0; i < 2 && !rc; i++)
        rc = ig_get_creal(&it, IGC_RANGE, i, pd, &range[i]);
    if (rc)
        return rc;
    for (int k = 0; k < nm; k++)
        for (int i = 0; i < n; i++) {
            double *P = cv->cp + 3 * i, x = P[0], y = P[1], z = P[2];
            for (int r = 0; r < 3; r++)
                P[r] =
                    m[k][4 * r] * x + m[k][4 * r + 1] * y + m[k][4 * r + 2] * z + m[k][4 * r + 3];
        }
    rc = nf_curve_check(cv);
    if (rc == NF_EKNOTS) {
        const char *why;
        int iu = ig_knot_diag(n - 1, pd, cv->U, &why);
        return ig_pfail(c, p, ig_field_at(c, p, 7 + iu), rc, "%s at T(%d) = %.17g", why, iu - pd,
                        cv->U[iu]);
    }
    if (rc == NF_EWEIGHT) {
        long i = 0;
        while (i < n - 1 && cv->w[i] > 0.0)
            i++;
        return ig_pfail(c, p, ig_field_at(c, p, 7 + n + pd + 1 + i), rc,
                        "weight W(%ld) = %.17g is not positive", i, cv->w[i]);
    }
    if (rc)
        return ig_pfail(c, p, 0, rc, "invalid curve: %s", nf_strerror(rc));
    if (!(range[0] < range[1]) || range[0] < cv->U[pd] || range[1] > cv->U[n])
        return ig_pfail(c, p, ig_field_at(c, p, 7 + n + pd + 1 + 4L * n), CF_EUNSUPPORTED,
                        "parameter range [%.17g, %.17g] is not within the knot domain [%.17g, "
                        "%.17g] (trimmed curves are not supported)",
                        range[0], range[1], cv->U[pd], cv->U[n]);
    if (range[0] != cv->U[pd] || range[1] != cv->U[n])
        return ig_pfail(c, p, ig_field_at(c, p, 7 + n + pd + 1 + 4L * n), CF_EUNSUPPORTED,
                        "parameter range [%.17g, %.17g] is a part of the knot domain [%.17g, "
                        "%.17g]: trimmed curves are not supported",
                        range[0], range[1], cv->U[pd], cv->U[n]);
    return CF_OK;
}

int cf_iges_read_curve(const char *path, int entity_de, long nth, nf_curve_t *out, char *msg,
                       size_t msglen)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out || entity_de < 0 || nth < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_read_curve: bad arguments");
    ig_rd_t c;
    double m[IG_MAX_CHAIN][12];
    int nm = 0;
    int rc = ig_load(&c, path, 126, entity_de, nth, 0, msg, msglen, m, &nm);
    if (!rc)
        rc = ig_curve(&c, &c.want[0], (const double(*)[12])m, nm, out);
    if (!rc && c.unit_mm != 1.0)
        for (long k = 0; k < 3L * out->n; k++)
            out->cp[k] *= c.unit_mm;
    ig_rd_free(&c);
    if (rc)
        cf_curve_free(out);
    return rc;
}

/* ------------------------------------------- entities 144, 142, 102 */

/* Every parameter of entity type at DE de (or the nth of its type when de
 * is 0) as integers (an empty field is 0, IGES's default): *v allocated,
 * *nv of them, *gotde its DE number. */
static int ig_ints(const char *path, int type, int de, long nth, long **v, long *nv, long *gotde,
                   char *msg, size_t ml)
{
    ig_rd_t c;
    double m[IG_MAX_CHAIN][12];
    int nm = 0;
    *v = NULL;
    int rc = ig_load(&c, path, type, de, nth, 0, msg, ml, m, &nm);
    long nf = 0;
    if (!rc)
        rc = ig_count(&c, &c.want[0], &nf);
    if (!rc && !(*v = calloc((size_t)nf, sizeof **v)))
        rc = ig_fail(&c, CF_ENOMEM, "out of memory");
    size_t pos = 0;
    for (long i = 0; !rc && i < nf; i++) {
        ig_fld_t f;
        ig_next(&c, &c.want[0], &pos, &f); /* counted before: cannot fail */
        int r = ig_int(&f, &(*v)[i]);
        if (r == IG_NUM_EMPTY)
            (*v)[i] = 0;
        else if (r != IG_NUM_OK)
            rc =
                ig_pfail(&c, &c.want[0], f.at, CF_EPARSE, "parameter %ld '%.*s' %s, not an integer",
                         i, (int)(f.n > 40 ? 40 : f.n), f.s, ig_numwhy(r));
    }
    if (!rc && (*v)[0] != type)
        rc = ig_pfail(&c, &c.want[0], 0, CF_EPARSE, "parameter data of entity %ld, D entry says %d",
                      (*v)[0], type);
    *nv = nf;
    *gotde = rc ? 0 : c.want[0].de;
    ig_rd_free(&c);
    if (rc) {
        free(*v);
        *v = NULL;
    }
    return rc;
}

/* The 126 at DE de, in parameter space: no unit applied. */
static int ig_pcurve(const char *path, long de, nf_curve_t *out, char *msg, size_t ml)
{
    ig_rd_t c;
    double m[IG_MAX_CHAIN][12];
    int nm = 0;
    memset(out, 0, sizeof *out);
    int rc = ig_load(&c, path, 126, (int)de, 0, 0, msg, ml, m, &nm);
    if (!rc)
        rc = ig_curve(&c, &c.want[0], (const double(*)[12])m, nm, out);
    ig_rd_free(&c);
    if (rc)
        cf_curve_free(out);
    return rc;
}

/* The parameter-space curve B of the 142 at DE de: one 126, or a 102 of
 * 126s, appended to t as a loop. */
static int ig_loop(const char *path, long de, cf_trim_t *t, char *msg, size_t ml)
{
    long *v, nv, got;
    if (de < 1 || de > IG_MAX_SEQ)
        return cf_fail(msg, ml, CF_EPARSE, "%s: trimmed surface: boundary pointer %ld", path, de);
    int rc = ig_ints(path, 142, (int)de, 0, &v, &nv, &got, msg, ml);
    if (rc)
        return rc;
    long bptr = nv > 3 ? v[3] : 0;
    free(v);
    if (bptr <= 0)
        return cf_fail(msg, ml, CF_EUNSUPPORTED,
                       "%s: DE %ld (142): no curve in parameter space (only model space: not "
                       "supported)",
                       path, de);
    long one[1] = {bptr}, *list = one, n = 1;
    char m2[8];
    /* One 126, or a composite curve (102) of them. */
    nf_curve_t probe;
    int is126 = ig_pcurve(path, bptr, &probe, m2, sizeof m2) == CF_OK;
    cf_curve_free(&probe);
    if (!is126) {
        if ((rc = ig_ints(path, 102, (int)bptr, 0, &v, &nv, &got, msg, ml)))
            return rc;
        n = nv > 1 ? v[1] : 0;
        if (n < 1 || n > CF_TRIM_MAX_CURVES || nv < 2 + n) {
            free(v);
            return cf_fail(msg, ml, CF_EPARSE, "%s: DE %ld (102): %ld curves", path, bptr, n);
        }
        list = v + 2;
    } else {
        v = NULL;
    }
    nf_curve_t *c = calloc((size_t)n, sizeof *c);
    rc = c ? CF_OK : cf_fail(msg, ml, CF_ENOMEM, "%s: out of memory", path);
    for (long i = 0; !rc && i < n; i++)
        rc = ig_pcurve(path, list[i], &c[i], msg, ml);
    free(v);
    if (rc) {
        for (long i = 0; c && i < n; i++)
            cf_curve_free(&c[i]);
        free(c);
        return rc;
    }
    if ((rc = cf_trim_add_loop(t, c, (int)n)))
        return cf_fail(msg, ml, rc, "%s: DE %ld: too many trim loops or curves", path, de);
    return CF_OK;
}

int cf_iges_read_trim(const char *path, int entity_de, cf_trim_t *out, char *msg, size_t msglen)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!path || !out || entity_de < 0)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_read_trim: bad arguments");
    long surf_de = 0;
    {
        /* Which 128 (its DE), and is there a 144 at all: the Directory
         * only (issue 20: the P section of a 10^5-point net is 8 MB, and
         * a caller reads the surface itself with cf_iges_read). */
        ig_rd_t c;
        double m[IG_MAX_CHAIN][12];
        int nm = 0, any144 = 0;
        int rc = ig_load(&c, path, 128, entity_de, 0, 1, msg, msglen, m, &nm);
        surf_de = c.nwant ? c.want[0].de : 0;
        for (long k = 0; !rc && k < c.nde; k++)
            any144 |= c.de[k].type == 144;
        ig_rd_free(&c);
        if (rc || !any144)
            return rc; /* no 144: the surface is whole */
    }
    int rc = CF_OK;
    for (long nth = 0;; nth++) {
        long *v, nv, got;
        char m2[512];
        if (ig_ints(path, 144, 0, nth, &v, &nv, &got, m2, sizeof m2) != CF_OK)
            break; /* no (more) 144: the surface is whole */
        /* 144: PTS N1 N2 PTO PTI(1..N2) */
        long n1 = nv > 2 ? v[2] : 0, n2 = nv > 3 ? v[3] : 0;
        if (nv < 5 || v[1] != surf_de) {
            free(v);
            continue;
        }
        if (n2 < 0 || n2 >= CF_TRIM_MAX_LOOPS || nv < 5 + n2)
            rc = cf_fail(msg, msglen, CF_EPARSE, "%s: DE %ld (144): %ld inner boundaries", path,
                         got, n2);
        else if (n1 == 0) { /* the outer boundary is the domain's */
            nf_surf_t s;
            if (!(rc = cf_iges_read(path, (int)surf_de, &s, msg, msglen))) {
                rc = cf_trim_add_domain(out, &s);
                cf_surf_free(&s);
            }
        } else
            rc = ig_loop(path, v[4], out, msg, msglen);
        for (long k = 0; !rc && k < n2; k++)
            rc = ig_loop(path, v[5 + k], out, msg, msglen);
        free(v);
        break;
    }
    if (rc)
        cf_trim_free(out);
    return rc;
}
