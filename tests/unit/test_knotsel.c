/* SPDX-License-Identifier: MIT */
/* test_knotsel.c: the knot chooser (nf_knotsel) and the loop's rules
 * (nf_loopctl): per-span counts against a brute-force span search; knots
 * where the misfit is, none where the data rows do not support a span,
 * u against v by misfit per control point (closed form), the caps; alpha per
 * level against a dense solve of Eq. 7 (ref_dense.c); and the whole loop on
 * a narrow bump against uniform refinement and held-out rows. */
#include "cf_test.h"
#include "nf_basis.h"
#include "nf_err.h"
#include "nf_knotsel.h"
#include "nf_loopctl.h"
#include "nf_refine.h"
#include "nf_surf.h"
#include "ref_dense.h"
#include "ref_kloop.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A bicubic plane x = u, y = v, z = 0 on [0,1]^2 with su x sv uniform
 * spans: control points at the Greville abscissae (linear precision). */
static void plane(nf_surf_t *s, int su, int sv)
{
    ref_kloop_surf(s, 3, 3, su + 3, sv + 3);
    for (int i = 0; i < su + 7; i++)
        s->U[i] = i < 4 ? 0.0 : (i > su + 2 ? 1.0 : (double)(i - 3) / su);
    for (int i = 0; i < sv + 7; i++)
        s->V[i] = i < 4 ? 0.0 : (i > sv + 2 ? 1.0 : (double)(i - 3) / sv);
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            double *c = s->cp + 3 * (i + (long)j * s->nu);
            c[0] = nf_greville(i, 3, s->U);
            c[1] = nf_greville(j, 3, s->V);
            c[2] = 0.0;
        }
    assert_int_equal(nf_surf_check(s), NF_OK);
}

/* Span slot of t by linear search (last span closed), independent of
 * nf_find_span. */
static int brute_slot(const double *T, int deg, int n, double t)
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

static void test_counts(void **state)
{
    (void)state;
    ref_seed(5);
    nf_surf_t s;
    ref_surf_random(&s, 3, 2, 11, 9, 0.0, 2.0, -1.0, 1.0, 1.0, 1.0);
    const int nsu = 8, nsv = 7;
    double *mem = malloc(sizeof(double) * NF_KNOTSEL_DOUBLES(11, 9, 3, 2));
    nf_knotsel_t a;
    const double tol = 0.3;
    assert_int_equal(nf_knotsel_init(&a, &s, 0.0, mem), NF_EARG);
    assert_int_equal(nf_knotsel_init(&a, &s, tol, mem), NF_OK);
    long nu[8] = {0}, nv[7] = {0}, out = 0;
    double ru[8] = {0}, rv[7] = {0}, g = 0.0;
    for (int k = 0; k < 5000; k++) {
        double u = ref_rand(0.0, 2.0), v = ref_rand(-1.0, 1.0), d = ref_rand(-1.0, 1.0);
        nf_knotsel_add(&a, u, v, d);
        int i = brute_slot(s.U, 3, 11, u), j = brute_slot(s.V, 2, 9, v);
        nu[i]++;
        nv[j]++;
        ru[i] += d * d;
        rv[j] += d * d;
        if (fabs(d) > tol) {
            out++;
            g += d * d;
        }
    }
    nf_knotsel_add(&a, NAN, 0.5, 1.0); /* ignored */
    assert_int_equal(a.n, 5000);
    assert_int_equal(a.out, out);
    assert_near(a.g, g, 1e-9 * g);
    for (int i = 0; i < nsu; i++) {
        assert_int_equal(nf_knotsel_span_points(&a, 0, i), nu[i]);
        assert_near(nf_knotsel_span_rss(&a, 0, i), ru[i], 1e-9 * (1 + ru[i]));
    }
    for (int j = 0; j < nsv; j++) {
        assert_int_equal(nf_knotsel_span_points(&a, 1, j), nv[j]);
        assert_near(nf_knotsel_span_rss(&a, 1, j), rv[j], 1e-9 * (1 + rv[j]));
    }
    free(mem);
    ref_surf_free(&s);
}

/* A pass counted in two parts and merged (nf_knotsel_merge) holds what one
 * pass over all points holds: the same counts, bounds and sums (to
 * rounding), so the chooser picks the same knots. */
static void test_merge_all(void **state)
{
    (void)state;
    ref_seed(17);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 12, 10, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    const long nd = NF_KNOTSEL_DOUBLES(12, 10, 3, 3);
    double *m1 = malloc(sizeof(double) * (size_t)nd), *m2 = malloc(sizeof(double) * (size_t)nd),
           *m3 = malloc(sizeof(double) * (size_t)nd);
    nf_knotsel_t all, one, two, other;
    const double tol = 0.2;
    assert_int_equal(nf_knotsel_init(&all, &s, tol, m1), NF_OK);
    assert_int_equal(nf_knotsel_init(&one, &s, tol, m2), NF_OK);
    assert_int_equal(nf_knotsel_init(&two, &s, tol, m3), NF_OK);
    for (int k = 0; k < 6000; k++) {
        /* misfit in one corner, as a feature draws knots */
        const double u = ref_rand(0.0, 1.0), v = ref_rand(0.0, 1.0),
                     d = (u > 0.6 && v < 0.3 ? 0.8 : 0.1) * ref_rand(-1.0, 1.0);
        nf_knotsel_add(&all, u, v, d);
        nf_knotsel_add(k < 2500 ? &one : &two, u, v, d);
    }
    assert_int_equal(nf_knotsel_merge(&one, &two), NF_OK);
    assert_int_equal(one.n, all.n);
    assert_int_equal(one.out, all.out);
    assert_near(one.rss, all.rss, 1e-12 * all.rss);
    assert_near(one.g, all.g, 1e-12 * all.g);
    for (int dir = 0; dir < 2; dir++)
        for (int i = 0; i < (dir ? 7 : 9); i++) {
            assert_int_equal(nf_knotsel_span_points(&one, dir, i),
                             nf_knotsel_span_points(&all, dir, i));
            const double r = nf_knotsel_span_rss(&all, dir, i);
            assert_near(nf_knotsel_span_rss(&one, dir, i), r, 1e-12 * (1 + r));
        }
    nf_knotsel_opts_t o;
    memset(&o, 0, sizeof o);
    nf_knotsel_cand_t ca[64], cb[64];
    int na = 0, nb = 0, sa = 0, sb = 0;
    nf_knotsel_choose(&all, &o, ca, 64, &na, &sa);
    nf_knotsel_choose(&one, &o, cb, 64, &nb, &sb);
    assert_true(na > 0);
    assert_int_equal(nb, na);
    assert_int_equal(sb, sa);
    for (int i = 0; i < na; i++) {
        assert_int_equal(cb[i].dir, ca[i].dir);
        assert_int_equal(cb[i].span, ca[i].span);
        assert_near(cb[i].x, ca[i].x, 1e-12);
    }
    /* Another surface's or tolerance's counts do not merge. */
    assert_int_equal(nf_knotsel_init(&other, &s, 2 * tol, m3), NF_OK);
    assert_int_equal(nf_knotsel_merge(&one, &other), NF_EARG);
    assert_int_equal(nf_knotsel_merge(NULL, &one), NF_EARG);
    free(m1);
    free(m2);
    free(m3);
    ref_surf_free(&s);
}

