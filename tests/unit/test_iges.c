/* SPDX-License-Identifier: MIT */
/* test_iges.c: IGES entity 128 reading and writing. Fixtures are small files
 * written by hand the way CAD systems write them (D exponents, Hollerith
 * strings holding delimiters, many entities, a 144 over the 128, custom
 * delimiters, a 124 matrix); the expected numbers are typed in, not taken
 * from the module. Writing is checked by re-reading bit-exactly and by
 * parsing the written file's layout here, independently of the reader. */

#include "cf_err.h"
#include "cf_iges.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_surf.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Generated from a short script and checked by test_fixtures_are_80_columns.
 * A: S 1-2, G 3-6, D 7-20 (DE 1 314, DE 3 128, DE 5 126, DE 7 142, DE 9 144
 * over DE 3, DE 11 128, DE 13 406), P 21-41 (P record k is line 20 + k).
 * B: parameter '/' and record '$' delimiters; DE 1 a 124 matrix, DE 3 a 128
 * using it. */
static const char *const iges_a[] = {
    "Exported by FooCAD 12.1 (test fixture written by hand for cellfit).     S      1",
    "Bracket part: two B-spline surfaces, one trimmed.                       S      2",
    "1H,,1H;,16Hpart, rev; A,B;C,11Hbracket.igs,23HFooCAD, Release 12; SP1,  G      1",
    "11HIGES 5.3 ;,,32,38,6,308,15,4Hpart,1.D0,2,2HMM,50,0.125,15H20240105.10G      2",
    "1500,1.0D-08,1000.0,12HJ. Smith, QA,21HAcme; Metrology, Inc.,11,0,15H202G      3",
    "40105.101500;                                                           G      4",
    "     314       1       0       0       0       0       0       000000200D      1",
    "     314       0       0       1       0                   COLOR       0D      2",
    "     128       2       0       0       0       0       0       000010000D      3",
    "     128       0       0       4       0                 SURFACE       0D      4",
    "     126       6       0       0       0       0       0       000010500D      5",
    "     126       0       0       2       0                   CURVE       0D      6",
    "     142       8       0       0       0       0       0       000010500D      7",
    "     142       0       0       1       0                CRVONSRF       0D      8",
    "     144       9       0       0       0       0       0       000000000D      9",
    "     144       0       0       1       0                 TRIMSRF       0D     10",
    "     128      10       0       0       0       0       0       000000000D     11",
    "     128       0       0      11       0                 SURFACE       0D     12",
    "     406      21       0       0       0       0       0       000000200D     13",
    "     406       0       0       1      15                    NAME       0D     14",
    "314,50.,50.,50.,4Hgrey;                                                1P      1",
    "128,1,1,1,1,0,0,1,0,0,0.D0,0.D0,1.D0,1.D0,0.0D+00,0.0D+00,             3P      2",
    "1.0D+00,1.0D+00,1.D0,1.D0,1.D0,1.D0,0.D0,0.D0,0.D0,1.D1,0.D0,          3P      3",
    "0.D0,0.D0,2.0D+01,0.D0,1.0D+01,2.0D+01,5.D0,0.D0,1.D0,0.D0,1.D0,       3P      4",
    "0,0;                                                                   3P      5",
    "126,1,1,0,0,1,0,0.,0.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,                   5P      6",
    "0.,1.,0.,0.,0.,1.;                                                     5P      7",
    "142,1,3,5,0,2;                                                         7P      8",
    "144,3,1,0,7;                                                           9P      9",
    "128,2,1,2,1,0,0,0,0,0,                                                11P     10",
    "-1.0E+00,-1.0E+00,-1.0E+00,2.5E0,2.5E0,2.5E0,                         11P     11",
    "10.,10.,20.,20.,                                                      11P     12",
    "1.,0.5,1.,1.,5.0E-01,1.,                                              11P     13",
    "0.,0.1,0.,                                                            11P     14",
    "3.25,0.1,2.,                                                          11P     15",
    "6.5,1.0D-1,0.,                                                        11P     16",
    "0.,1.6,-0.75,                                                         11P     17",
    "3.25D0,1.6,1.25,                                                      11P     18",
    "6.5,1.6,-7.5D-01,                                                     11P     19",
    "-1.,2.5,10.,20.,0,1,13;                                               11P     20",
    "406,1,8HSURFACE2;                                                     13P     21",
    "S      2G      4D     14P     21                                        T      1",
    NULL};
static const char *const iges_b[] = {
    "custom delimiters                                                       S      1",
    "1H//1H$/5Hb/c$d/7Hrot.igs/9HOther CAD/2Hv2/32/38/6/308/15/3Hrot/1./2/2HMG      1",
    "M/1/1./15H20240105.101500/1.E-6/100./1Hx/1Hy/11/0$                      G      2",
    "     124       1       0       0       0       0       0       000000000D      1",
    "     124       0       0       1       0                  MATRIX       0D      2",
    "     128       2       0       0       0       0       1       000000000D      3",
    "     128       0       0       2       0                    SURF       0D      4",
    "124/0./-1./0./10./1./0./0./20./0./0./1./30.$                           1P      1",
    "128/1/1/1/1/0/0/1/0/0/0./0./1./1./0./0./1./1./1./1./1./1./             3P      2",
    "1./2./3./4./5./6./7./8./9./10./11./12./0./1./0./1.$                    3P      3",
    "S      1G      2D      4P      3                                        T      1",
    NULL};

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
    snprintf(buf, n, "%s/cf_iges_%ld_%s", tmpdir, (long)getpid(), name);
}

enum { EOL_LF, EOL_CRLF, EOL_CR, EOL_NONE, EOL_TRIM };

/* Write fixture lines: LF, CRLF, CR, fixed 80-byte records without line
 * ends, or sequence numbers left-justified with trailing blanks trimmed. */
