/* SPDX-License-Identifier: MIT */
/* test_footprint.c: the data footprint (nf_footprint) and the pinned
 * control points (nf_fit_pin, issue 14 honest edges): counts against cells
 * computed independently, the per-control-point beta against a dense solve
 * of the modified Eq. 7, and a part measured over part of its domain only:
 * outside the footprint the fit stays at the nominal, inside it follows
 * the data. */
#include "cf_test.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_footprint.h"
#include "nf_solve.h"
#include "ref_dense.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Standard normal deviate (Box-Muller on ref_rand). */
static double gauss(void)
{
    const double a = 1.0 - ref_rand(0.0, 1.0), b = ref_rand(0.0, 1.0);
    return sqrt(-2.0 * log(a)) * cos(2.0 * 3.14159265358979323846 * b);
}

/* A smooth bicubic part on [0, 1]^2, uniform knots, control points 60 mm
 * across, heights a gentle wave plus off times a tilt-and-bulge: off = 0 is
 * the nominal, off > 0 the measured part that differs from it everywhere. */
static double *part(nf_surf_t *s, int nu, int nv, double off)
{
    double *mem = calloc((size_t)NF_SURF_DOUBLES(nu, nv, 3, 3), sizeof(double));
    assert_non_null(mem);
    nf_surf_wire(s, 3, 3, nu, nv, mem);
    for (int i = 0; i < nu + 4; i++)
        s->U[i] = i < 4 ? 0.0 : (i >= nu ? 1.0 : (double)(i - 3) / (nu - 3));
    for (int j = 0; j < nv + 4; j++)
        s->V[j] = j < 4 ? 0.0 : (j >= nv ? 1.0 : (double)(j - 3) / (nv - 3));
    s->w = NULL;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            const double x = 60.0 * i / (nu - 1), y = 60.0 * j / (nv - 1);
            double *c = s->cp + 3 * (i + (long)j * nu);
            c[0] = x;
            c[1] = y;
            c[2] =
                3.0 * sin(0.05 * x) * cos(0.04 * y) + off * (0.5 + x / 60.0 + 0.5 * sin(0.1 * y));
        }
    return mem;
}

static double *fp_mem(const nf_surf_t *s, size_t *bytes)
{
    const long b = nf_footprint_bytes(s->nu, s->nv, s->p, s->q);
    assert_true(b > 0);
    assert_int_equal(b, NF_BYTES_FOOTPRINT(s->nu, s->nv, s->p, s->q));
    *bytes = (size_t)b;
    void *m = malloc(*bytes);
    assert_non_null(m);
    return m;
}

/* Fit rows (u v x y z) on base with the defaults; control points flagged
 * in pin (NULL: none) get beta_pin (nf_fit_pin). P: 3N. */
static void fit(const nf_surf_t *base, const double *pts, long M, const unsigned char *pin,
                double beta_pin, nf_solver_t sv, double *P)
{
    const long need = nf_fit_bytes(base->nu, base->nv, base->p, base->q, sv);
    void *mem = malloc((size_t)need);
    assert_non_null(mem);
    nf_arena_t ar;
    nf_arena_init(&ar, mem, (size_t)need);
    nf_fit_params_t prm = {NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, sv};
    nf_fit_t f;
    assert_int_equal(nf_fit_init(&f, base, &prm, &ar), NF_OK);
    assert_int_equal(nf_fit_add_rows(&f, pts, M, NULL), NF_OK);
    assert_int_equal(nf_fit_pin(&f, 0, 1.0), NF_ESTATE); /* before finish */
    assert_int_equal(nf_fit_finish(&f), NF_OK);
    for (long i = 0; pin && i < f.n; i++)
        if (pin[i])
            assert_int_equal(nf_fit_pin(&f, i, beta_pin), NF_OK);
    nf_solve_opts_t o = {1e-14, 200000, 1};
    nf_solve_stats_t st;
    assert_int_equal(nf_fit_solve(&f, sv, &o, &st), NF_OK);
    memcpy(P, f.P, sizeof(double) * 3 * (size_t)f.n);
    free(mem);
}

