/* SPDX-License-Identifier: MIT */
/* test_refine.c: knot insertion (A5.3, A5.5, uniform refinement) leaves the
 * surface unchanged, builds the right knot vectors and nets, refuses what it
 * must before writing, and (independently of nf_surf_eval) a knot inserted p
 * times makes a control row interpolate the surface's isocurve. */

#include "cf_test.h"
#include "nf_err.h"
#include "nf_refine.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* out wired for a net of nu x nv on heap storage (tests only). */
static double *wire_out(const nf_surf_t *in, int nu, int nv, nf_surf_t *out)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, in->p, in->q), sizeof(double));
    assert_non_null(mem);
    nf_surf_wire(out, in->p, in->q, nu, nv, mem);
    return mem;
}

static double net_scale(const nf_surf_t *s)
{
    double m = 0.0;
    for (long i = 0; i < 3L * s->nu * s->nv; i++)
        m = fmax(m, fabs(s->cp[i]));
    return m;
}

/* The two surfaces agree at 2000 random parameters to 1e-12 relative. */
static void assert_same_surface(const nf_surf_t *a, const nf_surf_t *b)
{
    double u0, u1, v0, v1, tol = 1e-12 * net_scale(a), worst = 0.0;
    nf_surf_domain(a, &u0, &u1, &v0, &v1);
    double bu0, bu1, bv0, bv1;
    nf_surf_domain(b, &bu0, &bu1, &bv0, &bv1);
    assert_true(bu0 == u0 && bu1 == u1 && bv0 == v0 && bv1 == v1);
    for (int t = 0; t < 2000; t++) {
        double u = ref_rand(u0, u1), v = ref_rand(v0, v1), P[3], R[3];
        if (t < 4) { /* the corners too */
            u = t & 1 ? u1 : u0;
            v = t & 2 ? v1 : v0;
        }
        nf_surf_eval(a, u, v, P);
        nf_surf_eval(b, u, v, R);
        for (int c = 0; c < 3; c++) {
            worst = fmax(worst, fabs(P[c] - R[c]));
            assert_near(R[c], P[c], tol);
        }
    }
    assert_true(worst <= tol);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The knot vector out must be the sorted union of in and X. */
static void assert_merged(const double *K, int nk, const double *X, int r, const double *Kbar)
{
    double *all = malloc(sizeof(double) * (size_t)(nk + r));
    memcpy(all, K, sizeof(double) * (size_t)nk);
    memcpy(all + nk, X, sizeof(double) * (size_t)r);
    qsort(all, (size_t)(nk + r), sizeof(double), cmp_double);
    for (int i = 0; i < nk + r; i++)
        assert_true(Kbar[i] == all[i]);
    free(all);
}

/* r knots for knot vector K (n+1 points, degree p): random values, one of
 * them repeated up to p times, and (p >= 2) an existing interior knot once
 * more; sorted. Returns the count (<= cap). */
static int random_new_knots(const double *K, int n, int p, double *X, int cap)
{
    int r = 0;
    double a = K[p], b = K[n + 1];
    int plain = 1 + (int)ref_rand(0, 5);
    for (int i = 0; i < plain && r < cap; i++)
        X[r++] = ref_rand(a, b);
    double x = ref_rand(a, b);
    int times = 1 + (int)ref_rand(0, p);
    for (int i = 0; i < times && r < cap; i++)
        X[r++] = x;
    if (p >= 2 && n > p && r < cap) { /* existing knot K[p+1] (multiplicity 1) once more */
        X[r++] = K[p + 1];
    }
    qsort(X, (size_t)r, sizeof(double), cmp_double);
    return r;
}

/* Random surfaces, degrees 1..5 in each direction, non-uniform knots,
 * domains away from [0,1], rational and polynomial: refining in u or in v
 * leaves S unchanged; the knots are the merged vectors; out is valid. */
static void test_refine_same_surface(void **state)
{
    (void)state;
    ref_seed(101);
    for (int p = 1; p <= 5; p++)
        for (int q = 1; q <= 5; q++)
            for (int rational = 0; rational <= 1; rational++) {
                nf_surf_t s;
                int nu = p + 1 + (int)ref_rand(0, 6), nv = q + 1 + (int)ref_rand(0, 6);
                ref_surf_random(&s, p, q, nu, nv, -2.5, 4.0, 10.0, 10.75, 0.5, 2.0);
                if (!rational)
                    s.w = NULL;
                assert_int_equal(nf_surf_check(&s), NF_OK);
                for (int dir = 0; dir < 2; dir++) {
                    double X[16];
                    int r = dir == 0 ? random_new_knots(s.U, nu - 1, p, X, 16)
                                     : random_new_knots(s.V, nv - 1, q, X, 16);
                    nf_surf_t o;
                    int mu, mv;
                    assert_int_equal(
                        nf_refine_size(&s, dir == 0 ? r : 0, dir == 0 ? 0 : r, &mu, &mv), NF_OK);
                    assert_int_equal(mu, nu + (dir == 0 ? r : 0));
                    assert_int_equal(mv, nv + (dir == 0 ? 0 : r));
                    double *mem = wire_out(&s, mu, mv, &o);
                    for (long i = 0; i < (long)mu * mv; i++)
                        o.w[i] = 7.0; /* storage reused: weights must all be written */
                    int rc = dir == 0 ? nf_refine_u(&s, X, r, &o) : nf_refine_v(&s, X, r, &o);
                    assert_int_equal(rc, NF_OK);
                    assert_int_equal(nf_surf_check(&o), NF_OK);
                    if (dir == 0) {
                        assert_merged(s.U, nu + p + 1, X, r, o.U);
                        assert_memory_equal(o.V, s.V, sizeof(double) * (size_t)(nv + q + 1));
                    } else {
                        assert_merged(s.V, nv + q + 1, X, r, o.V);
                        assert_memory_equal(o.U, s.U, sizeof(double) * (size_t)(nu + p + 1));
                    }
                    if (!rational)
                        for (long i = 0; i < (long)mu * mv; i++)
                            assert_true(o.w[i] == 1.0);
                    assert_same_surface(&s, &o);
                    free(mem);
                }
                ref_surf_free(&s);
            }
}

/* One knot inserted 1..p times by A5.3 equals A5.5 with X = {x, ..., x} and
 * the surface; at an existing simple knot, p - 1 more are allowed, p not. */
static void test_insert_multiplicity(void **state)
{
    (void)state;
    ref_seed(202);
    for (int p = 1; p <= 5; p++) {
        nf_surf_t s;
        ref_surf_random(&s, p, 6 - p, p + 5, 8, 1.0, 3.5, -4.0, -1.0, 0.5, 2.0);
        for (int dir = 0; dir < 2; dir++) {
            const int deg = dir == 0 ? p : 6 - p;
            const double *K = dir == 0 ? s.U : s.V;
            const int n = dir == 0 ? s.nu - 1 : s.nv - 1;
            for (int at_knot = 0; at_knot <= 1; at_knot++) {
                double x = at_knot ? K[deg + 1] : 0.37 * K[deg] + 0.63 * K[n + 1];
                int room = at_knot ? deg - 1 : deg;
                for (int times = 1; times <= deg; times++) {
                    int ru = dir == 0 ? times : 0, rv = dir == 0 ? 0 : times;
                    nf_surf_t a, b;
                    double *ma = wire_out(&s, s.nu + ru, s.nv + rv, &a);
                    double *mb = wire_out(&s, s.nu + ru, s.nv + rv, &b);
                    double X[NF_MAX_DEGREE];
                    for (int i = 0; i < times; i++)
                        X[i] = x;
                    int ra = dir == 0 ? nf_refine_insert_u(&s, x, times, &a)
                                      : nf_refine_insert_v(&s, x, times, &a);
                    int rb =
                        dir == 0 ? nf_refine_u(&s, X, times, &b) : nf_refine_v(&s, X, times, &b);
                    if (times > room) {
                        assert_int_equal(ra, NF_EKNOTS);
                        assert_int_equal(rb, NF_EKNOTS);
                    } else {
                        assert_int_equal(ra, NF_OK);
                        assert_int_equal(rb, NF_OK);
                        long nn = (long)a.nu * a.nv;
                        double tol = 1e-13 * net_scale(&s);
                        for (long i = 0; i < 3 * nn; i++)
                            assert_near(a.cp[i], b.cp[i], tol);
                        for (long i = 0; i < nn; i++)
                            assert_near(a.w[i], b.w[i], 1e-13);
                        int nk = dir == 0 ? a.nu + p + 1 : a.nv + 6 - p + 1;
                        assert_memory_equal(dir == 0 ? a.U : a.V, dir == 0 ? b.U : b.V,
                                            sizeof(double) * (size_t)nk);
                        assert_same_surface(&s, &a);
                    }
                    free(ma);
                    free(mb);
                }
            }
        }
        ref_surf_free(&s);
    }
}

/* Independently of our evaluator: with u* inserted p times, the refined
 * row k (k the span of u* before insertion) is the isocurve S(u*, v), i.e.
 * the NURBS curve of that row with V, evaluated here by the recursive
 * definition (ref_bspline), equals nf_surf_eval of the original surface.
 * Likewise a column for v*. */
static void test_isocurve_row(void **state)
{
    (void)state;
    ref_seed(303);
    for (int p = 1; p <= 5; p++)
        for (int rational = 0; rational <= 1; rational++) {
            const int q = 1 + (p + 2) % 5;
            nf_surf_t s;
            ref_surf_random(&s, p, q, p + 4, q + 3, -1.0, 2.0, 5.0, 9.0, 0.3, 3.0);
            if (!rational)
                s.w = NULL;
            double tol = 1e-12 * net_scale(&s);
            for (int dir = 0; dir < 2; dir++) {
                const int deg = dir == 0 ? p : q;
                const double *K = dir == 0 ? s.U : s.V;
                const int n = dir == 0 ? s.nu - 1 : s.nv - 1;
                double x = ref_rand(K[deg], K[n + 1]);
                int k = deg; /* span of x: K[k] <= x < K[k+1] */
                while (!(K[k] <= x && x < K[k + 1]))
                    k++;
                nf_surf_t o;
                double *mem =
                    wire_out(&s, s.nu + (dir == 0 ? deg : 0), s.nv + (dir == 0 ? 0 : deg), &o);
                int rc = dir == 0 ? nf_refine_insert_u(&s, x, deg, &o)
                                  : nf_refine_insert_v(&s, x, deg, &o);
                assert_int_equal(rc, NF_OK);
                /* The other direction's knots and the curve along them. */
                const double *T = dir == 0 ? o.V : o.U;
                const int m = dir == 0 ? o.nv : o.nu, dg = dir == 0 ? q : p;
                double t0 = T[dg], t1 = T[m];
                for (int it = 0; it <= 100; it++) {
                    double t = t0 + (t1 - t0) * it / 100.0, num[3] = {0, 0, 0}, den = 0.0;
                    for (int j = 0; j < m; j++) {
                        long idx = dir == 0 ? k + (long)j * o.nu : j + (long)k * o.nu;
                        double b = ref_bspline(j, dg, T, m + dg + 1, t) * o.w[idx];
                        den += b;
                        for (int c = 0; c < 3; c++)
                            num[c] += b * o.cp[3 * idx + c];
                    }
                    double P[3];
                    nf_surf_eval(&s, dir == 0 ? x : t, dir == 0 ? t : x, P);
                    for (int c = 0; c < 3; c++)
                        assert_near(num[c] / den, P[c], tol);
                }
                free(mem);
            }
            ref_surf_free(&s);
        }
}

/* Uniform refinement: every non-empty span halved at its midpoint in both
 * directions, Nu' = Nu + spans_u, the span count doubles, S unchanged. */
static void test_uniform(void **state)
{
    (void)state;
    ref_seed(404);
    for (int p = 1; p <= 5; p++)
        for (int rational = 0; rational <= 1; rational++) {
            const int q = 6 - p;
            nf_surf_t s;
            ref_surf_random(&s, p, q, p + 1 + 2 * p, q + 3, 100.0, 100.5, -7.0, 3.0, 0.5, 2.0);
            if (p >= 2) { /* a double knot in u: its span count stays right */
                s.U[p + 2] = s.U[p + 1];
            }
            if (!rational)
                s.w = NULL;
            assert_int_equal(nf_surf_check(&s), NF_OK);
            int su, sv, mu, mv;
            nf_refine_spans(&s, &su, &sv);
            assert_int_equal(su, s.nu - p - (p >= 2 ? 1 : 0));
            assert_int_equal(sv, s.nv - q);
            assert_int_equal(nf_refine_uniform_size(&s, &mu, &mv), NF_OK);
            assert_int_equal(mu, s.nu + su);
            assert_int_equal(mv, s.nv + sv);
            nf_surf_t o;
            double *mem = wire_out(&s, mu, mv, &o);
            assert_int_equal(nf_refine_uniform(&s, &o), NF_OK);
            assert_int_equal(nf_surf_check(&o), NF_OK);
            int su2, sv2;
            nf_refine_spans(&o, &su2, &sv2);
            assert_int_equal(su2, 2 * su);
            assert_int_equal(sv2, 2 * sv);
            /* Each old span [a, b) became [a, m), [m, b) with m its midpoint. */
            for (int dir = 0; dir < 2; dir++) {
                const double *K = dir == 0 ? s.U : s.V, *Kb = dir == 0 ? o.U : o.V;
                const int n = dir == 0 ? s.nu - 1 : s.nv - 1, deg = dir == 0 ? p : q;
                double X[64] = {0};
                int r = 0;
                for (int i = deg; i <= n; i++)
                    if (K[i] < K[i + 1])
                        X[r++] = 0.5 * K[i] + 0.5 * K[i + 1];
                assert_merged(K, n + deg + 2, X, r, Kb);
            }
            assert_same_surface(&s, &o);
            /* Against the explicit two-step refinement. */
            nf_surf_t a, b;
            double Xu[64] = {0}, Xv[64] = {0};
            int ru = 0, rv = 0;
            for (int i = p; i < s.nu; i++)
                if (s.U[i] < s.U[i + 1])
                    Xu[ru++] = 0.5 * s.U[i] + 0.5 * s.U[i + 1];
            for (int j = q; j < s.nv; j++)
                if (s.V[j] < s.V[j + 1])
                    Xv[rv++] = 0.5 * s.V[j] + 0.5 * s.V[j + 1];
            double *ma = wire_out(&s, s.nu + ru, s.nv, &a);
            assert_int_equal(nf_refine_u(&s, Xu, ru, &a), NF_OK);
            if (!rational)
                a.w = NULL;
            double *mb = wire_out(&a, a.nu, a.nv + rv, &b);
            assert_int_equal(nf_refine_v(&a, Xv, rv, &b), NF_OK);
            for (long i = 0; i < 3L * b.nu * b.nv; i++)
                assert_near(b.cp[i], o.cp[i], 1e-12 * net_scale(&s));
            for (long i = 0; i < (long)b.nu * b.nv; i++)
                assert_near(b.w[i], o.w[i], 1e-13);
            free(ma);
            free(mb);
            free(mem);
            ref_surf_free(&s);
        }
}

/* Refused before writing: out keeps every byte. */
static void fill(double *mem, long n)
{
    for (long i = 0; i < n; i++)
        mem[i] = -777.25;
}

static void assert_untouched(const double *mem, long n)
{
    for (long i = 0; i < n; i++)
        assert_true(mem[i] == -777.25);
}

static void test_refusals(void **state)
{
    (void)state;
    ref_seed(505);
    nf_surf_t s, o;
    ref_surf_random(&s, 3, 2, 7, 6, 0.0, 2.0, 1.0, 3.0, 0.5, 2.0);
    const int nu = s.nu, nv = s.nv;
    double *mem = wire_out(&s, nu + 4, nv, &o);
    const long nm = NF_SURF_DOUBLES(nu + 4, nv, 3, 2);
    double bad[][4] = {
        {0.0, 0.5, 1.0, 1.5},          /* at the domain start */
        {0.5, 1.0, 1.5, 2.0},          /* at the domain end */
        {-0.1, 0.5, 1.0, 1.5},         /* outside */
        {0.5, 1.0, 2.5, 2.6},          /* outside */
        {0.5, 1.5, 1.0, 1.6},          /* decreasing */
        {0.3, 0.3, 0.3, 0.3},          /* multiplicity 4 > p = 3 */
        {0.5, NAN, 1.0, 1.5},          /* not a number */
        {0.5, 1.0, 1.5, INFINITY},     /* not finite */
        {s.U[4], s.U[4], s.U[4], 1.9}, /* existing knot: 1 + 3 > p */
    };
    for (size_t t = 0; t < sizeof bad / sizeof bad[0]; t++) {
        fill(mem, nm);
        assert_int_equal(nf_refine_u(&s, bad[t], 4, &o), NF_EKNOTS);
        assert_untouched(mem, nm);
    }
    fill(mem, nm);
    /* (4 times: the shape out is wired for; the knot is what is wrong.) */
    assert_int_equal(nf_refine_insert_u(&s, 0.0, 4, &o), NF_EKNOTS);
    assert_int_equal(nf_refine_insert_u(&s, 2.0, 4, &o), NF_EKNOTS);
    assert_int_equal(nf_refine_insert_u(&s, NAN, 4, &o), NF_EKNOTS);
    assert_int_equal(nf_refine_insert_u(&s, 1.0, 4, &o), NF_EKNOTS); /* 4 > p */
    assert_untouched(mem, nm);
    /* Out wired to the wrong shape, null pointers, negative counts. */
    double X[4] = {0.2, 0.4, 0.6, 0.8};
    assert_int_equal(nf_refine_u(&s, X, 3, &o), NF_EARG);
    assert_int_equal(nf_refine_v(&s, X, 4, &o), NF_EARG);
    assert_int_equal(nf_refine_u(&s, X, -1, &o), NF_EARG);
    assert_int_equal(nf_refine_u(&s, NULL, 4, &o), NF_EARG);
    assert_int_equal(nf_refine_u(NULL, X, 4, &o), NF_EARG);
    assert_int_equal(nf_refine_u(&s, X, 4, NULL), NF_EARG);
    assert_int_equal(nf_refine_uniform(&s, &o), NF_EARG);
    assert_int_equal(nf_refine_insert_u(&s, 0.5, 3, &o), NF_EARG);
    nf_surf_t o2 = o;
    o2.q = 3;
    assert_int_equal(nf_refine_u(&s, X, 4, &o2), NF_EARG);
    o2 = o;
    o2.w = NULL; /* rational input, nowhere to put the weights */
    assert_int_equal(nf_refine_u(&s, X, 4, &o2), NF_EARG);
    assert_untouched(mem, nm);
    /* An invalid input surface: nf_surf_check's answer. */
    nf_surf_t t = s;
    double keep = s.w[3];
    s.w[3] = -1.0;
    assert_int_equal(nf_refine_u(&t, X, 4, &o), NF_EWEIGHT);
    s.w[3] = keep;
    t.p = NF_MAX_DEGREE + 1;
    assert_int_equal(nf_refine_u(&t, X, 4, &o), NF_EDEGREE);
    assert_untouched(mem, nm);
    /* Good knots now go through. */
    assert_int_equal(nf_refine_u(&s, X, 4, &o), NF_OK);
    assert_same_surface(&s, &o);
    free(mem);
    ref_surf_free(&s);
}

/* Net sizes and the budget (NF_MAX_CP), refused before writing, with no
 * overflow for absurd counts. */
static void test_sizes_budget(void **state)
{
    (void)state;
    nf_surf_t s;
    ref_seed(606);
    ref_surf_random(&s, 3, 3, 10, 12, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    int nu = -1, nv = -1;
    assert_int_equal(nf_refine_size(&s, 0, 0, &nu, &nv), NF_OK);
    assert_int_equal(nu, 10);
    assert_int_equal(nv, 12);
    assert_int_equal(nf_refine_size(&s, 5, 7, &nu, &nv), NF_OK);
    assert_int_equal(nu, 15);
    assert_int_equal(nv, 19);
    nu = nv = -1;
    assert_int_equal(nf_refine_size(&s, INT_MAX, 0, &nu, &nv), NF_EBUDGET);
    assert_int_equal(nf_refine_size(&s, 0, INT_MAX, &nu, &nv), NF_EBUDGET);
    assert_int_equal(nf_refine_size(&s, INT_MAX, INT_MAX, &nu, &nv), NF_EBUDGET);
    assert_int_equal(nf_refine_size(&s, (int)(NF_MAX_CP / 12), 0, &nu, &nv), NF_EBUDGET);
    assert_int_equal(nu, -1); /* outputs only on success */
    assert_int_equal(nf_refine_size(&s, (int)(NF_MAX_CP / 12) - 10, 0, &nu, &nv), NF_OK);
    assert_true((long)nu * nv <= NF_MAX_CP);
    assert_int_equal(nf_refine_size(&s, -1, 0, &nu, &nv), NF_EARG);
    assert_int_equal(nf_refine_size(NULL, 0, 0, &nu, &nv), NF_EARG);
    ref_surf_free(&s);

    /* A net whose uniform refinement is over the board's budget: refused,
     * out untouched; nf_refine_uniform_size says so first. */
    int side = 2;
    while ((long)(2 * side - 3) * (2 * side - 3) <= NF_MAX_CP)
        side++;
    assert_true((long)side * side <= NF_MAX_CP);
    ref_surf_random(&s, 3, 3, side, side, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    assert_int_equal(nf_refine_uniform_size(&s, &nu, &nv), NF_EBUDGET);
    nf_surf_t o;
    double *mem = wire_out(&s, 2 * side - 3, 2 * side - 3, &o);
    const long nm = NF_SURF_DOUBLES(2 * side - 3, 2 * side - 3, 3, 3);
    fill(mem, nm);
    assert_int_equal(nf_refine_uniform(&s, &o), NF_EBUDGET);
    assert_untouched(mem, nm);
    free(mem);
    ref_surf_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_refine_same_surface),
        cmocka_unit_test(test_insert_multiplicity),
        cmocka_unit_test(test_isocurve_row),
        cmocka_unit_test(test_uniform),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_sizes_budget),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
