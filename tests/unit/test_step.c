/* SPDX-License-Identifier: MIT */
/* test_step.c: STEP AP242 surfaces (cf_step) and the extension dispatcher
 * (cf_surfio). Writing is checked by reading back bit-exactly (plain and
 * rational, several degrees, repeated interior knots, awkward numbers) and
 * by looking for the entities CAD systems need in the written text; reading
 * by a hand-written fixture in another writer's style (spaces, comments,
 * lower-case, a complex entity, metres, two surfaces) whose expected
 * numbers are typed in, and by damaged files whose errors name the line.
 * OpenCASCADE's reading of our files is checked in tests/cli/step.sh. */

#include "cf_err.h"
#include "cf_step.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_surf.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[512];
static char msg[1024];
static unsigned long long rng = 0x9E3779B97F4A7C15ULL;

static double unif(void) /* [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1p-53;
}

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
    snprintf(buf, n, "%s/cf_step_%ld_%s", tmpdir, (long)getpid(), name);
}

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)len + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)len, f), (size_t)len);
    b[len] = '\0';
    fclose(f);
    return b;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static int count(const char *hay, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle))
        n++;
    return n;
}

/* A random valid surface: clamped knots with a doubled interior knot when
 * there is room, coordinates of all magnitudes and signs, weights in
 * (0.2, 5) when rational. */
static void random_surface(nf_surf_t *s, int p, int q, int nu, int nv, int rational)
{
    assert_int_equal(cf_surf_alloc(s, p, q, nu, nv), CF_OK);
    for (int d = 0; d < 2; d++) {
        int deg = d ? q : p, n = d ? nv : nu;
        double *U = d ? s->V : s->U, a = -3.7 + unif(), b = a + 0.1 + 10 * unif();
        for (int i = 0; i <= deg; i++) {
            U[i] = a;
            U[n + i] = b;
        }
        for (int i = deg + 1; i < n; i++)
            U[i] = a + (b - a) * (i - deg) / (double)(n - deg);
        if (n - deg >= 3 && deg >= 2) /* a double interior knot */
            U[deg + 2] = U[deg + 1];
    }
    long n = (long)nu * nv;
    static const double scale[] = {1e-12, 1.0, 123.456, 1e6};
    for (long i = 0; i < 3 * n; i++)
        s->cp[i] = (unif() - 0.5) * scale[i % 4] * 7.0;
    for (long i = 0; i < n; i++)
        s->w[i] = rational ? 0.2 + 4.8 * unif() : 1.0;
    assert_int_equal(nf_surf_check(s), NF_OK);
}

static void assert_same(const nf_surf_t *a, const nf_surf_t *b)
{
    assert_int_equal(a->p, b->p);
    assert_int_equal(a->q, b->q);
    assert_int_equal(a->nu, b->nu);
    assert_int_equal(a->nv, b->nv);
    long n = (long)a->nu * a->nv;
    assert_memory_equal(a->U, b->U, sizeof(double) * (size_t)(a->nu + a->p + 1));
    assert_memory_equal(a->V, b->V, sizeof(double) * (size_t)(a->nv + a->q + 1));
    assert_memory_equal(a->cp, b->cp, sizeof(double) * (size_t)(3 * n));
    assert_non_null(b->w);
    for (long i = 0; i < n; i++)
        assert_memory_equal(&b->w[i], a->w ? &a->w[i] : &(double){1.0}, sizeof(double));
}