/* Points at random parameters in [ua, ub] x [0, 1] on t, Gaussian noise. */
static double *sample(const nf_surf_t *t, long M, double ua, double ub, double sigma)
{
    double *pts = malloc(sizeof(double) * 5 * (size_t)M);
    assert_non_null(pts);
    for (long k = 0; k < M; k++) {
        double *q = pts + 5 * k;
        q[0] = ref_rand(ua, ub);
        q[1] = ref_rand(0.0, 1.0);
        nf_surf_eval(t, q[0], q[1], q + 2);
        for (int c = 0; c < 3; c++)
            q[2 + c] += sigma * gauss();
    }
    return pts;
}

/* Two footprints of parts of the points merged (nf_footprint_merge) count
 * what one footprint of all of them counts, cell by cell; a saturated
 * cell stays saturated; another surface's footprint does not merge. */
static void test_merge(void **state)
{
    (void)state;
    ref_seed(1422);
    nf_surf_t s, t;
    double *sm = part(&s, 9, 7, 0.0), *tm = part(&t, 9, 7, 0.0);
    size_t bytes;
    void *m1 = fp_mem(&s, &bytes), *m2 = fp_mem(&s, &bytes), *m3 = fp_mem(&s, &bytes),
         *m4 = fp_mem(&t, &bytes);
    nf_footprint_t all, a, b, other;
    assert_int_equal(nf_footprint_init(&all, &s, m1, bytes), NF_OK);
    assert_int_equal(nf_footprint_init(&a, &s, m2, bytes), NF_OK);
    assert_int_equal(nf_footprint_init(&b, &s, m3, bytes), NF_OK);
    assert_int_equal(nf_footprint_init(&other, &t, m4, bytes), NF_OK);
    for (int k = 0; k < 4000; k++) {
        const double u = ref_rand(0.0, 0.7), v = ref_rand(0.2, 1.0);
        assert_int_equal(nf_footprint_add(&all, u, v), NF_OK);
        assert_int_equal(nf_footprint_add(k % 3 ? &a : &b, u, v), NF_OK);
    }
    assert_int_equal(nf_footprint_merge(&a, &b), NF_OK);
    assert_true(all.points == 4000 && a.points == 4000);
    assert_memory_equal(a.count, all.count, sizeof(uint32_t) * (size_t)(all.cu * all.cv));
    a.count[0] = UINT32_MAX - 1;
    b.count[0] = 5;
    assert_int_equal(nf_footprint_merge(&a, &b), NF_OK);
    assert_true(a.count[0] == UINT32_MAX);
    assert_int_equal(nf_footprint_merge(&a, &other), NF_EARG);
    assert_int_equal(nf_footprint_merge(&a, NULL), NF_EARG);
    free(m1);
    free(m2);
    free(m3);
    free(m4);
    free(sm);
    free(tm);
}

/* Counts per cell against the cell computed by hand (uniform knots: span
 * width 1 / (n - 3), cells half of it), and the statistics of a footprint
 * covering u < 0.5 exactly. */
