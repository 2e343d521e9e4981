/* SPDX-License-Identifier: MIT */
/* cf_iges_write.c: IGES 5.3 entities 128 (rational B-spline surface) and
 * 126 (rational B-spline curve), written as complete files (cf_iges.h; the
 * reader is cf_iges_read.c): fixed 80-column records, %.17g numbers, the
 * file replaced atomically (cf_atomic.h). */
#include "cf_atomic.h"
#include "cf_err.h"
#include "cf_fmt.h"
#include "cf_iges.h"
#include "cf_surf.h"
#include "cf_version.h"
#include "nf_err.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define IG_PCOLS 64 /* data columns of a P line */
#define IG_GCOLS 72 /* data columns of an S or G line */
#define IG_MAX_SEQ 9999999L

/* --------------------------------------------------------------- output */

#define IG_WBLK (81 * 64) /* lines gathered before an fwrite */

typedef struct ig_w {
    FILE *f; /* NULL: only count the lines */
    char sect;
    size_t width;  /* data columns of a free-format line: 72 (S, G) or 64 (P) */
    char cur[128]; /* the line being filled, with room for cf_fmt17_iges's word writes */
    size_t curlen;
    long seq;       /* lines of this section so far */
    long de;        /* P lines: DE number of the entity they belong to (0: 1) */
    char seqtxt[7]; /* columns 74-80: seq % 10^7 right-justified, counted up */
    long detxt_of;  /* the de that detxt holds, -1 none yet */
    char detxt[8];  /* columns 65-72 of a P line */
    size_t blen;
    char blk[IG_WBLK]; /* whole lines not yet written */
} ig_w_t;

/* x right-aligned in the w columns ending before end (x >= 0 fits). */
static void ig_rjust(char *end, int w, long x)
{
    for (int i = 0; i < w; i++, x /= 10)
        end[-1 - i] = i > 0 && x == 0 ? ' ' : (char)('0' + x % 10);
}

static void ig_winit(ig_w_t *w, FILE *f, char sect, size_t width)
{
    w->f = f;
    w->sect = sect;
    w->width = width;
    memset(w->cur, ' ', sizeof w->cur);
    w->curlen = 0;
    w->seq = 0;
    w->de = 0;
    memset(w->seqtxt, ' ', sizeof w->seqtxt);
    w->seqtxt[6] = '0';
    w->detxt_of = -1;
    w->blen = 0;
}

/* Lines gathered so far to the file (one fwrite per IG_WBLK bytes: an
 * fwrite a line cost about 140 instructions, a quarter of a line's). */
static void ig_wblk(ig_w_t *w)
{
    if (w->f && w->blen)
        fwrite(w->blk, 1, w->blen, w->f);
    w->blen = 0;
}

static void ig_wline(ig_w_t *w, const char *data, size_t n)
{
    w->seq++;
    if (!w->f)
        return;
    /* The sequence number counted up in place (the same bytes as
     * ig_rjust(seq % 10^7), which the division loop made a fifth of a
     * line); > 7 digits: refused after, as before. */
    int i = 6;
    while (i >= 0 && w->seqtxt[i] == '9')
        w->seqtxt[i--] = '0';
    if (i >= 0)
        w->seqtxt[i] = w->seqtxt[i] == ' ' ? '1' : (char)(w->seqtxt[i] + 1);
    else
        ig_rjust(w->seqtxt + 7, 7, w->seq % 10000000L);
    if (w->blen + 81 > sizeof w->blk)
        ig_wblk(w);
    char *line = w->blk + w->blen;
    w->blen += 81;
    if (n > 72)
        n = 72;
    /* fixed-size copies (the variable ones were library calls): the line
     * being filled is 128 bytes; blanks from n, eight at a time (what
     * passes column 72 is overwritten below) */
    if (data == w->cur)
        memcpy(line, data, 72);
    else
        memcpy(line, data, n);
    for (size_t j = n; j < 72; j += 8)
        memcpy(line + j, "        ", 8);
    /* P's back pointer to its DE, "%8ld" as before */
    if (w->sect == 'P') {
        const long de = w->de ? w->de : 1L;
        if (de != w->detxt_of) {
            ig_rjust(w->detxt + 8, 8, de);
            w->detxt_of = de;
        }
        memcpy(line + 64, w->detxt, 8);
    }
    line[72] = w->sect;
    memcpy(line + 73, w->seqtxt, 7);
    line[80] = '\n';
}