static void write_lines(const char *path, const char *const *lines, int eol)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (int i = 0; lines[i]; i++) {
        char l[96];
        snprintf(l, sizeof l, "%s", lines[i]);
        if (eol == EOL_TRIM) {
            long seq = atol(l + 73);
            sprintf(l + 73, "%ld", seq);
        }
        fputs(l, f);
        fputs(eol == EOL_CRLF ? "\r\n" : eol == EOL_CR ? "\r" : eol == EOL_NONE ? "" : "\n", f);
    }
    assert_int_equal(fclose(f), 0);
}

static void write_bytes(const char *path, const void *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

/* Copy of a fixture with line `line` (1-based) patched at column col (1-based). */
static const char **patched(const char *const *src, int line, int col, const char *text)
{
    static char store[64][81];
    static const char *out[65];
    char tmp[64][81];
    int i = 0;
    for (; src[i]; i++) /* src may be an earlier result: copy out first */
        snprintf(tmp[i], sizeof tmp[i], "%s", src[i]);
    for (int k = 0; k < i; k++) {
        memcpy(store[k], tmp[k], sizeof store[k]);
        out[k] = store[k];
    }
    out[i] = NULL;
    assert_true(line >= 1 && line <= i);
    memcpy(store[line - 1] + col - 1, text, strlen(text));
    return out;
}

/* Column of the first occurrence of text in a fixture line (1-based). */
static int col_of(const char *const *src, int line, const char *text)
{
    const char *p = strstr(src[line - 1], text);
    assert_non_null(p);
    return (int)(p - src[line - 1]) + 1;
}

static void assert_msg(const char *path, const char *what)
{
    if (!strstr(msg, path) || !strstr(msg, what))
        fail_msg("message '%s' lacks '%s' or '%s'", msg, path, what);
}

static void assert_doubles(const double *got, const double *want, int n)
{
    for (int i = 0; i < n; i++)
        if (memcmp(&got[i], &want[i], sizeof(double)))
            fail_msg("value %d: got %.17g, want %.17g", i, got[i], want[i]);
}

/* Surface DE 3 of fixture A: bilinear, corners (0,0,0) (10,0,0) (0,20,0) (10,20,5). */
static void check_a1(const nf_surf_t *s)
{
    static const double k[4] = {0, 0, 1, 1}, w[4] = {1, 1, 1, 1};
    static const double cp[12] = {0, 0, 0, 10, 0, 0, 0, 20, 0, 10, 20, 5};
    assert_int_equal(s->p, 1);
    assert_int_equal(s->q, 1);
    assert_int_equal(s->nu, 2);
    assert_int_equal(s->nv, 2);
    assert_non_null(s->w);
    assert_doubles(s->U, k, 4);
    assert_doubles(s->V, k, 4);
    assert_doubles(s->w, w, 4);
    assert_doubles(s->cp, cp, 12);
}

/* Surface DE 11 of fixture A: degree 2 x 1, domain [-1, 2.5] x [10, 20], rational. */
static void check_a2(const nf_surf_t *s)
{
    static const double U[6] = {-1, -1, -1, 2.5, 2.5, 2.5}, V[4] = {10, 10, 20, 20};
    static const double w[6] = {1, 0.5, 1, 1, 0.5, 1};
    static const double cp[18] = {0, 0.1, 0,     3.25, 0.1, 2,    6.5, 0.1, 0,
                                  0, 1.6, -0.75, 3.25, 1.6, 1.25, 6.5, 1.6, -0.75};
    assert_int_equal(s->p, 2);
    assert_int_equal(s->q, 1);
    assert_int_equal(s->nu, 3);
    assert_int_equal(s->nv, 2);
    assert_doubles(s->U, U, 6);
    assert_doubles(s->V, V, 4);
    assert_doubles(s->w, w, 6);
    assert_doubles(s->cp, cp, 18);
}

static void test_fixtures_are_80_columns(void **state)
{
    (void)state;
    for (int i = 0; iges_a[i]; i++)
        assert_int_equal(strlen(iges_a[i]), 80);
    for (int i = 0; iges_b[i]; i++)
        assert_int_equal(strlen(iges_b[i]), 80);
}

static void test_first_128(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "a.igs");
    write_lines(path, iges_a, EOL_LF);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_OK);
    check_a1(&s);
    /* The bilinear patch at its centre is the mean of the corners. */
    double P[3];
    nf_surf_eval(&s, 0.5, 0.5, P);
    assert_near(P[0], 5.0, 1e-15);
    assert_near(P[1], 10.0, 1e-15);
    assert_near(P[2], 1.25, 1e-15);
    cf_surf_free(&s);
    /* The same 128 named by its DE number (the 144 at DE 9 points to it). */
    assert_int_equal(cf_iges_read(path, 3, &s, msg, sizeof msg), CF_OK);
    check_a1(&s);
    cf_surf_free(&s);
    remove(path);
}

/* Global unit flag and name: coordinates come back in millimetres (as CAD
 * kernels convert them), knots and weights untouched; unknown units refused. */
static void test_units_to_mm(void **state)
{
    (void)state;
    static const struct {
        const char *field; /* replaces ",2,2HMM," in fixture A's G line 2 */
        double mm;
    } cases[] = {{",1,2HIN,", 25.4}, {",3,2HCM,", 10.0}, {",6,1HM ,", 1000.0}, {",2,2HMM,", 1.0}};
    char path[600];
    tmp_path(path, sizeof path, "units.igs");
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const char *lines[64];
        char g2[81];
        int n = 0;
        for (; iges_a[n]; n++)
            lines[n] = iges_a[n];
        lines[n] = NULL;
        int gl = 0; /* the G line with the unit fields */
        while (!strstr(iges_a[gl], ",2,2HMM,"))
            gl++;
        memcpy(g2, iges_a[gl], 81);
        memcpy(strstr(g2, ",2,2HMM,"), cases[k].field, 8);
        lines[gl] = g2;
        write_lines(path, lines, EOL_LF);
        nf_surf_t s, ref;
        assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_OK);
        write_lines(path, iges_a, EOL_LF);
        assert_int_equal(cf_iges_read(path, 0, &ref, msg, sizeof msg), CF_OK);
        for (int i = 0; i < 3 * s.nu * s.nv; i++)
            assert_near(s.cp[i], cases[k].mm * ref.cp[i], 1e-12 * fabs(cases[k].mm * ref.cp[i]));
        for (int i = 0; i < s.nu + s.p + 1; i++)
            assert_true(s.U[i] == ref.U[i]);
        cf_surf_free(&s);
        cf_surf_free(&ref);
    }
    const char *lines[64];
    char g2[81];
    int n = 0;
    for (; iges_a[n]; n++)
        lines[n] = iges_a[n];
    lines[n] = NULL;
    int gl = 0;
    while (!strstr(iges_a[gl], ",2,2HMM,"))
        gl++;
    memcpy(g2, iges_a[gl], 81);
    memcpy(strstr(g2, ",2,2HMM,"), ",3,2HXX,", 8);
    lines[gl] = g2;
    write_lines(path, lines, EOL_LF);
    nf_surf_t s;
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_non_null(strstr(msg, "unit"));
    remove(path);
}

