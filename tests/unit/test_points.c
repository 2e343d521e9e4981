/* SPDX-License-Identifier: MIT */
/* test_points.c: the streaming point reader. Expected values are typed in,
 * or are doubles the test printed with %.17g itself (C guarantees strtod
 * gives them back), or strtod's own result for the same token. Also prints
 * the parse rate for 10^6 generated `u v x y z` lines (no time assertion);
 * `test_points --bench [LINES]` runs only that. */

#include "cf_err.h"
#include "cf_points.h"
#include "cf_test.h"
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

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
    snprintf(buf, n, "%s/cf_points_%ld_%s", tmpdir, (long)getpid(), name);
}

static void write_bytes(const char *path, const void *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static void write_text(const char *path, const char *text)
{
    write_bytes(path, text, strlen(text));
}

static unsigned long long rng = 0x2545F4914F6CDD1DULL;

static unsigned long long next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static double urand(void)
{
    return (double)(next_u64() >> 11) / 9007199254740992.0;
}

static void assert_same(double got, double want, long where)
{
    if (memcmp(&got, &want, sizeof got))
        fail_msg("value %ld: got %.17g (%a), want %.17g (%a)", where, got, got, want, want);
}

static void assert_msg(const char *what)
{
    if (!strstr(msg, what))
        fail_msg("message '%s' lacks '%s'", msg, what);
}

/* Open text with want columns, read everything (up to max points). */
static long read_all(const char *path, int want, double *out, long max)
{
    cf_points_t *r;
    assert_int_equal(cf_points_open(&r, path, want, msg, sizeof msg), CF_OK);
    long n = cf_points_read(r, out, max, msg, sizeof msg);
    cf_points_close(r);
    return n;
}

static void test_three_columns(void **state)
{
    (void)state;
    char path[600];
    tmp_path(path, sizeof path, "p3.txt");
    write_text(path, "# x y z from the CMM\n"
                     "1 2 3\n"
                     "\n"
                     "  4.5,5.5 , 6.5   # trailing comment\n"
                     "\t-1e-3\t+.5\t1.5E+2\n"
                     "   # indented comment\n"
                     "1.7976931348623157e308,-0,5.\n"
                     "7 8 9"); /* no final newline */
    double v[32];
    static const double want[15] = {1,     2,       3,    4.5, 5.5, 6.5, -1e-3, 0.5,
                                    150.0, DBL_MAX, -0.0, 5.0, 7,   8,   9};
    assert_int_equal(read_all(path, 3, v, 10), 5);
    for (int i = 0; i < 15; i++)
        assert_same(v[i], want[i], i);
    remove(path);
}

static void test_five_columns_crlf(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[20];
    tmp_path(path, sizeof path, "p5.txt");
    write_text(path, "#u v x y z\r\n\r\n0.25 0.5 10 20 30\r\n  \r\n0.75,1,11,21,31 # c\r\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_cols(r), 5); /* known before the first read */
    assert_int_equal(cf_points_read(r, v, 1, msg, sizeof msg), 1);
    assert_int_equal(cf_points_line(r), 3);
    assert_int_equal(cf_points_read(r, v + 5, 4, msg, sizeof msg), 1);
    assert_int_equal(cf_points_line(r), 5);
    assert_int_equal(cf_points_read(r, v, 4, msg, sizeof msg), 0);
    static const double want[10] = {0.25, 0.5, 10, 20, 30, 0.75, 1, 11, 21, 31};
    for (int i = 0; i < 10; i++)
        assert_same(v[i], want[i], i);
    cf_points_close(r);
    /* want 3 on a 5-column file: the first data line is wrong. */
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 4, msg, sizeof msg), CF_EPARSE);
    assert_msg(":3: 5 values, expected 3");
    cf_points_close(r);
    /* u v pairs (what `cellfit eval` reads). */
    write_text(path, "0 0\n0.5 1\n");
    assert_int_equal(read_all(path, 2, v, 4), 2);
    assert_true(v[2] == 0.5 && v[3] == 1);
    remove(path);
}