/* The current line out, and every gathered line to the file. */
static void ig_flush(ig_w_t *w)
{
    if (w->curlen)
        ig_wline(w, w->cur, w->curlen);
    w->curlen = 0;
    ig_wblk(w);
}

/* A parameter of n bytes and its delimiter; parameters never straddle lines. */
static void ig_tokn(ig_w_t *w, const char *tok, size_t n, char delim)
{
    if (w->curlen + n + 1 > w->width) {
        if (w->curlen)
            ig_wline(w, w->cur, w->curlen);
        w->curlen = 0;
    }
    memcpy(w->cur + w->curlen, tok, n);
    w->curlen += n;
    w->cur[w->curlen++] = delim;
}

static void ig_tok(ig_w_t *w, const char *tok, char delim)
{
    ig_tokn(w, tok, strlen(tok), delim);
}

/* %.17g (round-trip exact) with the decimal point and capital E IGES
 * wants, formatted in place at the end of the line, moved to the start of
 * the next when it does not fit. */
static void ig_real_tok(ig_w_t *w, double x, char delim)
{
    char *at = w->cur + w->curlen;
    const size_t n = (size_t)cf_fmt17_iges(x, at, sizeof w->cur - w->curlen);
    if (w->curlen + n + 1 > w->width) {
        if (w->curlen)
            ig_wline(w, w->cur, w->curlen);
        memmove(w->cur, at, n);
        w->curlen = 0;
    }
    w->curlen += n;
    w->cur[w->curlen++] = delim;
}

static void ig_int_tok(ig_w_t *w, long x)
{
    char b[24];
    snprintf(b, sizeof b, "%ld", x);
    ig_tok(w, b, ',');
}

/* Hollerith string nH... */
static void ig_str_tok(ig_w_t *w, const char *str, char delim)
{
    char b[80];
    snprintf(b, sizeof b, "%zuH%s", strlen(str), str);
    ig_tok(w, b, delim);
}

/* The parameter data of the 128: counts, flags, knots, weights, points, range. */
static void ig_pdata(ig_w_t *w, const nf_surf_t *s, int poly)
{
    const long n = (long)s->nu * s->nv;
    double u0, u1, v0, v1;
    ig_int_tok(w, 128);
    ig_int_tok(w, s->nu - 1);
    ig_int_tok(w, s->nv - 1);
    ig_int_tok(w, s->p);
    ig_int_tok(w, s->q);
    ig_int_tok(w, 0); /* PROP1, PROP2: not closed */
    ig_int_tok(w, 0);
    ig_int_tok(w, poly);
    ig_int_tok(w, 0); /* PROP4, PROP5: not periodic */
    ig_int_tok(w, 0);
    for (long i = 0; i < s->nu + s->p + 1; i++)
        ig_real_tok(w, s->U[i], ',');
    for (long i = 0; i < s->nv + s->q + 1; i++)
        ig_real_tok(w, s->V[i], ',');
    for (long i = 0; i < n; i++)
        ig_real_tok(w, s->w ? s->w[i] : 1.0, ',');
    for (long i = 0; i < 3 * n; i++)
        ig_real_tok(w, s->cp[i], ',');
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    ig_real_tok(w, u0, ',');
    ig_real_tok(w, u1, ',');
    ig_real_tok(w, v0, ',');
    ig_real_tok(w, v1, ';');
    ig_flush(w);
}

/* Printable ASCII only, at most max characters; empty becomes dflt. */
static void ig_clean(char *dst, const char *src, size_t max, const char *dflt)
{
    size_t n = 0;
    for (; src && src[n] && n < max; n++)
        dst[n] = (src[n] >= 0x20 && src[n] < 0x7F) ? src[n] : '_';
    dst[n] = '\0';
    if (!n)
        snprintf(dst, max + 1, "%s", dflt);
}