/* Grid of gx x gy points within tolerance (d = 0), rows at (i + 0.5)/gx. */
static void grid(nf_knotsel_t *a, int gx, int gy)
{
    for (int j = 0; j < gy; j++)
        for (int i = 0; i < gx; i++)
            nf_knotsel_add(a, (i + 0.5) / gx, (j + 0.5) / gy, 0.0);
}

typedef struct sel {
    nf_surf_t s;
    double *mem;
    nf_knotsel_t a;
    nf_knotsel_cand_t c[64];
    int n, st;
} sel_t;

static void sel_start(sel_t *x, int su, int sv, double tol)
{
    plane(&x->s, su, sv);
    x->mem = malloc(sizeof(double) * (size_t)NF_KNOTSEL_DOUBLES(su + 3, sv + 3, 3, 3));
    assert_int_equal(nf_knotsel_init(&x->a, &x->s, tol, x->mem), NF_OK);
}

static void sel_end(sel_t *x)
{
    free(x->mem);
    free(x->s.U);
}

/* The first knot of a span alone (per_span 1): the rules below test its
 * placement; test_sides the knots on its sides. */
static const nf_knotsel_opts_t one = {0, 0, 0, 0.0, 0.0, 0, 0, 1, 0.0};

/* Misfit in one cell only: the first knot in each direction goes into
 * that cell's spans, a quarter span or more from their ends, near the
 * misfit's centre; nothing elsewhere. */
static void test_concentrated(void **state)
{
    (void)state;
    sel_t x;
    sel_start(&x, 8, 8, 0.1);
    grid(&x.a, 64, 64);
    /* Misfit at u in [0.40, 0.45], v in [0.30, 0.35]: u span 3, v span 2. */
    for (int j = 0; j < 6; j++)
        for (int i = 0; i < 6; i++)
            nf_knotsel_add(&x.a, 0.40 + 0.01 * i, 0.30 + 0.01 * j, 1.0);
    assert_int_equal(nf_knotsel_choose(&x.a, &one, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.st, NF_KNOTSEL_INSERT);
    assert_int_equal(x.n, 2); /* one per direction: the rest has no misfit */
    int seen[2] = {0, 0};
    for (int k = 0; k < x.n; k++) {
        const int dir = x.c[k].dir, span = x.c[k].span;
        assert_int_equal(span, dir ? 2 : 3);
        const double t0 = span / 8.0, t1 = (span + 1) / 8.0, mid = dir ? 0.325 : 0.425;
        assert_true(x.c[k].x >= t0 + 0.25 * (t1 - t0) && x.c[k].x <= t1 - 0.25 * (t1 - t0));
        /* The nearest admissible sub-bin boundary to the misfit's centre. */
        assert_true(fabs(x.c[k].x - mid) <= 0.5 * (t1 - t0) / NF_KNOTSEL_BINS + 1e-12);
        seen[dir]++;
    }
    assert_int_equal(seen[0], 1);
    assert_int_equal(seen[1], 1);
    /* The knots split into ascending arrays for nf_refine_u / _v. */
    double Xu[4], Xv[4];
    int ru, rv;
    assert_int_equal(nf_knotsel_split(x.c, x.n, Xu, 4, &ru, Xv, 4, &rv), NF_OK);
    assert_int_equal(ru, 1);
    assert_int_equal(rv, 1);
    assert_int_equal(nf_knotsel_split(x.c, x.n, Xu, 0, &ru, Xv, 4, &rv), NF_EARG);
    sel_end(&x);
}

/* The same cell with the default per_span (3): each direction also gets a
 * knot on each side of its first, at that side's misfit centroid (the
 * nearest sub-bin boundary within the side no closer than a quarter of the
 * side, rounded up to whole sub-bins, to its ends), scored by the side's
 * misfit per control point; worked out by hand from the sub-bins (width
 * 1/64): u span [0.375, 0.5): misfit rows 0.40 | 0.41 0.42 | 0.43 | 0.44
 * 0.45 in sub-bins 1, 2, 3, 4, centroid 0.425 -> 0.421875 (boundary 3);
 * left (sub-bins 0 .. 2, boundaries 1 .. 2 allowed; 0.40 .. 0.42, centroid
 * 0.41) -> 0.40625, right (sub-bins 3 .. 7, boundaries 5 .. 6; 0.43 ..
 * 0.45, centroid 0.44) -> 0.453125 (0.4375, boundary 4, would leave a fifth
 * of the side). v span [0.25, 0.375): 0.30 0.31 | 0.32 | 0.33 0.34 | 0.35
 * in sub-bins 3 .. 6, centroid 0.325 -> 0.328125 (boundary 5); left
 * (sub-bins 0 .. 4, boundaries 2 .. 3; centroid 0.31) -> 0.296875, right
 * (sub-bins 5 .. 7, boundaries 6 .. 7; centroid 0.34) -> 0.34375. g = 36
 * points of d^2 = 1, 18 a side; a knot line adds 11 control points. */
static void test_sides(void **state)
{
    (void)state;
    sel_t x;
    sel_start(&x, 8, 8, 0.1);
    grid(&x.a, 64, 64);
    for (int j = 0; j < 6; j++)
        for (int i = 0; i < 6; i++)
            nf_knotsel_add(&x.a, 0.40 + 0.01 * i, 0.30 + 0.01 * j, 1.0);
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.st, NF_KNOTSEL_INSERT);
    assert_int_equal(x.n, 6);
    const double want[2][3] = {{0.421875, 0.40625, 0.453125}, {0.328125, 0.296875, 0.34375}};
    int seen[2][3] = {{0, 0, 0}, {0, 0, 0}};
    for (int k = 0; k < x.n; k++) {
        const nf_knotsel_cand_t *c = &x.c[k];
        int hit = -1;
        for (int w = 0; w < 3; w++)
            if (fabs(c->x - want[c->dir][w]) < 1e-12)
                hit = w;
        assert_true(hit >= 0);
        if (hit < 0)
            break; /* (assert_true has failed; for the analyser) */
        seen[c->dir][hit]++;
        assert_int_equal(c->level, hit > 0);
        assert_near(c->score, (hit ? 18.0 : 36.0) / 11.0, 1e-9);
    }
    for (int d = 0; d < 2; d++)
        for (int w = 0; w < 3; w++)
            assert_int_equal(seen[d][w], 1);
    /* Best first: the two first knots (36 / 11), then the sides. */
    assert_int_equal(x.c[0].level, 0);
    assert_int_equal(x.c[1].level, 0);
    /* A side goes only with its span's first knot: with room for one knot
     * in the round (max_knots 1) it is the first knot alone. */
    nf_knotsel_opts_t k1 = {0, 0, 0, 0.0, 0.0, 1, 0, 0, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &k1, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 1);
    assert_int_equal(x.c[0].level, 0);
    /* Room for the first knots only (cap 2, the spans with misfit): the
     * sides wait, the first knots go in. */
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 2, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 2);
    assert_int_equal(x.c[0].level + x.c[1].level, 0);
    /* per_span 2: the first knot and the side holding more misfit (here
     * both hold 18: the left one, the first of equals). */
    nf_knotsel_opts_t two = {0, 0, 0, 0.0, 0.0, 0, 0, 2, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &two, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 4);
    for (int k = 0; k < x.n; k++)
        assert_true(x.c[k].level == 0 || fabs(x.c[k].x - want[x.c[k].dir][1]) < 1e-12);
    sel_end(&x);
}