static void test_first_line_decides(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[8];
    tmp_path(path, sizeof path, "auto.txt");
    write_text(path, "# c\n1 2 3\n4 5 6 7 8\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_cols(r), 3);
    assert_int_equal(cf_points_read(r, v, 2, msg, sizeof msg), CF_EPARSE);
    assert_msg(path);
    assert_msg(":3: 5 values, expected 3");
    /* Errors stay. */
    assert_int_equal(cf_points_read(r, v, 2, msg, sizeof msg), CF_EPARSE);
    assert_msg(":3:");
    cf_points_close(r);
    write_text(path, "\n\n1 2 3 4\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_EPARSE);
    assert_null(r);
    assert_msg(":3: 4 values");
    remove(path);
}

/* CSV with a header line: columns chosen by name, in any order, others
 * ignored; the header is skipped on rewind; missing names refused. */
static void test_csv_header(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[16];
    tmp_path(path, sizeof path, "h.csv");
    write_text(path, "# exported\n\"id\", Z ,x;y,intensity\r\n7,3.5,1,2,90\n8,4.5,1.5,2.5,91\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_cols(r), 3);
    assert_int_equal(cf_points_read(r, v, 8, msg, sizeof msg), 2);
    assert_int_equal(cf_points_line(r), 4);
    static const double want[6] = {1, 2, 3.5, 1.5, 2.5, 4.5};
    for (int i = 0; i < 6; i++)
        assert_same(v[i], want[i], i);
    assert_int_equal(cf_points_rewind(r), CF_OK);
    assert_int_equal(cf_points_read(r, v, 8, msg, sizeof msg), 2);
    assert_same(v[0], 1, 0);
    assert_int_equal(cf_points_line(r), 4);
    cf_points_close(r);
    /* u v x y z in another order: 5 columns, reordered. */
    write_text(path, "z,y,x,v,u\n30,20,10,0.5,0.25\n");
    assert_int_equal(read_all(path, 0, v, 4), 1);
    static const double want5[5] = {0.25, 0.5, 10, 20, 30};
    for (int i = 0; i < 5; i++)
        assert_same(v[i], want5[i], i);
    /* Asked for u v only (eval), from the same file. */
    assert_int_equal(read_all(path, 2, v, 4), 1);
    assert_same(v[0], 0.25, 0);
    assert_same(v[1], 0.5, 1);
    /* A row with the wrong count names its line and the header's count. */
    write_text(path, "x,y,z\n1,2,3\n1,2\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 4, msg, sizeof msg), CF_EPARSE);
    assert_msg(":3: 2 values, the header names 3");
    cf_points_close(r);
    /* Missing and repeated names. */
    write_text(path, "x,y,height\n1,2,3\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_EPARSE);
    assert_msg(":1: the header names no 'z' column");
    write_text(path, "x,y,z,x\n1,2,3,4\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_EPARSE);
    assert_msg("names column 'x' twice");
    /* Words naming no coordinate: junk, not a header. */
    write_text(path, "hello world\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 4, msg, sizeof msg), CF_EPARSE);
    assert_msg(":1: 'hello' is not a number");
    cf_points_close(r);
    /* Numbers among words: a bad data line, not a header. */
    write_text(path, "information 2 3\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 4, msg, sizeof msg), CF_EPARSE);
    assert_msg("'information' is not a number");
    cf_points_close(r);
    remove(path);
}

static void test_empty_files(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[5];
    tmp_path(path, sizeof path, "empty.txt");
    static const char *texts[] = {"", "\n\n", "# only a comment\n\r\n   \n"};
    for (int i = 0; i < 3; i++) {
        write_text(path, texts[i]);
        for (int want = 0; want <= 5; want += 5) {
            assert_int_equal(cf_points_open(&r, path, want, msg, sizeof msg), CF_OK);
            assert_int_equal(cf_points_cols(r), want);
            assert_int_equal(cf_points_read(r, v, 1, msg, sizeof msg), 0);
            assert_int_equal(cf_points_read(r, v, 1, msg, sizeof msg), 0);
            cf_points_close(r);
        }
    }
    remove(path);
}

/* A file over the 1 MiB buffer with comments between points, read in batches
 * of 7 so that batches and lines straddle refills. */
static void test_batches_across_buffer(void **state)
{
    (void)state;
    char path[600];
    const long n = 40000;
    double *x = malloc(sizeof(double) * 5 * (size_t)n);
    long *line = malloc(sizeof(long) * (size_t)n);
    assert_non_null(x);
    assert_non_null(line);
    tmp_path(path, sizeof path, "big.txt");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    long ln = 0;
    for (long i = 0; i < n; i++) {
        if (i % 13 == 0) {
            fprintf(f, "# block %ld\n", i);
            ln++;
        }
        for (int c = 0; c < 5; c++) {
            double t = (urand() - 0.5) * pow(10.0, (double)(int)(urand() * 12) - 4);
            x[5 * i + c] = t;
            fprintf(f, c ? (i % 2 ? ", %.17g" : " %.17g") : "%.17g", t);
        }
        fputs(i % 3 ? "\n" : "\r\n", f);
        line[i] = ++ln;
    }
    assert_int_equal(fclose(f), 0);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_true(st.st_size > 3 * (1L << 20));

    cf_points_t *r;
    double v[5 * 7];
    assert_int_equal(cf_points_open(&r, path, 5, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), -1); /* not read whole at open */
    for (int pass = 0; pass < 2; pass++) {
        long k = 0, got;
        while ((got = cf_points_read(r, v, 7, msg, sizeof msg)) > 0) {
            for (long j = 0; j < 5 * got; j++)
                assert_same(v[j], x[5 * k + j], 5 * k + j);
            k += got;
            assert_int_equal(cf_points_line(r), line[k - 1]);
        }
        assert_int_equal(got, 0);
        assert_int_equal(k, n);
        assert_int_equal(cf_points_rewind(r), CF_OK); /* second pass: the same again */
    }
    cf_points_close(r);
    free(x);
    free(line);
    remove(path);
}

/* A random decimal string in one of many forms. */
static void rand_token(char *b, size_t n)
{
    int mode = (int)(next_u64() % 11);
    double x;
    unsigned long long u = next_u64();
    switch (mode) {
    case 0: /* any finite double, full precision */
        memcpy(&x, &u, sizeof x);
        if (!isfinite(x))
            x = 1.0 / 3.0;
        snprintf(b, n, "%.17g", x);
        break;
    case 1: snprintf(b, n, "%.17g", (urand() - 0.5) * 1000.0); break;
    case 2:
        snprintf(b, n, "%.*g", 1 + (int)(next_u64() % 17), urand() * pow(10, (int)(u % 40) - 20));
        break;
    case 3: snprintf(b, n, "%.4f", (urand() - 0.5) * 2e4); break;
    case 4: snprintf(b, n, "%.6e", urand() * 1e-300); break;
    case 5: { /* digit strings of 1..25 digits, point anywhere, exponent */
        int nd = 1 + (int)(next_u64() % 25), dot = (int)(next_u64() % (unsigned)(nd + 1)), k = 0;
        if (u & 1)
            b[k++] = (u & 2) ? '-' : '+';
        for (int i = 0; i < nd; i++) {
            if (i == dot)
                b[k++] = '.';
            b[k++] = (char)('0' + next_u64() % 10);
        }
        if (u & 4)
            k += snprintf(b + k, n - (size_t)k, "%c%d", (u & 8) ? 'e' : 'E',
                          (int)(next_u64() % 70) - 35);
        b[k] = '\0';
        break;
    }
    case 7: { /* an integer exactly halfway between two doubles (2^53 .. 2^63) */
        int k = 1 + (int)(next_u64() % 10);
        unsigned long long mant = (1ULL << 52) | (next_u64() >> 12);
        snprintf(b, n, "%llu%s", (mant << k) + (1ULL << (k - 1)),
                 (u & 1)   ? ""
                 : (u & 2) ? ".000"
                           : "0e-1");
        break;
    }
    case 8: { /* the exact decimal of a halfway point, or one unit off in its last digit */
        double y = urand() * pow(10, (int)(u % 12) - 6);
        long double mid = ((long double)y + (long double)nextafter(y, 2 * y + 1)) / 2;
        int len = snprintf(b, n, "%.100Le", mid), e = len;
        while (e > 0 && b[e - 1] != 'e')
            e--;
        int last = e - 2; /* the last mantissa digit before "e" */
        while (last > 0 && b[last] == '0')
            last--;
        if ((u & 6) == 2 && b[last] > '0' && b[last] <= '9')
            b[last]--;
        else if ((u & 6) == 4 && last + 1 < e - 1)
            b[last + 1] = '1';
        break;
    }
    case 9: { /* the edges: subnormals, DBL_MIN, DBL_MAX and their neighbours */
        static const double edge[] = {DBL_MIN,
                                      DBL_MAX,
                                      4.9406564584124654e-324,
                                      2.2250738585072009e-308,
                                      1e-320,
                                      1.7976931348623157e308};
        double x0 = edge[u % 6];
        for (int i = (int)(next_u64() % 4); i > 0; i--)
            x0 = nextafter(x0, (u & 64) ? 0.0 : HUGE_VAL);
        if (!isfinite(x0))
            x0 = DBL_MAX;
        if (u & 128) { /* a random subnormal */
            unsigned long long bits = next_u64() >> 12;
            memcpy(&x0, &bits, sizeof x0);
        }
        if (u & 256)
            snprintf(b, n, "%.17g", x0);
        else
            snprintf(b, n, "%.*e", (u & 512) ? 16 : 25, x0);
        break;
    }
    case 10: { /* 19 to 40 significant digits, exponents over the whole range */
        int nd = 19 + (int)(next_u64() % 22), k = 0;
        if (u & 1)
            b[k++] = '-';
        b[k++] = (char)('1' + next_u64() % 9);
        b[k++] = '.';
        for (int i = 1; i < nd; i++)
            b[k++] = (char)('0' + next_u64() % 10);
        snprintf(b + k, n - (size_t)k, "e%d", (int)(next_u64() % 600) - 300);
        break;
    }
    default: { /* halfway between two doubles, 19-21 digits */
        double y = urand() * pow(10, (int)(u % 30) - 15);
        long double mid = ((long double)y + (long double)nextafter(y, 2 * y + 1)) / 2;
        snprintf(b, n, "%.*Le", 18 + (int)(next_u64() % 3), mid);
        break;
    }
    }
}

static void test_bit_identical_to_strtod(void **state)
{
    (void)state;
    char path[600];
    const long n = 300000; /* values, 3 per line */
    char(*tok)[128] = malloc(sizeof *tok * (size_t)n);
    assert_non_null(tok);
    tmp_path(path, sizeof path, "strtod.txt");
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (long i = 0; i < n; i++) {
        rand_token(tok[i], sizeof tok[i]);
        fprintf(f, "%s%s", tok[i], i % 3 == 2 ? "\n" : " ");
    }
    assert_int_equal(fclose(f), 0);
    cf_points_t *r;
    double v[3 * 1000];
    long k = 0, got;
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    while ((got = cf_points_read(r, v, 1000, msg, sizeof msg)) > 0) {
        for (long j = 0; j < 3 * got; j++, k++) {
            double want = strtod(tok[k], NULL);
            if (memcmp(&v[j], &want, sizeof want))
                fail_msg("'%s': got %a, strtod %a", tok[k], v[j], want);
        }
    }
    assert_int_equal(got, 0);
    assert_int_equal(k, n);
    cf_points_close(r);
    free(tok);
    remove(path);
}

/* Raw little-endian float64 (.xyz.bin, .uvxyz.bin): every value back bit for
 * bit (any finite pattern, across the 1 MB buffer, odd batch sizes), rewind,
 * and the refusals: a partial last point, a non-finite value, a column count
 * the extension does not give. */
static double rand_finite(void)
{
    for (;;) {
        unsigned long long u = next_u64();
        double x;
        memcpy(&x, &u, sizeof x);
        if (isfinite(x))
            return x;
    }
}

static void le_bytes(unsigned char *b, double x)
{
    unsigned long long u;
    memcpy(&u, &x, sizeof u);
    for (int i = 0; i < 8; i++)
        b[i] = (unsigned char)(u >> (8 * i));
}

/* cf_points_bound against counts the test knows: a small text file read
 * whole at open bounds its points by its lines (comments, blank lines, a
 * header and a last line without a newline among them), a raw file by its
 * size exactly, a text file past the buffer (test_batches_across_buffer)
 * and a binary PLY (test_ply_binary) not at all; PLY ascii by its lines
 * (test_ply_ascii).
 * The small file's buffer (its size and a page) still streams a file that
 * grew after open past that size, lines crossing its refills. */
static void test_bound_small_files(void **state)
{
    (void)state;
    char path[600];
    tmp_path(path, sizeof path, "bound.txt");
    write_text(path, "# heights\nx,y,z\n1,2,3\n\n4,5,6\n# mid\n7,8,9");
    cf_points_t *r;
    double v[3 * 16];
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    const long b = cf_points_bound(r);
    assert_int_equal(cf_points_read(r, v, 16, msg, sizeof msg), 3);
    assert_true(b >= 3);
    assert_int_equal(b, 7); /* its lines */
    assert_same(v[6], 7.0, 6);
    cf_points_close(r);
    /* raw: the size says the count */
    tmp_path(path, sizeof path, "bound.xyz.bin");
    unsigned char rb[8 * 3 * 5];
    for (int i = 0; i < 15; i++)
        le_bytes(rb + 8 * i, (double)i);
    write_bytes(path, rb, sizeof rb);
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), 5);
    assert_int_equal(cf_points_read(r, v, 16, msg, sizeof msg), 5);
    cf_points_close(r);
    /* A small file grown after open: every point, in order. */
    tmp_path(path, sizeof path, "grow.txt");
    write_text(path, "0 0 0\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), 2);
    const long n = 30000; /* about 0.6 MB: 70 times the 6-byte file's buffer (8 KiB) */
    FILE *f = fopen(path, "ab");
    assert_non_null(f);
    for (long i = 1; i < n; i++)
        fprintf(f, "%ld %ld.5 %ld\n", i, i, -i);
    assert_int_equal(fclose(f), 0);
    long k = 0, got;
    while ((got = cf_points_read(r, v, 16, msg, sizeof msg)) > 0)
        for (long j = 0; j < got; j++, k++) {
            assert_same(v[3 * j], (double)k, 3 * k);
            assert_same(v[3 * j + 1], k ? (double)k + 0.5 : 0.0, 3 * k + 1);
        }
    assert_int_equal(got, 0);
    assert_int_equal(k, n);
    cf_points_close(r);
    /* Opened again, the grown file is read whole at open: its lines. */
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), n + 1);
    cf_points_close(r);
    remove(path);
    tmp_path(path, sizeof path, "bound.txt");
    remove(path);
    tmp_path(path, sizeof path, "bound.xyz.bin");
    remove(path);
}

static void check_raw(const char *name, int cols, long n)
{
    char path[600];
    tmp_path(path, sizeof path, name);
    double *want = malloc(sizeof(double) * (size_t)(cols * n + 1));
    unsigned char *b = malloc(8 * (size_t)(cols * n) + 8);
    double *got = malloc(sizeof(double) * (size_t)(cols * n + 1));
    assert_true(want && b && got);
    for (long i = 0; i < cols * n; i++) {
        want[i] = rand_finite();
        le_bytes(b + 8 * i, want[i]);
    }
    write_bytes(path, b, 8 * (size_t)(cols * n));
    cf_points_t *r;
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_cols(r), cols);
    for (int pass = 0; pass < 2; pass++) {
        long k = 0, m;
        while ((m = cf_points_read(r, got + cols * k, 1 + k % 997 + (k % 3) * 40000, msg,
                                   sizeof msg)) > 0) {
            k += m;
            assert_int_equal(cf_points_line(r), k);
        }
        assert_int_equal(m, 0);
        assert_int_equal(k, n);
        for (long i = 0; i < cols * n; i++)
            assert_same(got[i], want[i], i);
        assert_int_equal(cf_points_rewind(r), CF_OK);
    }
    cf_points_close(r);
    if (n < 3) { /* the refusals below need three points */
        remove(path);
        free(want), free(b), free(got);
        return;
    }
    /* Wrong column count asked. */
    assert_int_equal(cf_points_open(&r, path, cols == 5 ? 3 : 5, msg, sizeof msg), CF_EPARSE);
    assert_msg("values per point");
    /* A partial last point: the whole points before it, then the error. */
    write_bytes(path, b, 8 * (size_t)(cols * 2 + 1));
    assert_int_equal(cf_points_open(&r, path, cols, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, got, 10, msg, sizeof msg), 2);
    assert_int_equal(cf_points_read(r, got, 10, msg, sizeof msg), CF_EPARSE);
    assert_msg("ends inside point 3");
    cf_points_close(r);
    /* A NaN in point 2. */
    le_bytes(b + 8 * (size_t)(cols + 1), NAN);
    write_bytes(path, b, 8 * (size_t)(cols * 3));
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, got, 10, msg, sizeof msg), CF_EPARSE);
    assert_msg("point 2: non-finite");
    cf_points_close(r);
    remove(path);
    free(want), free(b), free(got);
}

/* Non-finite values the large reads (straight into the caller's rows, the
 * branch-free check) refuse, with the point named: inf, -inf, quiet and
 * signalling NaN, at a block's start, inside it, and in the tail; finite
 * extremes (DBL_MAX, the smallest subnormal, -0) pass. */
static void test_raw_nonfinite_direct(void **state)
{
    (void)state;
    enum { N = 3001, C = 5 };
    char path[600];
    tmp_path(path, sizeof path, "nf.uvxyz.bin");
    static unsigned char b[8 * N * C];
    static double got[N * C];
    const unsigned long long bad[] = {0x7ff0000000000000ULL, 0xfff0000000000000ULL,
                                      0x7ff8000000000000ULL, 0x7ff0000000000001ULL,
                                      0xffffffffffffffffULL};
    const long at[] = {0, 1, 3, 4, 5 * 1000 + 2, N * C - 1};
    for (size_t a = 0; a < sizeof at / sizeof at[0]; a++)
        for (size_t v = 0; v < sizeof bad / sizeof bad[0]; v++) {
            for (long i = 0; i < N * C; i++)
                le_bytes(b + 8 * i, i % 3 == 0 ? DBL_MAX : i % 3 == 1 ? 4.9e-324 : -0.0);
            double x;
            memcpy(&x, &bad[v], sizeof x);
            le_bytes(b + 8 * at[a], x);
            write_bytes(path, b, sizeof b);
            cf_points_t *r;
            assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
            assert_int_equal(cf_points_read(r, got, N, msg, sizeof msg), CF_EPARSE);
            char want[64];
            snprintf(want, sizeof want, "point %ld: non-finite", at[a] / C + 1);
            assert_msg(want);
            cf_points_close(r);
        }
    for (long i = 0; i < N * C; i++)
        le_bytes(b + 8 * i, i % 3 == 0 ? -DBL_MAX : i % 3 == 1 ? -4.9e-324 : 0.0);
    write_bytes(path, b, sizeof b);
    cf_points_t *r;
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, got, N, msg, sizeof msg), N);
    assert_int_equal(cf_points_read(r, got, N, msg, sizeof msg), 0);
    cf_points_close(r);
    remove(path);
}