static double ig_maxabs(const double *x, long n)
{
    double mx = 0.0;
    for (long i = 0; i < n; i++)
        mx = fabs(x[i]) > mx ? fabs(x[i]) : mx;
    return mx;
}

static void ig_global_out(ig_w_t *w, double mx, const char *name, const char *fname,
                          const char *date)
{
    ig_str_tok(w, ",", ',');                 /* 1 parameter delimiter */
    ig_str_tok(w, ";", ',');                 /* 2 record delimiter */
    ig_str_tok(w, name, ',');                /* 3 product id (sender) */
    ig_str_tok(w, fname, ',');               /* 4 file name */
    ig_str_tok(w, "cellfit", ',');           /* 5 native system */
    ig_str_tok(w, cf_version_string(), ','); /* 6 preprocessor version */
    ig_int_tok(w, 32);                       /* 7 integer bits */
    ig_int_tok(w, 38);                       /* 8, 9 single precision */
    ig_int_tok(w, 6);
    ig_int_tok(w, 308); /* 10, 11 double precision */
    ig_int_tok(w, 15);
    ig_str_tok(w, name, ',');  /* 12 product id (receiver) */
    ig_real_tok(w, 1.0, ',');  /* 13 model space scale */
    ig_int_tok(w, 2);          /* 14 units: millimetres */
    ig_str_tok(w, "MM", ',');  /* 15 */
    ig_int_tok(w, 1);          /* 16 line weight gradations */
    ig_real_tok(w, 1.0, ',');  /* 17 maximum line width */
    ig_str_tok(w, date, ',');  /* 18 file generated */
    ig_real_tok(w, 1e-9, ','); /* 19 resolution */
    ig_real_tok(w, mx, ',');   /* 20 maximum coordinate */
    ig_str_tok(w, "cellfit", ',');
    ig_str_tok(w, "cellfit", ',');
    ig_int_tok(w, 11);        /* 23 IGES 5.3 */
    ig_int_tok(w, 0);         /* 24 no drafting standard */
    ig_str_tok(w, date, ';'); /* 25 model modified */
    ig_flush(w);
}

/* What every writer's S and G sections share: the sender's and the file's
 * names (printable, at most 64 characters), the UTC date, the open file. */
typedef struct ig_head {
    char nm[65], fname[65], date[72];
    cf_atomic_t aw;
} ig_head_t;

/* Fill h and open the temporary (cf_atomic); CF_OK or CF_EIO with msg. */
static int ig_global(ig_head_t *h, const char *path, const char *name, const char *dflt,
                     long long utc, char *msg, size_t msglen)
{
    const char *base = strrchr(path, '/');
    char dfile[72];
    snprintf(dfile, sizeof dfile, "%s.igs", dflt);
    ig_clean(h->nm, name, 64, dflt);
    ig_clean(h->fname, base ? base + 1 : path, 64, dfile);
    time_t t = (time_t)utc;
    struct tm tm;
    if (!gmtime_r(&t, &tm) || tm.tm_year + 1900 > 9999 || tm.tm_year + 1900 < 0) {
        t = 0;
        gmtime_r(&t, &tm);
    }
    snprintf(h->date, sizeof h->date, "%04d%02d%02d.%02d%02d%02d", tm.tm_year + 1900, tm.tm_mon + 1,
             tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec);
    return cf_atomic_open(&h->aw, path, msg, msglen);
}

/* Write the 8-column field k (0-based) of the D line at offset at: the
 * P pointers and counts known only once the P section is written. */
static int ig_patch(FILE *f, long at, int k, long x)
{
    char b[8];
    ig_rjust(b + 8, 8, x);
    return fseek(f, at + 8L * k, SEEK_SET) || fwrite(b, 1, 8, f) != 8;
}