static void test_second_128_by_de(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "a2.igs");
    write_lines(path, iges_a, EOL_LF);
    assert_int_equal(cf_iges_read(path, 11, &s, msg, sizeof msg), CF_OK);
    check_a2(&s);
    double u0, u1, v0, v1;
    nf_surf_domain(&s, &u0, &u1, &v0, &v1);
    assert_true(u0 == -1 && u1 == 2.5 && v0 == 10 && v1 == 20);
    cf_surf_free(&s);
    remove(path);
}

static void test_de_not_a_128(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "nf.igs");
    write_lines(path, iges_a, EOL_LF);
    assert_int_equal(cf_iges_read(path, 9, &s, msg, sizeof msg), CF_ENOTFOUND);
    assert_msg(path, "144");
    assert_msg(path, "line 15");
    assert_null(s.U);
    assert_int_equal(cf_iges_read(path, 4, &s, msg, sizeof msg), CF_ENOTFOUND);
    assert_int_equal(cf_iges_read(path, 15, &s, msg, sizeof msg), CF_ENOTFOUND);
    assert_int_equal(cf_iges_read(path, 99, &s, msg, sizeof msg), CF_ENOTFOUND);
    /* No 128 at all: both surfaces relabelled 130 on both D lines. */
    const char **l = patched(iges_a, 9, 6, "130");
    l = patched(l, 10, 6, "130");
    l = patched(l, 17, 6, "130");
    l = patched(l, 18, 6, "130");
    write_lines(path, l, EOL_LF);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_ENOTFOUND);
    assert_msg(path, "128");
    remove(path);
}

static void test_delimiters_and_matrix(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "b.igs");
    write_lines(path, iges_b, EOL_LF);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_OK);
    /* (x, y, z) -> (-y + 10, x + 20, z + 30), from the 124 at DE 1. */
    static const double cp[12] = {8, 21, 33, 5, 24, 36, 2, 27, 39, -1, 30, 42};
    static const double k[4] = {0, 0, 1, 1};
    assert_int_equal(s.nu, 2);
    assert_doubles(s.U, k, 4);
    assert_doubles(s.cp, cp, 12);
    cf_surf_free(&s);
    remove(path);
}

static void test_line_endings(void **state)
{
    (void)state;
    static const int eol[] = {EOL_CRLF, EOL_CR, EOL_NONE, EOL_TRIM};
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "eol.igs");
    for (size_t i = 0; i < sizeof eol / sizeof eol[0]; i++) {
        write_lines(path, iges_a, eol[i]);
        if (cf_iges_read(path, 0, &s, msg, sizeof msg))
            fail_msg("line end style %zu: %s", i, msg);
        check_a1(&s);
        cf_surf_free(&s);
        assert_int_equal(cf_iges_read(path, 11, &s, msg, sizeof msg), CF_OK);
        check_a2(&s);
        cf_surf_free(&s);
        write_lines(path, iges_b, eol[i]);
        assert_int_equal(cf_iges_read(path, 3, &s, msg, sizeof msg), CF_OK);
        assert_true(s.cp[0] == 8 && s.cp[11] == 42);
        cf_surf_free(&s);
    }
    remove(path);
}

/* ------------------------------------------------------------- writing */

static unsigned long long rng = 0x9E3779B97F4A7C15ULL;

static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

static unsigned char next_byte(void)
{
    return (unsigned char)(urand() * 256.0);
}

/* Random clamped knots on [a, b], interior ones strictly increasing. */
static void rand_knots(double *U, int n, int p, double a, double b)
{
    int m = n + p + 1;
    for (int i = 0; i <= p; i++) {
        U[i] = a;
        U[m - 1 - i] = b;
    }
    double t = a;
    for (int i = p + 1; i < n; i++) {
        t += (b - t) * (0.1 + 0.5 * urand()) / (n - i + 1) * 2;
        U[i] = t;
    }
}

static void rand_surface(nf_surf_t *s, int p, int q, int nu, int nv)
{
    assert_int_equal(cf_surf_alloc(s, p, q, nu, nv), CF_OK);
    rand_knots(s->U, nu, p, -3.5, 12.25);
    rand_knots(s->V, nv, q, 100.0, 101.5);
    for (int i = 0; i < nu * nv; i++) {
        s->w[i] = 0.5 + 1.5 * urand();
        s->cp[3 * i] = (urand() - 0.5) * 2000.0;
        s->cp[3 * i + 1] = (urand() - 0.5) * 1e-7;
        s->cp[3 * i + 2] = urand() * 3e5 + 1.0 / 3.0;
    }
    s->cp[0] = -0.0;
    s->cp[1] = 5e-324; /* subnormal */
    s->cp[2] = 1.7976931348623157e308;
    assert_int_equal(nf_surf_check(s), NF_OK);
}