/* Side knots only where the misfit is deep (NF_KNOTSEL_SIDE_DEPTH): the
 * cell of test_sides at tol 0.1 with misfit d of 36 points, the root mean
 * square of d worked out here. 5 tol (all at 0.5) or 4.47 tol (18 at 0.6,
 * 18 at 0.2: sqrt(0.2)): the first knot and both sides per direction (6);
 * 3 tol (all at 0.3) or 2.73 tol (4 at 0.7, 32 at 0.15: sqrt(0.0744), deep
 * points but a shallow span): the first knots alone (2), with uniform d
 * where test_concentrated puts them. side_depth < 0 gives every span with misfit
 * its sides, 2 gives them at 3 tol. Then both in one round on different
 * spans (ratio and share opened so both spans are taken): the deep span
 * gets its sides, the shallow one (2.5 tol) its first knot only. */
static void test_side_depth(void **state)
{
    (void)state;
    const double hi[4] = {0.5, 0.6, 0.3, 0.7}, lo[4] = {0.5, 0.2, 0.3, 0.15};
    const int nhi[4] = {36, 18, 36, 4}, want[4] = {6, 6, 2, 2};
    for (int t = 0; t < 4; t++) {
        sel_t x;
        sel_start(&x, 8, 8, 0.1);
        grid(&x.a, 64, 64);
        for (int k = 0; k < 36; k++)
            nf_knotsel_add(&x.a, 0.40 + 0.01 * (k % 6), 0.30 + 0.01 * (k / 6),
                           k < nhi[t] ? hi[t] : lo[t]);
        assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
        assert_int_equal(x.n, want[t]);
        if (want[t] == 2)
            for (int k = 0; k < x.n; k++) {
                assert_int_equal(x.c[k].level, 0);
                if (t == 2) /* uniform d: test_concentrated's places */
                    assert_near(x.c[k].x, x.c[k].dir ? 0.328125 : 0.421875, 1e-12);
            }
        if (t == 2) {
            nf_knotsel_opts_t all = {0, 0, 0, 0.0, 0.0, 0, 0, 0, -1.0};
            assert_int_equal(nf_knotsel_choose(&x.a, &all, x.c, 64, &x.n, &x.st), NF_OK);
            assert_int_equal(x.n, 6);
            nf_knotsel_opts_t two = {0, 0, 0, 0.0, 0.0, 0, 0, 0, 2.0};
            assert_int_equal(nf_knotsel_choose(&x.a, &two, x.c, 64, &x.n, &x.st), NF_OK);
            assert_int_equal(x.n, 6);
        }
        sel_end(&x);
    }
    sel_t x;
    sel_start(&x, 8, 8, 0.1);
    grid(&x.a, 64, 64);
    for (int k = 0; k < 36; k++) {
        nf_knotsel_add(&x.a, 0.40 + 0.01 * (k % 6), 0.30 + 0.01 * (k / 6), 1.0);
        nf_knotsel_add(&x.a, 0.80 + 0.01 * (k % 6), 0.80 + 0.01 * (k / 6), 0.25);
    }
    const nf_knotsel_opts_t open = {0, 0, 0, 0.01, 0.99, 0, 0, 0, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &open, x.c, 64, &x.n, &x.st), NF_OK);
    int per[2][8] = {{0}, {0}};
    for (int k = 0; k < x.n; k++)
        per[x.c[k].dir][x.c[k].span]++;
    assert_int_equal(x.n, 8);
    assert_int_equal(per[0][3], 3);
    assert_int_equal(per[1][2], 3);
    assert_int_equal(per[0][6], 1);
    assert_int_equal(per[1][6], 1);
    sel_end(&x);
}

