/* SPDX-License-Identifier: MIT */
/* test_loop.c: the bookkeeping of the fitting loop: per-span excess of the
 * points out of tolerance and the knots chosen from it (against a
 * brute-force span search and a sorted ranking), the ridge rule, and the
 * robust scale from the |r| histogram (against the nearest-rank order
 * statistic of a sorted array) with Tukey's weights (closed form). */

#include "cf_test.h"
#include "nf_err.h"
#include "nf_knots.h"
#include "nf_refine.h"
#include "nf_robust.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A bicubic 10 x 8 surface on [0,1]^2 whose u knots hold a double knot
 * (an empty span at 0.25): 7 span slots in u, 6 of them non-empty. */
static void make_surf(nf_surf_t *s)
{
    ref_surf_random(s, 3, 3, 10, 8, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    const double ui[6] = {0.1, 0.25, 0.25, 0.5, 0.7, 0.85};
    for (int i = 0; i < 6; i++)
        s->U[4 + i] = ui[i];
    assert_int_equal(nf_surf_check(s), NF_OK);
}

/* Slot of parameter t by linear search over the non-empty spans (the last
 * one closed on the right), independent of nf_find_span. */
static int brute_span(const double *T, int deg, int n, double t)
{
    int last = -1;
    for (int i = deg; i < n; i++)
        if (T[i] < T[i + 1]) {
            last = i;
            if (t >= T[i] && t < T[i + 1])
                return i - deg;
        }
    return last - deg;
}

typedef struct pt {
    double u, v, d;
} pt_t;

static void add_all(nf_spanres_t *r, const pt_t *p, int n)
{
    for (int k = 0; k < n; k++)
        nf_spanres_add(r, p[k].u, p[k].v, p[k].d);
}

/* Points within tolerance on a grid over the domain (the data range). */
static void add_background(nf_spanres_t *r)
{
    for (int j = 0; j < 60; j++)
        for (int i = 0; i < 60; i++)
            nf_spanres_add(r, (i + 0.5) / 60, (j + 0.5) / 60, 0.0);
}

static void test_spanres_counts(void **state)
{
    (void)state;
    ref_seed(11);
    nf_surf_t s;
    make_surf(&s);
    double mem[NF_SPANRES_DOUBLES(10, 8, 3, 3)];
    nf_spanres_t r;
    const double tol = 0.05;
    assert_int_equal(nf_spanres_init(&r, &s, tol, mem), NF_OK);
    assert_int_equal(nf_spanres_init(&r, &s, 0.0, mem), NF_EARG);
    assert_int_equal(nf_spanres_init(&r, &s, tol, mem), NF_OK);
    enum { M = 3000 };
    static pt_t p[M];
    double bu[7][4], bv[5][4], e2tot = 0.0;
    for (int i = 0; i < 7; i++)
        bu[i][0] = bu[i][1] = 0, bu[i][2] = HUGE_VAL, bu[i][3] = -HUGE_VAL;
    for (int i = 0; i < 5; i++)
        bv[i][0] = bv[i][1] = 0, bv[i][2] = HUGE_VAL, bv[i][3] = -HUGE_VAL;
    long out = 0;
    for (int k = 0; k < M; k++) {
        p[k].u = k == 0 ? 1.0 : ref_rand(0, 1); /* the domain's end too */
        p[k].v = k == 1 ? 0.0 : ref_rand(0, 1);
        p[k].d = ref_rand(-0.2, 0.2);
        double e = fabs(p[k].d) - tol;
        int a = brute_span(s.U, 3, 10, p[k].u), b = brute_span(s.V, 3, 8, p[k].v);
        bu[a][2] = fmin(bu[a][2], p[k].u), bu[a][3] = fmax(bu[a][3], p[k].u);
        bv[b][2] = fmin(bv[b][2], p[k].v), bv[b][3] = fmax(bv[b][3], p[k].v);
        if (e > 0) {
            bu[a][0] += 1, bu[a][1] += e * e;
            bv[b][0] += 1, bv[b][1] += e * e;
            e2tot += e * e;
            out++;
        }
    }
    add_all(&r, p, M);
    nf_spanres_add(&r, NAN, 0.5, 1.0); /* ignored */
    assert_int_equal(r.out, out);
    assert_near(r.e2, e2tot, 1e-12 * e2tot);
    for (int i = 0; i < 7; i++)
        for (int c = 0; c < 4; c++)
            assert_true(r.su[4 * i + c] == bu[i][c] ||
                        fabs(r.su[4 * i + c] - bu[i][c]) <= 1e-12 * fabs(bu[i][c]));
    for (int i = 0; i < 5; i++)
        for (int c = 0; c < 4; c++)
            assert_true(r.sv[4 * i + c] == bv[i][c] ||
                        fabs(r.sv[4 * i + c] - bv[i][c]) <= 1e-12 * fabs(bv[i][c]));
    /* The empty span [0.25, 0.25) gets nothing; u = 1 counts in the last span. */
    assert_true(r.su[4 * 2] == 0.0 && r.su[4 * 2 + 1] == 0.0 && r.su[4 * 2 + 2] == HUGE_VAL);
    assert_true(r.su[4 * 6 + 3] == 1.0);
    ref_surf_free(&s);
}

static const double *g_slot;
static int by_excess(const void *a, const void *b)
{
    int i = *(const int *)a, j = *(const int *)b;
    double x = g_slot[4 * i + 1], y = g_slot[4 * j + 1];
    return x < y ? 1 : x > y ? -1 : (i > j) - (i < j);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Expected picks: the spans sorted by excess (qsort), those with data on
 * both sides of their midpoint taken until they hold NF_KNOTS_SHARE of the
 * excess; each halved. */
static int brute_pick(const double *slot, const double *T, int deg, int n, int max, double *X)
{
    int idx[64] = {0}, m = 0, ns = n - deg;
    double total = 0, got = 0;
    for (int i = 0; i < ns; i++)
        idx[i] = i, total += slot[4 * i + 1];
    g_slot = slot;
    qsort(idx, (size_t)ns, sizeof idx[0], by_excess);
    for (int t = 0; t < ns && m < max && got < NF_KNOTS_SHARE * total; t++) {
        int i = idx[t];
        if (!(slot[4 * i + 1] > 0))
            break;
        double mid = 0.5 * (T[deg + i] + T[deg + i + 1]);
        if (!(slot[4 * i + 2] < mid && mid < slot[4 * i + 3]))
            continue;
        X[m++] = mid;
        got += slot[4 * i + 1];
    }
    qsort(X, (size_t)m, sizeof X[0], cmp_double);
    return m;
}

static void test_pick_matches_ranking(void **state)
{
    (void)state;
    nf_surf_t s;
    make_surf(&s);
    for (int trial = 0; trial < 50; trial++) {
        ref_seed(100 + (unsigned long long)trial);
        double mem[NF_SPANRES_DOUBLES(10, 8, 3, 3)];
        nf_spanres_t r;
        nf_spanres_init(&r, &s, 0.05, mem);
        if (trial % 2)
            add_background(&r); /* else the data range is the points' alone */
        /* Excess concentrated near a random spot, plus scattered noise. */
        double cu = ref_rand(0, 1), cv = ref_rand(0, 1);
        for (int k = 0; k < 400; k++) {
            double u = fmin(fmax(cu + ref_rand(-0.15, 0.15), 0), 1);
            double v = fmin(fmax(cv + ref_rand(-0.15, 0.15), 0), 1);
            nf_spanres_add(&r, u, v, ref_rand(0.0, 0.5));
            nf_spanres_add(&r, ref_rand(0, 1), ref_rand(0, 1), ref_rand(-0.08, 0.08));
        }
        for (int max = 1; max <= 7; max += 3) {
            double X[8] = {0}, Y[8] = {0};
            int spread = -1;
            int m = nf_spanres_pick(&r, 0, max, X, &spread);
            int want = brute_pick(r.su, s.U, 3, 10, max, Y);
            assert_int_equal(m, want);
            assert_true(m <= max);
            assert_true(spread == (m > NF_KNOTS_SPREAD * 6));
            for (int i = 0; i < m; i++) {
                assert_near(X[i], Y[i], 1e-15);
                if (i)
                    assert_true(X[i] > X[i - 1]); /* one knot per span: distinct */
            }
            m = nf_spanres_pick(&r, 1, max, X, NULL);
            want = brute_pick(r.sv, s.V, 3, 8, max, Y);
            assert_int_equal(m, want);
            for (int i = 0; i < m; i++)
                assert_near(X[i], Y[i], 1e-15);
        }
        /* The picks are valid knots: insertion accepts them. */
        double Xu[7], Xv[5];
        int ru, rv;
        nf_spanres_choose(&r, 7, Xu, &ru, 5, Xv, &rv);
        assert_true(ru + rv >= 1);
        nf_surf_t a, b;
        double *ma = calloc((size_t)NF_SURF_DOUBLES(10 + ru, 8, 3, 3), sizeof(double));
        double *mb = calloc((size_t)NF_SURF_DOUBLES(10 + ru, 8 + rv, 3, 3), sizeof(double));
        assert_non_null(ma);
        assert_non_null(mb);
        nf_surf_wire(&a, 3, 3, 10 + ru, 8, ma);
        nf_surf_wire(&b, 3, 3, 10 + ru, 8 + rv, mb);
        assert_int_equal(nf_refine_u(&s, Xu, ru, &a), NF_OK);
        assert_int_equal(nf_refine_v(&a, Xv, rv, &b), NF_OK);
        assert_int_equal(nf_surf_check(&b), NF_OK);
        free(ma);
        free(mb);
    }
    ref_surf_free(&s);
}

static void test_pick_location(void **state)
{
    (void)state;
    nf_surf_t s;
    make_surf(&s);
    double mem[NF_SPANRES_DOUBLES(10, 8, 3, 3)], X[4];
    nf_spanres_t r;
    /* Nothing out of tolerance: no knot. */
    nf_spanres_init(&r, &s, 0.05, mem);
    nf_spanres_add(&r, 0.3, 0.3, 0.05);
    nf_spanres_add(&r, 0.3, 0.3, -0.049);
    assert_int_equal(r.out, 0);
    assert_int_equal(nf_spanres_pick(&r, 0, 4, X, NULL), 0);
    /* All excess in span [0.5, 0.7) with data on both sides of 0.6: halved. */
    nf_spanres_add(&r, 0.52, 0.4, 0.15);
    nf_spanres_add(&r, 0.68, 0.4, -0.01);
    assert_int_equal(nf_spanres_pick(&r, 0, 4, X, NULL), 1);
    assert_true(X[0] == 0.6);
    /* The worst span [0.5, 0.7) has data on one side of its midpoint only
     * (narrower than the data spacing): the next span [0.7, 0.85) is split. */
    nf_spanres_init(&r, &s, 0.05, mem);
    nf_spanres_add(&r, 0.55, 0.4, 1.0);
    nf_spanres_add(&r, 0.58, 0.4, 1.0);
    nf_spanres_add(&r, 0.71, 0.4, 0.1);
    nf_spanres_add(&r, 0.84, 0.4, 0.0);
    assert_int_equal(nf_spanres_pick(&r, 0, 4, X, NULL), 1);
    assert_near(X[0], 0.775, 1e-15);
    ref_surf_free(&s);
}

/* A ridge along v at u = 0.6: the excess sits in one u span and in every
 * v span alike; only u is refined. A bump: both. */
static void test_choose_ridge(void **state)
{
    (void)state;
    nf_surf_t s;
    make_surf(&s);
    double mem[NF_SPANRES_DOUBLES(10, 8, 3, 3)], Xu[7], Xv[5];
    nf_spanres_t r;
    int ru, rv;
    nf_spanres_init(&r, &s, 0.05, mem);
    add_background(&r);
    for (int k = 0; k < 500; k++)
        nf_spanres_add(&r, 0.6 + 0.01 * sin(k), (k + 0.5) / 500.0, 0.3);
    nf_spanres_choose(&r, 7, Xu, &ru, 5, Xv, &rv);
    assert_int_equal(ru, 1);
    assert_int_equal(rv, 0);
    assert_true(Xu[0] == 0.6);
    nf_spanres_init(&r, &s, 0.05, mem);
    add_background(&r);
    for (int k = 0; k < 500; k++)
        nf_spanres_add(&r, 0.6 + 0.01 * sin(k), 0.3 + 0.01 * cos(k), 0.3);
    nf_spanres_choose(&r, 7, Xu, &ru, 5, Xv, &rv);
    assert_int_equal(ru, 1);
    assert_int_equal(rv, 1);
    ref_surf_free(&s);
}

/* Rejected points: 1 % spikes everywhere stay out of the spans; a cluster
 * of rejected misfit in one cell is folded into its spans. */
static void test_fold(void **state)
{
    (void)state;
    nf_surf_t s;
    make_surf(&s);
    double mem[NF_SPANRES_DOUBLES(10, 8, 3, 3)], X[7];
    nf_spanres_t r;
    /* The feature's cell: u [0.5, 0.7) (slot 4) x the v span holding 0.5. */
    int l = 4, kk = -1;
    for (int j = 3; j < 8; j++)
        if (s.V[j] <= 0.5 && 0.5 < s.V[j + 1])
            kk = j - 3;
    assert_true(kk >= 0 && s.U[l + 3] == 0.5 && s.U[l + 4] == 0.7);
    nf_spanres_init(&r, &s, 0.05, mem);
    ref_seed(5);
    int in_cell = 0; /* spikes that fall in the feature's cell fold with it */
    for (int k = 0; k < 20000; k++) {
        double u = ref_rand(0, 1), v = ref_rand(0, 1);
        if (k % 100 == 0) {
            nf_spanres_add_rejected(&r, u, v, 5.0);
            in_cell += u >= 0.5 && u < 0.7 && v >= s.V[kk + 3] && v < s.V[kk + 4];
        } else
            nf_spanres_add(&r, u, v, 0.01);
    }
    assert_int_equal(r.out, 0);
    assert_int_equal(r.rej, 200);
    assert_int_equal(r.all, 20000);
    assert_int_equal(nf_spanres_fold(&r), 0); /* spikes alone: nothing is a feature */
    assert_int_equal(nf_spanres_pick(&r, 0, 7, X, NULL), 0);
    /* A feature in that cell: 60 rejected points out of tolerance. */
    for (int k = 0; k < 60; k++)
        nf_spanres_add_rejected(&r, 0.55 + 0.1 * ref_rand(0, 1), 0.5, 0.3);
    assert_int_equal(nf_spanres_fold(&r), 1);
    assert_int_equal(nf_spanres_fold(&r), 0); /* cleared */
    const double e2 = 60 * 0.0625 + in_cell * 4.95 * 4.95;
    assert_int_equal(r.out, 60 + in_cell);
    assert_near(r.e2, e2, 1e-12 * e2);
    assert_near(r.su[4 * l + 1], e2, 1e-12 * e2);
    assert_near(r.sv[4 * kk + 1], e2, 1e-12 * e2);
    assert_int_equal(nf_spanres_pick(&r, 0, 7, X, NULL), 1);
    assert_true(X[0] == 0.6);
    ref_surf_free(&s);
}

static double gauss(void)
{
    return sqrt(-2.0 * log(ref_rand(1e-300, 1.0))) * cos(6.283185307179586 * ref_rand(0, 1));
}

/* The histogram's quantiles against the nearest-rank order statistic of
 * the sorted |r|. */
static void test_rhist_quantile(void **state)
{
    (void)state;
    static nf_rhist_t h;
    static double a[5001];
    const double ps[] = {0.01, 0.25, 0.5, 0.9, 0.99, 1.0};
    for (int trial = 0; trial < 12; trial++) {
        ref_seed(7 + (unsigned long long)trial);
        int n = trial == 0 ? 1 : 37 * trial * trial;
        nf_rhist_init(&h);
        for (int k = 0; k < n; k++) {
            double r;
            switch (trial % 3) {
            case 0: r = pow(10.0, ref_rand(-6, 1)) * (ref_rand(0, 1) < 0.5 ? -1 : 1); break;
            case 1: r = 0.005 * gauss(); break;
            default: r = k % 10 == 0 ? 0.0 : (k % 10 == 1 ? 5e-10 : 3.0 * gauss()); break;
            }
            a[k] = fabs(r);
            nf_rhist_add(&h, r);
        }
        nf_rhist_add(&h, INFINITY); /* ignored */
        assert_int_equal(h.n, n);
        qsort(a, (size_t)n, sizeof a[0], cmp_double);
        for (size_t t = 0; t < sizeof ps / sizeof ps[0]; t++) {
            long rank = (long)ceil(ps[t] * n);
            double exact = a[rank < 1 ? 0 : rank - 1], est = nf_rhist_quantile(&h, ps[t]);
            if (exact < NF_RHIST_LO)
                assert_true(est == 0.0);
            else
                assert_near(est, exact, NF_RHIST_RELERR * exact);
        }
    }
    nf_rhist_init(&h);
    assert_true(nf_rhist_quantile(&h, 0.5) == 0.0);
    assert_true(nf_rhist_sigma(&h) == 0.0);
}

/* MAD scale of Gaussian residuals with 1 % gross outliers (+/- 5 mm):
 * sigma within the histogram's error and the sampling spread (3 %). */
static void test_sigma_outliers(void **state)
{
    (void)state;
    static nf_rhist_t h;
    ref_seed(3);
    nf_rhist_init(&h);
    for (int k = 0; k < 100000; k++)
        nf_rhist_add(&h, k % 100 == 0 ? (k % 200 ? 5.0 : -5.0) : 0.005 * gauss());
    assert_near(nf_rhist_sigma(&h), 0.005, 0.03 * 0.005 + NF_RHIST_RELERR * 0.005);
    assert_true(h.max == 5.0);
}

static void test_tukey(void **state)
{
    (void)state;
    assert_true(nf_tukey(0.0, 2.0) == 1.0);
    assert_near(nf_tukey(1.0, 2.0), 0.5625, 1e-15);
    assert_near(nf_tukey(-1.0, 2.0), 0.5625, 1e-15);
    assert_near(nf_tukey(0.2, 1.0), 0.96 * 0.96, 1e-15);
    assert_true(nf_tukey(2.0, 2.0) == 0.0);
    assert_true(nf_tukey(-7.0, 2.0) == 0.0);
    assert_true(nf_tukey(NAN, 2.0) == 0.0);
}

/* nf_refine_widest by hand: the widest span halved, the first of equal
 * ones, counting the knots already chosen. */
static void test_refine_widest(void **state)
{
    (void)state;
    static const double B[] = {0, 0, 0, 1, 1, 1}; /* p = 2, n = 3: one span */
    double X[4];
    assert_int_equal(nf_refine_widest(B, 3, 2, 3, X), NF_OK);
    assert_true(X[0] == 0.25 && X[1] == 0.5 && X[2] == 0.75);
    static const double U[] = {0, 0, 0, 0.1, 1, 1, 1}; /* spans 0.1 and 0.9 */
    assert_int_equal(nf_refine_widest(U, 4, 2, 2, X), NF_OK);
    /* 0.55 splits [0.1, 1]; then [0.1, 0.55] and [0.55, 1] tie at 0.45:
     * the first, 0.325. */
    assert_true(X[0] == 0.325 && X[1] == 0.55);
    static const double R[] = {0, 0, 0, 0.5, 0.5, 1, 1, 1}; /* a double knot: spans 0.5, 0.5 */
    assert_int_equal(nf_refine_widest(R, 5, 2, 1, X), NF_OK);
    assert_true(X[0] == 0.25);
    assert_int_equal(nf_refine_widest(U, 4, 2, 0, NULL), NF_OK);
    assert_int_equal(nf_refine_widest(U, 4, 2, -1, X), NF_EARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spanres_counts), cmocka_unit_test(test_pick_matches_ranking),
        cmocka_unit_test(test_pick_location),  cmocka_unit_test(test_choose_ridge),
        cmocka_unit_test(test_fold),           cmocka_unit_test(test_rhist_quantile),
        cmocka_unit_test(test_sigma_outliers), cmocka_unit_test(test_tukey),
        cmocka_unit_test(test_refine_widest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