static void test_raw_float64(void **state)
{
    (void)state;
    check_raw("p.xyz.bin", 3, 70000);   /* 1.68 MB: crosses the buffer */
    check_raw("p.uvxyz.bin", 5, 30011); /* 1.2 MB, a prime count */
    check_raw("e.xyz.bin", 3, 0);       /* empty: no points */
}

static void test_rewind(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[9], w[9];
    tmp_path(path, sizeof path, "rw.txt");
    write_text(path, "1 2 3\n# c\n4 5 6\n7 8 9\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 2, msg, sizeof msg), 2);
    assert_int_equal(cf_points_line(r), 3);
    assert_int_equal(cf_points_rewind(r), CF_OK);
    assert_int_equal(cf_points_read(r, w, 3, msg, sizeof msg), 3);
    assert_int_equal(cf_points_line(r), 4);
    assert_memory_equal(v, w, sizeof(double) * 6);
    assert_true(w[8] == 9.0);
    cf_points_close(r);
    remove(path);
}

static void test_stdin_not_rewindable(void **state)
{
    (void)state;
    char path[600];
    cf_points_t *r;
    double v[6];
    tmp_path(path, sizeof path, "stdin.txt");
    write_text(path, "0.5 1.5 2.5 3.5 4.5\n");
    assert_non_null(freopen(path, "rb", stdin));
    assert_int_equal(cf_points_open(&r, "-", 5, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 2, msg, sizeof msg), 1);
    assert_true(v[0] == 0.5 && v[4] == 4.5);
    assert_int_equal(cf_points_rewind(r), CF_EUNSUPPORTED);
    cf_points_close(r);
    remove(path);
}

/* text must fail on line `line` with code and a message containing what. */
static void expect_error(const char *text, size_t len, int want, int line, const char *what)
{
    char path[600], where[700];
    cf_points_t *r;
    double v[3 * 16];
    tmp_path(path, sizeof path, "bad.txt");
    write_bytes(path, text, len);
    int rc = cf_points_open(&r, path, want, msg, sizeof msg);
    if (rc == CF_OK) {
        long got;
        while ((got = cf_points_read(r, v, 16, msg, sizeof msg)) > 0)
            ;
        rc = (int)got;
        cf_points_close(r);
    }
    if (rc != CF_EPARSE)
        fail_msg("'%.40s': got %d, want CF_EPARSE (%s)", text, rc, msg);
    snprintf(where, sizeof where, "%s:%d: ", path, line);
    assert_msg(where);
    assert_msg(what);
    remove(path);
}

#define EXPECT(text, want, line, what) expect_error(text, sizeof text - 1, want, line, what)

static void test_errors_name_the_line(void **state)
{
    (void)state;
    EXPECT("1 2 3\n4 5 6\n1 2 3 4\n", 3, 3, "4 values, expected 3");
    EXPECT("1 2 3\n4 5\n", 3, 2, "2 values, expected 3");
    EXPECT("1 2 3\n\nx 2 3\n", 3, 3, "'x' is not a number");
    EXPECT("1 2 3\n1 2 3abc\n", 3, 2, "'3abc' is not a number");
    EXPECT("1 2 3\n1 0x10 3\n", 3, 2, "'0x10'");
    EXPECT("1 2 3\n1.5.5 2 3\n", 3, 2, "'1.5.5'");
    EXPECT("1 2 3\n1 2 1e\n", 3, 2, "'1e'");
    EXPECT("1 2 3\n- 2 3\n", 3, 2, "'-'");
    EXPECT("1 2 3\n1 nan 3\n", 3, 2, "non-finite coordinate 'nan'");
    EXPECT("1 2 3\n# c\n1 2 -inf\n", 3, 3, "non-finite coordinate '-inf'");
    EXPECT("1 2 Infinity\n", 0, 1, "non-finite");
    EXPECT("information 2 3\n", 3, 1, "'information' is not a number");
    EXPECT("1 2 nan3\n", 3, 1, "'nan3' is not a number");
    EXPECT("1 2 3\n1 2 NaN(0x1)\n", 3, 2, "non-finite");
    EXPECT("1 2 3\n1 2 3\n1 1e999 3\n", 3, 3, "'1e999' out of double range");
    EXPECT("1 2 3\n-1.8e308 0 0\n", 3, 2, "out of double range");
    EXPECT("1 2 3\n1,,2,3\n", 3, 2, "empty field");
    EXPECT("1 2 3\n1,2,3,\n", 3, 2, "empty field");
    EXPECT("1 2 3\n,1,2,3\n", 3, 2, "empty field");
    EXPECT("1 2 3\n4 5 6\n7 8 9\n1 \0 3\n", 3, 4, "NUL byte");
    EXPECT("1 2 3\n4 5 6 # \0\n", 3, 2, "NUL byte");
    EXPECT("1 2 3\n\x01\x02\x03\n", 3, 2, "binary data");
    EXPECT("\x7f"
           "ELF\x02\x01\x01",
           0, 1, "binary data");
    EXPECT("1 2 3\n1 2 \xc3\xa9\n", 3, 2, "byte 0xc3");
    /* Overlong line on line 2: refused, not grown into. */
    char *longl = malloc(10000);
    assert_non_null(longl);
    strcpy(longl, "1 2 3\n");
    for (int i = 0; i < 1600; i++)
        strcat(longl, "1.0 ");
    strcat(longl, "\n4 5 6\n");
    expect_error(longl, strlen(longl), 3, 2, "longer than 4096");
    /* ...also when it is the last line and has no newline. */
    longl[strlen(longl) - 7] = '\0';
    expect_error(longl, strlen(longl), 3, 2, "longer than 4096");
    free(longl);
}

static void test_subnormal_and_extremes(void **state)
{
    (void)state;
    char path[600];
    double v[9];
    tmp_path(path, sizeof path, "ext.txt");
    write_text(path, "4.9406564584124654e-324 2.2250738585072014e-308 1e-400\n"
                     "9007199254740993 1e23 8.98846567431158e307\n"
                     "0.000000000000000000000000000001 123456789012345678901234567890 -0.0e5\n");
    assert_int_equal(read_all(path, 3, v, 3), 3);
    static const char *tok[9] = {"4.9406564584124654e-324",
                                 "2.2250738585072014e-308",
                                 "1e-400",
                                 "9007199254740993",
                                 "1e23",
                                 "8.98846567431158e307",
                                 "0.000000000000000000000000000001",
                                 "123456789012345678901234567890",
                                 "-0.0e5"};
    for (int i = 0; i < 9; i++)
        assert_same(v[i], strtod(tok[i], NULL), i);
    assert_true(signbit(v[8]));
    remove(path);
}

/* ----------------------------------------------------------------- PLY */

static void test_ply_ascii(void **state)
{
    (void)state;
    char path[600];
    double v[16];
    cf_points_t *r;
    tmp_path(path, sizeof path, "a.ply");
    write_text(path, "ply\n"
                     "format ascii 1.0\n"
                     "comment scanner output\n"
                     "element vertex 3\n"
                     "property float x\n"
                     "property float y\n"
                     "property float z\n"
                     "property uchar red\n"
                     "property list uchar int extra\n"
                     "property double nx\n"
                     "element face 1\n"
                     "property list uchar int vertex_indices\n"
                     "end_header\n"
                     "1.5 2.5 3.5 255 2 7 8 0.1\n"
                     "-1 0 1e2 0 0 1\n"
                     "4 5 6 1 1 9 0\n"
                     "3 0 1 2\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), 18); /* its 17 lines (header and face too) and one */
    assert_int_equal(cf_points_cols(r), 3);
    assert_int_equal(cf_points_read(r, v, 5, msg, sizeof msg), 3);
    assert_int_equal(cf_points_line(r), 16);
    static const double want[9] = {1.5, 2.5, 3.5, -1, 0, 100, 4, 5, 6};
    for (int i = 0; i < 9; i++)
        assert_same(v[i], want[i], i);
    assert_int_equal(cf_points_read(r, v, 5, msg, sizeof msg), 0);
    assert_int_equal(cf_points_rewind(r), CF_OK);
    assert_int_equal(cf_points_read(r, v, 1, msg, sizeof msg), 1);
    assert_true(v[0] == 1.5);
    cf_points_close(r);
    /* With s t: five columns u v x y z. */
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\n"
                     "property double y\nproperty double z\nproperty double s\n"
                     "property double t\nend_header\n1 2 3 0.25 0.75\n4 5 6 1 0\n");
    assert_int_equal(read_all(path, 0, v, 4), 2);
    static const double w5[10] = {0.25, 0.75, 1, 2, 3, 1, 0, 4, 5, 6};
    for (int i = 0; i < 10; i++)
        assert_same(v[i], w5[i], i);
    /* A short vertex line names its line. */
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                     "property float y\nproperty float z\nend_header\n1 2 3\n4 5\n");
    assert_int_equal(cf_points_open(&r, path, 3, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 5, msg, sizeof msg), CF_EPARSE);
    assert_msg(":9: too few values");
    cf_points_close(r);
    remove(path);
}

