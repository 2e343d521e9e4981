/* SPDX-License-Identifier: MIT */
/* test_devmap.c: the deviation map. The view plane of known tilted planes
 * (a long strip and a square plate, where the in-plane variances are equal),
 * the colour scale's segments, and rendered images of synthetic parts: a
 * plane with a Gaussian dent (blue at the dent, green far from it, the colour
 * bar in order, no gaps), sparse random points in a disc (gaps filled inside,
 * grey outside) and degenerate inputs. CF_DEVMAP_PNG=path keeps the dent map. */

#include "cf_devmap.h"
#include "cf_err.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char msg[1024];
static unsigned long long rng = 0xD1B54A32D192ED03ULL;

static double unif(void) /* [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1p-53;
}

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; i++)
        v[i] /= l;
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Points o + s a + t b on a tilted plane, s in [-ls, ls], t in [-lt, lt],
 * far from the origin. */
static void fit_tilted(double ls, double lt)
{
    double n0[3] = {0.3, -0.4, 0.8}, tmp[3] = {1, 0, 0}, a[3], b[3];
    double o[3] = {512.25, -301.5, 203.125};
    normalize(n0);
    cross(n0, tmp, b);
    normalize(b);
    cross(b, n0, a);
    cf_planefit_t pf;
    cf_devmap_plane_init(&pf);
    double c[3] = {0, 0, 0};
    long np = 0;
    /* A 100 x 100 grid, symmetric so that a and b are the principal axes
     * exactly (random points would tilt them by their sample correlation). */
    for (int k = 0; k < 10000; k++) {
        double s = ls * (-1 + 2.0 * (k % 100) / 99), t = lt * (-1 + 2.0 * (k / 100) / 99);
        double p[3];
        for (int i = 0; i < 3; i++) {
            p[i] = o[i] + s * a[i] + t * b[i];
            c[i] += p[i];
        }
        np++;
        cf_devmap_plane_add(&pf, p);
    }
    cf_plane_t pl;
    double sd[3];
    assert_int_equal(cf_devmap_plane_fit(&pf, &pl, sd, msg, sizeof msg), CF_OK);
    /* The normal to 1e-9, oriented: its largest component (z) positive. */
    for (int i = 0; i < 3; i++)
        assert_near(pl.n[i], n0[i], 1e-9);
    /* Right: X projected onto the plane (n has its smallest component on X). */
    double xp[3] = {1 - n0[0] * n0[0], -n0[0] * n0[1], -n0[0] * n0[2]};
    normalize(xp);
    for (int i = 0; i < 3; i++)
        assert_near(pl.e1[i], xp[i], 1e-9);
    double x[3];
    cross(pl.e1, pl.e2, x); /* right-handed, orthonormal */
    for (int i = 0; i < 3; i++) {
        assert_near(x[i], pl.n[i], 1e-12);
        assert_near(pl.o[i], c[i] / (double)np, 1e-9);
    }
    assert_near(pl.e1[0] * pl.e2[0] + pl.e1[1] * pl.e2[1] + pl.e1[2] * pl.e2[2], 0, 1e-14);
    /* Flatness: the square root of an eigenvalue at rounding level. */
    assert_true(sd[2] < 1e-7 * sd[0]);
    assert_true(sd[0] >= sd[1] && sd[1] > 10);
    assert_near(sd[0], ls > lt ? ls / sqrt(3) : lt / sqrt(3), 0.02 * fmax(ls, lt));
}

