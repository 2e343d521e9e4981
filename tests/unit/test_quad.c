/* SPDX-License-Identifier: MIT */
/* test_quad.c: the quadrilateral decomposition and projection of nf_quad
 * (Piegl & Tiller 2001, Section 3) against independent results: feet by
 * brute force (400 x 400 samples, Newton from the nearest), chord error by
 * sampling, shared vertices, exact circle and sphere patches (weights),
 * storage untouched by the point count, thinning against a full search;
 * the closed form on affine surfaces (nf_affine) against the brute force,
 * and the hodograph proof of a height field (nf_fold) against the shadow's
 * Jacobian and boundary sampled. */

#include "cf_test.h"
#include "nf_err.h"
#include "nf_fold.h"
#include "nf_quad.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TOL 1e-9
#define MAXQ 20000L
#define NB 400 /* brute-force samples per direction */

typedef struct fixture {
    nf_quad_t q;
    void *mem;
    size_t bytes;
} fixture_t;

static void quad_make(fixture_t *f, const nf_surf_t *s, double rel, long maxq)
{
    f->bytes = NF_QUAD_BYTES(maxq, s->nu, s->nv);
    f->mem = malloc(f->bytes);
    assert_non_null(f->mem);
    nf_quad_params_t prm = {rel, 0.0, 0};
    int rc = nf_quad_init(&f->q, s, &prm, maxq, f->mem, f->bytes);
    if (rc != NF_OK)
        fail_msg("nf_quad_init: %s", nf_strerror(rc));
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist3(const double *a, const double *b)
{
    const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot3(d, d));
}

/* Dense samples of s for the brute force. */
typedef struct dense {
    double *P;
    double dom[4];
} dense_t;

static void dense_make(dense_t *d, const nf_surf_t *s)
{
    nf_surf_domain(s, &d->dom[0], &d->dom[1], &d->dom[2], &d->dom[3]);
    d->P = malloc(sizeof(double) * 3 * NB * NB);
    assert_non_null(d->P);
    for (int j = 0; j < NB; j++)
        for (int i = 0; i < NB; i++)
            nf_surf_eval(s, d->dom[0] + (d->dom[1] - d->dom[0]) * i / (NB - 1),
                         d->dom[2] + (d->dom[3] - d->dom[2]) * j / (NB - 1),
                         d->P + 3 * (i + j * NB));
}

/* The reference foot: the nearest of the dense samples, Newton from it. */
static void brute(const nf_surf_t *s, const dense_t *d, const double Q[3], nf_proj_t *out)
{
    double best = INFINITY;
    int bi = 0;
    for (int k = 0; k < NB * NB; k++) {
        const double e = dist3(d->P + 3 * k, Q);
        if (e < best) {
            best = e;
            bi = k;
        }
    }
    const double u = d->dom[0] + (d->dom[1] - d->dom[0]) * (bi % NB) / (NB - 1);
    const double v = d->dom[2] + (d->dom[3] - d->dom[2]) * (bi / NB) / (NB - 1);
    int rc = nf_project(s, Q, u, v, TOL, out);
    assert_int_equal(rc, NF_OK);
}

/* Points Q = S(u, v) + h n (|h| <= hmax) and points beyond the boundary
 * (S at an edge pushed out along the edge's outward tangent). */
static void random_point(const nf_surf_t *s, double hmax, int k, double Q[3])
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    double u = ref_rand(u0, u1), v = ref_rand(v0, v1), d[27];
    double out_u = 0.0, out_v = 0.0;
    if (k % 10 == 9) { /* beyond an edge */
        if (ref_rand(0, 1) < 0.5) {
            u = ref_rand(0, 1) < 0.5 ? u0 : u1;
            out_u = u == u0 ? -1.0 : 1.0;
        } else {
            v = ref_rand(0, 1) < 0.5 ? v0 : v1;
            out_v = v == v0 ? -1.0 : 1.0;
        }
    }
    nf_surf_derivs(s, u, v, 1, d);
    const double *Su = d + 9, *Sv = d + 3;
    double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                   Su[0] * Sv[1] - Su[1] * Sv[0]};
    const double l = sqrt(dot3(n, n)), h = ref_rand(-hmax, hmax);
    const double lu = sqrt(dot3(Su, Su)), lv = sqrt(dot3(Sv, Sv));
    for (int c = 0; c < 3; c++)
        Q[c] = d[c] + h * n[c] / l + hmax * (out_u * Su[c] / lu + out_v * Sv[c] / lv);
}

/* nf_quad_project and the brute force give the same foot (parameters to
 * 1e-9 of the domain, or the same distance where the foot is not unique
 * to that: both are then nearest points). */