static void test_roundtrip_bit_exact(void **state)
{
    (void)state;
    static const int shape[][4] = {
        {1, 1, 2, 2}, {2, 3, 7, 5}, {3, 3, 9, 12}, {5, 2, 6, 11}, {1, 4, 30, 5}};
    char path[600];
    tmp_path(path, sizeof path, "rt.stp");
    for (size_t k = 0; k < sizeof shape / sizeof shape[0]; k++)
        for (int rational = 0; rational < 2; rational++) {
            nf_surf_t s, r;
            random_surface(&s, shape[k][0], shape[k][1], shape[k][2], shape[k][3], rational);
            assert_int_equal(cf_step_write(path, &s, "part", "1.2.3", msg, sizeof msg), CF_OK);
            assert_int_equal(cf_step_read(path, 0, &r, msg, sizeof msg), CF_OK);
            assert_same(&s, &r);
            char *t = read_text(path);
            /* The rational form only where weights differ from 1. */
            assert_int_equal(count(t, "RATIONAL_B_SPLINE_SURFACE("), rational);
            assert_int_equal(count(t, "B_SPLINE_SURFACE_WITH_KNOTS("), 1);
            free(t);
            cf_surf_free(&r);
            /* Without weights at all: read back with weights 1. */
            if (!rational) {
                double *w = s.w;
                s.w = NULL;
                assert_int_equal(cf_step_write(path, &s, NULL, NULL, msg, sizeof msg), CF_OK);
                assert_int_equal(cf_step_read(path, 0, &r, msg, sizeof msg), CF_OK);
                assert_same(&s, &r);
                cf_surf_free(&r);
                s.w = w;
            }
            cf_surf_free(&s);
        }
    remove(path);
}

/* The entities and the header a CAD import looks for, counted in the text. */
static void test_written_structure(void **state)
{
    (void)state;
    nf_surf_t s;
    random_surface(&s, 3, 2, 6, 4, 1);
    char path[600], tmp[700];
    tmp_path(path, sizeof path, "structure.step");
    assert_int_equal(
        cf_step_write_at(path, &s, "panel 'A'", "0.9-test", 1700000000LL, msg, sizeof msg), CF_OK);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(exists(tmp));
    char *t = read_text(path);
    assert_ptr_equal(strstr(t, "ISO-10303-21;\nHEADER;\n"), t);
    assert_non_null(strstr(t, "FILE_SCHEMA(('AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIB_LF { 1 "
                              "0 10303 442 1 1 4 }'));"));
    assert_non_null(strstr(t, "'cellfit 0.9-test'"));
    assert_non_null(strstr(t, "'2023-11-14T22:13:20'")); /* 1700000000 */
    assert_non_null(strstr(t, "PRODUCT('panel ''A''','panel ''A'''"));
    assert_non_null(strstr(t, "SI_UNIT(.MILLI.,.METRE.)"));
    assert_int_equal(count(t, "ADVANCED_FACE("), 1);
    assert_int_equal(count(t, "OPEN_SHELL("), 1);
    assert_int_equal(count(t, "SHELL_BASED_SURFACE_MODEL("), 1);
    assert_int_equal(count(t, "MANIFOLD_SURFACE_SHAPE_REPRESENTATION("), 1);
    assert_int_equal(count(t, "EDGE_LOOP("), 1);
    assert_int_equal(count(t, "EDGE_CURVE("), 4);
    assert_int_equal(count(t, "ORIENTED_EDGE("), 4);
    assert_int_equal(count(t, "VERTEX_POINT("), 4);
    assert_int_equal(count(t, "RATIONAL_B_SPLINE_CURVE("), 4);
    assert_int_equal(count(t, "CARTESIAN_POINT("), 6 * 4 + 1);
    assert_non_null(strstr(t, "ENDSEC;\nEND-ISO-10303-21;\n"));
    free(t);
    cf_surf_free(&s);
    remove(path);
}

/* Another writer's style: comments, spaces and line breaks anywhere,
 * lower-case keywords, a plane first, the rational complex entity with its
 * parts in another order, the unit in metres, points out of order. */