/* Balanced spans: on random misfit (clusters of random width, place and
 * size on a 64 x 64 grid, 8 x 8 spans), every knot the chooser returns
 * leaves new spans of at least a quarter of what it splits: a first knot a
 * quarter span from the span's ends, a side's knot a quarter side from the
 * side's ends (the side runs from the span's end to its first knot). At
 * the side's own centroid, unclamped, side knots fell a sub-bin from the
 * first knot: spans of 1/64 beside spans of 1/8 (the holes field's pile
 * at its hill). Checked from the knots alone, per span. */
static void test_side_balance(void **state)
{
    (void)state;
    ref_seed(14);
    int sides = 0;
    for (int trial = 0; trial < 200; trial++) {
        sel_t x;
        sel_start(&x, 8, 8, 0.1);
        grid(&x.a, 64, 64);
        const int nc = 1 + trial % 3;
        for (int c = 0; c < nc; c++) {
            const double u0 = ref_rand(0.0, 0.95), v0 = ref_rand(0.0, 0.95),
                         wu = ref_rand(0.005, 0.05), wv = ref_rand(0.005, 0.05),
                         d = ref_rand(0.2, 3.0);
            for (int j = 0; j < 8; j++)
                for (int i = 0; i < 8; i++)
                    nf_knotsel_add(&x.a, u0 + wu * i / 7.0, v0 + wv * j / 7.0, d);
        }
        assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
        for (int k = 0; k < x.n; k++) {
            const nf_knotsel_cand_t *c = &x.c[k];
            const double t0 = c->span / 8.0, t1 = (c->span + 1) / 8.0;
            double a = t0, b = t1; /* what this knot splits */
            if (c->level) {
                double x0 = -1.0; /* its span's first knot, taken in the same round */
                for (int m = 0; m < x.n; m++)
                    if (!x.c[m].level && x.c[m].dir == c->dir && x.c[m].span == c->span)
                        x0 = x.c[m].x;
                assert_true(x0 > t0 && x0 < t1);
                if (c->x < x0)
                    b = x0;
                else
                    a = x0;
                sides++;
            }
            assert_true(c->x - a >= 0.25 * (b - a) - 1e-12);
            assert_true(b - c->x >= 0.25 * (b - a) - 1e-12);
        }
        sel_end(&x);
    }
    assert_true(sides > 100); /* the rule was exercised */
}

/* nf_knotsel_merge_span: points a holds as data without misfit (NaN, a
 * robust pass's rejects) whose misfit b holds join a's span: a's
 * candidate then scores their d^2 per control point (closed form), and
 * nothing changes in the spans not merged. */
static void test_merge(void **state)
{
    (void)state;
    sel_t x, y;
    sel_start(&x, 8, 8, 0.1);
    grid(&x.a, 64, 64);
    y = x; /* the same surface: b counts on x's net */
    y.mem = malloc(sizeof(double) * (size_t)NF_KNOTSEL_DOUBLES(11, 11, 3, 3));
    assert_int_equal(nf_knotsel_init(&y.a, &x.s, 0.1, y.mem), NF_OK);
    double g = 0.0;
    for (int i = 0; i < 20; i++) { /* a cluster in u span 3, v span 2 */
        const double u = 0.40 + 0.002 * i, v = 0.30 + 0.001 * i, d = 2.0 + 0.1 * i;
        nf_knotsel_add(&x.a, u, v, NAN);
        nf_knotsel_add(&y.a, u, v, d);
        g += d * d;
    }
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 0); /* rejected points alone: no misfit */
    assert_int_equal(nf_knotsel_merge_span(&x.a, &y.a, 0, 3), NF_OK);
    assert_int_equal(nf_knotsel_merge_span(&x.a, &y.a, 1, 2), NF_OK);
    assert_int_equal(nf_knotsel_merge_span(&x.a, &y.a, 0, 8), NF_EARG);
    assert_near(x.a.g, g, 1e-9 * g);
    assert_int_equal(nf_knotsel_choose(&x.a, &one, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 2);
    for (int k = 0; k < 2; k++) {
        assert_int_equal(x.c[k].span, x.c[k].dir ? 2 : 3);
        assert_near(x.c[k].score, g / 11.0, 1e-9 * g);
    }
    free(y.mem);
    sel_end(&x);
}

/* Data rows at v = 0.05 + 0.1 j: each v span of width 1/16 holds one row
 * at most, so no v knot may go in (it would leave a span without a row, or
 * with one row for its new control points); u, densely sampled, gets its
 * knot. With the misfit on a row spread across all u (a ridge along u),
 * the only splittable direction is blocked: status data limit. */