static void check_against_brute(const nf_surf_t *s, double hmax, int npts)
{
    fixture_t f;
    quad_make(&f, s, NF_QUAD_REL_TOL, MAXQ);
    dense_t d;
    dense_make(&d, s);
    for (int k = 0; k < npts; k++) {
        double Q[3];
        random_point(s, hmax, k, Q);
        nf_proj_t a, b;
        int rc = nf_quad_project(&f.q, Q, TOL, &a);
        assert_int_equal(rc, NF_OK);
        brute(s, &d, Q, &b);
        const double du = fabs(a.u - b.u) / (d.dom[1] - d.dom[0]);
        const double dv = fabs(a.v - b.v) / (d.dom[3] - d.dom[2]);
        if (!(du <= TOL && dv <= TOL))
            fail_msg("point %d (%.17g %.17g %.17g): quad foot (%.17g, %.17g) dist %.17g, brute "
                     "(%.17g, %.17g) dist %.17g",
                     k, Q[0], Q[1], Q[2], a.u, a.v, a.dist, b.u, b.v, b.dist);
        assert_near(fabs(a.dist), fabs(b.dist), 1e-9 * (1.0 + fabs(b.dist)));
        assert_int_equal(a.clamped, b.clamped);
        /* The start itself lies in the foot's quadrilateral or a neighbour
         * (the range search found the right one, not only Newton). */
        double u0, v0;
        nf_quad_start(&f.q, Q, &u0, &v0);
        int i = 0, j = 0;
        while (i + 2 < f.q.nu && f.q.ul[i + 1] < b.u)
            i++;
        while (j + 2 < f.q.nv && f.q.vl[j + 1] < b.v)
            j++;
        const double ulo = f.q.ul[i > 0 ? i - 1 : 0], uhi = f.q.ul[i + 2 < f.q.nu ? i + 2 : i + 1];
        const double vlo = f.q.vl[j > 0 ? j - 1 : 0], vhi = f.q.vl[j + 2 < f.q.nv ? j + 2 : j + 1];
        if (!(u0 >= ulo && u0 <= uhi && v0 >= vlo && v0 <= vhi))
            fail_msg("point %d: start (%.6g, %.6g) outside the foot's quadrilateral's "
                     "neighbourhood [%.6g, %.6g] x [%.6g, %.6g]",
                     k, u0, v0, ulo, uhi, vlo, vhi);
    }
    free(d.P);
    free(f.mem);
}

/* Heights of the random net scaled: waves of +-20 mm on a 10 mm net, so
 * that the distance has many valleys and a poor start lands in the wrong
 * one. */
static void wavy(nf_surf_t *s, double f)
{
    for (long k = 0; k < (long)s->nu * s->nv; k++)
        s->cp[3 * k + 2] *= f;
}

static void test_curved(void **state)
{
    (void)state;
    ref_seed(11);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 8, 7, 0.0, 1.0, 0.0, 2.0, 1.0, 1.0);
    wavy(&s, 4.0);
    check_against_brute(&s, 1.0, 300);
    ref_surf_free(&s);
    /* Rational, weights 0.5 .. 2. */
    ref_surf_random(&s, 3, 2, 6, 6, -1.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    wavy(&s, 4.0);
    check_against_brute(&s, 1.0, 300);
    ref_surf_free(&s);
}

/* A long narrow strip: 70 mm by 0.07 mm (v pulled in by 1e-3). */
static void test_thin(void **state)
{
    (void)state;
    ref_seed(12);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 8, 5, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    for (int j = 1; j < s.nv; j++)
        for (int i = 0; i < s.nu; i++) {
            double *P = s.cp + 3 * (i + (long)j * s.nu), *P0 = s.cp + 3 * i;
            for (int c = 0; c < 3; c++)
                P[c] = P0[c] + 1e-3 * (P[c] - P0[c]);
        }
    check_against_brute(&s, 0.01, 300);
    ref_surf_free(&s);
}

/* The 270-degree cylinder of radius 40 and length 100 (three quarter arcs,
 * degree 2 x 1, double knots at 1/3 and 2/3) in mem; weights 1, 1/sqrt 2
 * (exact) with rational set, else all 1 (a polynomial that folds too). */
static void cylinder270(nf_surf_t *c3, double *mem, int rational)
{
    nf_surf_wire(c3, 2, 1, 7, 2, mem);
    const double U[] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 3}, V[] = {0, 0, 1, 1};
    memcpy(c3->U, U, sizeof U);
    memcpy(c3->V, V, sizeof V);
    const double P[7][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}};
    const double c = sqrt(0.5), w[7] = {1, c, 1, c, 1, c, 1};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 7; i++) {
            double *C = c3->cp + 3 * (i + 7 * j);
            C[0] = 40 * P[i][0];
            C[1] = 40 * P[i][1];
            C[2] = 100.0 * j;
            c3->w[i + 7 * j] = rational ? w[i] : 1.0;
        }
}

/* Exact quarter cylinder (radius R, degree 2 x 1, weights 1, 1/sqrt 2, 1)
 * and sphere patch (a 90-degree meridian arc revolved by 90 degrees). */
static void cylinder(nf_surf_t *s, double R, double L, double *mem)
{
    nf_surf_wire(s, 2, 1, 3, 2, mem);
    const double U[] = {0, 0, 0, 1, 1, 1}, V[] = {0, 0, 1, 1};
    memcpy(s->U, U, sizeof U);
    memcpy(s->V, V, sizeof V);
    const double P[3][2] = {{R, 0}, {R, R}, {0, R}}, w[3] = {1, sqrt(0.5), 1};
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            double *C = s->cp + 3 * (i + 3 * j);
            C[0] = P[i][0];
            C[1] = P[i][1];
            C[2] = L * j;
            s->w[i + 3 * j] = w[i];
        }
}

static void sphere(nf_surf_t *s, double R, double *mem)
{
    nf_surf_wire(s, 2, 2, 3, 3, mem);
    const double K[] = {0, 0, 0, 1, 1, 1};
    memcpy(s->U, K, sizeof K);
    memcpy(s->V, K, sizeof K);
    const double c = sqrt(0.5);
    /* meridian (radius, height) from -45 to 45 degrees */
    const double m[3][2] = {{R * c, -R * c}, {R / c, 0}, {R * c, R * c}}, mw[3] = {1, c, 1};
    const double r[3][2] = {{1, 0}, {1, 1}, {0, 1}}, rw[3] = {1, c, 1};
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            double *C = s->cp + 3 * (i + 3 * j);
            C[0] = m[j][0] * r[i][0];
            C[1] = m[j][0] * r[i][1];
            C[2] = m[j][1];
            s->w[i + 3 * j] = rw[i] * mw[j];
        }
}