static void test_cells_and_stats(void **state)
{
    (void)state;
    ref_seed(1421);
    nf_surf_t s;
    double *sm = part(&s, 9, 7, 0.0); /* 6 x 4 spans: 12 x 8 cells */
    size_t bytes;
    void *m = fp_mem(&s, &bytes);
    nf_footprint_t fp;
    assert_int_equal(nf_footprint_init(&fp, &s, m, bytes - 1), NF_EARENA);
    assert_int_equal(nf_footprint_init(&fp, &s, m, bytes), NF_OK);
    assert_int_equal(fp.cu, 12);
    assert_int_equal(fp.cv, 8);
    static long ref[8][12];
    memset(ref, 0, sizeof ref);
    for (int k = 0; k < 4000; k++) {
        const double u = ref_rand(0.0, 0.5), v = ref_rand(0.0, 1.0);
        assert_int_equal(nf_footprint_add(&fp, u, v), NF_OK);
        ref[(int)(v * 8.0)][(int)(u * 12.0)]++;
    }
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 12; i++)
            assert_int_equal(nf_footprint_cell(&fp, i, j), ref[j][i]);
    double box[4];
    nf_footprint_cell_box(&fp, 5, 3, box);
    assert_near(box[0], 5.0 / 12.0, 1e-15);
    assert_near(box[1], 6.0 / 12.0, 1e-15);
    assert_near(box[2], 3.0 / 8.0, 1e-15);
    assert_near(box[3], 4.0 / 8.0, 1e-15);
    assert_int_equal(nf_footprint_add(&fp, 1.5, 0.5), NF_EDOMAIN);
    assert_int_equal(nf_footprint_add(&fp, NAN, 0.5), NF_ENONFINITE);
    /* Pinned: support spans a-3..a of 6 from the first (0-based), i.e.
     * u in [(a - 3) / 6, (a + 1) / 6] within [0, 1]: no data when
     * (a - 3) / 6 >= 0.5, a >= 6: columns 6, 7, 8 of 9, every row. */
    assert_int_equal(nf_footprint_pin(&fp, 1), 3 * 7);
    for (int b = 0; b < 7; b++)
        for (int a = 0; a < 9; a++)
            assert_int_equal(fp.pin[a + 9 * b], a >= 6);
    nf_footprint_stats_t st;
    nf_footprint_stats(&fp, &st);
    print_message("footprint: %ld cells, %ld filled, %ld empty, %ld on the outline, %ld "
                  "control points pinned\n",
                  st.cells, st.filled, st.empty, st.outline, st.pinned);
    assert_int_equal(st.cells, 96);
    assert_int_equal(st.filled, 48);
    assert_int_equal(st.empty, 48);
    assert_int_equal(st.outline, 8); /* column 5, one per row of cells */
    assert_int_equal(st.pinned, 21);
    /* No cell has all its 16 control points pinned: every span has one
     * (column a = l - 3 <= 5) whose support reaches into the data. */
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 12; i++)
            assert_int_equal(nf_footprint_cell_pinned(&fp, i, j), i >= 12);
    free(m);
    free(sm);
}

/* nf_fit_pin is beta_i in the diagonal of Eq. 7: against the dense solve of
 * Eq. 7 with beta_i added to A_ii and beta_i P0_i to b_i. */
static void test_pin_dense(void **state)
{
    (void)state;
    ref_seed(1422);
    nf_surf_t s;
    ref_surf_random(&s, 3, 3, 8, 7, 0, 1, 0, 1, 0.5, 2.0);
    const long M = 3000, n = (long)s.nu * s.nv;
    double *pts = malloc(sizeof(double) * 5 * (size_t)M);
    for (long k = 0; k < M; k++) {
        double *q = pts + 5 * k;
        q[0] = ref_rand(0.0, 0.55);
        q[1] = ref_rand(0.0, 1.0);
        for (int c = 0; c < 3; c++)
            q[2 + c] = ref_rand(-5.0, 5.0) + 10.0 * c * q[c % 2];
    }
    size_t bytes;
    void *m = fp_mem(&s, &bytes);
    nf_footprint_t fp;
    assert_int_equal(nf_footprint_init(&fp, &s, m, bytes), NF_OK);
    for (long k = 0; k < M; k++)
        assert_int_equal(nf_footprint_add(&fp, pts[5 * k], pts[5 * k + 1]), NF_OK);
    const long pinned = nf_footprint_pin(&fp, 1);
    assert_true(pinned > 0 && pinned < n);
    double *A, *b, *X = malloc(sizeof(double) * 3 * (size_t)n);
    double *P = malloc(sizeof(double) * 3 * (size_t)n);
    const double bp = 0.7;
    ref_eq7(&s, pts, M, NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, &A, &b);
    for (long i = 0; i < n; i++)
        if (fp.pin[i]) {
            A[i * n + i] += bp;
            for (int c = 0; c < 3; c++)
                b[3 * i + c] += bp * s.cp[3 * i + c];
        }
    assert_int_equal(ref_solve(A, b, n, X), 0);
    const nf_solver_t which[] = {NF_SOLVER_CHOL, NF_SOLVER_PCG, NF_SOLVER_GS};
    for (int w = 0; w < 3; w++) {
        fit(&s, pts, M, fp.pin, bp, which[w], P);
        double d = 0.0, sc = 0.0;
        for (long i = 0; i < 3 * n; i++) {
            d = fmax(d, fabs(P[i] - X[i]));
            sc = fmax(sc, fabs(X[i]));
        }
        print_message("pinned %ld of %ld, %s: |P - dense| %.3g (scale %.3g)\n", pinned, n,
                      nf_solver_name(which[w]), d, sc);
        assert_true(d <= 1e-9 * sc);
    }
    /* Arguments. */
    nf_fit_t f;
    memset(&f, 0, sizeof f);
    f.finished = 1;
    f.n = n;
    assert_int_equal(nf_fit_pin(&f, -1, 1.0), NF_EARG);
    assert_int_equal(nf_fit_pin(&f, n, 1.0), NF_EARG);
    assert_int_equal(nf_fit_pin(&f, 0, -1.0), NF_EARG);
    assert_int_equal(nf_fit_pin(&f, 0, INFINITY), NF_EARG);
    free(A);
    free(b);
    free(X);
    free(P);
    free(m);
    free(pts);
    ref_surf_free(&s);
}

