/* SPDX-License-Identifier: MIT */
/* test_trim.c: trimmed faces (cf_trim, cf_iges_read_trim, the trimmed
 * writers). The 3-D edge over a trim curve is checked against closed
 * forms on an affine surface S(u, v) = (100 u, 80 v, 3 u + 2 v): a cubic
 * trim curve maps to a cubic, which the cubic interpolation must reproduce
 * exactly; a circle maps to an ellipse, on which every point of the edge
 * must lie within its stated error. IGES written trimmed reads back to the
 * same trim bit for bit (one-curve and many-curve loops, a rational curve);
 * STEP written trimmed holds its bounds and the same surface, and reads back
 * to the same trim bit for bit; open loops and curves off the domain are
 * refused. OpenCASCADE's view of these files is
 * tests/cli/trim.sh's. */

#include "cf_err.h"
#include "cf_iges.h"
#include "cf_step.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_test.h"
#include "cf_trim.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char msg[1024];

static void tmp_path(char *buf, size_t n, const char *name)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(buf, n, "%s/cf_trim_%ld_%s", d && *d ? d : "/tmp", (long)getpid(), name);
}

/* S(u, v) = (100 u, 80 v, 3 u + 2 v) on [0, 1]^2: degree 1, 2 x 2. */
static void affine(nf_surf_t *s)
{
    assert_int_equal(cf_surf_alloc(s, 1, 1, 2, 2), CF_OK);
    const double U[4] = {0, 0, 1, 1};
    const double P[12] = {0, 0, 0, 100, 0, 3, 0, 80, 2, 100, 80, 5};
    memcpy(s->U, U, sizeof U);
    memcpy(s->V, U, sizeof U);
    memcpy(s->cp, P, sizeof P);
}

static void exact(double u, double v, double out[3])
{
    out[0] = 100 * u, out[1] = 80 * v, out[2] = 3 * u + 2 * v;
}