static void test_rational_exact(void **state)
{
    (void)state;
    ref_seed(13);
    double mc[NF_SURF_DOUBLES(3, 2, 2, 1)], ms[NF_SURF_DOUBLES(3, 3, 2, 2)];
    nf_surf_t cyl, sph;
    const double R = 40.0;
    cylinder(&cyl, R, 100.0, mc);
    sphere(&sph, R, ms);
    assert_int_equal(nf_surf_check(&cyl), NF_OK);
    assert_int_equal(nf_surf_check(&sph), NF_OK);
    check_against_brute(&cyl, 2.0, 200);
    check_against_brute(&sph, 2.0, 200);
    /* The distance is exact: |Q - axis| - R, |Q - centre| - R inside. */
    fixture_t fc, fs;
    quad_make(&fc, &cyl, NF_QUAD_REL_TOL, MAXQ);
    quad_make(&fs, &sph, NF_QUAD_REL_TOL, MAXQ);
    for (int k = 0; k < 200; k++) {
        const double a = ref_rand(0.05, 1.52), z = ref_rand(1, 99), rr = R + ref_rand(-3, 3);
        const double Q[3] = {rr * cos(a), rr * sin(a), z};
        nf_proj_t pr;
        assert_int_equal(nf_quad_project(&fc.q, Q, TOL, &pr), NF_OK);
        assert_near(fabs(pr.dist), fabs(rr - R), 1e-9);
        assert_near(atan2(pr.foot[1], pr.foot[0]), a, 1e-9);
        const double b = ref_rand(-0.7, 0.7);
        const double P[3] = {rr * cos(b) * cos(a), rr * cos(b) * sin(a), rr * sin(b)};
        assert_int_equal(nf_quad_project(&fs.q, P, TOL, &pr), NF_OK);
        assert_near(fabs(pr.dist), fabs(rr - R), 1e-9);
        assert_near(sqrt(dot3(pr.foot, pr.foot)), R, 1e-9);
    }
    free(fc.mem);
    free(fs.mem);
}

/* Every quadrilateral deviates from the surface by at most the tolerance:
 * |S(u, v) - B(s, t)| sampled 9 x 9 over each (B the bilinear quadrilateral
 * of its corners, (s, t) the local parameters). */
static void check_chord(const nf_surf_t *s, double rel)
{
    fixture_t f;
    quad_make(&f, s, rel, MAXQ);
    const nf_quad_t *q = &f.q;
    double worst = 0.0;
    for (int j = 0; j + 1 < q->nv; j++)
        for (int i = 0; i + 1 < q->nu; i++) {
            double C[4][3];
            nf_surf_eval(s, q->ul[i], q->vl[j], C[0]);
            nf_surf_eval(s, q->ul[i + 1], q->vl[j], C[1]);
            nf_surf_eval(s, q->ul[i], q->vl[j + 1], C[2]);
            nf_surf_eval(s, q->ul[i + 1], q->vl[j + 1], C[3]);
            for (int b = 0; b <= 8; b++)
                for (int a = 0; a <= 8; a++) {
                    const double st = a / 8.0, tt = b / 8.0;
                    double S[3], B[3];
                    nf_surf_eval(s, q->ul[i] + st * (q->ul[i + 1] - q->ul[i]),
                                 q->vl[j] + tt * (q->vl[j + 1] - q->vl[j]), S);
                    for (int c = 0; c < 3; c++)
                        B[c] = (1 - tt) * ((1 - st) * C[0][c] + st * C[1][c]) +
                               tt * ((1 - st) * C[2][c] + st * C[3][c]);
                    worst = fmax(worst, dist3(S, B));
                }
        }
    if (!(worst <= q->tol))
        fail_msg("chord error %.6g above the tolerance %.6g", worst, q->tol);
    free(f.mem);
}