static const char *fixture =
    "ISO-10303-21;\n"
    "HEADER;\n"
    "FILE_DESCRIPTION(('hand-written; fixture'),'2;1');\n"
    "FILE_NAME('f.stp','2024-01-05T10:15:00',('J. Smith; QA'),(''),'x','y','');\n"
    "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\n"
    "ENDSEC;\n"
    "DATA;\n"
    "/* units: metres */\n"
    "#5 = ( LENGTH_UNIT ( ) NAMED_UNIT ( * ) SI_UNIT ( $ , .METRE. ) ) ;\n"
    "#7 = PLANE ( 'p;(1)' , #8 ) ;\n"
    "#20 = ( BOUNDED_SURFACE() B_SPLINE_SURFACE ( 1, 2,\n"
    "  ( ( #101 , #102 , #103 ) , ( #104 , #105 , #106 ) ),\n"
    "  .UNSPECIFIED., .F., .F., .F. )\n"
    "  b_spline_surface_with_knots ( ( 2, 2 ), ( 3, 3 ), ( 0., 2.5 ), ( -1., 1.E0 ),\n"
    "  .UNSPECIFIED. )\n"
    "  GEOMETRIC_REPRESENTATION_ITEM ( ) RATIONAL_B_SPLINE_SURFACE ( (( 1., 0.5, 1. ),\n"
    "  ( 2., 1., 4.0E-01 )) ) REPRESENTATION_ITEM ( 'a ''quoted'' name' ) SURFACE ( ) ) ;\n"
    "#106 = CARTESIAN_POINT ( '' , ( 0.006, 0.002, -0.5 ) ) ;\n"
    "#101 = CARTESIAN_POINT ( '' , ( 0., 0., 0. ) ) ;\n"
    "#102=CARTESIAN_POINT('',(0.,0.001,0.));\n"
    "#103 = CARTESIAN_POINT('',(0.,0.002,1.25E-3));\n"
    "#104 = CARTESIAN_POINT('',(0.006,0.,0.));#105 = CARTESIAN_POINT('',(0.006,0.001,0.5));\n"
    "#30 = B_SPLINE_SURFACE_WITH_KNOTS('second',1,1,((#101,#102),(#104,#105)),\n"
    "  .PLANE_SURF.,.F.,.F.,.F.,(2,2),(2,2),(0.,1.),(0.,1.),.UNSPECIFIED.);\n"
    "#8 = AXIS2_PLACEMENT_3D('',#101,$,$);\n"
    "ENDSEC;\n"
    "END-ISO-10303-21;\n";

static void test_read_fixture(void **state)
{
    (void)state;
    char path[600];
    tmp_path(path, sizeof path, "fixture.stp");
    write_text(path, fixture);
    nf_surf_t s;
    assert_int_equal(cf_step_read(path, 0, &s, msg, sizeof msg), CF_OK);
    assert_int_equal(s.p, 1);
    assert_int_equal(s.q, 2);
    assert_int_equal(s.nu, 2);
    assert_int_equal(s.nv, 3);
    static const double U[] = {0, 0, 2.5, 2.5}, V[] = {-1, -1, -1, 1, 1, 1};
    assert_memory_equal(s.U, U, sizeof U);
    assert_memory_equal(s.V, V, sizeof V);
    /* STEP [u][v] to ours u fastest; metres to mm (a product, so compared
     * to the decimal value within rounding). */
    static const double P[6][3] = {{0, 0, 0},   {6, 0, 0},    {0, 1, 0},
                                   {6, 1, 500}, {0, 2, 1.25}, {6, 2, -500}};
    static const double W[6] = {1, 2, 0.5, 1, 1, 0.4};
    for (int k = 0; k < 6; k++) {
        for (int d = 0; d < 3; d++)
            assert_near(s.cp[3 * k + d], P[k][d], 1e-12);
        assert_near(s.w[k], W[k], 0);
    }
    cf_surf_free(&s);
    /* The second surface by its number; the plane is not one. */
    assert_int_equal(cf_step_read(path, 30, &s, msg, sizeof msg), CF_OK);
    assert_int_equal(s.nu, 2);
    assert_int_equal(s.nv, 2);
    assert_near(s.cp[3 * 3 + 2], 500, 1e-12); /* #105 at (1, 1) */
    cf_surf_free(&s);
    assert_int_equal(cf_step_read(path, 7, &s, msg, sizeof msg), CF_EUNSUPPORTED);
    assert_non_null(strstr(msg, "PLANE"));
    assert_non_null(strstr(msg, ":10:")); /* #7's line */
    assert_int_equal(cf_step_read(path, 99, &s, msg, sizeof msg), CF_ENOTFOUND);
    assert_null(s.U);
    remove(path);
}