static void test_plane_fit(void **state)
{
    (void)state;
    fit_tilted(100, 40); /* a strip */
    fit_tilted(40, 100);
    fit_tilted(75, 75); /* a square plate: two equal principal variances */
    /* A part in the XY plane is seen from +Z with X to the right, Y up,
     * although its principal axes are diagonal. */
    cf_planefit_t pf;
    cf_devmap_plane_init(&pf);
    for (int k = 0; k < 1000; k++) {
        double t = 300 * unif(), w = 50 * unif();
        double p[3] = {t + w, t - w, 7.5};
        cf_devmap_plane_add(&pf, p);
    }
    cf_plane_t pl;
    assert_int_equal(cf_devmap_plane_fit(&pf, &pl, NULL, msg, sizeof msg), CF_OK);
    assert_near(pl.n[2], 1, 1e-12);
    assert_near(pl.e1[0], 1, 1e-12);
    assert_near(pl.e2[1], 1, 1e-12);
    /* A wall facing Y: seen from +Y, Z up and so -X to the right. */
    cf_devmap_plane_init(&pf);
    for (int k = 0; k < 1000; k++) {
        double p[3] = {100 * unif(), -20.0, 60 * unif()};
        cf_devmap_plane_add(&pf, p);
    }
    assert_int_equal(cf_devmap_plane_fit(&pf, &pl, NULL, msg, sizeof msg), CF_OK);
    assert_near(pl.n[1], 1, 1e-12);
    assert_near(pl.e1[0], -1, 1e-12);
    assert_near(pl.e2[2], 1, 1e-12);
    /* No points. */
    cf_devmap_plane_init(&pf);
    assert_int_equal(cf_devmap_plane_fit(&pf, &pl, NULL, msg, sizeof msg), CF_EEMPTY);
    /* Given axes: made orthonormal; parallel ones refused. */
    double o[3] = {1, 2, 3}, e1[3] = {2, 0, 0}, e2[3] = {1, 3, 0}, e3[3] = {-4, 0, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, e1, e2, msg, sizeof msg), CF_OK);
    assert_near(pl.e1[0], 1, 0);
    assert_near(pl.e2[0], 0, 1e-15);
    assert_near(pl.e2[1], 1, 1e-15);
    assert_near(pl.n[2], 1, 1e-15);
    assert_int_equal(cf_plane_from_axes(&pl, o, e1, e3, msg, sizeof msg), CF_EARG);
}

/* A map on the fixed scale of +/- 3 tol unless scale_from_data. */
static cf_devmap_t *make_map_s(const cf_plane_t *pl, double tol, cf_devmap_cell_t cell,
                               int scale_from_data)
{
    cf_devmap_opts_t o = {
        .tol = tol, .range = scale_from_data ? 0 : 3, .cell = cell, .title = "test part"};
    cf_devmap_t *m = NULL;
    assert_int_equal(cf_devmap_create(&m, pl, &o, msg, sizeof msg), CF_OK);
    return m;
}

static cf_devmap_t *make_map(const cf_plane_t *pl, double tol, cf_devmap_cell_t cell)
{
    return make_map_s(pl, tol, cell, 0);
}