static void test_flatness(void **state)
{
    (void)state;
    ref_seed(14);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 9, 8, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    check_chord(&s, 0.005);
    check_chord(&s, 0.001);
    ref_surf_free(&s);
    ref_surf_random(&s, 2, 3, 7, 6, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    check_chord(&s, 0.005);
    ref_surf_free(&s);
    double ms[NF_SURF_DOUBLES(3, 3, 2, 2)];
    sphere(&s, 40.0, ms);
    check_chord(&s, 0.002);
    /* A finer tolerance gives more quadrilaterals. */
    fixture_t a, b;
    quad_make(&a, &s, 0.005, MAXQ);
    quad_make(&b, &s, 0.0005, MAXQ);
    assert_true(nf_quad_count(&b.q) > nf_quad_count(&a.q));
    free(a.mem);
    free(b.mem);
}

/* Crack-free: the blanket is the tensor grid of the sorted parameter
 * lists, every vertex the surface point there, and neighbours' shared
 * corners the same points (no vertex of one on an edge of another). */
static void test_crack_free(void **state)
{
    (void)state;
    ref_seed(15);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 10, 6, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    fixture_t f;
    quad_make(&f, &s, 0.002, MAXQ);
    const nf_quad_t *q = &f.q;
    double u0, u1, v0, v1;
    nf_surf_domain(&s, &u0, &u1, &v0, &v1);
    assert_true(q->nu > 2 && q->nv > 2);
    assert_true(q->ul[0] == u0 && q->ul[q->nu - 1] == u1);
    assert_true(q->vl[0] == v0 && q->vl[q->nv - 1] == v1);
    for (int i = 0; i + 1 < q->nu; i++)
        assert_true(q->ul[i] < q->ul[i + 1]);
    for (int j = 0; j + 1 < q->nv; j++)
        assert_true(q->vl[j] < q->vl[j + 1]);
    for (int j = 0; j < q->nv; j++)
        for (int i = 0; i < q->nu; i++) {
            double S[3];
            nf_surf_eval(&s, q->ul[i], q->vl[j], S);
            assert_true(dist3(S, q->xyz + 3 * (i + (long)j * q->nu)) == 0.0);
        }
    /* Refinement happened locally in the lists, yet every quadrilateral's
     * corners are grid vertices: each quad's right edge is its
     * neighbour's left edge, point for point, at every subdivision. */
    for (int j = 0; j + 1 < q->nv; j++)
        for (int i = 0; i + 2 < q->nu; i++) {
            double a[3], b[3];
            nf_surf_eval(&s, q->ul[i + 1], q->vl[j], a); /* quad i's corner 10 */
            nf_surf_eval(&s, q->ul[i + 1], q->vl[j + 1], b);
            assert_true(dist3(a, q->xyz + 3 * (i + 1 + (long)j * q->nu)) == 0.0);
            assert_true(dist3(b, q->xyz + 3 * (i + 1 + (long)(j + 1) * q->nu)) == 0.0);
        }
    free(f.mem);
    ref_surf_free(&s);
}

/* Memory flat in the points: the storage is NF_QUAD_BYTES(maxq, nu, nv), fixed
 * before the first point; projecting 10 or 20000 points changes neither the
 * grid nor a byte beyond the storage (canary) nor the decomposition. */
static void test_memory_flat(void **state)
{
    (void)state;
    ref_seed(16);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 8, 8, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    const long maxq = 4000;
    const size_t bytes = NF_QUAD_BYTES(maxq, s.nu, s.nv);
    unsigned char *mem = malloc(bytes + 4096);
    assert_non_null(mem);
    memset(mem, 0, bytes); /* bytes init leaves unused are compared too (valgrind) */
    memset(mem + bytes, 0xA5, 4096);
    nf_quad_t q;
    nf_quad_params_t prm = {NF_QUAD_REL_TOL, 0.0, 0};
    assert_int_equal(nf_quad_init(&q, &s, &prm, maxq, mem, bytes), NF_OK);
    const nf_quad_t before = q;
    unsigned char *copy = malloc(bytes);
    assert_non_null(copy);
    memcpy(copy, mem, bytes);
    for (int round = 0; round < 2; round++) {
        const int m = round == 0 ? 10 : 20000;
        for (int k = 0; k < m; k++) {
            double Q[3];
            random_point(&s, 1.0, k, Q);
            nf_proj_t pr;
            assert_true(nf_quad_project(&q, Q, TOL, &pr) >= 0);
        }
        assert_int_equal(q.gx, before.gx);
        assert_int_equal(q.gy, before.gy);
        assert_int_equal(q.nu, before.nu);
        assert_int_equal(q.nv, before.nv);
        assert_int_equal(q.cstart[(long)q.gx * q.gy], before.cstart[(long)q.gx * q.gy]);
        assert_memory_equal(mem, copy, bytes); /* the storage is read only */
        for (int k = 0; k < 4096; k++)
            assert_int_equal(mem[bytes + k], 0xA5);
    }
    free(copy);
    free(mem);
    ref_surf_free(&s);
}

/* Thinning keeps, per vertex, exactly the nearest point within r: the
 * brute force over all points and vertices agrees index for index. */
static void test_thin_nearest(void **state)
{
    (void)state;
    ref_seed(17);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 7, 6, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    fixture_t f;
    quad_make(&f, &s, 0.002, MAXQ);
    const long nvx = (long)f.q.nu * f.q.nv;
    double *best = malloc(sizeof(double) * (size_t)NF_THIN_DOUBLES(MAXQ));
    long *idx = malloc(sizeof(long) * (size_t)NF_THIN_LONGS(MAXQ));
    const int M = 3000;
    double *P = malloc(sizeof(double) * 3 * M);
    assert_true(best && idx && P);
    const double r = 0.6; /* about the point spacing: many balls hold one point or none */
    nf_thin_t t;
    assert_int_equal(nf_thin_init(&t, &f.q, r, best, idx), NF_OK);
    assert_int_equal(nf_thin_verts(&t), nvx);
    for (int k = 0; k < M; k++) {
        random_point(&s, 1.0, k, P + 3 * k);
        assert_int_equal(nf_thin_add(&t, P + 3 * k, k), NF_OK);
    }
    long kept = 0;
    for (long v = 0; v < nvx; v++) {
        const double *V = f.q.xyz + 3 * v;
        long bk = -1;
        double bd = INFINITY;
        for (int k = 0; k < M; k++) {
            const double d = dist3(P + 3 * k, V);
            if (d <= r && d < bd) {
                bd = d;
                bk = k;
            }
        }
        assert_int_equal(idx[v], bk);
        if (bk >= 0) {
            kept++;
            assert_memory_equal(best + 4 * v + 1, P + 3 * bk, 3 * sizeof(double));
        }
    }
    assert_true(kept > 0 && kept < M);
    free(P);
    free(idx);
    free(best);
    free(f.mem);
    ref_surf_free(&s);
}

/* A cylinder beyond 180 degrees folds over in its maximum-area plane; a
 * quarter does not. */
static void test_fold(void **state)
{
    (void)state;
    double mc[NF_SURF_DOUBLES(3, 2, 2, 1)];
    nf_surf_t cyl;
    cylinder(&cyl, 40.0, 100.0, mc);
    fixture_t f;
    quad_make(&f, &cyl, NF_QUAD_REL_TOL, MAXQ);
    assert_int_equal(f.q.folded, 0);
    free(f.mem);
    /* 270 degrees: three quarter arcs, double knots at 1/3 and 2/3. */
    double m3[NF_SURF_DOUBLES(7, 2, 2, 1)];
    nf_surf_t c3;
    cylinder270(&c3, m3, 1);
    assert_int_equal(nf_surf_check(&c3), NF_OK);
    quad_make(&f, &c3, NF_QUAD_REL_TOL, MAXQ);
    assert_int_equal(f.q.folded, 1);
    free(f.mem);
}

/* Far points are counted (and dropped on request); feet on the boundary
 * are counted as clamped; a budget too small is refused. */
static void test_flags_and_budget(void **state)
{
    (void)state;
    double mc[NF_SURF_DOUBLES(3, 2, 2, 1)];
    nf_surf_t cyl;
    cylinder(&cyl, 40.0, 100.0, mc);
    const size_t bytes = NF_QUAD_BYTES(MAXQ, cyl.nu, cyl.nv);
    void *mem = malloc(bytes);
    assert_non_null(mem);
    nf_quad_t q;
    nf_quad_params_t prm = {NF_QUAD_REL_TOL, 5.0, 1};
    assert_int_equal(nf_quad_init(&q, &cyl, &prm, MAXQ, mem, bytes), NF_OK);
    nf_proj_t pr;
    const double near[3] = {41 * cos(0.5), 41 * sin(0.5), 50}, far[3] = {50, 30, 50};
    const double beyond[3] = {40 * cos(0.5), 40 * sin(0.5), 103};
    assert_int_equal(nf_quad_project(&q, near, TOL, &pr), NF_OK);
    assert_int_equal(q.n_far, 0);
    assert_int_equal(nf_quad_project(&q, far, TOL, &pr), NF_QUAD_DROPPED);
    assert_int_equal(q.n_far, 1);
    assert_int_equal(nf_quad_project(&q, beyond, TOL, &pr), NF_OK);
    assert_int_equal(pr.clamped, 1);
    assert_near(pr.v, 1.0, 0.0);
    assert_int_equal(q.n_clamped, 1);
    /* Refusals. */
    assert_int_equal(nf_quad_init(&q, &cyl, &prm, MAXQ, mem, bytes - 1), NF_EARENA);
    prm.rel_tol = 1e-5;
    assert_int_equal(nf_quad_init(&q, &cyl, &prm, 8, mem, bytes), NF_EBUDGET);
    prm.rel_tol = 0.0;
    assert_int_equal(nf_quad_init(&q, &cyl, &prm, MAXQ, mem, bytes), NF_EARG);
    free(mem);
}

/* The power form of a polynomial bicubic's spans (nf_quad_power) against
 * A4.4's derivatives (nf_surf_derivs) at random parameters, its layout as
 * the header states it; Newton's feet with it as without it; and the
 * surfaces it is not for left on the basis path. */
static double power_eval(const double *C, double x, double y, int du, int dv, int c)
{
    static const double f[4][4] = {
        {1, 1, 1, 1}, {0, 1, 2, 3}, {0, 0, 2, 6}}; /* d^k s^m / s^(m-k) */
    double r = 0.0;
    for (int n = dv; n < 4; n++)
        for (int m = du; m < 4; m++)
            r += C[16 * n + 4 * m + c] * f[du][m] * pow(x, m - du) * f[dv][n] * pow(y, n - dv);
    return r;
}

static void test_power_form(void **state)
{
    (void)state;
    ref_seed(21);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 9, 8, 0.0, 1.0, 0.0, 2.0, 1.0, 1.0);
    wavy(&s, 4.0);
    const size_t nb = NF_QUAD_NEWTON_BYTES(s.nu, s.nv), pb = NF_QUAD_POWER_BYTES(s.nu, s.nv);
    assert_int_equal(pb, sizeof(double) * 64 * (s.nu - 3) * (s.nv - 3));
    void *m1 = malloc(nb), *m2 = malloc(nb);
    double *pf = malloc(pb);
    assert_true(m1 && m2 && pf);
    nf_quad_t a, b;
    assert_int_equal(nf_quad_newton_init(&a, &s, m1, nb), NF_OK);
    assert_int_equal(nf_quad_newton_init(&b, &s, m2, nb), NF_OK);
    assert_int_equal(nf_quad_power(&a, pf, pb - 1), NF_EARENA);
    assert_null(a.pf);
    assert_int_equal(nf_quad_power(&a, pf, pb), NF_OK);
    assert_ptr_equal(a.pf, pf);
    double u0, u1, v0, v1, size = 0.0;
    nf_surf_domain(&s, &u0, &u1, &v0, &v1);
    for (long k = 0; k < 3L * s.nu * s.nv; k++)
        size = fmax(size, fabs(s.cp[k]));
    /* (order in u, order in v) -> nf_surf_derivs's index (k u, l v: 3 (3 k + l)) */
    static const int ord[6][2] = {{0, 0}, {1, 0}, {0, 1}, {2, 0}, {1, 1}, {0, 2}};
    for (int t = 0; t < 2000; t++) {
        const double u = ref_rand(u0, u1), v = ref_rand(v0, v1);
        const int l = nf_find_span(s.nu - 1, 3, u, s.U), k = nf_find_span(s.nv - 1, 3, v, s.V);
        const double *C = pf + 64 * ((l - 3) + (long)(k - 3) * (s.nu - 3));
        double d[27];
        nf_surf_derivs(&s, u, v, 2, d);
        for (int e = 0; e < 6; e++)
            for (int c = 0; c < 3; c++) {
                const double want = d[3 * (3 * ord[e][0] + ord[e][1]) + c];
                const double got = power_eval(C, u - s.U[l], v - s.V[k], ord[e][0], ord[e][1], c);
                const double sc = size * pow(s.nu, ord[e][0]) * pow(s.nv, ord[e][1]);
                if (!(fabs(got - want) <= 1e-11 * sc))
                    fail_msg("(%g, %g) order (%d, %d) coordinate %d: power form %.17g, A4.4 %.17g",
                             u, v, ord[e][0], ord[e][1], c, got, want);
            }
        assert_true(C[16 * (t % 4) + 4 * ((t / 4) % 4) + 3] == 0.0);
    }
    /* Newton from the same starts: the same feet to the tolerance. */
    int both = 0;
    for (int t = 0; t < 500; t++) {
        const double u = ref_rand(u0, u1), v = ref_rand(v0, v1), h = ref_rand(-0.1, 0.1);
        double d[27], Q[3];
        nf_surf_derivs(&s, u, v, 1, d);
        const double *Su = d + 9, *Sv = d + 3;
        const double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                             Su[0] * Sv[1] - Su[1] * Sv[0]};
        for (int c = 0; c < 3; c++)
            Q[c] = d[c] + h * n[c] / sqrt(dot3(n, n));
        double ua = u + ref_rand(-0.02, 0.02) * (u1 - u0),
               va = v + ref_rand(-0.02, 0.02) * (v1 - v0);
        ua = fmin(fmax(ua, u0 + 1e-3), u1 - 1e-3);
        va = fmin(fmax(va, v0 + 1e-3), v1 - 1e-3);
        double ub = ua, vb = va;
        nf_proj_t pa, pbf;
        const int ra = nf_quad_newton(&a, Q, TOL, &ua, &va, &pa);
        const int rb = nf_quad_newton(&b, Q, TOL, &ub, &vb, &pbf);
        assert_int_equal(ra, rb);
        if (!ra)
            continue;
        both++;
        assert_true(fabs(pa.u - pbf.u) <= 10 * TOL * (u1 - u0));
        assert_true(fabs(pa.v - pbf.v) <= 10 * TOL * (v1 - v0));
        assert_near(pa.dist, pbf.dist, 1e-9 * (1.0 + fabs(pbf.dist)));
    }
    assert_true(both > 400);
    ref_surf_free(&s);
    /* Rational, or not bicubic: the basis path (no power form, NF_OK). */
    ref_surf_random(&s, 3, 3, 6, 6, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    assert_int_equal(nf_quad_newton_init(&a, &s, m1, nb), NF_OK);
    assert_int_equal(nf_quad_power(&a, pf, pb), NF_OK);
    assert_null(a.pf);
    ref_surf_free(&s);
    ref_surf_random(&s, 3, 2, 6, 6, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    assert_int_equal(nf_quad_newton_init(&a, &s, m1, nb), NF_OK);
    assert_int_equal(nf_quad_power(&a, pf, pb), NF_OK);
    assert_null(a.pf);
    assert_int_equal(nf_quad_power(&a, NULL, pb), NF_EARG);
    ref_surf_free(&s);
    free(m1);
    free(m2);
    free(pf);
}

/* An affine bicubic: control points at O + g_i A + h_j B (g, h the Greville
 * abscissae of non-uniform knots), A and B at 60 degrees, tilted in space. */
static void affine_surf(nf_surf_t *s)
{
    ref_surf_random(s, 3, 3, 7, 6, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0);
    const double O[3] = {5.0, -3.0, 2.0}, A[3] = {40.0, 5.0, 10.0}, B[3] = {20.0, 30.0, -15.0};
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            const double g = nf_greville(i, 3, s->U), h = nf_greville(j, 3, s->V);
            for (int c = 0; c < 3; c++)
                s->cp[3 * (i + (long)j * s->nu) + c] = O[c] + g * A[c] + h * B[c];
        }
}