static size_t put(unsigned char *b, const void *x, size_t n)
{
    /* the test machine is little-endian, as binary_little_endian wants */
    memcpy(b, x, n);
    return n;
}

static void test_ply_binary(void **state)
{
    (void)state;
    char path[600];
    double v[16];
    cf_points_t *r;
    unsigned char b[4096];
    size_t n = 0;
    const char *hdr = "ply\r\n"
                      "format binary_little_endian 1.0\r\n"
                      "element camera 2\r\n"
                      "property list uchar float params\r\n"
                      "property short id\r\n"
                      "element vertex 3\r\n"
                      "property float x\r\n"
                      "property float y\r\n"
                      "property double z\r\n"
                      "property uchar quality\r\n"
                      "property float u\r\n"
                      "property float v\r\n"
                      "element face 1\r\n"
                      "property list uchar int vertex_indices\r\n"
                      "end_header\r\n";
    n += put(b + n, hdr, strlen(hdr));
    for (int c = 0; c < 2; c++) { /* two cameras: 3 floats each, then a short */
        unsigned char cnt = 3;
        float fl[3] = {1, 2, 3};
        short id = (short)c;
        n += put(b + n, &cnt, 1);
        n += put(b + n, fl, sizeof fl);
        n += put(b + n, &id, 2);
    }
    static const float xf[3] = {1.5f, -2.25f, 1e-3f}, yf[3] = {0, 7, 8}, uf[3] = {0, 0.5f, 1};
    static const double zd[3] = {0.1, -1e300, 3};
    for (int i = 0; i < 3; i++) {
        unsigned char q = 9;
        n += put(b + n, &xf[i], 4);
        n += put(b + n, &yf[i], 4);
        n += put(b + n, &zd[i], 8);
        n += put(b + n, &q, 1);
        n += put(b + n, &uf[i], 4);
        n += put(b + n, &uf[2 - i], 4);
    }
    tmp_path(path, sizeof path, "b.ply");
    write_bytes(path, b, n);
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_bound(r), -1); /* binary: its bytes are not lines */
    assert_int_equal(cf_points_cols(r), 5);
    for (int pass = 0; pass < 2; pass++) {
        assert_int_equal(cf_points_read(r, v, 3, msg, sizeof msg), 3);
        for (int i = 0; i < 3; i++) {
            assert_same(v[5 * i], (double)uf[i], i);
            assert_same(v[5 * i + 1], (double)uf[2 - i], i);
            assert_same(v[5 * i + 2], (double)xf[i], i);
            assert_same(v[5 * i + 3], (double)yf[i], i);
            assert_same(v[5 * i + 4], zd[i], i);
        }
        assert_int_equal(cf_points_line(r), 3); /* vertex number */
        assert_int_equal(cf_points_read(r, v, 3, msg, sizeof msg), 0);
        assert_int_equal(cf_points_rewind(r), CF_OK);
    }
    cf_points_close(r);
    /* Only x y z wanted. */
    assert_int_equal(read_all(path, 3, v, 5), 3);
    assert_same(v[3], (double)xf[1], 0);
    /* Truncated inside the last vertex. */
    write_bytes(path, b, n - 3);
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_points_read(r, v, 3, msg, sizeof msg), CF_EPARSE);
    assert_msg("file ends");
    cf_points_close(r);
    /* Big-endian is a valid PLY we do not read. */
    write_text(path, "ply\nformat binary_big_endian 1.0\nelement vertex 0\nend_header\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_msg("binary_big_endian");
    /* No x y z. */
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nend_header\n1\n");
    assert_int_equal(cf_points_open(&r, path, 0, msg, sizeof msg), CF_EPARSE);
    assert_msg("x, y and z");
    remove(path);
}