/* Largest |S_a - S_b| over a 9 x 9 grid in each cell for which sel() holds. */
typedef int (*cell_sel_t)(const nf_footprint_t *fp, int i, int j);

static double gap_in(const nf_footprint_t *fp, cell_sel_t sel, const nf_surf_t *a,
                     const nf_surf_t *b, long *ncells)
{
    double g = 0.0;
    *ncells = 0;
    for (int j = 0; j < fp->cv; j++)
        for (int i = 0; i < fp->cu; i++) {
            if (!sel(fp, i, j))
                continue;
            ++*ncells;
            double box[4];
            nf_footprint_cell_box(fp, i, j, box);
            for (int y = 0; y <= 8; y++)
                for (int x = 0; x <= 8; x++) {
                    const double u = box[0] + (box[1] - box[0]) * x / 8.0,
                                 v = box[2] + (box[3] - box[2]) * y / 8.0;
                    double A[3], B[3];
                    nf_surf_eval(a, u, v, A);
                    nf_surf_eval(b, u, v, B);
                    g = fmax(g, sqrt((A[0] - B[0]) * (A[0] - B[0]) + (A[1] - B[1]) * (A[1] - B[1]) +
                                     (A[2] - B[2]) * (A[2] - B[2])));
                }
        }
    return g;
}

/* Largest excursion of a's z beyond the interval between n's and t's z
 * (all three share x, y up to the fit: the parts are height fields) over a
 * 9 x 9 grid in each cell for which sel() holds: 0 for a blend between the
 * nominal and the part, > 0 for an overshoot (an extrapolation). */
static double overshoot_in(const nf_footprint_t *fp, cell_sel_t sel, const nf_surf_t *a,
                           const nf_surf_t *n, const nf_surf_t *t)
{
    double g = 0.0;
    for (int j = 0; j < fp->cv; j++)
        for (int i = 0; i < fp->cu; i++) {
            if (!sel(fp, i, j))
                continue;
            double box[4];
            nf_footprint_cell_box(fp, i, j, box);
            for (int y = 0; y <= 8; y++)
                for (int x = 0; x <= 8; x++) {
                    const double u = box[0] + (box[1] - box[0]) * x / 8.0,
                                 v = box[2] + (box[3] - box[2]) * y / 8.0;
                    double A[3], N[3], T[3];
                    nf_surf_eval(a, u, v, A);
                    nf_surf_eval(n, u, v, N);
                    nf_surf_eval(t, u, v, T);
                    const double lo = fmin(N[2], T[2]), hi = fmax(N[2], T[2]);
                    g = fmax(g, fmax(lo - A[2], A[2] - hi));
                }
        }
    return g;
}