static void test_rows(void **state)
{
    (void)state;
    sel_t x;
    sel_start(&x, 16, 16, 0.1);
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 200; i++)
            nf_knotsel_add(&x.a, (i + 0.5) / 200, 0.05 + 0.1 * j, 0.0);
    for (int i = 0; i < 20; i++)
        nf_knotsel_add(&x.a, 0.52 + 0.001 * i, 0.45, 1.0);
    assert_int_equal(nf_knotsel_choose(&x.a, &one, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.st, NF_KNOTSEL_INSERT);
    assert_int_equal(x.n, 1);
    assert_int_equal(x.c[0].dir, 0);
    sel_end(&x);

    sel_start(&x, 16, 16, 0.1);
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 200; i++)
            nf_knotsel_add(&x.a, (i + 0.5) / 200, 0.05 + 0.1 * j, 0.0);
    /* Misfit all along the row v = 0.45, in every u span: u would split
     * (scoring low per control point, but the only candidates) ... */
    for (int i = 0; i < 200; i++)
        nf_knotsel_add(&x.a, (i + 0.5) / 200, 0.45, 1.0);
    assert_int_equal(nf_knotsel_choose(&x.a, &one, x.c, 64, &x.n, &x.st), NF_OK);
    for (int k = 0; k < x.n; k++)
        assert_int_equal(x.c[k].dir, 0);
    /* ... unless u needs more points per new span than its spans hold. */
    nf_knotsel_opts_t o = {0, 0, 10000, 0.0, 0.0, 0, 0, 1, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &o, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 0);
    assert_int_equal(x.st, NF_KNOTSEL_DATA);
    sel_end(&x);

    /* Two rows in a v span, 0.40 and 0.43 (span [0.375, 0.4375)): a
     * boundary between them is admissible with min_rows 1, not with 2. */
    sel_start(&x, 16, 16, 0.1);
    for (int i = 0; i < 1000; i++) { /* 2000 points: half of them above the 380 control points */
        nf_knotsel_add(&x.a, (i + 0.5) / 1000, 0.40, 0.0);
        nf_knotsel_add(&x.a, (i + 0.5) / 1000, 0.43, i % 7 == 0 ? 1.0 : 0.0);
    }
    assert_int_equal(nf_knotsel_choose(&x.a, &one, x.c, 64, &x.n, &x.st), NF_OK);
    double xv = -1.0; /* the v knot */
    for (int k = 0; k < x.n; k++)
        if (x.c[k].dir == 1)
            xv = x.c[k].x;
    assert_true(xv > 0.40 && xv < 0.43);
    nf_knotsel_opts_t two = {0, 2, 0, 0.0, 0.0, 0, 0, 1, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &two, x.c, 64, &x.n, &x.st), NF_OK);
    for (int k = 0; k < x.n; k++)
        assert_int_equal(x.c[k].dir, 0);
    sel_end(&x);
}

/* A misfit in one cell, on nets of 20 x 6 and 6 x 20 spans: a u knot adds
 * Nv control points, a v knot Nu, so the direction with the smaller cost
 * ranks first, with scores g / cost (g summed here by hand). */
static void test_gain_order(void **state)
{
    (void)state;
    for (int flip = 0; flip < 2; flip++) {
        sel_t x;
        const int su = flip ? 6 : 20, sv = flip ? 20 : 6;
        sel_start(&x, su, sv, 0.1);
        grid(&x.a, 200, 200);
        double g = 0.0;
        for (int i = 0; i < 40; i++) {
            double d = 0.5 + 0.01 * i;
            nf_knotsel_add(&x.a, 0.51 + 0.0005 * i, 0.52 + 0.0005 * i, d);
            g += d * d;
        }
        nf_knotsel_opts_t o = {0, 0, 0, 0.01, 0.99, 0, 0, 1, 0.0};
        assert_int_equal(nf_knotsel_choose(&x.a, &o, x.c, 64, &x.n, &x.st), NF_OK);
        assert_int_equal(x.n, 2);
        const int first = flip ? 1 : 0; /* the direction adding fewer control points */
        assert_int_equal(x.c[0].dir, first);
        assert_near(x.c[0].score, g / (first ? su + 3 : sv + 3), 1e-9 * g);
        assert_near(x.c[1].score, g / (first ? sv + 3 : su + 3), 1e-9 * g);
        /* With the default ratio (0.25) the costlier line (9 vs 23: 0.39)
         * still goes in; with ratio 0.5 it waits. */
        o.ratio = 0.5;
        assert_int_equal(nf_knotsel_choose(&x.a, &o, x.c, 64, &x.n, &x.st), NF_OK);
        assert_int_equal(x.n, 1);
        assert_int_equal(x.c[0].dir, first);
        sel_end(&x);
    }
}

/* The net never passes half the points seen, nor max_cp; when the first
 * split would, the status says which cap. */
static void test_caps(void **state)
{
    (void)state;
    sel_t x;
    sel_start(&x, 5, 5, 0.1); /* 8 x 8 = 64 control points */
    /* 170 points: half is 85, so one knot line (72) fits, two (80) too,
     * three (88 or 90) not. Misfit everywhere so that every span bids. */
    for (int j = 0; j < 10; j++)
        for (int i = 0; i < 17; i++)
            nf_knotsel_add(&x.a, (i + 0.5) / 17, (j + 0.5) / 10, 1.0 + 0.01 * (i + j));
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.st, NF_KNOTSEL_INSERT);
    int ru = 0, rv = 0;
    for (int k = 0; k < x.n; k++)
        x.c[k].dir ? rv++ : ru++;
    assert_true((8L + ru) * (8 + rv) <= 85);
    assert_true(x.n >= 1);
    /* The round budget: the best candidate always, then only what fits. */
    for (long add = 1; add <= 16; add += 15) {
        nf_knotsel_opts_t b = {0, 0, 0, 0.0, 0.0, 0, add, 0, 0.0};
        assert_int_equal(nf_knotsel_choose(&x.a, &b, x.c, 64, &x.n, &x.st), NF_OK);
        ru = rv = 0;
        for (int k = 0; k < x.n; k++)
            x.c[k].dir ? rv++ : ru++;
        assert_int_equal(x.n, add == 1 ? 1 : 2);
        assert_true(add == 1 || (8L + ru) * (8 + rv) - 64 <= add);
    }
    /* max_cp below half the points binds instead. */
    nf_knotsel_opts_t o = {70, 1, 1, 0.0, 0.0, 0, 0, 0, 0.0};
    assert_int_equal(nf_knotsel_choose(&x.a, &o, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 0);
    assert_int_equal(x.st, NF_KNOTSEL_MAX_CP);
    sel_end(&x);

    sel_start(&x, 5, 5, 0.1);
    for (int j = 0; j < 8; j++) /* 128 points: half is 64, the net already */
        for (int i = 0; i < 16; i++)
            nf_knotsel_add(&x.a, (i + 0.5) / 16, (j + 0.5) / 8, 1.0);
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.n, 0);
    assert_int_equal(x.st, NF_KNOTSEL_HALF_PTS);
    /* Nothing out of tolerance: nothing to do. */
    assert_int_equal(nf_knotsel_init(&x.a, &x.s, 0.1, x.mem), NF_OK);
    grid(&x.a, 16, 16);
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, 64, &x.n, &x.st), NF_OK);
    assert_int_equal(x.st, NF_KNOTSEL_NONE_OUT);
    assert_int_equal(nf_knotsel_choose(&x.a, NULL, x.c, -1, &x.n, &x.st), NF_EARG);
    for (int st = 0; st <= NF_KNOTSEL_MAX_CP; st++)
        assert_string_not_equal(nf_knotsel_status_str(st), "unknown status");
    sel_end(&x);
}