static void test_roundtrip_bit_exact(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s, r;
    tmp_path(path, sizeof path, "rt.igs");
    rand_surface(&s, 3, 3, 9, 7);
    assert_int_equal(cf_iges_write_at(path, &s, "random bicubic", 1700000000LL, msg, sizeof msg),
                     CF_OK);
    assert_int_equal(cf_iges_read(path, 0, &r, msg, sizeof msg), CF_OK);
    assert_int_equal(r.p, 3);
    assert_int_equal(r.q, 3);
    assert_int_equal(r.nu, 9);
    assert_int_equal(r.nv, 7);
    assert_memory_equal(r.U, s.U, sizeof(double) * 13);
    assert_memory_equal(r.V, s.V, sizeof(double) * 11);
    assert_memory_equal(r.w, s.w, sizeof(double) * 63);
    assert_memory_equal(r.cp, s.cp, sizeof(double) * 189);
    cf_surf_free(&r);
    /* Without weights: read back with weights 1. */
    s.w = NULL;
    assert_int_equal(cf_iges_write_at(path, &s, NULL, 0, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_iges_read(path, 1, &r, msg, sizeof msg), CF_OK);
    for (int i = 0; i < 63; i++)
        assert_true(r.w[i] == 1.0);
    assert_memory_equal(r.cp, s.cp, sizeof(double) * 189);
    cf_surf_free(&r);
    cf_surf_free(&s);
    remove(path);
}

/* Whole file in memory, NUL-terminated. */
static char *slurp(const char *path, long *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)*n + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)*n, f), (size_t)*n);
    b[*n] = '\0';
    fclose(f);
    return b;
}

/* The layout of a written file, parsed here by fixed columns. */
static void test_written_structure(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "layout.igs");
    rand_surface(&s, 3, 2, 6, 5);
    assert_int_equal(cf_iges_write_at(path, &s, "layout", 1700000000LL, msg, sizeof msg), CF_OK);
    long n;
    char *b = slurp(path, &n);
    assert_int_equal(n % 81, 0);
    long nl = n / 81, cnt[5] = {0, 0, 0, 0, 0};
    const char *order = "SGDPT";
    int sect = 0;
    char *g = calloc((size_t)nl, 72), *pd = calloc((size_t)nl, 64);
    size_t gl = 0, pl = 0;
    for (long i = 0; i < nl; i++) {
        char *l = b + 81 * i;
        assert_int_equal(l[80], '\n');
        const char *at = strchr(order, l[72]);
        assert_non_null(at);
        int k = (int)(at - order);
        assert_true(k >= sect);
        sect = k;
        cnt[k]++;
        char seq[8];
        memcpy(seq, l + 73, 7);
        seq[7] = '\0';
        assert_int_equal(atol(seq), cnt[k]);
        assert_true(seq[6] != ' '); /* right-justified */
        if (k == 1) {               /* parameters never straddle lines: drop the padding */
            size_t w = 72;
            while (w > 0 && l[w - 1] == ' ')
                w--;
            memcpy(g + gl, l, w);
            gl += w;
        }
        if (k == 3) {
            assert_memory_equal(l + 64, "       1", 8); /* back pointer to DE 1 */
            memcpy(pd + pl, l, 64);
            pl += 64;
        }
    }
    assert_int_equal(cnt[2], 2);
    assert_int_equal(cnt[4], 1);
    /* T: counts of S G D P. */
    char t[81], want[41];
    memcpy(t, b + 81 * (nl - 1), 80);
    t[80] = '\0';
    snprintf(want, sizeof want, "S%7ldG%7ldD%7ldP%7ld", cnt[0], cnt[1], cnt[2], cnt[3]);
    assert_memory_equal(t, want, 32);
    /* D: type 128, parameter data at P 1, line count = P lines, form 0. */
    const char *d1 = b + 81 * (cnt[0] + cnt[1]), *d2 = d1 + 81;
    assert_memory_equal(d1, "     128       1", 16);
    assert_memory_equal(d2, "     128", 8);
    char f[9];
    memcpy(f, d2 + 24, 8);
    f[8] = '\0';
    assert_int_equal(atol(f), cnt[3]);
    memcpy(f, d2 + 32, 8);
    assert_int_equal(atol(f), 0);
    /* G: delimiters, units mm, IGES 5.3, the timestamp 1700000000 in UTC. */
    g[gl] = '\0';
    assert_memory_equal(g, "1H,,1H;,", 8);
    assert_non_null(strstr(g, ",2,2HMM,"));
    assert_non_null(strstr(g, "15H20231114.221320"));
    assert_non_null(strstr(g, ",11,0,15H20231114.221320;"));
    /* P: every value in order, by strtod (so independent of the reader). */
    pd[pl] = '\0';
    long nf = 0, need = 10 + 10 + 8 + 4 * 30 + 4;
    double v[300];
    char *p = pd, *end;
    for (;;) {
        while (*p == ' ')
            p++;
        assert_true(nf < 300);
        v[nf++] = strtod(p, &end);
        assert_true(end > p);
        p = end;
        while (*p == ' ')
            p++;
        if (*p == ';')
            break;
        assert_int_equal(*p, ',');
        p++;
    }
    assert_int_equal(nf, need);
    static const double head[10] = {128, 5, 4, 3, 2, 0, 0, 0, 0, 0};
    assert_doubles(v, head, 10);
    assert_doubles(v + 10, s.U, 10);
    assert_doubles(v + 20, s.V, 8);
    assert_doubles(v + 28, s.w, 30);
    assert_doubles(v + 58, s.cp, 90);
    double dom[4] = {-3.5, 12.25, 100.0, 101.5};
    assert_doubles(v + 148, dom, 4);
    free(g);
    free(pd);
    free(b);
    /* Equal weights: PROP3 = 1 (polynomial). */
    for (int i = 0; i < 30; i++)
        s.w[i] = 2.0;
    assert_int_equal(cf_iges_write_at(path, &s, "poly", 0, msg, sizeof msg), CF_OK);
    b = slurp(path, &n);
    char *p1 = strstr(b, "128,5,4,3,2,");
    assert_non_null(p1);
    assert_memory_equal(p1 + 12, "0,0,1,0,0,", 10);
    assert_non_null(strstr(b, "15H19700101.000000"));
    free(b);
    cf_surf_free(&s);
    remove(path);
}