/* ----------------------------------------------------------- benchmark */

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Parse rate for `lines` generated u v x y z lines, in two number styles. */
static void bench(long lines)
{
    char path[600];
    static const char *style[2] = {"%.6f %.6f %.4f %.4f %.4f\n", "%.17g %.17g %.17g %.17g %.17g\n"};
    static const char *label[2] = {"CMM style (%.6f/%.4f)", "full precision (%.17g)"};
    tmp_path(path, sizeof path, "bench.txt");
    for (int s = 0; s < 2; s++) {
        FILE *f = fopen(path, "wb");
        assert_non_null(f);
        for (long i = 0; i < lines; i++)
            fprintf(f, style[s], urand(), urand(), (urand() - 0.5) * 1000, (urand() - 0.5) * 1000,
                    (urand() - 0.5) * 100);
        assert_int_equal(fclose(f), 0);
        cf_points_t *r;
        static double v[5 * 4096];
        double t0 = now(), sum = 0;
        long n = 0, got;
        assert_int_equal(cf_points_open(&r, path, 5, msg, sizeof msg), CF_OK);
        while ((got = cf_points_read(r, v, 4096, msg, sizeof msg)) > 0) {
            n += got;
            sum += v[0];
        }
        double dt = now() - t0;
        cf_points_close(r);
        assert_int_equal(got, 0);
        assert_int_equal(n, lines);
        printf("points bench: %ld lines u v x y z, %s: %.3f s, %.2f M lines/s (checksum %.3f)\n",
               lines, label[s], dt, (double)lines / dt / 1e6, sum);
    }
    remove(path);
}