/* The stop rules, round by round: the 95.56 -> 95.58 -> 95.63 %
 * stops for no progress (two rounds in a row under 0.1 point), a single
 * lost round does not; then the chooser's status and the round limit. */
/* Sum of squared residuals of the least-squares piecewise-constant fit of
 * y (n samples at t = (i + 0.5) / n) on m equal bins: each bin's mean,
 * computed here by brute force (the model has m parameters). */
static double bins_rss(const double *y, int n, int m)
{
    double ss = 0.0;
    for (int b = 0; b < m; b++) {
        double sum = 0.0;
        int k = 0;
        for (int i = 0; i < n; i++)
            if ((i * m) / n == b)
                sum += y[i], k++;
        const double mean = k ? sum / k : 0.0;
        for (int i = 0; i < n; i++)
            if ((i * m) / n == b)
                ss += (y[i] - mean) * (y[i] - mean);
    }
    return ss;
}

/* nf_loopctl_supported on least-squares fits computed here: on pure noise
 * (a Gaussian sample, fixed seed) doubling the bins of a piecewise-constant
 * fit takes about one variance per bin added, and the rule says no
 * (Akaike's 2 per parameter); a step the coarse bins straddle, under the
 * same noise, is shape the finer bins take out, and it says yes. Then the
 * cases it leaves alone. */
static void test_supported(void **state)
{
    (void)state;
    enum { N = 4096 };
    static double y[N], step[N];
    unsigned long long r = 0x9E3779B97F4A7C15ULL;
    for (int i = 0; i < N; i += 2) { /* Box-Muller, sigma 0.1 */
        double u[2];
        for (int k = 0; k < 2; k++) {
            r ^= r << 13, r ^= r >> 7, r ^= r << 17;
            u[k] = ((double)(r >> 11) + 0.5) / 9007199254740992.0;
        }
        const double m = 0.1 * sqrt(-2.0 * log(u[0]));
        y[i] = m * cos(6.283185307179586 * u[1]);
        y[i + 1] = m * sin(6.283185307179586 * u[1]);
    }
    for (int i = 0; i < N; i++) /* a step at t = 0.3: inside a bin of 8, on an edge of 64 */
        step[i] = y[i] + ((double)i + 0.5 >= 0.3 * N ? 1.0 : 0.0);
    int noise_no = 0, step_yes = 0;
    for (int m = 8; m <= 256; m *= 2) {
        const double a = bins_rss(y, N, m), b = bins_rss(y, N, 2 * m);
        /* about one variance (0.01) per bin added: the noise's share */
        assert_true(a - b > 0.3 * 0.01 * m && a - b < 2.0 * 0.01 * m);
        noise_no += !nf_loopctl_supported(a, m, b, 2 * m, N);
    }
    assert_int_equal(noise_no, 6); /* never supported on noise */
    for (int m = 8; m <= 32; m *= 2) {
        const double a = bins_rss(step, N, m), b = bins_rss(step, N, 2 * m);
        step_yes += nf_loopctl_supported(a, m, b, 2 * m, N);
    }
    assert_true(step_yes >= 1); /* the split that isolates the step is supported */
    /* 8 -> 16 bins: the step (0.3 of 4096 = 1228.8) moves from inside a bin
     * of 512 to inside one of 256, half the straddling error gone. */
    assert_true(nf_loopctl_supported(bins_rss(step, N, 8), 8, bins_rss(step, N, 16), 16, N));
    /* Left alone: no control point added, no room, sums not finite. */
    assert_true(nf_loopctl_supported(1.0, 10, 1.0, 10, 100));
    assert_true(nf_loopctl_supported(1.0, 10, 1.0, 9, 100));
    assert_true(nf_loopctl_supported(1.0, 10, 0.99, 100, 100));
    assert_true(nf_loopctl_supported(NAN, 10, 0.5, 20, 100));
    assert_true(nf_loopctl_supported(1.0, 10, INFINITY, 20, 100));
    /* The edge by hand: 10 added, variance 0.5 / 80: a fall of 0.125 is
     * exactly 2 variances each (supported), just under it not. */
    assert_true(nf_loopctl_supported(0.625, 10, 0.5, 20, 100));
    assert_false(nf_loopctl_supported(0.6249, 10, 0.5, 20, 100));
}

static void test_verdict(void **state)
{
    (void)state;
    nf_loopctl_t c;
    const int ins = NF_KNOTSEL_INSERT;
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 95.56, 99.0, 0, 0, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_int_equal(nf_loopctl_verdict(&c, 95.58, 99.0, 0, 1, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_int_equal(nf_loopctl_verdict(&c, 95.63, 99.0, 0, 2, 12, ins), NF_LOOPCTL_NO_PROGRESS);
    /* A coarse round that loses share, then one that gains: no stop. */
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 47.7, 99.0, 0, 0, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_int_equal(nf_loopctl_verdict(&c, 39.7, 99.0, 0, 1, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_int_equal(nf_loopctl_verdict(&c, 53.3, 99.0, 0, 2, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_near(c.best, 53.3, 0.0);
    assert_int_equal(c.stall, 0);
    /* min_gain given: 0.5 point; 53.7 and 53.9 are under it. */
    assert_int_equal(nf_loopctl_verdict(&c, 53.7, 99.0, 0.5, 3, 12, ins), NF_LOOPCTL_CONTINUE);
    assert_int_equal(nf_loopctl_verdict(&c, 53.9, 99.0, 0.5, 4, 12, ins), NF_LOOPCTL_NO_PROGRESS);
    /* Met wins over everything. */
    assert_int_equal(nf_loopctl_verdict(&c, 99.0, 99.0, 0, 5, 12, NF_KNOTSEL_DATA), NF_LOOPCTL_MET);
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 50.0, 99.0, 0, 0, 12, NF_KNOTSEL_DATA),
                     NF_LOOPCTL_DATA_LIMIT);
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 50.0, 99.0, 0, 0, 12, NF_KNOTSEL_HALF_PTS),
                     NF_LOOPCTL_DATA_LIMIT);
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 50.0, 99.0, 0, 0, 12, NF_KNOTSEL_MAX_CP),
                     NF_LOOPCTL_MAX_CP);
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_verdict(&c, 50.0, 99.0, 0, 11, 12, ins), NF_LOOPCTL_MAX_ROUNDS);
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_MET), "met");
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_DATA_LIMIT), "not_met_data_limit");
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_MAX_CP), "not_met_max_cp");
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_NO_PROGRESS), "not_met_no_progress");
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_MAX_ROUNDS), "not_met_max_rounds");
    assert_string_equal(nf_loopctl_str(NF_LOOPCTL_CONTINUE), "continue");
}

