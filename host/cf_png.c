/* cf_png.c: PNG writer (zlib deflate, per-row adaptive filters, CRC-32),
 * RGB canvas and bitmap font. The zlib stream is produced while rows are
 * pushed: deflate's output gathers in one 64 KB buffer and each full buffer
 * goes out as its own IDAT chunk, so memory does not depend on the image
 * height (one row under five filters, the buffer and zlib's state). */
#include "cf_png.h"
#include "cf_err.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

/* ---- canvas -------------------------------------------------------------- */

int cf_image_init(cf_image_t *im, int w, int h, uint32_t bg, char *msg, size_t msglen)
{
    if (!im)
        return cf_fail(msg, msglen, CF_EARG, "cf_image_init: NULL image");
    im->w = im->h = 0;
    im->px = NULL;
    if (w < 1 || h < 1 || w > CF_PNG_MAX_DIM || h > CF_PNG_MAX_DIM)
        return cf_fail(msg, msglen, CF_EARG, "image size %d x %d outside 1..%d", w, h,
                       CF_PNG_MAX_DIM);
    im->px = malloc((size_t)w * (size_t)h * 3);
    if (!im->px)
        return cf_fail(msg, msglen, CF_ENOMEM, "out of memory for a %d x %d image", w, h);
    im->w = w;
    im->h = h;
    cf_image_fill(im, 0, 0, w, h, bg);
    return CF_OK;
}

void cf_image_free(cf_image_t *im)
{
    if (!im)
        return;
    free(im->px);
    im->px = NULL;
    im->w = im->h = 0;
}

void cf_image_set(cf_image_t *im, int x, int y, uint32_t rgb)
{
    if (x < 0 || y < 0 || x >= im->w || y >= im->h)
        return;
    unsigned char *p = im->px + ((size_t)y * (size_t)im->w + (size_t)x) * 3;
    p[0] = (unsigned char)(rgb >> 16);
    p[1] = (unsigned char)(rgb >> 8);
    p[2] = (unsigned char)rgb;
}