/* The closed form (nf_quad_project on an affine surface) against the brute
 * force: feet inside, beyond an edge (clamped) and beyond a corner; a net
 * off the map by 1e-6 of its size, or unequal weights, are not affine. */
static void test_affine(void **state)
{
    (void)state;
    ref_seed(31);
    nf_surf_t s;
    affine_surf(&s);
    fixture_t f;
    quad_make(&f, &s, NF_QUAD_REL_TOL, MAXQ);
    assert_int_equal(f.q.aff.ok, 1);
    free(f.mem);
    check_against_brute(&s, 5.0, 300);
    /* beyond the corners, on both sides of the plane */
    dense_t d;
    dense_make(&d, &s);
    quad_make(&f, &s, NF_QUAD_REL_TOL, MAXQ);
    for (int k = 0; k < 16; k++) {
        const double u = d.dom[k & 1], v = d.dom[2 + ((k >> 1) & 1)];
        double S[27], Q[3];
        nf_surf_derivs(&s, u, v, 1, S);
        const double *Su = S + 9, *Sv = S + 3;
        double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                       Su[0] * Sv[1] - Su[1] * Sv[0]};
        const double nl = sqrt(dot3(n, n));
        const double su = (k & 1) ? 0.3 : -0.3, sv = ((k >> 1) & 1) ? 0.2 : -0.2;
        const double h = (k & 4) ? 7.0 : -7.0, a = (k & 8) ? 1.0 : 0.1;
        for (int c = 0; c < 3; c++)
            Q[c] = S[c] + a * (su * Su[c] + sv * Sv[c]) + h * n[c] / nl;
        nf_proj_t pa, pb;
        assert_int_equal(nf_quad_project(&f.q, Q, TOL, &pa), NF_OK);
        brute(&s, &d, Q, &pb);
        assert_near(pa.u, pb.u, TOL * (d.dom[1] - d.dom[0]));
        assert_near(pa.v, pb.v, TOL * (d.dom[3] - d.dom[2]));
        assert_near(pa.dist, pb.dist, 1e-9 * (1.0 + fabs(pb.dist)));
        assert_int_equal(pa.clamped, pb.clamped);
        assert_int_equal(pa.clamped, 1);
    }
    /* feet on an edge to rounding (points on the edge's normal line) are
     * not clamped, as nf_project says; a point 1e160 away still gets a foot
     * in the domain and a finite distance */
    for (int k = 0; k < 200; k++) {
        const int e = k % 4;
        const double t = ref_rand(0.05, 0.95);
        const double u = e < 2 ? d.dom[e] : d.dom[0] + t * (d.dom[1] - d.dom[0]);
        const double v = e < 2 ? d.dom[2] + t * (d.dom[3] - d.dom[2]) : d.dom[e];
        double S[27], Q[3];
        nf_surf_derivs(&s, u, v, 1, S);
        const double *Su = S + 9, *Sv = S + 3;
        double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                       Su[0] * Sv[1] - Su[1] * Sv[0]};
        const double nl = sqrt(dot3(n, n)), h = ref_rand(-9.0, 9.0);
        for (int c = 0; c < 3; c++)
            Q[c] = S[c] + h * n[c] / nl;
        nf_proj_t pa, pb;
        assert_int_equal(nf_quad_project(&f.q, Q, TOL, &pa), NF_OK);
        assert_int_equal(nf_project(&s, Q, u, v, TOL, &pb), NF_OK);
        assert_int_equal(pa.clamped, 0);
        assert_int_equal(pb.clamped, 0);
        assert_near(pa.u, u, 1e-12 * (d.dom[1] - d.dom[0]));
        assert_near(pa.v, v, 1e-12 * (d.dom[3] - d.dom[2]));
        assert_near(pa.dist, h, 1e-9);
    }
    const double far[3] = {-3e159, 7e159, 1e160};
    nf_proj_t pf, pn;
    assert_int_equal(nf_quad_project(&f.q, far, TOL, &pf), NF_OK);
    assert_int_equal(
        nf_project(&s, far, 0.5 * (d.dom[0] + d.dom[1]), 0.5 * (d.dom[2] + d.dom[3]), TOL, &pn),
        NF_OK);
    assert_true(pf.u >= d.dom[0] && pf.u <= d.dom[1] && pf.v >= d.dom[2] && pf.v <= d.dom[3]);
    assert_true(isfinite(pf.dist) && pf.clamped == 1);
    assert_near(fabs(pf.dist) / fabs(pn.dist), 1.0, 1e-12);
    free(f.mem);
    free(d.P);
    /* not affine */
    nf_affine_t af;
    s.cp[3 * (2 + 2 * s.nu) + 2] += 1e-6 * 60.0;
    assert_int_equal(nf_affine_init(&af, &s), 0);
    s.cp[3 * (2 + 2 * s.nu) + 2] -= 1e-6 * 60.0;
    assert_int_equal(nf_affine_init(&af, &s), 1);
    s.w[5] = 1.5;
    assert_int_equal(nf_affine_init(&af, &s), 0);
    ref_surf_free(&s);
}