/* A cubic Bezier in (u, v) with control points B (u, v pairs). */
static void bezier(nf_curve_t *c, const double B[8])
{
    assert_int_equal(cf_curve_alloc(c, 3, 4), CF_OK);
    const double U[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    memcpy(c->U, U, sizeof U);
    for (int i = 0; i < 4; i++)
        c->cp[3 * i] = B[2 * i], c->cp[3 * i + 1] = B[2 * i + 1], c->cp[3 * i + 2] = 0;
}

/* The full circle of centre (a, b), radius r as a rational quadratic of 9
 * points (NURBS Book Ex. 7.2 layout), parameter [0, 1]. */
static void circle(nf_curve_t *c, double a, double b, double r)
{
    assert_int_equal(cf_curve_alloc(c, 2, 9), CF_OK);
    const double U[12] = {0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1};
    const double d[9][2] = {{1, 0},   {1, 1},  {0, 1},  {-1, 1}, {-1, 0},
                            {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    memcpy(c->U, U, sizeof U);
    for (int i = 0; i < 9; i++) {
        c->cp[3 * i] = a + r * d[i][0];
        c->cp[3 * i + 1] = b + r * d[i][1];
        c->w[i] = i % 2 ? sqrt(0.5) : 1.0;
    }
}

static void line(nf_curve_t *c, double u0, double v0, double u1, double v1)
{
    assert_int_equal(cf_curve_alloc(c, 1, 2), CF_OK);
    const double U[4] = {0, 0, 1, 1};
    memcpy(c->U, U, sizeof U);
    c->cp[0] = u0, c->cp[1] = v0, c->cp[3] = u1, c->cp[4] = v1;
}

static void test_edge_cubic_exact(void **state)
{
    (void)state;
    nf_surf_t s;
    nf_curve_t c, e;
    double err = -1;
    affine(&s);
    const double B[8] = {0.1, 0.2, 0.7, 0.05, 0.3, 0.9, 0.85, 0.6};
    bezier(&c, B);
    assert_int_equal(cf_trim_edge3d(&s, &c, CF_TRIM_EDGE_TOL, &e, &err), CF_OK);
    assert_true(err >= 0 && err < 1e-10);
    assert_int_equal(e.n, 9); /* the first try: a cubic is exact */
    for (int k = 0; k <= 1000; k++) {
        double t = k / 1000.0, m = 1 - t, uv[2], P[3], Q[3];
        for (int j = 0; j < 2; j++) /* Bernstein form, not our evaluator */
            uv[j] = m * m * m * B[j] + 3 * m * m * t * B[2 + j] + 3 * m * t * t * B[4 + j] +
                    t * t * t * B[6 + j];
        exact(uv[0], uv[1], P);
        nf_curve_eval(&e, t, Q);
        for (int j = 0; j < 3; j++)
            assert_near(Q[j], P[j], 1e-10);
    }
    cf_curve_free(&e);
    cf_curve_free(&c);
    cf_surf_free(&s);
}

static void test_edge_circle_within_error(void **state)
{
    (void)state;
    nf_surf_t s;
    nf_curve_t c, e;
    double err = -1;
    affine(&s);
    circle(&c, 0.5, 0.5, 0.3);
    assert_int_equal(cf_trim_edge3d(&s, &c, CF_TRIM_EDGE_TOL, &e, &err), CF_OK);
    assert_true(err > 0 && err <= CF_TRIM_EDGE_TOL);
    double worst = 0;
    for (int k = 0; k <= 4000; k++) {
        double Q[3];
        nf_curve_eval(&e, k / 4000.0, Q);
        /* Back to (u, v) by the affine map's inverse: on the circle, and z on the plane. */
        double u = Q[0] / 100, v = Q[1] / 80;
        worst = fmax(worst, fabs(hypot(u - 0.5, v - 0.5) - 0.3) * 80);
        assert_near(Q[2], 3 * u + 2 * v, 1e-9);
    }
    assert_true(worst <=
                1.5 * err); /* the stated error bounds the edge (midpoints are its worst) */
    cf_curve_free(&e);
    cf_curve_free(&c);
    cf_surf_free(&s);
}

/* Outer: one rational circle; holes: a triangle of three lines, and one cubic loop closed by a line. */
static void make_trim(cf_trim_t *t)
{
    memset(t, 0, sizeof *t);
    nf_curve_t *o = calloc(1, sizeof *o), *h = calloc(3, sizeof *h), *g = calloc(2, sizeof *g);
    assert_non_null(o);
    assert_non_null(h);
    assert_non_null(g);
    circle(o, 0.5, 0.5, 0.45);
    line(&h[0], 0.3, 0.3, 0.3, 0.45);
    line(&h[1], 0.3, 0.45, 0.45, 0.3);
    line(&h[2], 0.45, 0.3, 0.3, 0.3);
    const double B[8] = {0.6, 0.6, 0.75, 0.62, 0.7, 0.8, 0.6, 0.7};
    bezier(&g[0], B);
    line(&g[1], 0.6, 0.7, 0.6, 0.6);
    assert_int_equal(cf_trim_add_loop(t, o, 1), CF_OK);
    assert_int_equal(cf_trim_add_loop(t, h, 3), CF_OK);
    assert_int_equal(cf_trim_add_loop(t, g, 2), CF_OK);
}

static void test_iges_roundtrip(void **state)
{
    (void)state;
    nf_surf_t s, r;
    cf_trim_t t, back;
    char path[512];
    double err = -1;
    affine(&s);
    make_trim(&t);
    tmp_path(path, sizeof path, "t.igs");
    assert_int_equal(cf_surfio_write_trimmed(path, &s, &t, "trim", NULL, &err, msg, sizeof msg),
                     CF_OK);
    assert_true(err >= 0 && err <= CF_TRIM_EDGE_TOL);
    assert_int_equal(cf_iges_read_trim(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_int_equal(back.nloops, 3);
    assert_true(cf_trim_equal(&t, &back));
    assert_int_equal(cf_iges_read(path, 0, &r, msg, sizeof msg), CF_OK);
    assert_memory_equal(r.cp, s.cp, sizeof(double) * 12);
    cf_surf_free(&r);
    cf_trim_free(&back);
    /* N1 = 0 in the 144: the outer boundary is the domain's four sides. */
    FILE *f = fopen(path, "r+b");
    assert_non_null(f);
    static char text[1 << 20];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    char *at = strstr(text, "\n144,1,1,2,");
    assert_non_null(at);
    at[7] = '0'; /* same length: the fixed columns stay */
    rewind(f);
    assert_int_equal(fwrite(text, 1, n, f), n);
    fclose(f);
    assert_int_equal(cf_iges_read_trim(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_int_equal(back.nloops, 3);
    assert_int_equal(back.loop[0].n, 4);
    assert_near(back.loop[0].c[1].cp[0], 1.0, 0); /* (u1, v0) to (u1, v1) */
    assert_near(back.loop[0].c[1].cp[4], 1.0, 0);
    assert_true(cf_trim_equal(&(cf_trim_t){2, t.loop + 1}, &(cf_trim_t){2, back.loop + 1}));
    cf_trim_free(&back);
    /* Not trimmed: no loops. */
    assert_int_equal(cf_iges_write(path, &s, "plain", msg, sizeof msg), CF_OK);
    assert_int_equal(cf_surfio_read_trim(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_int_equal(back.nloops, 0);
    remove(path);
    cf_trim_free(&t);
    cf_surf_free(&s);
}

static int count(const char *text, const char *what)
{
    int n = 0;
    for (const char *p = strstr(text, what); p; p = strstr(p + 1, what))
        n++;
    return n;
}

static void test_step_bounds(void **state)
{
    (void)state;
    nf_surf_t s, r;
    cf_trim_t t;
    char path[512];
    affine(&s);
    make_trim(&t);
    tmp_path(path, sizeof path, "t.stp");
    assert_int_equal(cf_surfio_write_trimmed(path, &s, &t, "trim", "v", NULL, msg, sizeof msg),
                     CF_OK);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char text[1 << 20];
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = '\0';
    fclose(f);
    assert_int_equal(count(text, "ADVANCED_FACE("), 1);
    assert_int_equal(count(text, "FACE_OUTER_BOUND("), 1);
    assert_int_equal(count(text, "=FACE_BOUND("), 2);
    assert_int_equal(count(text, "EDGE_LOOP("), 3);
    assert_int_equal(count(text, "EDGE_CURVE("), 6);
    assert_int_equal(count(text, "=PCURVE("), 6);
    assert_int_equal(count(text, "SURFACE_CURVE("), 6);
    assert_int_equal(count(text, "VERTEX_POINT("), 6);
    assert_int_equal(cf_step_read(path, 0, &r, msg, sizeof msg), CF_OK);
    assert_memory_equal(r.cp, s.cp, sizeof(double) * 12);
    cf_surf_free(&r);
    /* Read back: the same loops, curves in the same order and direction. */
    cf_trim_t back;
    assert_int_equal(cf_step_read_trim(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_int_equal(back.nloops, 3);
    assert_true(cf_trim_equal(&t, &back));
    cf_trim_free(&back);
    /* An untrimmed STEP face (3-D edges only): the whole surface. */
    assert_int_equal(cf_step_write(path, &s, "plain", "v", msg, sizeof msg), CF_OK);
    assert_int_equal(cf_surfio_read_trim(path, 0, &back, msg, sizeof msg), CF_OK);
    assert_int_equal(back.nloops, 0);
    remove(path);
    cf_trim_free(&t);
    cf_surf_free(&s);
}

static void test_refused(void **state)
{
    (void)state;
    nf_surf_t s;
    cf_trim_t t;
    char path[512];
    affine(&s);
    tmp_path(path, sizeof path, "bad.igs");
    /* An open loop: two lines that do not meet. */
    memset(&t, 0, sizeof t);
    nf_curve_t *c = calloc(2, sizeof *c);
    assert_non_null(c);
    line(&c[0], 0.1, 0.1, 0.9, 0.1);
    line(&c[1], 0.9, 0.2, 0.1, 0.1);
    assert_int_equal(cf_trim_add_loop(&t, c, 2), CF_OK);
    assert_int_equal(cf_surfio_write_trimmed(path, &s, &t, "x", NULL, NULL, msg, sizeof msg),
                     CF_EARG);
    assert_non_null(strstr(msg, "open"));
    assert_int_equal(access(path, F_OK), -1);
    cf_trim_free(&t);
    /* A curve off the domain. */
    c = calloc(1, sizeof *c);
    assert_non_null(c);
    circle(c, 0.5, 0.5, 0.6);
    assert_int_equal(cf_trim_add_loop(&t, c, 1), CF_OK);
    assert_int_equal(cf_surfio_write_trimmed(path, &s, &t, "x", NULL, NULL, msg, sizeof msg),
                     CF_EARG);
    assert_non_null(strstr(msg, "outside"));
    cf_trim_free(&t);
    /* The domain's sides as a loop: closed and inside. */
    assert_int_equal(cf_trim_add_domain(&t, &s), CF_OK);
    assert_int_equal(cf_trim_check(&t, &s, 1e-12, msg, sizeof msg), CF_OK);
    cf_trim_free(&t);
    cf_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edge_cubic_exact), cmocka_unit_test(test_edge_circle_within_error),
        cmocka_unit_test(test_iges_roundtrip),   cmocka_unit_test(test_step_bounds),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
