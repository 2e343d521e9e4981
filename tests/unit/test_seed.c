/* SPDX-License-Identifier: MIT */
/* test_seed.c: the seed grid's samples (nf_seed_init_uv, evaluated as a
 * separable tensor product) against nf_surf_eval at the documented sample
 * parameters, against the Cox-de Boor reference (ref_rbasis_row) on a
 * subset, and against the grid of the transposed surface: non-uniform,
 * rational, mixed degrees, repeated knots, 1 and NF_SEED_MAX_NS samples,
 * and nets much longer than a chunk of samples. */

#include "cf_test.h"
#include "nf_err.h"
#include "nf_project.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Samples may differ from nf_surf_eval's by rounding only. */
#define REL 1e-12

/* The documented sample parameter i of n over [a, b]. */
static double param(int i, int n, double a, double b)
{
    if (n == 1)
        return 0.5 * a + 0.5 * b;
    return i == n - 1 ? b : a + (b - a) * i / (n - 1);
}

/* Size of the control net: its bounding box diagonal, or its largest
 * coordinate when that is larger (rounding scales with it). */
static double net_size(const nf_surf_t *s)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double big = 0.0;
    for (long k = 0; k < (long)s->nu * s->nv; k++)
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], s->cp[3 * k + c]);
            hi[c] = fmax(hi[c], s->cp[3 * k + c]);
            big = fmax(big, fabs(s->cp[3 * k + c]));
        }
    const double d = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                          (hi[2] - lo[2]) * (hi[2] - lo[2]));
    return fmax(d, big);
}

/* Largest |sample - nf_surf_eval| over the grid pts (nsu x nsv, layout of
 * nf_seed_t), relative to the net's size. */
static double grid_dev(const nf_surf_t *s, int nsu, int nsv, const double *pts)
{
    double ua, ub, va, vb, dev = 0.0;
    nf_surf_domain(s, &ua, &ub, &va, &vb);
    const long n2 = (long)nsu * nsv;
    for (int j = 0; j < nsv; j++)
        for (int i = 0; i < nsu; i++) {
            double P[3];
            nf_surf_eval(s, param(i, nsu, ua, ub), param(j, nsv, va, vb), P);
            const long k = i + (long)j * nsu;
            for (int c = 0; c < 3; c++)
                dev = fmax(dev, fabs(pts[c * n2 + k] - P[c]));
        }
    return dev / net_size(s);
}

/* The same against the full Cox-de Boor row, every stride-th sample. */
static double ref_dev(const nf_surf_t *s, int nsu, int nsv, const double *pts, long stride)
{
    double ua, ub, va, vb, dev = 0.0;
    nf_surf_domain(s, &ua, &ub, &va, &vb);
    const long n2 = (long)nsu * nsv, N = (long)s->nu * s->nv;
    double *R = malloc(sizeof(double) * (size_t)N);
    assert_non_null(R);
    for (long k = 0; k < n2; k += stride) {
        const int i = (int)(k % nsu), j = (int)(k / nsu);
        ref_rbasis_row(s, param(i, nsu, ua, ub), param(j, nsv, va, vb), R);
        for (int c = 0; c < 3; c++) {
            double x = 0.0;
            for (long t = 0; t < N; t++)
                x += R[t] * s->cp[3 * t + c];
            dev = fmax(dev, fabs(pts[c * n2 + k] - x));
        }
    }
    free(R);
    return dev / net_size(s);
}

/* The surface with u and v exchanged (p <-> q, U <-> V, the net
 * transposed): S'(v, u) = S(u, v). Heap storage in t->U (free it). */
static void transpose(const nf_surf_t *s, nf_surf_t *t)
{
    double *mem = malloc(sizeof(double) * (size_t)NF_SURF_DOUBLES(s->nv, s->nu, s->q, s->p));
    assert_non_null(mem);
    nf_surf_wire(t, s->q, s->p, s->nv, s->nu, mem);
    memcpy(t->U, s->V, sizeof(double) * (size_t)(s->nv + s->q + 1));
    memcpy(t->V, s->U, sizeof(double) * (size_t)(s->nu + s->p + 1));
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            const long a = i + (long)j * s->nu, b = j + (long)i * s->nv;
            for (int c = 0; c < 3; c++)
                t->cp[3 * b + c] = s->cp[3 * a + c];
            t->w[b] = s->w ? s->w[a] : 1.0;
        }
    if (!s->w)
        t->w = NULL;
}