static void test_colours(void **state)
{
    (void)state;
    cf_plane_t pl;
    double o[3] = {0, 0, 0}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, x, y, msg, sizeof msg), CF_OK);
    cf_devmap_t *m = make_map(&pl, 0.05, CF_DEVMAP_MEAN);
    uint32_t green = cf_devmap_colour(m, 0);
    assert_true(((green >> 8) & 0xFF) > (green >> 16) && ((green >> 8) & 0xFF) > (green & 0xFF));
    assert_int_equal(cf_devmap_colour(m, 0.05), green); /* |d| <= tol inclusive */
    assert_int_equal(cf_devmap_colour(m, -0.05), green);
    assert_true(cf_devmap_colour(m, 0.0501) != green);
    assert_true(cf_devmap_colour(m, -0.0501) != green);
    /* Ascending deviations step through 11 distinct colours, symmetric steps. */
    uint32_t seen[16];
    int ns = 0;
    for (double d = -0.2; d <= 0.2; d += 0.0005) {
        uint32_t c = cf_devmap_colour(m, d);
        if (!ns || seen[ns - 1] != c) {
            for (int k = 0; k < ns; k++)
                assert_true(seen[k] != c); /* never back to an earlier colour */
            seen[ns++] = c;
        }
    }
    assert_int_equal(ns, 11);
    uint32_t lo = cf_devmap_colour(m, -0.12), hi = cf_devmap_colour(m, 0.12); /* 2.4 tol */
    /* Negative blue, positive red; 3 tol is still the last step. */
    assert_true((lo & 0xFF) > (lo >> 16));
    assert_true((hi >> 16) > (hi & 0xFF));
    assert_int_equal(cf_devmap_colour(m, 0.15), cf_devmap_colour(m, 0.14));
    assert_true(cf_devmap_colour(m, 0.1501) != cf_devmap_colour(m, 0.15));
    /* Before begin: no raster. */
    double p[3] = {0, 0, 0};
    int px, py;
    assert_int_equal(cf_devmap_add(m, p, 0.0), CF_EARG);
    assert_int_equal(cf_devmap_pixel(m, p, &px, &py), -1);
    cf_image_t im;
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_EEMPTY);
    cf_devmap_free(m);
    cf_devmap_opts_t bad = {.tol = 0};
    assert_int_equal(cf_devmap_create(&m, &pl, &bad, msg, sizeof msg), CF_EARG);
    bad.tol = 0.1;
    bad.range = 0.5;
    assert_int_equal(cf_devmap_create(&m, &pl, &bad, msg, sizeof msg), CF_EARG);
    bad.range = 0;
    assert_int_equal(cf_devmap_create(&m, &pl, &bad, msg, sizeof msg), CF_OK);
    /* A fixed end must lie above the tolerance, and within 1000 of them. */
    assert_int_equal(cf_devmap_set_scale(m, 0.1, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_devmap_set_scale(m, 100.01, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_devmap_set_scale(m, -0.3, msg, sizeof msg), CF_EARG);
    assert_int_equal(cf_devmap_set_scale(m, 0.3, msg, sizeof msg), CF_OK);
    assert_near(cf_devmap_scale_end(m), 0.3, 1e-15);
    cf_devmap_free(m);
}

static int is_green(uint32_t c)
{
    int r = c >> 16, g = (c >> 8) & 0xFF, b = c & 0xFF;
    return g > r + 60 && g > b + 60;
}

static int is_blue(uint32_t c)
{
    int r = c >> 16, g = (c >> 8) & 0xFF, b = c & 0xFF;
    return b > r + 100 && b > g + 100;
}

/* A column of the image in which the colours of the whole scale appear as
 * consecutive runs, from above the scale at the top to below it. */
static int find_colour_bar(const cf_image_t *im, const cf_devmap_t *m)
{
    static const double t[11] = {9, 2.9, 2.4, 1.9, 1.4, 0, -1.4, -1.9, -2.4, -2.9, -9};
    uint32_t want[11];
    for (int k = 0; k < 11; k++)
        want[k] = cf_devmap_colour(m, t[k] * 0.05);
    for (int x = 0; x < im->w; x++) {
        int k = 0;
        for (int y = 0; y < im->h && k < 11; y++) {
            uint32_t c = cf_image_get(im, x, y);
            if (c == want[k])
                k++;
            else if (k > 0 && c != want[k - 1] && c != 0x000000)
                k = 0; /* not a run, nor a tolerance line: start again */
        }
        if (k == 11)
            return x;
    }
    return -1;
}

/* z = 0 plane, 200 x 150 mm, 1 mm grid, a dent of 2.7 tol at (60, 50). */
static double dent(double x, double y)
{
    double r2 = (x - 60) * (x - 60) + (y - 50) * (y - 50);
    return -2.7 * 0.05 * exp(-r2 / (2 * 12.0 * 12.0));
}

static void test_dent_map(void **state)
{
    (void)state;
    const double tol = 0.05;
    cf_planefit_t pf;
    cf_devmap_plane_init(&pf);
    /* Pass 1: the view. */
    for (int j = 0; j <= 150; j++)
        for (int i = 0; i <= 200; i++) {
            double p[3] = {i, j, dent(i, j)};
            cf_devmap_plane_add(&pf, p);
        }
    cf_plane_t pl;
    assert_int_equal(cf_devmap_plane_fit(&pf, &pl, NULL, msg, sizeof msg), CF_OK);
    cf_devmap_t *m = make_map(&pl, tol, CF_DEVMAP_MEAN);
    static cf_stats_t st;
    assert_int_equal(cf_stats_init(&st, tol), CF_OK);
    /* Pass 2: the extent; pass 3: the deviations (the dent's own depth). */
    for (int j = 0; j <= 150; j++)
        for (int i = 0; i <= 200; i++) {
            double p[3] = {i, j, dent(i, j)};
            cf_devmap_extent(m, p);
        }
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    for (int j = 0; j <= 150; j++)
        for (int i = 0; i <= 200; i++) {
            double p[3] = {i, j, dent(i, j)};
            assert_int_equal(cf_devmap_add(m, p, dent(i, j)), CF_OK);
            cf_stats_add(&st, dent(i, j));
        }
    assert_int_equal(cf_devmap_outside(m), 0);
    cf_image_t im;
    assert_int_equal(cf_devmap_render(m, &st, &im, msg, sizeof msg), CF_OK);
    /* The file (kept for looking at when CF_DEVMAP_PNG names it). */
    const char *keep = getenv("CF_DEVMAP_PNG");
    char path[600];
    const char *d = getenv("CF_TEST_TMP");
    snprintf(path, sizeof path, "%s/cf_devmap_%ld.png", d && *d ? d : "/tmp", (long)getpid());
    mkdir(d && *d ? d : "/tmp", 0777);
    assert_int_equal(cf_devmap_write_png(m, &st, keep ? keep : path, msg, sizeof msg), CF_OK);
    FILE *f = fopen(keep ? keep : path, "rb");
    assert_non_null(f);
    unsigned char sig[8];
    assert_int_equal(fread(sig, 1, 8, f), 8);
    fclose(f);
    assert_memory_equal(sig, "\x89PNG\r\n\x1a\n", 8);
    if (!keep)
        remove(path);
    int cw, ch, iw, ih;
    cf_devmap_size(m, &cw, &ch, &iw, &ih);
    assert_true(iw == im.w && ih == im.h && iw <= 1200 && ih <= 900);
    assert_true(cw >= 150 && ch >= 110); /* 1 mm points: about 1 mm cells */
    /* The dent centre is blue (2.7 tol deep: the darkest blue step); the
     * plate far from it green. */
    double c[3] = {60, 50, dent(60, 50)};
    int x, y;
    assert_int_equal(cf_devmap_pixel(m, c, &x, &y), 0);
    uint32_t at = cf_image_get(&im, x, y);
    if (!is_blue(at) || at != cf_devmap_colour(m, -2.7 * tol))
        fail_msg("dent centre pixel (%d, %d) is %06x", x, y, (unsigned)at);
    static const double far[][2] = {{180, 130}, {190, 10}, {120, 140}, {10, 140}, {150, 75}};
    for (size_t k = 0; k < sizeof far / sizeof far[0]; k++) {
        double p[3] = {far[k][0], far[k][1], 0};
        assert_int_equal(cf_devmap_pixel(m, p, &x, &y), 0);
        at = cf_image_get(&im, x, y);
        if (!is_green(at))
            fail_msg("pixel (%d, %d) at (%g, %g) mm is %06x, not green", x, y, far[k][0], far[k][1],
                     (unsigned)at);
    }
    /* Orientation: +x to the right, +y up. */
    double p0[3] = {20, 20, 0}, p1[3] = {180, 130, 0};
    int x0, y0, x1, y1;
    cf_devmap_pixel(m, p0, &x0, &y0);
    cf_devmap_pixel(m, p1, &x1, &y1);
    assert_true(x1 > x0 + 500 && y1 < y0 - 350);
    /* No grey (no data) inside the part. */
    long grey = 0;
    for (int yy = y1; yy <= y0; yy++)
        for (int xx = x0; xx <= x1; xx++)
            grey += cf_image_get(&im, xx, yy) == 0xD9D9D9;
    assert_int_equal(grey, 0);
    /* The colour bar right of the map; dark title text at the top. */
    int bar = find_colour_bar(&im, m);
    assert_true(bar > x1);
    long ink = 0;
    for (int yy = 14; yy < 34; yy++)
        for (int xx = 20; xx < 200; xx++)
            ink += cf_image_get(&im, xx, yy) == 0x000000;
    assert_true(ink > 100);
    cf_image_free(&im);
    cf_devmap_free(m);
}

/* Sparse random points in a disc: the gaps between them are filled, the
 * corners of the bounding square (outside the disc) stay grey. */
static void test_sparse_disc(void **state)
{
    (void)state;
    cf_plane_t pl;
    double o[3] = {0, 0, 0}, ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, ex, ey, msg, sizeof msg), CF_OK);
    cf_devmap_t *m = make_map(&pl, 0.1, CF_DEVMAP_MEAN);
    enum { NP = 3000 };
    static double pts[NP][2];
    for (int k = 0; k < NP; k++) {
        double r = 50 * sqrt(unif()), a = 6.283185307179586 * unif();
        pts[k][0] = r * cos(a);
        pts[k][1] = r * sin(a);
        double p[3] = {pts[k][0], pts[k][1], 0};
        cf_devmap_extent(m, p);
    }
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    for (int k = 0; k < NP; k++) {
        double p[3] = {pts[k][0], pts[k][1], 0};
        assert_int_equal(cf_devmap_add(m, p, 0.0), CF_OK);
    }
    int cw, ch;
    cf_devmap_size(m, &cw, &ch, NULL, NULL);
    assert_true(cw < 120 && ch < 120); /* cells follow the point spacing, not the pixels */
    cf_image_t im;
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    long in = 0, holes = 0;
    for (int k = 0; k < 4000; k++) {
        double r = 45 * sqrt(unif()), a = 6.283185307179586 * unif();
        double p[3] = {r * cos(a), r * sin(a), 0};
        int x, y;
        assert_int_equal(cf_devmap_pixel(m, p, &x, &y), 0);
        uint32_t c = cf_image_get(&im, x, y);
        in++;
        holes += c == 0xD9D9D9;
    }
    if (holes > in / 100)
        fail_msg("%ld of %ld pixels inside the disc have no data", holes, in);
    for (int k = 0; k < 4; k++) { /* the corners of the bounding square */
        double p[3] = {k & 1 ? 48 : -48, k & 2 ? 48 : -48, 0};
        int x, y;
        assert_int_equal(cf_devmap_pixel(m, p, &x, &y), 0);
        assert_int_equal(cf_image_get(&im, x, y), 0xD9D9D9);
    }
    cf_image_free(&im);
    cf_devmap_free(m);
}