/* The shadow of s in the plane across N = (sum of its net's u edges) x
 * (sum of its v edges), F(u, v) = (e1.S, e2.S): its Jacobian's determinant
 * at 121 x 121 parameters (> 0: F keeps orientation) and its boundary, 400
 * points, a simple polygon (no two edges that do not share a corner
 * cross). Both together: F is one-to-one, s a height field along N. 1 if
 * so, 0 and the first failure in why. */
static int shadow_one_to_one(const nf_surf_t *s, char *why, size_t wl)
{
    const long nu = s->nu, nv = s->nv;
    double A[3] = {0, 0, 0}, B[3] = {0, 0, 0}, N[3], e1[3], e2[3];
    for (long j = 0; j < nv; j++)
        for (int c = 0; c < 3; c++)
            A[c] += s->cp[3 * (nu - 1 + j * nu) + c] - s->cp[3 * j * nu + c];
    for (long i = 0; i < nu; i++)
        for (int c = 0; c < 3; c++)
            B[c] += s->cp[3 * (i + (nv - 1) * nu) + c] - s->cp[3 * i + c];
    N[0] = A[1] * B[2] - A[2] * B[1];
    N[1] = A[2] * B[0] - A[0] * B[2];
    N[2] = A[0] * B[1] - A[1] * B[0];
    const double nl = sqrt(dot3(N, N)), an = dot3(A, N) / nl;
    for (int c = 0; c < 3; c++) {
        N[c] /= nl;
        e1[c] = A[c] - an * N[c];
    }
    const double el = sqrt(dot3(e1, e1));
    for (int c = 0; c < 3; c++)
        e1[c] /= el;
    e2[0] = N[1] * e1[2] - N[2] * e1[1];
    e2[1] = N[2] * e1[0] - N[0] * e1[2];
    e2[2] = N[0] * e1[1] - N[1] * e1[0];
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (int j = 0; j <= 120; j++)
        for (int i = 0; i <= 120; i++) {
            double D[27];
            nf_surf_derivs(s, u0 + (u1 - u0) * i / 120.0, v0 + (v1 - v0) * j / 120.0, 1, D);
            const double *Su = D + 9, *Sv = D + 3;
            const double det = dot3(Su, e1) * dot3(Sv, e2) - dot3(Su, e2) * dot3(Sv, e1);
            if (!(det > 0.0)) {
                snprintf(why, wl, "det %.3g at (%d, %d) of 120 x 120", det, i, j);
                return 0;
            }
        }
    enum { NB4 = 400 };
    static double x[NB4], y[NB4];
    for (int k = 0; k < NB4; k++) {
        const int e = k / (NB4 / 4);
        const double t = (double)(k % (NB4 / 4)) / (NB4 / 4);
        const double u = e == 0   ? u0 + t * (u1 - u0)
                         : e == 1 ? u1
                         : e == 2 ? u1 - t * (u1 - u0)
                                  : u0;
        const double v = e == 0   ? v0
                         : e == 1 ? v0 + t * (v1 - v0)
                         : e == 2 ? v1
                                  : v1 - t * (v1 - v0);
        double P[3];
        nf_surf_eval(s, u, v, P);
        x[k] = dot3(P, e1);
        y[k] = dot3(P, e2);
    }
    for (int a = 0; a < NB4; a++)
        for (int b = a + 2; b < NB4; b++) {
            if (a == 0 && b == NB4 - 1)
                continue; /* they share corner 0 */
            const int a2 = (a + 1) % NB4, b2 = (b + 1) % NB4;
            const double d1 = (x[a2] - x[a]) * (y[b] - y[a]) - (y[a2] - y[a]) * (x[b] - x[a]);
            const double d2 = (x[a2] - x[a]) * (y[b2] - y[a]) - (y[a2] - y[a]) * (x[b2] - x[a]);
            const double d3 = (x[b2] - x[b]) * (y[a] - y[b]) - (y[b2] - y[b]) * (x[a] - x[b]);
            const double d4 = (x[b2] - x[b]) * (y[a2] - y[b]) - (y[b2] - y[b]) * (x[a2] - x[b]);
            if (((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0))) {
                snprintf(why, wl, "boundary edges %d and %d cross", a, b);
                return 0;
            }
        }
    return 1;
}