/* Largest |a - b^T| over the grids a (nsu x nsv) and b (nsv x nsu). */
static double transposed_dev(const double *a, const double *b, int nsu, int nsv, double size)
{
    const long n2 = (long)nsu * nsv;
    double dev = 0.0;
    for (int j = 0; j < nsv; j++)
        for (int i = 0; i < nsu; i++)
            for (int c = 0; c < 3; c++)
                dev =
                    fmax(dev, fabs(a[c * n2 + i + (long)j * nsu] - b[c * n2 + j + (long)i * nsv]));
    return dev / size;
}

/* The grid of s at nsu x nsv against nf_surf_eval, the reference (every
 * stride-th sample, 0: none) and the transposed surface's grid; returns
 * the largest deviation of the first. The counts are those asked for:
 * above NF_SEED_MAX_NS the grid has NF_SEED_MAX_NS. */
static double check_grid(const nf_surf_t *s, int nsu, int nsv, long stride, const char *what)
{
    assert_int_equal(nf_surf_check(s), NF_OK);
    const int mu = nsu > NF_SEED_MAX_NS ? NF_SEED_MAX_NS : nsu,
              mv = nsv > NF_SEED_MAX_NS ? NF_SEED_MAX_NS : nsv;
    double *pts = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(mu, mv));
    double *tp = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(mu, mv));
    assert_non_null(pts);
    assert_non_null(tp);
    nf_seed_t g;
    nf_seed_init_uv(&g, s, nsu, nsv, pts);
    assert_int_equal(g.nsu, mu);
    assert_int_equal(g.nsv, mv);
    assert_ptr_equal(g.pts, pts);
    const double dev = grid_dev(s, mu, mv, pts);
    const double rdev = stride > 0 ? ref_dev(s, mu, mv, pts, stride) : -1.0; /* none */
    nf_surf_t t;
    transpose(s, &t);
    nf_seed_t gt;
    nf_seed_init_uv(&gt, &t, nsv, nsu, tp);
    const double tdev = transposed_dev(pts, tp, mu, mv, net_size(s));
    free(t.U);
    print_message("%-28s %4d x %-4d p %d q %d %-10s: eval %.2e, ref %9.2e, transposed %.2e\n", what,
                  mu, mv, s->p, s->q, s->w ? "rational" : "polynomial", dev, rdev, tdev);
    assert_true(dev <= REL);
    assert_true(rdev <= REL);
    assert_true(tdev <= REL);
    free(pts);
    free(tp);
    return dev;
}

/* (a) bicubic, non-uniform knots, polynomial; and the check catches a
 * grid with u and v swapped (the transposed surface's grid as it is) and
 * one sample moved by a part in 10^9. */
static void test_seed_bicubic(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(11);
    ref_surf_random(&s, 3, 3, 9, 7, -1.0, 2.0, 0.5, 4.0, 1.0, 1.0);
    s.w = NULL;
    check_grid(&s, 33, 33, 7, "bicubic non-uniform");
    check_grid(&s, 73, 41, 13, "bicubic non-uniform");

    const int ns = 33;
    double *pts = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(ns, ns));
    double *sw = malloc(sizeof(double) * (size_t)NF_SEED_DOUBLES(ns, ns));
    assert_non_null(pts);
    assert_non_null(sw);
    nf_seed_t g;
    nf_seed_init(&g, &s, ns, pts);
    assert_int_equal(g.ns, ns);
    assert_true(grid_dev(&s, ns, ns, pts) <= REL);
    nf_surf_t t;
    transpose(&s, &t);
    nf_seed_init(&g, &t, ns, sw); /* S(v, u) at sample (i, j): u and v swapped */
    const double swapped = grid_dev(&s, ns, ns, sw);
    print_message("u and v swapped: %.2e\n", swapped);
    assert_true(swapped > 1e-3);
    const long n2 = (long)ns * ns;
    pts[n2 + 5 + 7 * ns] *= 1.0 + 1e-9; /* one y, one part in 10^9 */
    assert_true(grid_dev(&s, ns, ns, pts) > REL);
    free(t.U);
    free(pts);
    free(sw);
    ref_surf_free(&s);
}

/* (b) rational, weights 0.2 .. 5 (homogeneous sums, divided at the end). */
static void test_seed_rational(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(22);
    ref_surf_random(&s, 3, 3, 8, 10, 0.0, 1.0, 0.0, 1.0, 0.2, 5.0);
    check_grid(&s, 41, 29, 5, "rational");
    check_grid(&s, 29, 41, 5, "rational");
    ref_surf_free(&s);
    /* far from the origin: rounding relative to the coordinates */
    ref_surf_random(&s, 2, 4, 11, 6, 5.0, 6.0, -2.0, -1.0, 0.5, 2.0);
    for (long k = 0; k < 3L * s.nu * s.nv; k++)
        s.cp[k] += 1000.0;
    check_grid(&s, 37, 19, 3, "rational, offset 1000");
    ref_surf_free(&s);
}