/* Degenerate inputs render; max-|d| cells show an isolated outlier; the
 * raster does not grow with the number of points. */
static void test_degenerate(void **state)
{
    (void)state;
    cf_plane_t pl;
    double o[3] = {0, 0, 0}, ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, ex, ey, msg, sizeof msg), CF_OK);
    cf_image_t im;
    /* One point. */
    cf_devmap_t *m = make_map(&pl, 0.05, CF_DEVMAP_MEAN);
    double p[3] = {5, 5, 0};
    cf_devmap_extent(m, p);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_devmap_add(m, p, 0.3), CF_OK);
    double q[3] = {500, 5, 0};
    assert_int_equal(cf_devmap_add(m, q, 0.3), CF_OK);
    assert_int_equal(cf_devmap_outside(m), 1);
    assert_int_equal(cf_devmap_add(m, p, NAN), CF_EARG);
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    cf_image_free(&im);
    cf_devmap_free(m);
    /* Collinear points. */
    m = make_map(&pl, 0.05, CF_DEVMAP_MEAN);
    for (int k = 0; k <= 100; k++) {
        double r[3] = {k, 0, 0};
        cf_devmap_extent(m, r);
    }
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    for (int k = 0; k <= 100; k++) {
        double r[3] = {k, 0, 0};
        cf_devmap_add(m, r, 0.001 * k);
    }
    assert_int_equal(cf_devmap_outside(m), 0);
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    cf_image_free(&im);
    cf_devmap_free(m);
    /* Max |d|: one outlier among zeros shows in its cell's colour. */
    m = make_map(&pl, 0.05, CF_DEVMAP_MAXABS);
    cf_devmap_set_extent(m, 0, 100, 0, 100, 40000);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    for (int j = 0; j < 200; j++)
        for (int i = 0; i < 200; i++) {
            double r[3] = {0.25 + 0.5 * i, 0.25 + 0.5 * j, 0};
            cf_devmap_add(m, r, i == 100 && j == 100 ? 1.0 : 0.0);
        }
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    double r[3] = {50.25, 50.25, 0};
    int x, y;
    assert_int_equal(cf_devmap_pixel(m, r, &x, &y), 0);
    assert_int_equal(cf_image_get(&im, x, y), cf_devmap_colour(m, 1.0));
    cf_image_free(&im);
    cf_devmap_free(m);
    /* The raster for 10^6 and 10^9 points is the same size. */
    int a[2], b[2];
    m = make_map(&pl, 0.05, CF_DEVMAP_MEAN);
    cf_devmap_set_extent(m, 0, 400, 0, 300, 1000000);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    cf_devmap_size(m, &a[0], &a[1], NULL, NULL);
    cf_devmap_free(m);
    m = make_map(&pl, 0.05, CF_DEVMAP_MEAN);
    cf_devmap_set_extent(m, 0, 400, 0, 300, 1000000000LL);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    cf_devmap_size(m, &b[0], &b[1], NULL, NULL);
    cf_devmap_free(m);
    assert_true(a[0] == b[0] && a[1] == b[1] && a[0] <= 1200 && a[1] <= 900);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The scale's end is the smallest the rule allows that covers the 99th
 * percentile of |d| (found here by sorting), symmetric, with at most 1 %
 * of the points in the off-scale colours. */