/* The round budget, by hand: 100 control points more brought 20 points of
 * share; 9 are missing, so 45 more, within [50, 200] -> 50 (more than
 * NF_LOOPCTL_FINE_GAP missing: FITPACK's half-step floor); a round that
 * gained nothing may double; never under one knot line. */
static void test_budget(void **state)
{
    (void)state;
    nf_loopctl_t c;
    nf_loopctl_init(&c);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 0); /* no history: no limit */
    nf_loopctl_record(&c, 70.0, 400);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 0);
    nf_loopctl_record(&c, 90.0, 500);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 50);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 80), 80);
    nf_loopctl_record(&c, 90.1, 550); /* 50 more for 0.1 point: est 4,450 -> 2 x 50 */
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 100);
    nf_loopctl_record(&c, 89.0, 650); /* lost share: twice the last step */
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 200);
}

/* Near the goal (at most NF_LOOPCTL_FINE_GAP points missing) the budget
 * is the estimate, not half the last step: the last round takes the knot
 * lines the missing share needs (cliffs at 4,047 points: 2 lines where 1
 * met). By hand: 100 more brought 4 points, 1 missing: est 25 (the floor
 * said 50); 50 more brought 1.8, 0.2 missing: est 5.6 -> one line, 10 (the
 * floor said 25); a lost round still doubles. */
static void test_budget_near_goal(void **state)
{
    (void)state;
    nf_loopctl_t c;
    nf_loopctl_init(&c);
    nf_loopctl_record(&c, 94.0, 400);
    nf_loopctl_record(&c, 98.0, 500);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 25);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 30), 30); /* one knot line at least */
    nf_loopctl_record(&c, 97.0, 600);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 200);
    nf_loopctl_record(&c, 98.8, 650);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 10);
    /* After a fine step that misses the goal: 25 more brought 0.9 of 1
     * missing: est 2.8, one line (10) again; 25 more that brought 0.2 of 1
     * missing: est 100, capped by twice the step before the fine one
     * (200), not twice the fine step (50). */
    nf_loopctl_init(&c);
    nf_loopctl_record(&c, 94.0, 400);
    nf_loopctl_record(&c, 98.0, 500);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 25);
    nf_loopctl_record(&c, 98.9, 525);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 10);
    nf_loopctl_init(&c);
    nf_loopctl_record(&c, 94.0, 400);
    nf_loopctl_record(&c, 98.0, 500);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 25);
    nf_loopctl_record(&c, 98.2, 525);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 100);
    /* 5.5 missing: the floor again (100 for 13.5 points: est 40.7 -> 50) */
    nf_loopctl_init(&c);
    nf_loopctl_record(&c, 80.0, 400);
    nf_loopctl_record(&c, 93.5, 500);
    assert_int_equal(nf_loopctl_budget(&c, 99.0, 10), 50);
}

/* alpha per level: closed form on uniform nets, and the fit with the scaled
 * alpha equal to a dense solve of Eq. 7 with that alpha, on data with a
 * hole (control points there held by alpha and beta alone). */
static void test_alpha(void **state)
{
    (void)state;
    nf_surf_t s0, s1;
    plane(&s0, 2, 3);
    plane(&s1, 8, 6);
    /* Spacing 1/2 x 1/3 against 1/8 x 1/6: (h0 / h)^2 = 4 x 2. */
    assert_near(nf_loopctl_alpha(0.1, &s0, &s1, 2.0), 0.1 * 4.0 * 2.0, 1e-15);
    assert_near(nf_loopctl_alpha(0.1, &s0, &s1, -2.0), 0.1 / 8.0, 1e-15);
    assert_near(nf_loopctl_alpha(0.1, &s0, &s1, 1.0), 0.1 * sqrt(8.0), 1e-15);
    assert_near(nf_loopctl_alpha(0.1, &s0, &s1, 0.0), 0.1, 0.0);
    assert_near(nf_loopctl_alpha(0.1, &s0, &s0, -2.0), 0.1, 0.0);
    assert_true(isnan(nf_loopctl_alpha(NAN, &s0, &s1, 2.0)));
    /* Local refinement: s1 with two knots more in u, spacing 1/10. */
    nf_surf_t s2;
    ref_kloop_surf(&s2, 3, 3, s1.nu + 2, s1.nv);
    const double X[2] = {0.3, 0.7};
    assert_int_equal(nf_refine_u(&s1, X, 2, &s2), NF_OK);
    assert_near(nf_loopctl_alpha(0.1, &s0, &s2, 2.0), 0.1 * 5.0 * 2.0, 1e-14);

    /* The dense reference: z = smooth field sampled outside a hole. */
    enum { G = 30 };
    double *pts = malloc(sizeof(double) * 5 * G * G);
    long M = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double u = (i + 0.5) / G, v = (j + 0.5) / G;
            if (fabs(u - 0.55) < 0.2 && fabs(v - 0.5) < 0.2)
                continue;
            double *r = pts + 5 * M++;
            r[0] = u;
            r[1] = v;
            r[2] = u;
            r[3] = v;
            r[4] = sin(3 * u) * cos(2 * v);
        }
    const double alpha = nf_loopctl_alpha(0.1, &s0, &s2, NF_LOOPCTL_ALPHA_K);
    ref_kloop_cfg_t c;
    memset(&c, 0, sizeof c);
    ref_kloop_out_t o;
    c.tol = 1e9; /* one fit, met at once */
    c.within = 100.0;
    c.beta = 1e-3;
    c.max_rounds = 1;
    c.alpha = alpha; /* the level's alpha, given as is (no scaling from s2 itself) */
    assert_int_equal(ref_kloop_run(&s2, pts, M, &c, &o), NF_OK);
    const long N = (long)s2.nu * s2.nv;
    double *A, *b, *x = malloc(sizeof(double) * 3 * (size_t)N);
    ref_eq7(&s2, pts, M, alpha, 1e-3, &A, &b);
    assert_int_equal(ref_solve(A, b, N, x), 0);
    double err = 0.0, mag = 0.0;
    for (long i = 0; i < 3 * N; i++) {
        err = fmax(err, fabs(o.fit.cp[i] - x[i]));
        mag = fmax(mag, fabs(x[i]));
    }
    assert_true(err <= 1e-8 * mag);
    free(A);
    free(b);
    free(x);
    free(pts);
    ref_kloop_free(&o);
    free(s0.U);
    free(s1.U);
    free(s2.U);
}