int cf_iges_write_at(const char *path, const nf_surf_t *s, const char *name, long long utc,
                     char *msg, size_t msglen)
{
    if (!path || !*path || !s)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_write: bad arguments");
    int rc = nf_surf_check(s);
    if (rc)
        return cf_fail(msg, msglen, rc, "%s: not written: invalid surface: %s", path,
                       nf_strerror(rc));
    int poly = 1;
    for (long i = 1; s->w && i < (long)s->nu * s->nv; i++)
        poly &= s->w[i] == s->w[0];
    ig_head_t h;
    if ((rc = ig_global(&h, path, name, "surface", utc, msg, msglen)))
        return rc;
    FILE *f = h.aw.f;
    char text[160];
    long cnt[4];
    ig_w_t ws;
    ig_winit(&ws, f, 'S', IG_GCOLS);
    int tl = snprintf(text, sizeof text,
                      "cellfit: rational B-spline surface %s (IGES 5.3, one entity 128)", h.nm);
    for (int at = 0; at < tl; at += IG_GCOLS)
        ig_wline(&ws, text + at, (size_t)(tl - at));
    ig_flush(&ws);
    cnt[0] = ws.seq;

    ig_w_t wg;
    ig_winit(&wg, f, 'G', IG_GCOLS);
    ig_global_out(&wg, ig_maxabs(s->cp, 3L * s->nu * s->nv), h.nm, h.fname, h.date);
    cnt[1] = wg.seq;

    /* The D entry's P line count is patched in after the P section: no dry
     * run formatting every number twice (issue 20). */
    char d[2][96];
    snprintf(d[0], sizeof d[0], "%8d%8d%8d%8d%8d%8d%8d%8d%8s%c%7d\n", 128, 1, 0, 0, 0, 0, 0, 0,
             "00000000", 'D', 1);
    snprintf(d[1], sizeof d[1], "%8d%8d%8d%8ld%8d%8s%8s%8.8s%8d%c%7d\n", 128, 0, 0, 0L, 0, "", "",
             "BSURF", 0, 'D', 2);
    fputs(d[0], f);
    fputs(d[1], f);
    cnt[2] = 2;

    ig_w_t wp;
    ig_winit(&wp, f, 'P', IG_PCOLS);
    ig_pdata(&wp, s, poly);
    cnt[3] = wp.seq;
    if (cnt[3] > IG_MAX_SEQ) {
        cf_atomic_abort(&h.aw);
        return cf_fail(msg, msglen, CF_EUNSUPPORTED,
                       "%s: not written: %ld parameter lines exceed IGES's 7-digit sequence "
                       "numbers",
                       path, cnt[3]);
    }

    fprintf(f, "S%7ldG%7ldD%7ldP%7ld%40sT%7d\n", cnt[0], cnt[1], cnt[2], cnt[3], "", 1);
    if (ig_patch(f, 81L * (cnt[0] + cnt[1] + 1), 3, cnt[3])) {
        cf_atomic_abort(&h.aw);
        return cf_fail(msg, msglen, CF_EIO, "%s: not written: %s", path, strerror(errno));
    }
    return cf_atomic_commit(&h.aw, 0, msg, msglen);
}

int cf_iges_write(const char *path, const nf_surf_t *s, const char *name, char *msg, size_t msglen)
{
    return cf_iges_write_at(path, s, name, cf_atomic_stamp(), msg, msglen);
}

/* ------------------------------------------------- entity 126 output */

static void ig_cdata(ig_w_t *w, const nf_curve_t *c)
{
    int poly = 1;
    for (int i = 1; c->w && i < c->n; i++)
        poly &= c->w[i] == c->w[0];
    ig_int_tok(w, 126);
    ig_int_tok(w, c->n - 1);
    ig_int_tok(w, c->p);
    ig_int_tok(w, 0); /* PROP1: not known to be planar */
    ig_int_tok(w, 0); /* PROP2: open */
    ig_int_tok(w, poly);
    ig_int_tok(w, 0); /* PROP4: not periodic */
    for (int i = 0; i < c->n + c->p + 1; i++)
        ig_real_tok(w, c->U[i], ',');
    for (int i = 0; i < c->n; i++)
        ig_real_tok(w, c->w ? c->w[i] : 1.0, ',');
    for (long i = 0; i < 3L * c->n; i++)
        ig_real_tok(w, c->cp[i], ',');
    ig_real_tok(w, c->U[c->p], ',');
    ig_real_tok(w, c->U[c->n], ',');
    ig_real_tok(w, 0.0, ','); /* normal: unused for a non-planar curve */
    ig_real_tok(w, 0.0, ',');
    ig_real_tok(w, 0.0, ';');
    ig_flush(w);
}