static void check_auto(const char *name, double tol, double (*dev)(int, int), int keep)
{
    enum { N = 120 };
    cf_plane_t pl;
    double o[3] = {0, 0, 0}, ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, ex, ey, msg, sizeof msg), CF_OK);
    cf_devmap_t *m = make_map_s(&pl, tol, CF_DEVMAP_MEAN, 1);
    cf_devmap_set_extent(m, 0, N - 1, 0, N - 1, (long long)N * N);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    static double a[N * N];
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            double p[3] = {i, j, 0}, d = dev(i, j);
            a[j * N + i] = fabs(d);
            assert_int_equal(cf_devmap_add(m, p, d), CF_OK);
        }
    qsort(a, N * N, sizeof a[0], cmp_double);
    double p99 = a[(99 * N * N + 99) / 100 - 1]; /* the smallest value 99 % do not exceed */
    cf_image_t im;
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    double end = cf_devmap_scale_end(m);
    static const double steps[] = {0.25, 0.5, 1, 2, 2.5, 5, 10, 20, 25, 50, 100, 200};
    int k = 0;
    while (k < 11 && (1 + 4 * steps[k]) * tol < p99 * (1 - 1e-12))
        k++;
    if (fabs(end - (1 + 4 * steps[k]) * tol) > 1e-12 * tol)
        fail_msg("%s: scale end %.17g mm, want %.17g (P99 %.17g)", name, end,
                 (1 + 4 * steps[k]) * tol, p99);
    long off = 0;
    uint32_t lo = cf_devmap_colour(m, -2 * end), hi = cf_devmap_colour(m, 2 * end);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            uint32_t c = cf_devmap_colour(m, dev(i, j));
            off += c == lo || c == hi;
        }
    assert_true(off <= N * N / 100);
    /* Symmetric, and the tolerance band is green either side. */
    assert_int_equal(cf_devmap_colour(m, tol), cf_devmap_colour(m, -tol));
    assert_int_equal(cf_devmap_colour(m, tol), cf_devmap_colour(m, 0));
    assert_true(cf_devmap_colour(m, end) != hi && cf_devmap_colour(m, -end) != lo);
    assert_true(cf_devmap_colour(m, end * 1.001) == hi);
    const char *dir = getenv("CF_DEVMAP_PNG_DIR");
    if (keep && dir) {
        char path[600];
        snprintf(path, sizeof path, "%s/auto-%s.png", dir, name);
        assert_int_equal(cf_png_write_image(path, &im, msg, sizeof msg), CF_OK);
    }
    cf_image_free(&im);
    cf_devmap_free(m);
}

