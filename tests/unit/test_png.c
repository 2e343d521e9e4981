/* SPDX-License-Identifier: MIT */
/* test_png.c: the PNG writer, checked by a decoder written here (chunk walk,
 * bitwise CRC-32 without a table, zlib's inflate, the PNG filters undone)
 * and, when python3 is installed, by Python's zlib with its own unfiltering;
 * compression on flat and map-like images; the canvas and the font against
 * typed-in dot patterns. */

#include "cf_err.h"
#include "cf_png.h"
#include "cf_test.h"
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

static char tmpdir[512];
static char msg[1024];

static void make_tmpdir(void)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", d && *d ? d : "/tmp");
    for (char *p = tmpdir + 1; *p; p++) /* mkdir -p */
        if (*p == '/') {
            *p = '\0';
            mkdir(tmpdir, 0777);
            *p = '/';
        }
    mkdir(tmpdir, 0777);
}

static void tmp_path(char *buf, size_t n, const char *name)
{
    snprintf(buf, n, "%s/cf_png_%ld_%s", tmpdir, (long)getpid(), name);
}

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

static unsigned char *read_all(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)len + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* CRC-32 (ISO 3309, reflected 0xEDB88320) one bit at a time. */
static uint32_t crc_bits(uint32_t crc, const unsigned char *p, size_t n)
{
    crc = ~crc;
    for (size_t i = 0; i < n; i++) {
        crc ^= p[i];
        for (int k = 0; k < 8; k++)
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1)));
    }
    return ~crc;
}

/* Adler-32 by RFC 1950's definition, modulo after every byte. */
static uint32_t adler_def(const unsigned char *p, size_t n)
{
    uint32_t a = 1, b = 0;
    for (size_t i = 0; i < n; i++) {
        a = (a + p[i]) % 65521;
        b = (b + a) % 65521;
    }
    return b << 16 | a;
}

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* PNG spec 9.4: undo filter type ft on row r (len bytes, 3 per pixel)
 * given the previous reconstructed row (NULL for the first). */
static void unfilter(unsigned char *r, const unsigned char *prev, size_t len, int ft)
{
    for (size_t i = 0; i < len; i++) {
        int a = i >= 3 ? r[i - 3] : 0, b = prev ? prev[i] : 0, c = i >= 3 && prev ? prev[i - 3] : 0;
        int pred = 0;
        if (ft == 1)
            pred = a;
        else if (ft == 2)
            pred = b;
        else if (ft == 3)
            pred = (a + b) >> 1;
        else if (ft == 4) {
            int p = a + b - c, pa = p > a ? p - a : a - p, pb = p > b ? p - b : b - p;
            int pc = p > c ? p - c : c - p;
            pred = (pa <= pb && pa <= pc) ? a : (pb <= pc) ? b : c;
        }
        r[i] = (unsigned char)(r[i] + pred);
    }
}

/* Decode path (an RGB8 PNG) and compare with rgb: chunks and their CRCs
 * walked here, the zlib stream inflated by zlib's uncompress (which checks
 * the Adler-32), the filters undone here. Returns the compressed size. */