int cf_iges_write_curves(const char *path, const nf_curve_t *c, int nc, const char *name, char *msg,
                         size_t msglen)
{
    if (!path || !*path || !c || nc < 1 || nc > 9999)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_write_curves: bad arguments");
    double mx = 0.0;
    for (int k = 0; k < nc; k++) {
        int rc = nf_curve_check(&c[k]);
        if (rc)
            return cf_fail(msg, msglen, rc, "%s: not written: curve %d invalid: %s", path, k + 1,
                           nf_strerror(rc));
        mx = fmax(mx, ig_maxabs(c[k].cp, 3L * c[k].n));
    }
    ig_head_t h;
    int orc = ig_global(&h, path, name, "curves", cf_atomic_stamp(), msg, msglen);
    if (orc)
        return orc;
    FILE *f = h.aw.f;
    char text[160];
    long cnt[4];
    ig_w_t ws;
    ig_winit(&ws, f, 'S', IG_GCOLS);
    int tl = snprintf(text, sizeof text,
                      "cellfit: %d rational B-spline curves %s (IGES 5.3, entity 126)", nc, h.nm);
    for (int at = 0; at < tl; at += IG_GCOLS)
        ig_wline(&ws, text + at, (size_t)(tl - at));
    ig_flush(&ws);
    cnt[0] = ws.seq;
    ig_w_t wg;
    ig_winit(&wg, f, 'G', IG_GCOLS);
    ig_global_out(&wg, mx, h.nm, h.fname, h.date);
    cnt[1] = wg.seq;
    long pstart = 1;
    for (int k = 0; k < nc; k++) { /* D entries: each curve's P line count from a dry run */
        ig_w_t dry;
        ig_winit(&dry, NULL, 'P', IG_PCOLS);
        ig_cdata(&dry, &c[k]);
        fprintf(f, "%8d%8ld%8d%8d%8d%8d%8d%8d%8s%c%7d\n", 126, pstart, 0, 0, 0, 0, 0, 0, "00000000",
                'D', 2 * k + 1);
        fprintf(f, "%8d%8d%8d%8ld%8d%8s%8s%8.8s%8d%c%7d\n", 126, 0, 0, dry.seq, 0, "", "", "BCURVE",
                k + 1, 'D', 2 * k + 2);
        pstart += dry.seq;
    }
    cnt[2] = 2L * nc;
    ig_w_t wp;
    ig_winit(&wp, f, 'P', IG_PCOLS);
    for (int k = 0; k < nc; k++) {
        wp.de = 2L * k + 1;
        ig_cdata(&wp, &c[k]);
    }
    cnt[3] = wp.seq;
    fprintf(f, "S%7ldG%7ldD%7ldP%7ld%40sT%7d\n", cnt[0], cnt[1], cnt[2], cnt[3], "", 1);
    return cf_atomic_commit(&h.aw, 0, msg, msglen);
}

/* ------------------------------------------ trimmed surface output */

enum { IGT_SURF, IGT_CURVE, IGT_INTS };

/* One entity of a trimmed-surface file. */
typedef struct ig_ent {
    int type, kind;
    const char *status; /* D field 9 */
    const char *label;
    const nf_curve_t *c; /* IGT_CURVE */
    long *iv;            /* IGT_INTS: the parameters after the type */
    int niv;
} ig_ent_t;

static void ig_edata(ig_w_t *w, const ig_ent_t *e, const nf_surf_t *s, int poly)
{
    if (e->kind == IGT_SURF) {
        ig_pdata(w, s, poly);
    } else if (e->kind == IGT_CURVE) {
        ig_cdata(w, e->c);
    } else {
        ig_int_tok(w, e->type);
        for (int i = 0; i < e->niv; i++) {
            char b[24];
            snprintf(b, sizeof b, "%ld", e->iv[i]);
            ig_tok(w, b, i + 1 < e->niv ? ',' : ';');
        }
        ig_flush(w);
    }
}