/* The height field of the loop test: a narrow bump (sigma 0.05 of the
 * unit square) on a slope. */
static double bump(double u, double v)
{
    const double du = u - 0.37, dv = v - 0.61;
    return exp(-(du * du + dv * dv) / (2 * 0.05 * 0.05)) + 0.2 * u;
}

static int cmp_dbl(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The whole loop on an 80 x 80 grid with every 5th row held out (5120
 * points fitted, 1280 held out), T = 0.01 (1 % of the height), 99 %
 * within: the chooser meets it with fewer control points than uniform
 * refinement needs for the same share, never more than half the points,
 * and the held-out rows' 99th percentile stays within 2 T. */
static void test_loop_bump(void **state)
{
    (void)state;
    enum { G = 80, K = 5 };
    const double T = 0.01;
    double *pts = calloc(5 * G * G, sizeof(double)), *hold = calloc(5 * G * G, sizeof(double));
    long M = 0, H = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            const double u = (i + 0.5) / G, v = (j + 0.5) / G;
            double *r = j % K == K / 2 ? hold + 5 * H++ : pts + 5 * M++;
            r[0] = u;
            r[1] = v;
            r[2] = u;
            r[3] = v;
            r[4] = bump(u, v);
        }
    nf_surf_t base;
    plane(&base, 1, 1);
    ref_kloop_cfg_t c;
    memset(&c, 0, sizeof c);
    c.tol = T;
    c.within = 99.0;
    c.alpha = 0.1;
    c.beta = 1e-3;
    c.max_rounds = 30;
    c.scale_alpha = 1;
    c.alpha_k = NF_LOOPCTL_ALPHA_K;
    c.progress = 1;
    c.budget = 1;
    ref_kloop_out_t ours, uni;
    assert_int_equal(ref_kloop_run(&base, pts, M, &c, &ours), NF_OK);
    c.uniform = 1;
    c.scale_alpha = 0;
    c.progress = 0;
    c.budget = 0;
    assert_int_equal(ref_kloop_run(&base, pts, M, &c, &uni), NF_OK);
    assert_int_equal(ours.verdict, NF_LOOPCTL_MET);
    assert_int_equal(uni.verdict, NF_LOOPCTL_MET);
    assert_true(ours.within_pct >= 99.0);
    /* The share within is recounted here on the returned fit. */
    long in = 0;
    for (long k = 0; k < M; k++)
        in += ref_kloop_dist(&ours.fit, pts + 5 * k) <= T;
    assert_near(100.0 * (double)in / (double)M, ours.within_pct, 1e-12);
    assert_true(ours.cp == (long)ours.fit.nu * ours.fit.nv);
    assert_true(ours.cp < uni.cp);
    assert_true(2 * ours.cp <= M);
    double *d = malloc(sizeof(double) * (size_t)H);
    for (long k = 0; k < H; k++)
        d[k] = ref_kloop_dist(&ours.fit, hold + 5 * k);
    qsort(d, (size_t)H, sizeof(double), cmp_dbl);
    const double p99 = d[(long)ceil(0.99 * (double)H) - 1]; /* nearest rank */
    print_message("loop: %ld points, ours %ld control points (%d x %d, %.3f %% within, %d rounds), "
                  "uniform %ld; held-out p99 %.4g (2T %.3g)\n",
                  M, ours.cp, ours.fit.nu, ours.fit.nv, ours.within_pct, ours.rounds, uni.cp, p99,
                  2 * T);
    assert_true(p99 <= 2 * T);
    free(d);
    free(pts);
    free(hold);
    ref_kloop_free(&ours);
    ref_kloop_free(&uni);
    free(base.U);
}

int main(void)
{
    const struct CMUnitTest t[] = {
        cmocka_unit_test(test_counts),     cmocka_unit_test(test_concentrated),
        cmocka_unit_test(test_sides),      cmocka_unit_test(test_side_balance),
        cmocka_unit_test(test_side_depth), cmocka_unit_test(test_merge),
        cmocka_unit_test(test_merge_all),  cmocka_unit_test(test_rows),
        cmocka_unit_test(test_gain_order), cmocka_unit_test(test_caps),
        cmocka_unit_test(test_verdict),    cmocka_unit_test(test_supported),
        cmocka_unit_test(test_budget),     cmocka_unit_test(test_budget_near_goal),
        cmocka_unit_test(test_alpha),      cmocka_unit_test(test_loop_bump),
    };
    return cmocka_run_group_tests(t, NULL, NULL);
}