static void test_bench(void **state)
{
    (void)state;
    const char *e = getenv("CF_BENCH_LINES");
    bench(e && atol(e) > 0 ? atol(e) : 1000000);
}

int main(int argc, char **argv)
{
    make_tmpdir();
    if (argc > 1 && !strcmp(argv[1], "--bench")) {
        bench(argc > 2 && atol(argv[2]) > 0 ? atol(argv[2]) : 1000000);
        return 0;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_three_columns),
        cmocka_unit_test(test_five_columns_crlf),
        cmocka_unit_test(test_first_line_decides),
        cmocka_unit_test(test_empty_files),
        cmocka_unit_test(test_csv_header),
        cmocka_unit_test(test_batches_across_buffer),
        cmocka_unit_test(test_bit_identical_to_strtod),
        cmocka_unit_test(test_raw_float64),
        cmocka_unit_test(test_bound_small_files),
        cmocka_unit_test(test_raw_nonfinite_direct),
        cmocka_unit_test(test_rewind),
        cmocka_unit_test(test_stdin_not_rewindable),
        cmocka_unit_test(test_errors_name_the_line),
        cmocka_unit_test(test_subnormal_and_extremes),
        cmocka_unit_test(test_ply_ascii),
        cmocka_unit_test(test_ply_binary),
        cmocka_unit_test(test_bench),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