static size_t check_png(const char *path, const unsigned char *rgb, int w, int h)
{
    size_t n;
    unsigned char *f = read_all(path, &n);
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    assert_true(n >= 8 && !memcmp(f, sig, 8));
    size_t pos = 8, zlen = 0;
    unsigned char *z = malloc(n);
    assert_non_null(z);
    int nchunk = 0, seen_iend = 0, idat_done = 0;
    while (pos < n) {
        assert_true(pos + 12 <= n);
        uint32_t len = rd32(f + pos);
        assert_true(pos + 12 + len <= n);
        const unsigned char *type = f + pos + 4, *data = f + pos + 8;
        assert_int_equal(crc_bits(0, type, 4 + (size_t)len), rd32(data + len));
        if (nchunk == 0) { /* IHDR first */
            assert_memory_equal(type, "IHDR", 4);
            assert_int_equal(len, 13);
            assert_int_equal(rd32(data), (uint32_t)w);
            assert_int_equal(rd32(data + 4), (uint32_t)h);
            assert_int_equal(data[8], 8);
            assert_int_equal(data[9], 2);
            assert_int_equal(data[10], 0);
            assert_int_equal(data[11], 0);
            assert_int_equal(data[12], 0);
        } else if (!memcmp(type, "IDAT", 4)) {
            assert_false(idat_done); /* IDAT chunks are consecutive */
            assert_true(len > 0);
            memcpy(z + zlen, data, len);
            zlen += len;
        } else {
            if (zlen)
                idat_done = 1;
            if (!memcmp(type, "IEND", 4)) {
                assert_int_equal(len, 0);
                seen_iend = 1;
                pos += 12;
                break;
            }
        }
        nchunk++;
        pos += 12 + len;
    }
    assert_true(seen_iend);
    assert_int_equal(pos, n); /* nothing after IEND */
    assert_true(zlen >= 2 + 4);
    assert_int_equal(z[0] & 0x0F, 8);              /* deflate */
    assert_int_equal((z[0] * 256 + z[1]) % 31, 0); /* header check */
    assert_int_equal(z[1] & 0x20, 0);              /* no preset dictionary */
    size_t stride = 1 + 3 * (size_t)w, rawcap = (size_t)h * stride;
    uLongf rawlen = (uLongf)rawcap + 1; /* one spare byte: a longer stream would show */
    unsigned char *raw = malloc(rawcap + 1);
    assert_non_null(raw);
    assert_int_equal(uncompress(raw, &rawlen, z, (uLong)zlen), Z_OK);
    assert_int_equal(rawlen, rawcap);
    assert_int_equal(rd32(z + zlen - 4), adler_def(raw, rawcap)); /* by RFC 1950's definition */
    for (int y = 0; y < h; y++) {
        unsigned char *r = raw + (size_t)y * stride;
        assert_true(r[0] <= 4); /* filter types 0..4 */
        unfilter(r + 1, y ? r + 1 - stride : NULL, stride - 1, r[0]);
        assert_memory_equal(r + 1, rgb + (size_t)y * 3 * (size_t)w, 3 * (size_t)w);
    }
    free(raw);
    free(z);
    free(f);
    return n;
}

/* Python's zlib as a second, unrelated decoder: it checks every chunk CRC,
 * inflates the IDAT stream, undoes the filters and prints
 * "w h crc32(pixels)". */
static const char *py_check =
    "import sys, zlib, struct\n"
    "d = open(sys.argv[1], 'rb').read()\n"
    "assert d[:8] == b'\\x89PNG\\r\\n\\x1a\\n'\n"
    "p, z, w, h = 8, b'', 0, 0\n"
    "while p < len(d):\n"
    "    n, t = struct.unpack('>I4s', d[p:p + 8])\n"
    "    c = d[p + 4:p + 8 + n]\n"
    "    assert zlib.crc32(c) == struct.unpack('>I', d[p + 8 + n:p + 12 + n])[0], t\n"
    "    if t == b'IHDR': w, h = struct.unpack('>II', c[4:12])\n"
    "    if t == b'IDAT': z += c[4:]\n"
    "    p += 12 + n\n"
    "r = zlib.decompress(z)\n"
    "s = 3 * w + 1\n"
    "assert len(r) == h * s\n"
    "out, prev = bytearray(), bytearray(s - 1)\n"
    "for y in range(h):\n"
    "    ft, row = r[y * s], bytearray(r[y * s + 1:(y + 1) * s])\n"
    "    for i in range(s - 1):\n"
    "        a = row[i - 3] if i >= 3 else 0\n"
    "        b = prev[i]\n"
    "        c = prev[i - 3] if i >= 3 else 0\n"
    "        if ft == 0: q = 0\n"
    "        elif ft == 1: q = a\n"
    "        elif ft == 2: q = b\n"
    "        elif ft == 3: q = (a + b) // 2\n"
    "        elif ft == 4:\n"
    "            pp = a + b - c\n"
    "            pa, pb, pc = abs(pp - a), abs(pp - b), abs(pp - c)\n"
    "            q = a if pa <= pb and pa <= pc else (b if pb <= pc else c)\n"
    "        else: raise SystemExit('bad filter %d' % ft)\n"
    "        row[i] = (row[i] + q) & 255\n"
    "    out += row\n"
    "    prev = row\n"
    "print(w, h, zlib.crc32(bytes(out)))\n";

static const char *find_python(void)
{
    if (access("/usr/bin/python3", X_OK) == 0)
        return "/usr/bin/python3";
    if (system("python3 -c '' >/dev/null 2>&1") == 0)
        return "python3";
    return NULL;
}