/* Inside: a cell with data whose 4-neighbours all hold data too. */
static int sel_inside(const nf_footprint_t *fp, int i, int j)
{
    if (!nf_footprint_cell(fp, i, j))
        return 0;
    const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
    for (int t = 0; t < 4; t++) {
        const int a = nb[t][0], b = nb[t][1];
        if (a >= 0 && a < fp->cu && b >= 0 && b < fp->cv && !nf_footprint_cell(fp, a, b))
            return 0;
    }
    return 1;
}

/* The band between: no data, but some control point of the cell bears data. */
static int sel_band(const nf_footprint_t *fp, int i, int j)
{
    return !nf_footprint_cell(fp, i, j) && !nf_footprint_cell_pinned(fp, i, j);
}

/* A part measured over u < 0.45 only, differing from its nominal by 0.5 to
 * 2 mm everywhere: where every control point is pinned the fit stays at
 * the nominal within the noise sigma, inside the footprint it follows the
 * part within 3 sigma, and between the two it blends from one to the other
 * without overshooting either; without the pins the unmeasured side moves
 * away from the nominal (the extrapolation of issue 14). */
static void test_honest_edges(void **state)
{
    (void)state;
    ref_seed(1423);
    nf_surf_t nom, truth;
    double *nm = part(&nom, 14, 10, 0.0), *tm = part(&truth, 14, 10, 1.0);
    const long M = 20000, n = (long)nom.nu * nom.nv;
    const double sigma = 0.005;
    double *pts = sample(&truth, M, 0.0, 0.45, sigma);
    size_t bytes;
    void *m = fp_mem(&nom, &bytes);
    nf_footprint_t fp;
    assert_int_equal(nf_footprint_init(&fp, &nom, m, bytes), NF_OK);
    for (long k = 0; k < M; k++)
        assert_int_equal(nf_footprint_add(&fp, pts[5 * k], pts[5 * k + 1]), NF_OK);
    nf_footprint_pin(&fp, 1);
    nf_footprint_stats_t st;
    nf_footprint_stats(&fp, &st);
    double *P = malloc(sizeof(double) * 3 * (size_t)n);
    nf_surf_t fitted = nom;
    fitted.cp = P;
    long nout, nin;
    fit(&nom, pts, M, NULL, 0.0, NF_SOLVER_CHOL, P);
    const double out_free = gap_in(&fp, nf_footprint_cell_pinned, &fitted, &nom, &nout);
    const double in_free = gap_in(&fp, sel_inside, &fitted, &truth, &nin);
    const double band_over_free = overshoot_in(&fp, sel_band, &fitted, &nom, &truth);
    fit(&nom, pts, M, fp.pin, NF_FOOTPRINT_BETA, NF_SOLVER_CHOL, P);
    const double out_pin = gap_in(&fp, nf_footprint_cell_pinned, &fitted, &nom, &nout);
    const double in_pin = gap_in(&fp, sel_inside, &fitted, &truth, &nin);
    long nband;
    const double band_nom = gap_in(&fp, sel_band, &fitted, &nom, &nband);
    const double band_part = gap_in(&fp, sel_band, &fitted, &truth, &nband);
    const double band_over = overshoot_in(&fp, sel_band, &fitted, &nom, &truth);
    print_message("honest edges: the band between (%ld no-data cells within reach of data-bearing "
                  "control points): up to %.3g mm from the nominal, %.3g mm from the part, "
                  "%.3g mm beyond the two in z (%.3g without the pins)\n",
                  nband, band_nom, band_part, band_over, band_over_free);
    print_message("honest edges: %ld cells (%ld filled, %ld no data, %ld outline), %ld of %ld "
                  "control points pinned; outside (%ld cells) the fit is %.3g mm from the nominal "
                  "(%.3g without the pins), inside (%ld cells) %.3g mm from the part (%.3g without "
                  "the pins; noise sigma %.3g)\n",
                  st.cells, st.filled, st.empty, st.outline, st.pinned, n, nout, out_pin, out_free,
                  nin, in_pin, in_free, sigma);
    assert_true(nout > 0 && nin > 0);
    assert_true(out_pin <= sigma);
    /* The largest deviation over 10^4 grid points of a least-squares fit to
     * data with noise sigma per coordinate: 3 sigma (the fit without pins
     * is further still, by its extrapolating edge control points). */
    assert_true(in_pin <= 3.0 * sigma);
    assert_true(out_free > 10.0 * sigma); /* the pins are what keeps it there */
    /* Between the data and the pinned side the surface blends from the
     * part to the nominal: it never leaves the interval between them. */
    assert_true(band_over <= sigma);
    free(P);
    free(m);
    free(pts);
    free(nm);
    free(tm);
}