static void test_write_uses_source_date_epoch(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    long n;
    tmp_path(path, sizeof path, "sde.igs");
    rand_surface(&s, 2, 2, 3, 3);
    setenv("SOURCE_DATE_EPOCH", "946684799", 1); /* 1999-12-31 23:59:59 UTC */
    assert_int_equal(cf_iges_write(path, &s, "x", msg, sizeof msg), CF_OK);
    unsetenv("SOURCE_DATE_EPOCH");
    char *b = slurp(path, &n);
    assert_non_null(strstr(b, "15H19991231.235959"));
    free(b);
    cf_surf_free(&s);
    remove(path);
}

static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static void test_write_failures_leave_nothing(void **state)
{
    (void)state;
    char path[600], tmp[700];
    nf_surf_t s;
    rand_surface(&s, 3, 3, 4, 4);
    tmp_path(path, sizeof path, "nodir/x.igs");
    assert_int_equal(cf_iges_write(path, &s, "x", msg, sizeof msg), CF_EIO);
    assert_msg(path, "x.igs");
    assert_false(exists(path));
    /* The target is a directory: the rename fails, the temporary goes. */
    tmp_path(path, sizeof path, "isdir");
    assert_int_equal(mkdir(path, 0777), 0);
    assert_int_equal(cf_iges_write(path, &s, "x", msg, sizeof msg), CF_EIO);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(exists(tmp));
    rmdir(path);
    /* An invalid surface is refused before any file is made. */
    tmp_path(path, sizeof path, "bad.igs");
    s.U[4] = s.U[5] + 1.0;
    assert_int_equal(cf_iges_write(path, &s, "x", msg, sizeof msg), NF_EKNOTS);
    assert_false(exists(path));
    cf_surf_free(&s);
}

/* --------------------------------------------------------------- errors */

/* Read a patched fixture A: expect code and a message naming line `what`. */
static void expect_a(const char *const *lines, int de, int code, const char *what)
{
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "err.igs");
    write_lines(path, lines, EOL_LF);
    int rc = cf_iges_read(path, de, &s, msg, sizeof msg);
    if (rc != code)
        fail_msg("got %d (%s), want %d; message: %s", rc, cf_strerror(rc), code, msg);
    assert_msg(path, what);
    assert_null(s.U);
    remove(path);
}

static void test_garbled_number(void **state)
{
    (void)state;
    /* P record 4 (line 24) holds 2.0D+01 for Y(0,1). */
    int c = col_of(iges_a, 24, "2.0D+01");
    expect_a(patched(iges_a, 24, c, "2.0Q+01"), 0, CF_EPARSE, "line 24 (P record 4");
    expect_a(patched(iges_a, 24, c, "2.0D+  "), 0, CF_EPARSE, "line 24 (P record 4");
    expect_a(patched(iges_a, 24, c, "       "), 0, CF_EPARSE, "line 24 (P record 4");
    /* Out of double range. */
    expect_a(patched(iges_a, 24, c, "2.0D999"), 0, CF_EPARSE, "out of range");
    /* K1 is not an integer. */
    expect_a(patched(iges_a, 22, 5, "x"), 0, CF_EPARSE, "line 22 (P record 2");
}

static void test_invalid_surfaces(void **state)
{
    (void)state;
    /* u knots 0 0 1 .5: decreasing, found by nf_surf_check's rules. */
    int c = col_of(iges_a, 22, "1.D0,1.D0,0.0D");
    expect_a(patched(iges_a, 22, c + 5, ".5D0"), 0, NF_EKNOTS, "line 22 (P record 2");
    expect_a(patched(iges_a, 22, c + 5, ".5D0"), 0, NF_EKNOTS, "decreases");
    /* Weight W(1,1) of DE 11 zero (P record 13, line 33). */
    c = col_of(iges_a, 33, "5.0E-01");
    expect_a(patched(iges_a, 33, c, "0.0E-01"), 11, NF_EWEIGHT, "line 33 (P record 13");
    expect_a(patched(iges_a, 33, c, "-.5E-01"), 11, NF_EWEIGHT, "W(1,1)");
    /* One degree over the board's in u for DE 11 (sim: 6; linux-cell: 8). */
    char over[2] = {(char)('0' + NF_MAX_DEGREE + 1), '\0'};
    _Static_assert(NF_MAX_DEGREE + 1 <= 9, "the patched field holds one digit");
    expect_a(patched(iges_a, 30, 9, over), 11, NF_EDEGREE, "line 30 (P record 10");
}

/* A file with one 128 whose parameter text is params (free format). */
static void write_one(const char *path, const char *params)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "%-72sS%7d\n", "generated", 1);
    fprintf(f, "%-72sG%7d\n", "1H,,1H;;", 1);
    long n = (long)strlen(params), lines = (n + 63) / 64;
    fprintf(f, "%8d%8d%8d%8d%8d%8d%8d%8d%8sD%7d\n", 128, 1, 0, 0, 0, 0, 0, 0, "00000000", 1);
    fprintf(f, "%8d%8d%8d%8ld%8d%8s%8s%8s%8dD%7d\n", 128, 0, 0, lines, 0, "", "", "", 0, 2);
    for (long i = 0; i < lines; i++)
        fprintf(f, "%-64.64s%8dP%7ld\n", params + 64 * i, 1, i + 1);
    fprintf(f, "S%7dG%7dD%7dP%7ld%40sT%7d\n", 1, 1, 2, lines, "", 1);
    assert_int_equal(fclose(f), 0);
}

static void expect_one(const char *params, int code, const char *what)
{
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "one.igs");
    write_one(path, params);
    int rc = cf_iges_read(path, 0, &s, msg, sizeof msg);
    if (rc != code)
        fail_msg("got %d (%s), want %d; message: %s", rc, cf_strerror(rc), code, msg);
    if (what)
        assert_msg(path, what);
    if (rc)
        assert_null(s.U);
    cf_surf_free(&s);
    remove(path);
}