/* Entities: the 128 (DE 1), per loop its 2-D curves [102], 3-D curves [102],
 * 142; the 144 last. ents and ints sized by the caller from the counts. */
static int ig_trim_ents(const cf_trim_t *t, const nf_curve_t *e3, ig_ent_t *ents, long *ints)
{
    int ne = 0, ic = 0;
    long *iv = ints;
    long bound[CF_TRIM_MAX_LOOPS];
    ents[ne++] = (ig_ent_t){128, IGT_SURF, "00010000", "BSURF", NULL, NULL, 0};
    for (int k = 0; k < t->nloops; k++) {
        const cf_trim_loop_t *l = &t->loop[k];
        long side[2];
        for (int d = 0; d < 2; d++) { /* 0: parameter space, 1: model space */
            long first = 2L * ne + 1;
            for (int i = 0; i < l->n; i++)
                ents[ne++] = (ig_ent_t){126,
                                        IGT_CURVE,
                                        d ? "00010000" : "00010500",
                                        d ? "EDGE" : "PCURVE",
                                        d ? &e3[ic + i] : &l->c[i],
                                        NULL,
                                        0};
            side[d] = first;
            if (l->n > 1) {
                iv[0] = l->n;
                for (int i = 0; i < l->n; i++)
                    iv[1 + i] = first + 2L * i;
                ents[ne++] = (ig_ent_t){102, IGT_INTS, d ? "00010000" : "00010500", "CCURVE", NULL,
                                        iv,  l->n + 1};
                side[d] = 2L * ne - 1;
                iv += l->n + 1;
            }
        }
        ic += l->n;
        /* 142: CRTN 0 (unspecified), SPTR, BPTR, CPTR, PREF 1 (S(B) preferred) */
        iv[0] = 0, iv[1] = 1, iv[2] = side[0], iv[3] = side[1], iv[4] = 1;
        ents[ne++] = (ig_ent_t){142, IGT_INTS, "00010000", "BOUNDARY", NULL, iv, 5};
        iv += 5;
        bound[k] = 2L * ne - 1;
    }
    iv[0] = 1, iv[1] = 1, iv[2] = t->nloops - 1; /* 144: PTS N1 N2 PTO PTI... */
    for (int k = 0; k < t->nloops; k++)
        iv[3 + k] = bound[k];
    ents[ne++] = (ig_ent_t){144, IGT_INTS, "00000000", "TRIMSURF", NULL, iv, 3 + t->nloops};
    return ne;
}