/* A bicubic 7 x 6 net at the Greville points of a 100 mm square (uniform
 * knots), heights +-15 mm. */
static void square_net(nf_surf_t *s)
{
    ref_surf_random(s, 3, 3, 7, 6, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    for (int k = 0; k <= 3; k++) {
        s->U[k] = s->V[k] = 0.0;
        s->U[7 + k] = s->V[6 + k] = 1.0;
    }
    s->U[4] = 0.25, s->U[5] = 0.5, s->U[6] = 0.75;
    s->V[4] = 1.0 / 3.0, s->V[5] = 2.0 / 3.0;
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            double *C = s->cp + 3 * (i + (long)j * s->nu);
            C[0] = 100.0 * nf_greville(i, 3, s->U);
            C[1] = 100.0 * nf_greville(j, 3, s->V);
            C[2] = ref_rand(-15.0, 15.0);
        }
}

/* nf_fold_free is a proof: every net it passes is a height field along its
 * N (the shadow one-to-one above). Nets up to and past a fold, in steps:
 * sheared as a whole (x += k (y - 50), y += k (x - 50): folds at k = 1),
 * one column sheared (x of column 3 += 2 k (y - 50)), one column pushed past
 * the next in x, jittered nets, steep ones (heights x 20);
 * it passes some of each family and declines the rest; the 270-degree
 * cylinder and a plate hemmed back over itself are declined. */