/* Parameter text of a valid-shaped 128: degree p x p, n x n points. */
static char *params_128(int K, int M)
{
    int n = K + 1;
    size_t cap = (size_t)(64 + 48 * (2 * (n + M + 1) + 4 * n * n));
    char *b = malloc(cap), *e = b;
    assert_non_null(b);
    e += sprintf(e, "128,%d,%d,%d,%d,0,0,1,0,0", K, K, M, M);
    for (int d = 0; d < 2; d++)
        for (int i = 0; i < n + M + 1; i++)
            e += sprintf(e, ",%d.", i <= M ? 0 : i >= n ? n - M : i - M);
    for (int i = 0; i < n * n; i++)
        e += sprintf(e, ",1.");
    for (int i = 0; i < n * n; i++)
        e += sprintf(e, ",%d.,%d.,0.", i % n, i / n);
    sprintf(e, ";");
    return b;
}

/* Near a midpoint M between two adjacent doubles of [2^e, 2^(e+1)) with e
 * = 73, 83 or 93: m 10^k for k = 3, 6 or 9 and m = M / 10^k rounded (19
 * digits), within 10^k / 2 < 2^(e-64) of M; so m 10^k rounded to a 64-bit
 * significand is M itself, and only a midpoint check tells which way the
 * double goes (M < 10^(19+k): the mantissa's fraction halved until so). */
static void near_midpoint_text(char *b, size_t bl, unsigned long long bits)
{
    static const int E[3] = {73, 83, 93}, K[3] = {3, 6, 9};
    const int w = (int)(bits % 3);
    unsigned __int128 p10 = 1, lim, M;
    for (int i = 0; i < K[w]; i++)
        p10 *= 10;
    lim = p10 * 10000000000000000000ULL; /* 10^(19+k) */
    unsigned long long frac = bits >> 12;
    do {
        M = (unsigned __int128)(2 * ((1ULL << 52) | frac) + 1) << (E[w] - 53);
        frac >>= 1;
    } while (M >= lim);
    const unsigned long long m = (unsigned long long)((M + p10 / 2) / p10);
    snprintf(b, bl, "%lluE%d", m + (bits & 4 ? 0 : bits & 8 ? 1 : -1ULL), K[w]);
}

/* An exact midpoint between two adjacent doubles of [2^e, 2^(e+1)), 48 <=
 * e <= 62, as the decimal it is: (2 mant + 1) 2^(e-53), 19 or 20 digits,
 * the point placed exactly; sometimes with the point moved and an exponent
 * making up for it, or the last digit off by one (just off the midpoint);
 * and half the time near_midpoint_text. */
static void midpoint_text(char *b, size_t bl, unsigned long long bits)
{
    if (bits & 0x1000) {
        near_midpoint_text(b, bl, bits);
        return;
    }
    const int e = 48 + (int)(bits % 15);
    const unsigned long long odd = 2 * ((1ULL << 52) | (bits >> 12)) + 1; /* < 2^54 */
    unsigned __int128 n = odd;
    int frac = 0; /* digits after the point */
    if (e >= 53)
        n <<= e - 53;
    else
        for (frac = 0; frac < 53 - e; frac++)
            n *= 5; /* odd / 2^(53-e) = odd 5^(53-e) / 10^(53-e) */
    if (bits & 0x800)
        n += bits & 0x400 ? 1 : -1; /* just off */
    char dg[48];
    int nd = 0;
    for (unsigned __int128 t = n; t; t /= 10)
        dg[nd++] = (char)('0' + (int)(t % 10));
    char *o = b;
    const int shift = (int)(bits >> 40 & 7); /* the point moved left, E+shift after */
    for (int i = nd - 1; i >= 0; i--) {
        *o++ = dg[i];
        if (i == frac + shift && i > 0)
            *o++ = '.';
    }
    if (shift)
        snprintf(o, bl - (size_t)(o - b), "E%d", shift);
    else
        *o = '\0';
}

/* Number text of class k for a random double-ish value r in [0, 1). */
static void num_text(char *b, size_t bl, int k, double r, unsigned long long bits)
{
    static const char *blank[5] = {"", " ", "  ", "\t", " \t "};
    double x;
    switch (k % 16) {
    case 0: snprintf(b, bl, "%.17g", (r - 0.5) * 400.0); break; /* what writers write */
    case 1: snprintf(b, bl, "%.15E", (r - 0.5) * 1e5); break;   /* CAD style, E */
    case 2:                                                     /* Fortran D */
        snprintf(b, bl, "%.16E", r * 1e-3);
        *strchr(b, 'E') = 'D';
        break;
    case 3: snprintf(b, bl, "%.30f", r * 10.0); break;                    /* > 19 digits */
    case 4: snprintf(b, bl, "0.0000000%llu%llu", bits, bits >> 7); break; /* leading zeros, long */
    case 5: snprintf(b, bl, "%.6e", r * 1e300); break;                    /* huge */
    case 6: snprintf(b, bl, "%.17e", r * 1e-300); break;                  /* tiny */
    case 7: snprintf(b, bl, "%.3e", ldexp(r, -1060)); break;              /* subnormal */
    case 8: /* a midpoint between two doubles near 2^53 and 2^60, exactly or just off */
        x = ldexp(1.0, 53 + (int)(bits % 8));
        snprintf(b, bl, "%.0f%s", x + (double)(bits >> 40 & 0xFF) * 2.0,
                 bits & 1   ? ".5"
                 : bits & 2 ? ".50000000000000000000001"
                            : ".49999999999999999999");
        break;
    case 9: snprintf(b, bl, "%s%llu.", bits & 1 ? "-" : "+", bits >> 1); break; /* 19-20 digits */
    case 10: snprintf(b, bl, ".%llu", bits % 100000000000ULL); break; /* no integer part */
    case 12: midpoint_text(b, bl, bits); break; /* exact ties for the x87 and Eisel-Lemire checks */
    case 13: /* blanks and tabs around, a '+', lower-case e and d */
        snprintf(b, bl, "%s%s%.*e%s", blank[bits % 5], bits & 8 ? "+" : "",
                 (int)(bits >> 4 & 15) + 1, (r + 0.01) * pow(10.0, (int)(bits >> 8 & 31) - 15),
                 blank[(bits >> 16) % 5]);
        if (bits & 0x200000)
            *strchr(b, 'e') = 'd';
        break;
    case 14: /* zeros: signed, padded, "1." and ".5" forms */
        switch (bits % 6) {
        case 0: snprintf(b, bl, "%s0.%s", bits & 8 ? "-" : "+", bits & 16 ? "0" : ""); break;
        case 1: snprintf(b, bl, "-0.0D0"); break;
        case 2: snprintf(b, bl, "%025.12f", r * 1000.0); break;
        case 3: snprintf(b, bl, "%.0f.", r * 1e6); break;
        case 4: snprintf(b, bl, "0000.%s", "00000000000000000000001250000"); break;
        default: snprintf(b, bl, "%.17g000000", r); break;
        }
        break;
    case 15: /* 17 digits, D exponents over the whole range */
        snprintf(b, bl, "%.16E", (r + 0.1) * pow(10.0, (int)(bits % 600) - 300));
        *strchr(b, 'E') = 'D';
        break;
    default: snprintf(b, bl, "%lluE-%d", bits % 10000000ULL, (int)(bits >> 50) % 40); break;
    }
}