/* (c) degrees (2, 3) and (1, 4), unequal counts, both kinds. */
static void test_seed_degrees(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(33);
    ref_surf_random(&s, 2, 3, 10, 7, 0.0, 3.0, 1.0, 2.0, 0.5, 2.0);
    check_grid(&s, 50, 17, 7, "degrees (2, 3)");
    s.w = NULL;
    check_grid(&s, 17, 50, 7, "degrees (2, 3)");
    ref_surf_free(&s);
    ref_surf_random(&s, 1, 4, 12, 9, -4.0, 4.0, 0.0, 0.25, 0.5, 2.0);
    check_grid(&s, 13, 70, 9, "degrees (1, 4)");
    s.w = NULL;
    check_grid(&s, 96, 5, 9, "degrees (1, 4)");
    ref_surf_free(&s);
    for (int p = 1; p <= NF_MAX_DEGREE; p++) {
        const int q = 1 + (p + 2) % NF_MAX_DEGREE;
        ref_surf_random(&s, p, q, p + 5, q + 4, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
        check_grid(&s, 8 * 5 + 1, 8 * 4 + 1, 11, "degrees 1..max");
        ref_surf_free(&s);
    }
}

/* (d) 1 sample (the domain's middle), 2 (the corners), and NF_SEED_MAX_NS
 * in one direction (a larger count reduced to it). */
static void test_seed_counts(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(44);
    ref_surf_random(&s, 3, 2, 9, 8, 0.0, 1.0, 0.0, 2.0, 0.5, 2.0);
    check_grid(&s, 1, 1, 1, "1 x 1");
    check_grid(&s, 2, 2, 1, "2 x 2");
    check_grid(&s, 1, 9, 1, "1 x n");
    check_grid(&s, NF_SEED_MAX_NS, 3, 97, "NF_SEED_MAX_NS x 3");
    check_grid(&s, 2, NF_SEED_MAX_NS + 7, 97, "2 x (NF_SEED_MAX_NS + 7)");
    double one[3], P[3], ua, ub, va, vb;
    nf_seed_t g;
    nf_seed_init(&g, &s, 0, one); /* counts below 1 are 1 */
    nf_surf_domain(&s, &ua, &ub, &va, &vb);
    nf_surf_eval(&s, 0.5 * (ua + ub), 0.5 * (va + vb), P);
    for (int c = 0; c < 3; c++)
        assert_near(one[c], P[c], REL * net_size(&s));
    ref_surf_free(&s);
}

/* (e) repeated interior knots (multiplicity 2, and p: a crease), on
 * sample parameters, so that samples fall exactly on them. */
static void test_seed_repeated_knots(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(55);
    ref_surf_random(&s, 3, 3, 10, 8, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    /* U: 0 0 0 0 | .25 .5 .5 .75 .75 .75 | 1 1 1 1 (samples at i / 16) */
    static const double U[] = {0, 0, 0, 0, 0.25, 0.5, 0.5, 0.75, 0.75, 0.75, 1, 1, 1, 1};
    static const double V[] = {0, 0, 0, 0, 0.125, 0.375, 0.375, 0.625, 1, 1, 1, 1};
    memcpy(s.U, U, sizeof U);
    memcpy(s.V, V, sizeof V);
    check_grid(&s, 17, 9, 3, "repeated knots, on samples");
    check_grid(&s, 33, 43, 11, "repeated knots");
    s.w = NULL;
    check_grid(&s, 17, 17, 3, "repeated knots, on samples");
    ref_surf_free(&s);
}

/* Nets much longer than a chunk of samples: few samples per span (each
 * chunk a handful of samples far apart) and many (chunks end mid-span). */
static void test_seed_long_nets(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(66);
    ref_surf_random(&s, 3, 2, 200, 6, 0.0, 1.0, 0.0, 1.0, 0.5, 2.0);
    const int counts[] = {2, 5, 15, 16, 17, 31, 32, 33, 64, 65, 197, 1601};
    for (size_t t = 0; t < sizeof counts / sizeof counts[0]; t++)
        check_grid(&s, counts[t], 7, 0, "200 x 6 net");
    check_grid(&s, 65, 7, 41, "200 x 6 net");
    ref_surf_free(&s);
    ref_surf_random(&s, 2, 3, 8, 150, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    s.w = NULL;
    check_grid(&s, 33, 1201, 0, "8 x 150 net");
    ref_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seed_bicubic),        cmocka_unit_test(test_seed_rational),
        cmocka_unit_test(test_seed_degrees),        cmocka_unit_test(test_seed_counts),
        cmocka_unit_test(test_seed_repeated_knots), cmocka_unit_test(test_seed_long_nets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