/* One change to the fixture, the error it must give, and the line. */
static void damaged(const char *from, const char *to, int err, const char *line)
{
    char path[600];
    tmp_path(path, sizeof path, "damaged.stp");
    const char *at = strstr(fixture, from);
    assert_non_null(at);
    size_t n = strlen(fixture), a = (size_t)(at - fixture), fl = strlen(from), tl = strlen(to);
    char *t = malloc(n - fl + tl + 1);
    assert_non_null(t);
    memcpy(t, fixture, a);
    memcpy(t + a, to, tl);
    memcpy(t + a + tl, at + fl, n - a - fl + 1);
    write_text(path, t);
    free(t);
    nf_surf_t s;
    msg[0] = '\0';
    int rc = cf_step_read(path, 0, &s, msg, sizeof msg);
    if (rc != err)
        fail_msg("'%s' -> '%s': %s (%d), want %s: %s", from, to, cf_strerror(rc), rc,
                 cf_strerror(err), msg);
    if (line && !strstr(msg, line))
        fail_msg("'%s' -> '%s': message '%s' without '%s'", from, to, msg, line);
    assert_null(s.U);
    remove(path);
}

static void test_damaged(void **state)
{
    (void)state;
    damaged("( 2, 2 ), ( 3, 3 )", "( 2, 2 ), ( 3, 2 )", CF_EPARSE, ":14:");         /* knot count */
    damaged("( 0., 2.5 )", "( 2.5, 0. )", CF_EPARSE, ":14:");                       /* decreasing */
    damaged("#105 = CARTESIAN_POINT", "#107 = CARTESIAN_POINT", CF_EPARSE, ":11:"); /* missing */
    damaged("#103 = CARTESIAN_POINT('',(0.,0.002,1.25E-3))", "#103 = DIRECTION('',(0.,0.,1.))",
            CF_EPARSE, ":21:");
    damaged("(0.006,0.,0.)", "(0.006,0.)", CF_EPARSE, ":22:");
    damaged("( 2., 1., 4.0E-01 )", "( 2., 1. )", CF_EPARSE, NULL); /* weights and net differ */
    damaged("( 2., 1., 4.0E-01 )", "( 2., 1., -4.0E-01 )", NF_EWEIGHT, ":11:");
    damaged("( #104 , #105 , #106 )", "( #104 , #105 )", CF_EPARSE, ":12:"); /* ragged net */
    char over[32]; /* one degree over the board's (sim: 6; linux-cell: 8) */
    snprintf(over, sizeof over, "1, %d,\n", NF_MAX_DEGREE + 1);
    damaged("1, 2,\n", over, NF_EDEGREE, ":11:");
    damaged("0.006, 0.002, -0.5 ) ) ;", "0.006, 0.002, -0.5 ) )", CF_EPARSE, NULL);
    damaged("( 0.006, 0.002, -0.5 )", "( 0.006, 0.002, x0.5 )", CF_EPARSE, ":18:");
    damaged("SI_UNIT ( $ , .METRE. )", "SI_UNIT ( .KILO. , .GRAM. )", CF_EUNSUPPORTED, ":9:");
    damaged("NAMED_UNIT ( * ) SI_UNIT ( $ , .METRE. )", "CONVERSION_BASED_UNIT('INCH',#9)",
            CF_EUNSUPPORTED, ":9:");
    damaged("DATA;", "DATUM;", CF_EPARSE, NULL);
    damaged("ISO-10303-21;\nHEADER", "ISO-10303-28;\nHEADER", CF_EPARSE, ":1:");
    damaged("#30 = B_SPLINE", "#20 = B_SPLINE", CF_EPARSE, "twice");
    nf_surf_t s;
    assert_int_equal(cf_step_read("/nonexistent-cf/x.stp", 0, &s, msg, sizeof msg), CF_EIO);
}

