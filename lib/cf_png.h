/* SPDX-License-Identifier: MIT */
/* cf_png.h: PNG output through zlib: 8-bit RGB images, each row under the
 * PNG filter that suits it best, compressed by deflate (a 1200 x 900
 * deviation map: tens of KB, against 3.2 MB stored), plus an RGB canvas with
 * filled rectangles and a bitmap font, enough to label a deviation map
 * (numbers, "mm", "RMS", file names). */
#ifndef CF_PNG_H
#define CF_PNG_H

#include <stddef.h>
#include <stdint.h>

#define CF_PNG_MAX_DIM 16384 /* width and height limit, pixels */

/* Colours are 0xRRGGBB. */
typedef struct cf_image {
    int w, h;
    unsigned char *px; /* w * h * 3 bytes, R G B, row-major, top row first */
} cf_image_t;

/* Allocate a w x h canvas filled with bg. CF_EARG for a size outside
 * 1..CF_PNG_MAX_DIM, CF_ENOMEM. */
int cf_image_init(cf_image_t *im, int w, int h, uint32_t bg, char *msg, size_t msglen);
void cf_image_free(cf_image_t *im);

/* Pixel set/get; set ignores coordinates outside the canvas, get returns 0. */
void cf_image_set(cf_image_t *im, int x, int y, uint32_t rgb);
uint32_t cf_image_get(const cf_image_t *im, int x, int y);

/* Filled rectangle and 1-pixel outline, clipped to the canvas. */
void cf_image_fill(cf_image_t *im, int x, int y, int w, int h, uint32_t rgb);
void cf_image_box(cf_image_t *im, int x, int y, int w, int h, uint32_t rgb);

/* Text in the 8x13 font: each glyph is 7 x 13 dots of scale x scale pixels
 * on an 8 x 13 cell (one column of spacing; row 0 blank, capitals and
 * digits on rows 1-9, descenders on rows 10-12), (x, y) the top-left
 * corner of the first cell. Printable ASCII and, as UTF-8, '±' and
 * 'µ'; anything else draws as '?'. '\n' is not interpreted. g and 9,
 * 0 and O, 1, l and I are drawn distinctly. Returns the width drawn, in
 * pixels. */
#define CF_FONT_W 8  /* advance per glyph at scale 1 */
#define CF_FONT_H 13 /* rows per glyph and line height at scale 1 */
int cf_image_text(cf_image_t *im, int x, int y, int scale, uint32_t rgb, const char *s);
int cf_text_width(const char *s, int scale); /* what cf_image_text would return */

/* Write rgb (w x h, layout as cf_image_t.px) to path as a PNG: first to
 * "path.tmp", flushed and synced, then renamed over path, so a failure never
 * leaves a partial file under either name. Memory: a 64 KB output buffer,
 * five filtered rows and zlib's deflate state (about 270 KB at level 9).
 * CF_EARG (size, NULL), CF_ENOMEM or CF_EIO; msg names the file. */
int cf_png_write(const char *path, const unsigned char *rgb, int w, int h, char *msg,
                 size_t msglen);
int cf_png_write_image(const char *path, const cf_image_t *im, char *msg, size_t msglen);

#endif