uint32_t cf_image_get(const cf_image_t *im, int x, int y)
{
    if (x < 0 || y < 0 || x >= im->w || y >= im->h)
        return 0;
    const unsigned char *p = im->px + ((size_t)y * (size_t)im->w + (size_t)x) * 3;
    return (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | p[2];
}

void cf_image_fill(cf_image_t *im, int x, int y, int w, int h, uint32_t rgb)
{
    int x0 = x < 0 ? 0 : x, y0 = y < 0 ? 0 : y;
    int x1 = x + w > im->w ? im->w : x + w, y1 = y + h > im->h ? im->h : y + h;
    for (int j = y0; j < y1; j++)
        for (int i = x0; i < x1; i++)
            cf_image_set(im, i, j, rgb);
}

void cf_image_box(cf_image_t *im, int x, int y, int w, int h, uint32_t rgb)
{
    if (w < 1 || h < 1)
        return;
    cf_image_fill(im, x, y, w, 1, rgb);
    cf_image_fill(im, x, y + h - 1, w, 1, rgb);
    cf_image_fill(im, x, y, 1, h, rgb);
    cf_image_fill(im, x + w - 1, y, 1, h, rgb);
}

/* ---- 5x7 font ------------------------------------------------------------- */

/* The classic public-domain 5x7 LCD font, ASCII 32..126: five columns per
 * glyph, left to right, bit 0 the top dot of a column. */
static const unsigned char font5x7[95][5] = {
    {0x00, 0x00, 0x00, 0x00, 0x00}, /*   */
    {0x00, 0x00, 0x5F, 0x00, 0x00}, /* ! */
    {0x00, 0x07, 0x00, 0x07, 0x00}, /* " */
    {0x14, 0x7F, 0x14, 0x7F, 0x14}, /* # */
    {0x24, 0x2A, 0x7F, 0x2A, 0x12}, /* $ */
    {0x23, 0x13, 0x08, 0x64, 0x62}, /* % */
    {0x36, 0x49, 0x55, 0x22, 0x50}, /* & */
    {0x00, 0x05, 0x03, 0x00, 0x00}, /* ' */
    {0x00, 0x1C, 0x22, 0x41, 0x00}, /* ( */
    {0x00, 0x41, 0x22, 0x1C, 0x00}, /* ) */
    {0x08, 0x2A, 0x1C, 0x2A, 0x08}, /* * */
    {0x08, 0x08, 0x3E, 0x08, 0x08}, /* + */
    {0x00, 0x50, 0x30, 0x00, 0x00}, /* , */
    {0x08, 0x08, 0x08, 0x08, 0x08}, /* - */
    {0x00, 0x60, 0x60, 0x00, 0x00}, /* . */
    {0x20, 0x10, 0x08, 0x04, 0x02}, /* / */
    {0x3E, 0x51, 0x49, 0x45, 0x3E}, /* 0 */
    {0x00, 0x42, 0x7F, 0x40, 0x00}, /* 1 */
    {0x42, 0x61, 0x51, 0x49, 0x46}, /* 2 */
    {0x21, 0x41, 0x45, 0x4B, 0x31}, /* 3 */
    {0x18, 0x14, 0x12, 0x7F, 0x10}, /* 4 */
    {0x27, 0x45, 0x45, 0x45, 0x39}, /* 5 */
    {0x3C, 0x4A, 0x49, 0x49, 0x30}, /* 6 */
    {0x01, 0x71, 0x09, 0x05, 0x03}, /* 7 */
    {0x36, 0x49, 0x49, 0x49, 0x36}, /* 8 */
    {0x06, 0x49, 0x49, 0x29, 0x1E}, /* 9 */
    {0x00, 0x36, 0x36, 0x00, 0x00}, /* : */
    {0x00, 0x56, 0x36, 0x00, 0x00}, /* ; */
    {0x08, 0x14, 0x22, 0x41, 0x00}, /* < */
    {0x14, 0x14, 0x14, 0x14, 0x14}, /* = */
    {0x00, 0x41, 0x22, 0x14, 0x08}, /* > */
    {0x02, 0x01, 0x51, 0x09, 0x06}, /* ? */
    {0x32, 0x49, 0x79, 0x41, 0x3E}, /* @ */
    {0x7E, 0x11, 0x11, 0x11, 0x7E}, /* A */
    {0x7F, 0x49, 0x49, 0x49, 0x36}, /* B */
    {0x3E, 0x41, 0x41, 0x41, 0x22}, /* C */
    {0x7F, 0x41, 0x41, 0x22, 0x1C}, /* D */
    {0x7F, 0x49, 0x49, 0x49, 0x41}, /* E */
    {0x7F, 0x09, 0x09, 0x09, 0x01}, /* F */
    {0x3E, 0x41, 0x49, 0x49, 0x7A}, /* G */
    {0x7F, 0x08, 0x08, 0x08, 0x7F}, /* H */
    {0x00, 0x41, 0x7F, 0x41, 0x00}, /* I */
    {0x20, 0x40, 0x41, 0x3F, 0x01}, /* J */
    {0x7F, 0x08, 0x14, 0x22, 0x41}, /* K */
    {0x7F, 0x40, 0x40, 0x40, 0x40}, /* L */
    {0x7F, 0x02, 0x0C, 0x02, 0x7F}, /* M */
    {0x7F, 0x04, 0x08, 0x10, 0x7F}, /* N */
    {0x3E, 0x41, 0x41, 0x41, 0x3E}, /* O */
    {0x7F, 0x09, 0x09, 0x09, 0x06}, /* P */
    {0x3E, 0x41, 0x51, 0x21, 0x5E}, /* Q */
    {0x7F, 0x09, 0x19, 0x29, 0x46}, /* R */
    {0x46, 0x49, 0x49, 0x49, 0x31}, /* S */
    {0x01, 0x01, 0x7F, 0x01, 0x01}, /* T */
    {0x3F, 0x40, 0x40, 0x40, 0x3F}, /* U */
    {0x1F, 0x20, 0x40, 0x20, 0x1F}, /* V */
    {0x3F, 0x40, 0x38, 0x40, 0x3F}, /* W */
    {0x63, 0x14, 0x08, 0x14, 0x63}, /* X */
    {0x07, 0x08, 0x70, 0x08, 0x07}, /* Y */
    {0x61, 0x51, 0x49, 0x45, 0x43}, /* Z */
    {0x00, 0x7F, 0x41, 0x41, 0x00}, /* [ */
    {0x02, 0x04, 0x08, 0x10, 0x20}, /* \ */
    {0x00, 0x41, 0x41, 0x7F, 0x00}, /* ] */
    {0x04, 0x02, 0x01, 0x02, 0x04}, /* ^ */
    {0x40, 0x40, 0x40, 0x40, 0x40}, /* _ */
    {0x00, 0x01, 0x02, 0x04, 0x00}, /* ` */
    {0x20, 0x54, 0x54, 0x54, 0x78}, /* a */
    {0x7F, 0x48, 0x44, 0x44, 0x38}, /* b */
    {0x38, 0x44, 0x44, 0x44, 0x20}, /* c */
    {0x38, 0x44, 0x44, 0x48, 0x7F}, /* d */
    {0x38, 0x54, 0x54, 0x54, 0x18}, /* e */
    {0x08, 0x7E, 0x09, 0x01, 0x02}, /* f */
    {0x0C, 0x52, 0x52, 0x52, 0x3E}, /* g */
    {0x7F, 0x08, 0x04, 0x04, 0x78}, /* h */
    {0x00, 0x44, 0x7D, 0x40, 0x00}, /* i */
    {0x20, 0x40, 0x44, 0x3D, 0x00}, /* j */
    {0x7F, 0x10, 0x28, 0x44, 0x00}, /* k */
    {0x00, 0x41, 0x7F, 0x40, 0x00}, /* l */
    {0x7C, 0x04, 0x18, 0x04, 0x78}, /* m */
    {0x7C, 0x08, 0x04, 0x04, 0x78}, /* n */
    {0x38, 0x44, 0x44, 0x44, 0x38}, /* o */
    {0x7C, 0x14, 0x14, 0x14, 0x08}, /* p */
    {0x08, 0x14, 0x14, 0x18, 0x7C}, /* q */
    {0x7C, 0x08, 0x04, 0x04, 0x08}, /* r */
    {0x48, 0x54, 0x54, 0x54, 0x20}, /* s */
    {0x04, 0x3F, 0x44, 0x40, 0x20}, /* t */
    {0x3C, 0x40, 0x40, 0x20, 0x7C}, /* u */
    {0x1C, 0x20, 0x40, 0x20, 0x1C}, /* v */
    {0x3C, 0x40, 0x30, 0x40, 0x3C}, /* w */
    {0x44, 0x28, 0x10, 0x28, 0x44}, /* x */
    {0x0C, 0x50, 0x50, 0x50, 0x3C}, /* y */
    {0x44, 0x64, 0x54, 0x4C, 0x44}, /* z */
    {0x00, 0x08, 0x36, 0x41, 0x00}, /* { */
    {0x00, 0x00, 0x7F, 0x00, 0x00}, /* | */
    {0x00, 0x41, 0x36, 0x08, 0x00}, /* } */
    {0x08, 0x04, 0x08, 0x10, 0x08}, /* ~ */
};
static const unsigned char glyph_pm[5] = {0x44, 0x44, 0x5F, 0x44, 0x44}; /* ± */
static const unsigned char glyph_mu[5] = {0x7C, 0x20, 0x20, 0x10, 0x3C}; /* µ */

/* The glyph at *s, advancing *s past one UTF-8 code point. */
static const unsigned char *next_glyph(const char **s)
{
    const unsigned char *p = (const unsigned char *)*s;
    unsigned c = *p++;
    const unsigned char *g = font5x7['?' - 32];
    if (c >= 32 && c < 127)
        g = font5x7[c - 32];
    else if (c == 0xC2 && (*p == 0xB1 || *p == 0xB5))
        g = *p++ == 0xB1 ? glyph_pm : glyph_mu;
    else if (c >= 0xC0) /* another multi-byte code point: skip its continuation bytes */
        while ((*p & 0xC0) == 0x80)
            p++;
    *s = (const char *)p;
    return g;
}

int cf_text_width(const char *s, int scale)
{
    int n = 0;
    while (*s) {
        next_glyph(&s);
        n++;
    }
    return n * CF_FONT_W * scale;
}

int cf_image_text(cf_image_t *im, int x, int y, int scale, uint32_t rgb, const char *s)
{
    int x0 = x;
    while (*s) {
        const unsigned char *g = next_glyph(&s);
        for (int col = 0; col < 5; col++)
            for (int row = 0; row < 7; row++)
                if (g[col] >> row & 1)
                    cf_image_fill(im, x + col * scale, y + row * scale, scale, scale, rgb);
        x += CF_FONT_W * scale;
    }
    return x - x0;
}

/* ---- PNG ------------------------------------------------------------------ */

#define PW_OUT 65536u /* compressed bytes per IDAT chunk */

typedef struct pw {
    FILE *f;
    uint32_t tab[256];
    uint32_t crc; /* of the chunk being written */
    z_stream z;
    unsigned char *out;  /* PW_OUT bytes: deflate output, one IDAT chunk */
    unsigned char *cand; /* 5 rows of 1 + 3w bytes: the row under each filter */
    int zerr;            /* deflate failed */
} pw_t;

static void be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* Bytes into the file and into the chunk's CRC; write errors surface via
 * ferror at the end. */
static void pw_out(pw_t *w, const void *data, size_t n)
{
    const unsigned char *p = data;
    uint32_t c = w->crc;
    for (size_t i = 0; i < n; i++)
        c = w->tab[(c ^ p[i]) & 0xFF] ^ (c >> 8);
    w->crc = c;
    fwrite(p, 1, n, w->f);
}

static void chunk_begin(pw_t *w, const char *type, uint32_t len)
{
    unsigned char b[4];
    be32(b, len);
    fwrite(b, 1, 4, w->f);
    w->crc = 0xFFFFFFFFu;
    pw_out(w, type, 4);
}

static void chunk_end(pw_t *w)
{
    unsigned char b[4];
    be32(b, w->crc ^ 0xFFFFFFFFu);
    fwrite(b, 1, 4, w->f);
}

/* What deflate has produced so far as one IDAT chunk. */
static void pw_idat(pw_t *w)
{
    uint32_t n = (uint32_t)(PW_OUT - w->z.avail_out);
    if (n) {
        chunk_begin(w, "IDAT", n);
        pw_out(w, w->out, n);
        chunk_end(w);
    }
    w->z.next_out = w->out;
    w->z.avail_out = PW_OUT;
}

/* n bytes into the zlib stream (flush Z_FINISH ends it); a full output
 * buffer goes out as an IDAT chunk, so memory does not grow with the image. */
static void pw_deflate(pw_t *w, const unsigned char *p, size_t n, int flush)
{
    w->z.next_in = (unsigned char *)(uintptr_t)p; /* zlib's next_in is not const */
    w->z.avail_in = (uInt)n;
    for (;;) {
        int r = deflate(&w->z, flush);
        if (r == Z_STREAM_ERROR) {
            w->zerr = 1;
            return;
        }
        if (w->z.avail_out == 0) {
            pw_idat(w);
            continue;
        }
        if (flush == Z_FINISH ? r == Z_STREAM_END : w->z.avail_in == 0)
            break;
    }
    if (flush == Z_FINISH)
        pw_idat(w);
}

static int paeth(int a, int b, int c)
{
    int p = a + b - c, pa = abs(p - a), pb = abs(p - b), pc = abs(p - c);
    return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

/* The row under each PNG filter (None, Sub, Up, Average, Paeth; PNG spec
 * 9.2, 3 bytes per pixel) into w->cand, and the index of the one with the
 * smallest sum of absolute values taken as signed bytes: the heuristic
 * libpng and the PNG spec (12.8) suggest, which on a map's flat colour
 * areas picks runs of zeros that deflate shrinks best. */
static int pw_filter(pw_t *w, const unsigned char *row, const unsigned char *prev, size_t len)
{
    unsigned long sum[5] = {0, 0, 0, 0, 0};
    int best = 0;
    for (int f = 0; f < 5; f++) {
        unsigned char *o = w->cand + (size_t)f * (len + 1);
        o[0] = (unsigned char)f;
        for (size_t i = 0; i < len; i++) {
            int x = row[i], a = i >= 3 ? row[i - 3] : 0, b = prev ? prev[i] : 0;
            int c = i >= 3 && prev ? prev[i - 3] : 0;
            int pred = f == 0 ? 0 : f == 1 ? a : f == 2 ? b : f == 3 ? (a + b) / 2 : paeth(a, b, c);
            unsigned char v = (unsigned char)(x - pred);
            o[i + 1] = v;
            sum[f] += v < 128 ? v : 256u - v;
        }
        if (sum[f] < sum[best])
            best = f;
    }
    return best;
}

static int pw_stream(pw_t *w, const unsigned char *rgb, int wd, int ht)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    unsigned char ihdr[13];
    fwrite(sig, 1, 8, w->f);
    be32(ihdr, (uint32_t)wd);
    be32(ihdr + 4, (uint32_t)ht);
    ihdr[8] = 8;  /* bits per sample */
    ihdr[9] = 2;  /* colour type: RGB */
    ihdr[10] = 0; /* deflate */
    ihdr[11] = 0; /* adaptive filtering: a filter type per row */
    ihdr[12] = 0; /* no interlace */
    chunk_begin(w, "IHDR", 13);
    pw_out(w, ihdr, 13);
    chunk_end(w);
    size_t row = (size_t)wd * 3;
    for (int y = 0; y < ht && !w->zerr; y++) {
        const unsigned char *r = rgb + (size_t)y * row;
        int f = pw_filter(w, r, y ? r - row : NULL, row);
        pw_deflate(w, w->cand + (size_t)f * (row + 1), row + 1, Z_NO_FLUSH);
    }
    if (!w->zerr)
        pw_deflate(w, NULL, 0, Z_FINISH);
    chunk_begin(w, "IEND", 0);
    chunk_end(w);
    return w->zerr || ferror(w->f) ? -1 : 0;
}

int cf_png_write(const char *path, const unsigned char *rgb, int w, int h, char *msg, size_t msglen)
{
    if (!path || !rgb)
        return cf_fail(msg, msglen, CF_EARG, "cf_png_write: NULL argument");
    if (w < 1 || h < 1 || w > CF_PNG_MAX_DIM || h > CF_PNG_MAX_DIM)
        return cf_fail(msg, msglen, CF_EARG, "%s: image size %d x %d outside 1..%d", path, w, h,
                       CF_PNG_MAX_DIM);
    char tmp[4096];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp)
        return cf_fail(msg, msglen, CF_EARG, "%s: path too long", path);
    pw_t *pw = calloc(1, sizeof *pw);
    unsigned char *out = malloc(PW_OUT);
    unsigned char *cand = malloc(5 * ((size_t)w * 3 + 1));
    /* Level 9 and the default strategy: a map is mostly flat colour, which
     * deflate's long matches take best; the whole image costs a few ms. */
    if (!pw || !out || !cand || deflateInit(&pw->z, 9) != Z_OK) {
        free(pw);
        free(out);
        free(cand);
        return cf_fail(msg, msglen, CF_ENOMEM, "%s: out of memory", path);
    }
    pw->out = out;
    pw->cand = cand;
    pw->z.next_out = out;
    pw->z.avail_out = PW_OUT;
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++)
            c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        pw->tab[n] = c;
    }
    int ec = CF_OK;
    pw->f = fopen(tmp, "wb");
    if (!pw->f) {
        ec = cf_fail(msg, msglen, CF_EIO, "%s: cannot create: %s", tmp, strerror(errno));
        goto out;
    }
    int bad = pw_stream(pw, rgb, w, h);
    /* Data must be on disk before the rename makes it visible under path. */
    if (!bad)
        bad = fflush(pw->f) || fsync(fileno(pw->f));
    int eno = errno;
    if (fclose(pw->f) && !bad) {
        bad = 1;
        eno = errno;
    }
    if (bad) {
        remove(tmp);
        ec = cf_fail(msg, msglen, CF_EIO, "%s: write failed: %s", tmp,
                     pw->zerr ? "deflate error" : strerror(eno));
        goto out;
    }
    if (rename(tmp, path)) {
        eno = errno;
        remove(tmp);
        ec = cf_fail(msg, msglen, CF_EIO, "%s: cannot rename %s to it: %s", path, tmp,
                     strerror(eno));
    }
out:
    deflateEnd(&pw->z);
    free(out);
    free(cand);
    free(pw);
    return ec;
}

int cf_png_write_image(const char *path, const cf_image_t *im, char *msg, size_t msglen)
{
    if (!im || !im->px)
        return cf_fail(msg, msglen, CF_EARG, "cf_png_write_image: no image");
    return cf_png_write(path, im->px, im->w, im->h, msg, msglen);
}