static void test_failures_leave_nothing(void **state)
{
    (void)state;
    nf_surf_t s;
    random_surface(&s, 2, 2, 3, 3, 0);
    assert_int_equal(cf_step_write("/nonexistent-cf/x.stp", &s, NULL, NULL, msg, sizeof msg),
                     CF_EIO);
    assert_false(exists("/nonexistent-cf/x.stp.tmp"));
    char path[600], tmp[700];
    tmp_path(path, sizeof path, "dir.stp");
    assert_int_equal(mkdir(path, 0777), 0);
    assert_int_equal(cf_step_write(path, &s, NULL, NULL, msg, sizeof msg), CF_EIO);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    assert_false(exists(tmp));
    assert_int_equal(rmdir(path), 0);
    s.U[1] = 5; /* unclamped, decreasing */
    tmp_path(path, sizeof path, "bad.stp");
    assert_int_equal(cf_step_write(path, &s, NULL, NULL, msg, sizeof msg), NF_EKNOTS);
    assert_false(exists(path));
    cf_surf_free(&s);
}

/* The extension chooses the format, both ways; IGES and STEP give the same
 * surface. */
static void test_surfio(void **state)
{
    (void)state;
    nf_surf_t s, a, b;
    random_surface(&s, 3, 2, 5, 4, 1);
    char pi[600], ps[600], px[600];
    tmp_path(pi, sizeof pi, "io.IGES");
    tmp_path(ps, sizeof ps, "io.Step");
    tmp_path(px, sizeof px, "io.stl");
    assert_int_equal(cf_surfio_format(pi), CF_SURFIO_IGES);
    assert_int_equal(cf_surfio_format(ps), CF_SURFIO_STEP);
    assert_int_equal(cf_surfio_format("a.stp/x"), CF_SURFIO_UNKNOWN);
    assert_int_equal(cf_surfio_format("x.igs"), CF_SURFIO_IGES);
    assert_int_equal(cf_surfio_format("x.stpx"), CF_SURFIO_UNKNOWN);
    assert_int_equal(cf_surfio_write(pi, &s, "io", "1", msg, sizeof msg), CF_OK);
    assert_int_equal(cf_surfio_write(ps, &s, "io", "1", msg, sizeof msg), CF_OK);
    /* Another extension: written as IGES, read back by its content. */
    assert_int_equal(cf_surfio_write(px, &s, "io", "1", msg, sizeof msg), CF_OK);
    assert_true(exists(px));
    char *t = read_text(ps);
    assert_non_null(strstr(t, "ISO-10303-21;"));
    free(t);
    t = read_text(pi);
    assert_int_equal(t[72], 'S'); /* IGES Start section */
    free(t);
    assert_int_equal(cf_surfio_read(pi, 0, &a, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_surfio_read(ps, 0, &b, msg, sizeof msg), CF_OK);
    assert_same(&s, &a);
    assert_same(&s, &b);
    cf_surf_free(&a);
    assert_int_equal(cf_surfio_read(px, 0, &a, msg, sizeof msg), CF_OK);
    assert_same(&s, &a);
    cf_surf_free(&a);
    t = read_text(px);
    assert_int_equal(t[72], 'S'); /* IGES */
    free(t);
    /* A STEP file under another name is read as STEP. */
    rename(ps, px);
    assert_int_equal(cf_surfio_read(px, 0, &a, msg, sizeof msg), CF_OK);
    assert_same(&s, &a);
    cf_surf_free(&a);
    remove(px);
    cf_surf_free(&b);
    cf_surf_free(&s);
    remove(pi);
    remove(ps);
}

int main(void)
{
    make_tmpdir();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_roundtrip_bit_exact),    cmocka_unit_test(test_written_structure),
        cmocka_unit_test(test_read_fixture),           cmocka_unit_test(test_damaged),
        cmocka_unit_test(test_failures_leave_nothing), cmocka_unit_test(test_surfio),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