int cf_iges_write_trimmed_at(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                             const char *name, long long utc, double *edge_err, char *msg,
                             size_t msglen)
{
    if (!path || !*path || !s || !t || t->nloops < 1 || t->nloops > CF_TRIM_MAX_LOOPS)
        return cf_fail(msg, msglen, CF_EARG, "cf_iges_write_trimmed: bad arguments");
    int rc = nf_surf_check(s);
    if (rc)
        return cf_fail(msg, msglen, rc, "%s: not written: invalid surface: %s", path,
                       nf_strerror(rc));
    long ncurves = 0;
    for (int k = 0; k < t->nloops; k++)
        ncurves += t->loop[k].n;
    long nents = 2 + 2 * ncurves + 3L * t->nloops, nints = 4 + 2 * ncurves + 9L * t->nloops;
    nf_curve_t *e3 = calloc((size_t)ncurves, sizeof *e3);
    ig_ent_t *ents = calloc((size_t)nents, sizeof *ents);
    long *ints = calloc((size_t)nints, sizeof *ints), *dpl = calloc((size_t)nents, sizeof *dpl);
    double emax = 0.0;
    rc = e3 && ents && ints && dpl ? CF_OK : CF_ENOMEM;
    for (int k = 0, ic = 0; !rc && k < t->nloops; k++)
        for (int i = 0; !rc && i < t->loop[k].n; i++, ic++) {
            double e;
            rc = cf_trim_edge3d(s, &t->loop[k].c[i], CF_TRIM_EDGE_TOL, &e3[ic], &e);
            emax = fmax(emax, e);
        }
    if (rc) {
        rc = cf_fail(msg, msglen, rc, "%s: not written: %s", path,
                     rc == CF_ENOMEM ? "out of memory" : "a 3-D edge cannot be interpolated");
        goto out;
    }
    if (edge_err)
        *edge_err = emax;
    int ne = ig_trim_ents(t, e3, ents, ints);
    int poly = 1;
    for (long i = 1; s->w && i < (long)s->nu * s->nv; i++)
        poly &= s->w[i] == s->w[0];
    ig_head_t h;
    if ((rc = ig_global(&h, path, name, "surface", utc, msg, msglen)))
        goto out;
    FILE *f = h.aw.f;
    char text[200];
    long cnt[4];
    ig_w_t ws;
    ig_winit(&ws, f, 'S', IG_GCOLS);
    int tl = snprintf(text, sizeof text,
                      "cellfit: trimmed rational B-spline surface %s (IGES 5.3, entity 144 over "
                      "128, %d boundaries)",
                      h.nm, t->nloops);
    for (int at = 0; at < tl; at += IG_GCOLS)
        ig_wline(&ws, text + at, (size_t)(tl - at));
    ig_flush(&ws);
    cnt[0] = ws.seq;
    ig_w_t wg;
    ig_winit(&wg, f, 'G', IG_GCOLS);
    ig_global_out(&wg, ig_maxabs(s->cp, 3L * s->nu * s->nv), h.nm, h.fname, h.date);
    cnt[1] = wg.seq;
    /* P pointers and line counts patched in after the P section (no dry
     * run of the 128's numbers). */
    for (int i = 0; i < ne; i++) {
        fprintf(f, "%8d%8ld%8d%8d%8d%8d%8d%8d%8s%c%7d\n", ents[i].type, 0L, 0, 0, 0, 0, 0, 0,
                ents[i].status, 'D', 2 * i + 1);
        fprintf(f, "%8d%8d%8d%8ld%8d%8s%8s%8.8s%8d%c%7d\n", ents[i].type, 0, 0, 0L, 0, "", "",
                ents[i].label, 0, 'D', 2 * i + 2);
    }
    cnt[2] = 2L * ne;
    ig_w_t wp;
    ig_winit(&wp, f, 'P', IG_PCOLS);
    for (int i = 0; i < ne; i++) {
        long before = wp.seq;
        wp.de = 2L * i + 1;
        ig_edata(&wp, &ents[i], s, poly);
        dpl[i] = wp.seq - before;
    }
    cnt[3] = wp.seq;
    if (cnt[3] > IG_MAX_SEQ) {
        cf_atomic_abort(&h.aw);
        rc = cf_fail(msg, msglen, CF_EUNSUPPORTED,
                     "%s: not written: %ld parameter lines exceed IGES's 7-digit sequence numbers",
                     path, cnt[3]);
        goto out;
    }
    fprintf(f, "S%7ldG%7ldD%7ldP%7ld%40sT%7d\n", cnt[0], cnt[1], cnt[2], cnt[3], "", 1);
    long d0 = 81L * (cnt[0] + cnt[1]), pstart = 1;
    int bad = 0;
    for (int i = 0; i < ne && !bad; i++) {
        bad = ig_patch(f, d0 + 81L * 2 * i, 1, pstart) ||
              ig_patch(f, d0 + 81L * (2 * i + 1), 3, dpl[i]);
        pstart += dpl[i];
    }
    if (bad) {
        cf_atomic_abort(&h.aw);
        rc = cf_fail(msg, msglen, CF_EIO, "%s: not written: %s", path, strerror(errno));
        goto out;
    }
    rc = cf_atomic_commit(&h.aw, 0, msg, msglen);
out:
    for (long i = 0; e3 && i < ncurves; i++)
        cf_curve_free(&e3[i]);
    free(e3);
    free(ents);
    free(ints);
    free(dpl);
    return rc;
}