/* Every real the reader parses equals strtod's value of the same text (its
 * Fortran D read as E): bit for bit, over formats writers use and the hard
 * cases (long mantissas, exact midpoints, huge, tiny, subnormal, blanks and
 * tabs, numbers split across lines). Odd rounds end the 128 with Hollerith
 * strings holding both delimiters (fields a count must not split). */
static void test_numbers_as_strtod(void **state)
{
    (void)state;
    enum { K = 15, N = (K + 1) * (K + 1), ROUNDS = 8 };
    unsigned long long st = 0x9E3779B97F4A7C15ULL;
    char path[600];
    tmp_path(path, sizeof path, "num.igs");
    for (int round = 0; round < ROUNDS; round++) {
        static char params[N * 3 * 80 + 4096];
        static char text[N * 3][72];
        char *e = params;
        e += sprintf(e, "128,%d,%d,1,1,0,0,1,0,0", K, K);
        for (int d = 0; d < 2; d++)
            for (int i = 0; i < K + 3; i++)
                e += sprintf(e, ",%d.", i == 0 ? 0 : i > K ? K : i - 1);
        for (int i = 0; i < N; i++)
            e += sprintf(e, ",1.");
        for (int i = 0; i < 3 * N; i++) {
            st ^= st << 13, st ^= st >> 7, st ^= st << 17;
            num_text(text[i], sizeof text[i], i + round, (double)(st >> 11) / 9007199254740992.0,
                     st);
            e += sprintf(e, ",%s", text[i]);
        }
        /* Hollerith strings that a count ignoring them would take for 10 or
         * 4 fields, making the reader look for a parameter range there */
        sprintf(e, "%s;", round % 4 == 1 ? ",9H,,,,,,,,," : round % 4 == 3 ? ",3h,,," : "");
        write_one(path, params);
        nf_surf_t s;
        int rc = cf_iges_read(path, 0, &s, msg, sizeof msg);
        if (rc)
            fail_msg("round %d: %s", round, msg);
        for (int i = 0; i < 3 * N; i++) {
            char t[72];
            memcpy(t, text[i], sizeof t);
            char *dd = strpbrk(t, "Dd");
            if (dd)
                *dd = 'E';
            double want = strtod(t, NULL);
            if (memcmp(&want, &s.cp[i], sizeof want))
                fail_msg("'%s': read %.17g, strtod %.17g", text[i], s.cp[i], want);
        }
        cf_surf_free(&s);
    }
    remove(path);
}

static void test_counts(void **state)
{
    (void)state;
    /* The board's highest degree reads, one more is refused. */
    char *ok = params_128(NF_MAX_DEGREE + 1, NF_MAX_DEGREE);
    expect_one(ok, CF_OK, NULL);
    free(ok);
    char *deg = params_128(NF_MAX_DEGREE + 1, NF_MAX_DEGREE + 1);
    expect_one(deg, NF_EDEGREE, "line 5 (P record 1");
    free(deg);
    /* Counts far beyond the data: refused before any allocation. */
    expect_one("128,999999999,999999999,3,3,0,0,1,0,0,0.,0.,0.,0.,1.,1.,1.,1.;", CF_EPARSE,
               "need 4000000002000000018");
    expect_one("128,2147483647,3,3,3,0,0,1,0,0,0.;", CF_EPARSE, "line 5 (P record 1");
    expect_one("128,-1,3,3,3,0,0,1,0,0,0.;", CF_EPARSE, "negative");
    expect_one("128,3,3,3;", CF_EPARSE, "at least 10");
    /* The least square net over the board's NF_MAX_CP, all points present
     * (sim: 201 x 201; linux-cell: 1049 x 1049). */
    int side = 1;
    while ((long)side * side <= NF_MAX_CP)
        side++;
    char *big = params_128(side - 1, 1), what[64];
    snprintf(what, sizeof what, "%d x %d", side, side);
    expect_one(big, NF_EBUDGET, what);
    free(big);
    /* One value short. */
    char *shrt = params_128(3, 3);
    char *semi = strrchr(shrt, ',');
    strcpy(semi, ";");
    expect_one(shrt, CF_EPARSE, "need ");
    free(shrt);
    /* No record delimiter. */
    expect_one("128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.", CF_EPARSE, "record delimiter");
}