static void python_check(const char *path, const unsigned char *rgb, int w, int h)
{
    const char *py = find_python();
    if (!py) {
        fprintf(stderr, "test_png: python3 not found: zlib cross-check NOT run (the C "
                        "decoder above still checked the file)\n");
        return;
    }
    char script[600], cmd[1400], line[256];
    tmp_path(script, sizeof script, "check.py");
    FILE *f = fopen(script, "w");
    assert_non_null(f);
    fputs(py_check, f);
    assert_int_equal(fclose(f), 0);
    snprintf(cmd, sizeof cmd, "%s '%s' '%s'", py, script, path);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    assert_non_null(fgets(line, sizeof line, p));
    assert_int_equal(pclose(p), 0);
    remove(script);
    unsigned long pw, ph, pc;
    assert_int_equal(sscanf(line, "%lu %lu %lu", &pw, &ph, &pc), 3);
    assert_int_equal(pw, (unsigned long)w);
    assert_int_equal(ph, (unsigned long)h);
    assert_int_equal(pc, (unsigned long)crc_bits(0, rgb, (size_t)w * (size_t)h * 3));
}

static unsigned char *pattern(int w, int h, unsigned seed)
{
    unsigned char *p = malloc((size_t)w * (size_t)h * 3);
    assert_non_null(p);
    unsigned s = seed;
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; i++) {
        s = s * 1103515245u + 12345u;
        p[i] = (unsigned char)(s >> 16);
    }
    return p;
}

static size_t write_and_check(int w, int h, const char *name)
{
    char path[600];
    tmp_path(path, sizeof path, name);
    unsigned char *rgb = pattern(w, h, (unsigned)(w * 7919 + h));
    assert_int_equal(cf_png_write(path, rgb, w, h, msg, sizeof msg), CF_OK);
    size_t bytes = check_png(path, rgb, w, h);
    python_check(path, rgb, w, h);
    char tmp[700];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(exists(tmp));
    free(rgb);
    remove(path);
    return bytes;
}

/* A map-like image: flat colour areas, a smooth ramp, text, lines. */
static void map_like(cf_image_t *im)
{
    for (int y = 0; y < im->h; y++)
        for (int x = 0; x < im->w; x++) {
            int band = (x / 97 + y / 61) % 5;
            static const uint32_t pal[5] = {0x28BE46, 0x0064FF, 0xFFB400, 0xD9D9D9, 0xDC1414};
            cf_image_set(im, x, y, x < im->w / 3 ? pal[band] : (uint32_t)((x * 255 / im->w) << 8));
        }
    for (int k = 0; k < 30; k++)
        cf_image_text(im, 10 + 7 * k, 10 + 25 * k, 1, 0x000000, "RMS 0.012 mm igs 90Ol1");
}

static void test_roundtrip(void **state)
{
    (void)state;
    size_t raw;
    assert_true(write_and_check(1, 1, "1x1.png") > 0);
    /* Random bytes do not compress: the file stays near the raw size
     * (180,200 bytes), i.e. nothing was dropped. */
    raw = 200 * (1 + 3 * 300);
    assert_true(write_and_check(300, 200, "300x200.png") >= raw);
    assert_true(write_and_check(28, 771, "28x771.png") > 0);
    /* Output longer than one 64 KB IDAT chunk, and rows longer than a chunk. */
    assert_true(write_and_check(6000, 12, "6000x12.png") > 65536);
    {
        char path[600];
        tmp_path(path, sizeof path, "white.png");
        unsigned char *rgb = malloc(16384 * 3 * 2);
        assert_non_null(rgb);
        memset(rgb, 0xFF, 16384 * 3 * 2);
        assert_int_equal(cf_png_write(path, rgb, 16384, 2, msg, sizeof msg), CF_OK);
        /* 98,306 raw bytes of one value: deflate takes them to a few hundred. */
        assert_true(check_png(path, rgb, 16384, 2) < 1000);
        python_check(path, rgb, 16384, 2);
        remove(path);
        free(rgb);
    }
    {
        /* A 1200 x 900 map-like canvas: 3.2 MB raw, far below 200 KB. */
        cf_image_t im;
        char path[600];
        assert_int_equal(cf_image_init(&im, 1200, 900, 0xFFFFFF, msg, sizeof msg), CF_OK);
        map_like(&im);
        tmp_path(path, sizeof path, "map.png");
        assert_int_equal(cf_png_write_image(path, &im, msg, sizeof msg), CF_OK);
        size_t bytes = check_png(path, im.px, im.w, im.h);
        assert_true(bytes < 200 * 1000);
        python_check(path, im.px, im.w, im.h);
        remove(path);
        cf_image_free(&im);
    }
}