/* nf_footprint_add_rows against the per-point nf_footprint_add on uneven
 * knots (the uniform guess misses): the same counts, refused rows (NaN,
 * outside the domain) skipped and not counted; and the cells at the
 * boundaries by hand: a span's midpoint opens its upper cell, the
 * domain's end is in the last. */
static void test_rows_and_boundaries(void **state)
{
    (void)state;
    ref_seed(977);
    nf_surf_t s;
    double *sm = part(&s, 9, 7, 0.0); /* 6 x 4 spans */
    const double U[] = {0, 0, 0, 0, 0.0625, 0.3125, 0.34375, 0.6875, 0.875, 1, 1, 1, 1};
    memcpy(s.U, U, sizeof U);
    size_t bytes;
    void *ma = fp_mem(&s, &bytes), *mb = fp_mem(&s, &bytes);
    nf_footprint_t a, b;
    assert_int_equal(nf_footprint_init(&a, &s, ma, bytes), NF_OK);
    assert_int_equal(nf_footprint_init(&b, &s, mb, bytes), NF_OK);
    enum { M = 5000, W = 6 };
    static double rows[M * W];
    long ok = 0;
    for (long k = 0; k < M; k++) {
        double *r = rows + W * k;
        r[0] = ref_rand(-0.1, 1.1);
        r[1] = k % 4 ? r[1 - W] : ref_rand(-0.1, 1.1); /* rows of 4 points share v */
        if (k % 97 == 0)
            r[k % 2] = NAN;
        if (k % 89 == 0) /* knots and span midpoints exactly */
            r[0] = U[4 + k % 5], r[1] = 0.5 * (U[5 + k % 4] + U[6 + k % 4]);
        r[2] = r[3] = r[4] = r[5] = 1e300; /* not read */
        ok += nf_footprint_add(&a, r[0], r[1]) == NF_OK;
    }
    assert_true(ok > M / 2 && ok < M);
    assert_int_equal(nf_footprint_add_rows(&b, rows, M, W), ok);
    assert_int_equal(b.points, ok);
    assert_int_equal(a.points, ok);
    for (int j = 0; j < b.cv; j++)
        for (int i = 0; i < b.cu; i++)
            assert_int_equal(nf_footprint_cell(&b, i, j), nf_footprint_cell(&a, i, j));
    /* By hand (dyadic knots: the midpoints exact): span 1 of u is
     * [0.0625, 0.3125), its cells 2 (lower) and 3. */
    nf_footprint_init(&a, &s, ma, bytes);
    const double pts[][2] = {
        {0.1875, 0.0}, {nextafter(0.1875, 0.0), 0.0}, {1.0, 1.0}, {0.0625, 0.5}};
    const int cell[][2] = {{3, 0}, {2, 0}, {11, 7}, {2, 4}};
    for (int k = 0; k < 4; k++) {
        assert_int_equal(nf_footprint_add_rows(&a, pts[k], 1, 2), 1);
        assert_int_equal(nf_footprint_cell(&a, cell[k][0], cell[k][1]), 1);
    }
    free(ma);
    free(mb);
    free(sm);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cells_and_stats),     cmocka_unit_test(test_merge),
        cmocka_unit_test(test_pin_dense),           cmocka_unit_test(test_honest_edges),
        cmocka_unit_test(test_rows_and_boundaries),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