static void test_damaged_files(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    tmp_path(path, sizeof path, "dmg.igs");
    /* Truncated after P record 3 (line 23): no T line. */
    static const char *cut[24];
    for (int i = 0; i < 23; i++)
        cut[i] = iges_a[i];
    cut[23] = NULL;
    expect_a(cut, 0, CF_EPARSE, "line 23");
    expect_a(cut, 0, CF_EPARSE, "truncated");
    /* Truncated in the middle of a line. */
    write_lines(path, iges_a, EOL_LF);
    long n;
    char *b = slurp(path, &n);
    write_bytes(path, b, 81 * 22 + 30);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EPARSE);
    assert_msg(path, "line 23");
    free(b);
    /* T counts that disagree with the file. */
    expect_a(patched(iges_a, 42, 25, "P     20"), 0, CF_EPARSE, "line 42");
    /* A P line missing (sequence numbers jump). */
    static const char *gap[43];
    int k = 0;
    for (int i = 0; iges_a[i]; i++)
        if (i != 24)
            gap[k++] = iges_a[i];
    gap[k] = NULL;
    expect_a(gap, 0, CF_EPARSE, "line 25");
    /* Sections out of order: a D line among the P lines. */
    expect_a(patched(iges_a, 30, 73, "D"), 0, CF_EPARSE, "line 30");
    /* A column-73 letter that is no section. */
    expect_a(patched(iges_a, 3, 73, "X"), 0, CF_EPARSE, "line 3");
    /* The parameter pointer of DE 3 beyond the P section. */
    expect_a(patched(iges_a, 9, 9, "      99"), 0, CF_EPARSE, "DE 3");
    /* Its line count beyond the file (the P data's room is sized by the
     * count, bounded by the file's size): refused, nothing allocated for
     * the count. */
    expect_a(patched(iges_a, 10, 25, "     500"), 0, CF_EPARSE, "DE 3");
    expect_a(patched(iges_a, 10, 25, " 9999999"), 0, CF_EPARSE, "DE 3");
    /* Empty file, blank file. */
    write_bytes(path, "", 0);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EPARSE);
    assert_msg(path, "line 1");
    write_bytes(path, "\n\n  \n", 5);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EPARSE);
    assert_msg(path, "line");
    /* Not there. */
    tmp_path(path, sizeof path, "missing.igs");
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EIO);
    assert_msg(path, "cannot open");
}

static void test_binary_input(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    unsigned char junk[4096];
    tmp_path(path, sizeof path, "bin.igs");
    for (size_t i = 0; i < sizeof junk; i++)
        junk[i] = next_byte();
    junk[5] = 0;
    write_bytes(path, junk, sizeof junk);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EPARSE);
    assert_msg(path, "line 1");
    /* Text with a NUL on line 3. */
    char text[81 * 4];
    snprintf(text, sizeof text, "%s\n%s\n%s\n", iges_a[0], iges_a[1], iges_a[2]);
    text[81 * 2 + 10] = '\0';
    write_bytes(path, text, 81 * 3);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EPARSE);
    assert_msg(path, "line 3");
    assert_msg(path, "binary");
    /* Binary IGES: 'B' in column 73 of the first record. */
    char flag[160];
    memset(flag, ' ', sizeof flag);
    flag[72] = 'B';
    flag[80] = 1;
    write_bytes(path, flag, sizeof flag);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_msg(path, "binary IGES");
    flag[72] = 'C';
    write_bytes(path, flag, 80);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_msg(path, "compressed");
    write_bytes(path, "\x1f\x8b\x08\x00rest", 8);
    assert_int_equal(cf_iges_read(path, 0, &s, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_msg(path, "gzip");
    remove(path);
}

/* Random damage to fixture A must give a code, never a crash (run under
 * ASan in make test); successes must still be valid surfaces. */
static void test_mutations(void **state)
{
    (void)state;
    char path[600];
    nf_surf_t s;
    long n;
    tmp_path(path, sizeof path, "mut.igs");
    write_lines(path, iges_a, EOL_LF);
    char *orig = slurp(path, &n);
    char *b = malloc((size_t)n);
    assert_non_null(b);
    static const char alphabet[] = "0123456789.,;+-EDH  \n/PT1";
    for (int it = 0; it < 3000; it++) {
        memcpy(b, orig, (size_t)n);
        int k = 1 + (int)(urand() * 4);
        for (int j = 0; j < k; j++) {
            long at = (long)(urand() * (double)n);
            b[at] = urand() < 0.9 ? alphabet[(int)(urand() * (sizeof alphabet - 1))]
                                  : (char)(next_byte());
        }
        long len = urand() < 0.1 ? (long)(urand() * (double)n) : n;
        write_bytes(path, b, (size_t)len);
        int rc = cf_iges_read(path, urand() < 0.5 ? 0 : 11, &s, msg, sizeof msg);
        if (rc == CF_OK) {
            assert_int_equal(nf_surf_check(&s), NF_OK);
            cf_surf_free(&s);
        } else {
            assert_null(s.U);
            assert_true(strlen(msg) > 0);
        }
    }
    free(b);
    free(orig);
    remove(path);
}

int main(void)
{
    make_tmpdir();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fixtures_are_80_columns),
        cmocka_unit_test(test_first_128),
        cmocka_unit_test(test_second_128_by_de),
        cmocka_unit_test(test_units_to_mm),
        cmocka_unit_test(test_de_not_a_128),
        cmocka_unit_test(test_delimiters_and_matrix),
        cmocka_unit_test(test_line_endings),
        cmocka_unit_test(test_roundtrip_bit_exact),
        cmocka_unit_test(test_written_structure),
        cmocka_unit_test(test_write_uses_source_date_epoch),
        cmocka_unit_test(test_write_failures_leave_nothing),
        cmocka_unit_test(test_garbled_number),
        cmocka_unit_test(test_invalid_surfaces),
        cmocka_unit_test(test_numbers_as_strtod),
        cmocka_unit_test(test_counts),
        cmocka_unit_test(test_damaged_files),
        cmocka_unit_test(test_binary_input),
        cmocka_unit_test(test_mutations),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