static double dev_ramp(int i, int j) /* 0 .. 6 tol, along x */
{
    (void)j;
    return 0.05 * 6.0 * i / 119.0;
}

static double dev_warp(int i, int j) /* a warped part: -0.4 .. +1.1 mm, tol 0.05 */
{
    double x = i / 119.0, y = j / 119.0;
    return -0.4 + 1.5 * x * x * (0.5 + 0.5 * y);
}

static double dev_small(int i, int j) /* everything within 0.8 tol */
{
    return 0.04 * sin(i * 0.3) * cos(j * 0.2);
}

static double dev_outliers(int i, int j) /* 0.5 % spikes of 50 tol on a flat part */
{
    return (i * 131 + j * 71) % 200 == 0 ? 2.5 : 0.01 * sin(i * 0.1);
}

static void test_auto_scale(void **state)
{
    (void)state;
    check_auto("ramp", 0.05, dev_ramp, 0);
    check_auto("warp", 0.05, dev_warp, 1);
    check_auto("small", 0.05, dev_small, 0);
    check_auto("outliers", 0.05, dev_outliers, 0);
    /* A fixed scale in mm holds whatever the data. */
    cf_plane_t pl;
    double o[3] = {0, 0, 0}, ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    assert_int_equal(cf_plane_from_axes(&pl, o, ex, ey, msg, sizeof msg), CF_OK);
    cf_devmap_opts_t fo = {.tol = 0.05, .title = "fixed"};
    cf_devmap_t *m = NULL;
    assert_int_equal(cf_devmap_create(&m, &pl, &fo, msg, sizeof msg), CF_OK);
    assert_int_equal(cf_devmap_set_scale(m, 0.3, msg, sizeof msg), CF_OK);
    cf_devmap_set_extent(m, 0, 10, 0, 10, 100);
    assert_int_equal(cf_devmap_begin(m, msg, sizeof msg), CF_OK);
    for (int k = 0; k < 100; k++) {
        double p[3] = {k % 10, k / 10, 0};
        assert_int_equal(cf_devmap_add(m, p, 3.0 * k / 100), CF_OK);
    }
    cf_image_t im;
    assert_int_equal(cf_devmap_render(m, NULL, &im, msg, sizeof msg), CF_OK);
    assert_near(cf_devmap_scale_end(m), 0.3, 1e-15);
    assert_true(cf_devmap_colour(m, 0.29) != cf_devmap_colour(m, 0.31));
    assert_int_equal(cf_devmap_colour(m, 0.31), cf_devmap_colour(m, 2.9));
    cf_image_free(&im);
    cf_devmap_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_fit),  cmocka_unit_test(test_colours),
        cmocka_unit_test(test_dent_map),   cmocka_unit_test(test_sparse_disc),
        cmocka_unit_test(test_degenerate), cmocka_unit_test(test_auto_scale),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