/* Overwriting keeps the new content; failures leave no file under either name. */
static void test_failures(void **state)
{
    (void)state;
    unsigned char px[12] = {0};
    char path[600], tmp[700];
    assert_int_equal(cf_png_write("/nonexistent-dir-cf/x.png", px, 2, 2, msg, sizeof msg), CF_EIO);
    assert_non_null(strstr(msg, "/nonexistent-dir-cf/x.png.tmp"));
    assert_false(exists("/nonexistent-dir-cf/x.png"));
    assert_int_equal(cf_png_write("x.png", px, 0, 2, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_png_write("x.png", px, 2, CF_PNG_MAX_DIM + 1, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_png_write("x.png", NULL, 2, 2, msg, sizeof msg), CF_EARG);
    /* The target is a directory: the rename fails and the .tmp is removed. */
    tmp_path(path, sizeof path, "dir.png");
    assert_int_equal(mkdir(path, 0777), 0);
    assert_int_equal(cf_png_write(path, px, 2, 2, msg, sizeof msg), CF_EIO);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(exists(tmp));
    assert_int_equal(rmdir(path), 0);
    /* Overwrite an existing file. */
    tmp_path(path, sizeof path, "over.png");
    unsigned char *a = pattern(40, 30, 1), *b = pattern(40, 30, 2);
    assert_int_equal(cf_png_write(path, a, 40, 30, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_png_write(path, b, 40, 30, msg, sizeof msg), CF_OK);
    check_png(path, b, 40, 30);
    remove(path);
    free(a);
    free(b);
}

/* Dots of a glyph drawn at scale 1 at (x0, 0), one 8-character row string
 * per row of the 8 x 13 cell (the 8th column is spacing). */
static void expect_glyph(const cf_image_t *im, int x0, const char *const rows[13])
{
    for (int r = 0; r < 13; r++)
        for (int c = 0; c < 8; c++) {
            int on = cf_image_get(im, x0 + c, r) == 0x000000;
            if (on != (rows[r][c] == '#'))
                fail_msg("glyph at x %d: dot (%d, %d) is %s", x0, c, r, on ? "set" : "clear");
        }
}

/* Pixels in which two glyphs differ, drawn at scale 1. */
static int glyph_diff(const char *a, const char *b)
{
    cf_image_t im;
    assert_int_equal(cf_image_init(&im, 16, 13, 0xFFFFFF, msg, sizeof msg), CF_OK);
    cf_image_text(&im, 0, 0, 1, 0x000000, a);
    cf_image_text(&im, 8, 0, 1, 0x000000, b);
    int n = 0;
    for (int y = 0; y < 13; y++)
        for (int x = 0; x < 8; x++) {
            n += cf_image_get(&im, x, y) != cf_image_get(&im, x + 8, y);
        }
    cf_image_free(&im);
    return n;
}

static void test_font(void **state)
{
    (void)state;
    cf_image_t im;
    assert_int_equal(cf_image_init(&im, 80, 30, 0xFFFFFF, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_image_text(&im, 0, 0, 1, 0x000000, "0g9l\xC2\xB1"), 5 * CF_FONT_W);
    static const char *const zero[13] = {"........", "..###...", ".#...#..", ".#...#..", ".#..##..",
                                         ".#.#.#..", ".##..#..", ".#...#..", ".#...#..", "..###...",
                                         "........", "........", "........"};
    static const char *const g[13] = {"........", "........", "........", "........", "..####..",
                                      ".#...#..", ".#...#..", ".#...#..", ".#...#..", "..####..",
                                      ".....#..", ".#...#..", "..###..."};
    static const char *const nine[13] = {"........", "..###...", ".#...#..", ".#...#..", ".#...#..",
                                         "..####..", ".....#..", ".....#..", "....#...", ".###....",
                                         "........", "........", "........"};
    static const char *const l[13] = {"........", "..##....", "...#....", "...#....", "...#....",
                                      "...#....", "...#....", "...#....", "...#....", "....##..",
                                      "........", "........", "........"};
    static const char *const pm[13] = {"........", "........", "...#....", "...#....", ".#####..",
                                       "...#....", "...#....", "........", ".#####..", "........",
                                       "........", "........", "........"};
    expect_glyph(&im, 0, zero);
    expect_glyph(&im, 8, g);
    expect_glyph(&im, 16, nine);
    expect_glyph(&im, 24, l);
    expect_glyph(&im, 32, pm);
    /* The pairs the 5x7 font confused ("igs" read "i9s") differ clearly. */
    assert_true(glyph_diff("g", "9") >= 8);
    assert_true(glyph_diff("0", "O") >= 8);
    assert_true(glyph_diff("1", "l") >= 6);
    assert_true(glyph_diff("1", "I") >= 6);
    assert_true(glyph_diff("l", "I") >= 6);
    assert_true(glyph_diff("5", "S") >= 4);
    assert_true(glyph_diff("8", "B") >= 4);
    /* Every printable glyph differs from every other one. */
    for (int a = 33; a < 127; a++)
        for (int b = a + 1; b < 127; b++) {
            char sa[2] = {(char)a, 0}, sb[2] = {(char)b, 0};
            if (glyph_diff(sa, sb) < 2)
                fail_msg("'%c' and '%c' differ in fewer than 2 dots", a, b);
        }
    /* Scale 2: each dot 2 x 2; '1' has its stem in column 3, rows 1-9. */
    cf_image_fill(&im, 0, 0, 80, 30, 0xFFFFFF);
    assert_int_equal(cf_image_text(&im, 10, 2, 2, 0xFF0000, "1"), 2 * CF_FONT_W);
    for (int r = 1; r <= 9; r++)
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++)
                assert_int_equal(cf_image_get(&im, 10 + 6 + dx, 2 + 2 * r + dy), 0xFF0000);
    assert_int_equal(cf_image_get(&im, 10 + 6, 2), 0xFFFFFF); /* row 0 blank */
    /* Widths: one glyph per code point, unknown ones as '?'. */
    assert_int_equal(cf_text_width("RMS 0.012 mm", 1), 12 * CF_FONT_W);
    assert_int_equal(cf_text_width("\xC2\xB1\xC2\xB5m", 2), 3 * 2 * CF_FONT_W);
    assert_int_equal(cf_text_width("\xE2\x82\xAC", 1), CF_FONT_W); /* euro sign: '?' */
    /* Drawing clips at the canvas edges. */
    cf_image_fill(&im, 0, 0, 80, 30, 0xFFFFFF);
    cf_image_text(&im, 75, 25, 3, 0x0000FF, "W");
    cf_image_text(&im, -20, -5, 3, 0x0000FF, "W");
    cf_image_box(&im, -1, -1, 82, 32, 0x00FF00);
    assert_int_equal(cf_image_get(&im, 75, 28), 0x0000FF); /* W's first dot: row 1, column 0 */
    assert_int_equal(cf_image_get(&im, 79, 29), 0xFFFFFF);
    cf_image_free(&im);
    assert_int_equal(cf_image_init(&im, 0, 10, 0, msg, sizeof msg), CF_EARG);
    assert_null(im.px);
}

/* A canvas written with cf_png_write_image decodes to the same pixels. */
static void test_canvas_png(void **state)
{
    (void)state;
    cf_image_t im;
    char path[600];
    assert_int_equal(cf_image_init(&im, 120, 40, 0xF0F0F0, msg, sizeof msg), CF_OK);
    cf_image_fill(&im, 5, 5, 30, 30, 0x2080FF);
    cf_image_box(&im, 4, 4, 32, 32, 0x000000);
    cf_image_text(&im, 40, 12, 2, 0x202020, "0.05mm");
    tmp_path(path, sizeof path, "canvas.png");
    assert_int_equal(cf_png_write_image(path, &im, msg, sizeof msg), CF_OK);
    check_png(path, im.px, im.w, im.h);
    python_check(path, im.px, im.w, im.h);
    remove(path);
    cf_image_free(&im);
}

int main(void)
{
    make_tmpdir();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_roundtrip),
        cmocka_unit_test(test_failures),
        cmocka_unit_test(test_font),
        cmocka_unit_test(test_canvas_png),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