static void test_fold_free(void **state)
{
    (void)state;
    ref_seed(32);
    int passed = 0, declined = 0, fam[5] = {0, 0, 0, 0, 0};
    char why[128];
    for (int t = 0; t < 5 * 40; t++) {
        const int f = t / 40, step = t % 40;
        nf_surf_t s;
        square_net(&s);
        for (int j = 0; j < s.nv; j++)
            for (int i = 0; i < s.nu; i++) {
                double *C = s.cp + 3 * (i + (long)j * s.nu);
                const double x = C[0], y = C[1], k = 0.04 * step;
                if (f == 0) {
                    C[0] = x + k * (y - 50.0);
                    C[1] = y + k * (x - 50.0);
                } else if (f == 1 && i == 3) {
                    C[0] = x + 2.0 * k * (y - 50.0);
                } else if (f == 2 && i == 3) {
                    C[0] = x + 30.0 * k;
                } else if (f == 3) {
                    const double jit = 0.15 * step;
                    C[0] = x + ref_rand(-jit, jit);
                    C[1] = y + ref_rand(-jit, jit);
                } else if (f == 4) {
                    C[2] *= 0.5 * step;
                }
            }
        if (!nf_fold_free(&s)) {
            declined++;
            ref_surf_free(&s);
            continue;
        }
        passed++;
        fam[f]++;
        if (!shadow_one_to_one(&s, why, sizeof why))
            fail_msg("family %d step %d passed but is no height field: %s", f, step, why);
        ref_surf_free(&s);
    }
    printf("nf_fold_free: %d of 200 nets proven (%d %d %d %d %d by family), %d declined\n", passed,
           fam[0], fam[1], fam[2], fam[3], fam[4], declined);
    for (int f = 0; f < 5; f++)
        assert_true(fam[f] > 0 && (f == 3 || f == 4 || fam[f] < 40)); /* past a fold */
    /* folds: the 270-degree cylinder, and a plate hemmed back over itself */
    double m3[NF_SURF_DOUBLES(7, 2, 2, 1)];
    nf_surf_t c3;
    cylinder270(&c3, m3, 0);
    assert_int_equal(nf_fold_free(&c3), 0); /* polynomial here: the hodograph bound decides */
    nf_surf_t hem;
    ref_surf_random(&hem, 3, 3, 8, 5, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    for (int j = 0; j < hem.nv; j++)
        for (int i = 0; i < hem.nu; i++) {
            double *C = hem.cp + 3 * (i + (long)j * hem.nu);
            C[0] = i < 5 ? 10.0 * i : 10.0 * (8 - i); /* back over itself */
            C[1] = 10.0 * j;
            C[2] = i < 5 ? 0.0 : 3.0;
        }
    assert_int_equal(shadow_one_to_one(&hem, why, sizeof why), 0);
    assert_int_equal(nf_fold_free(&hem), 0);
    ref_surf_free(&hem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_curved),           cmocka_unit_test(test_thin),
        cmocka_unit_test(test_rational_exact),   cmocka_unit_test(test_flatness),
        cmocka_unit_test(test_crack_free),       cmocka_unit_test(test_memory_flat),
        cmocka_unit_test(test_thin_nearest),     cmocka_unit_test(test_fold),
        cmocka_unit_test(test_flags_and_budget), cmocka_unit_test(test_power_form),
        cmocka_unit_test(test_affine),           cmocka_unit_test(test_fold_free),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
