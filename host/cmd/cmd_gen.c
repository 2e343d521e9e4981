/* SPDX-License-Identifier: MIT */
/* cmd_gen.c: `cellfit gen`: write the synthetic part's nominal surface and
 * points measured on the real part (raster in the nominal's parameters,
 * Gaussian noise along z, optional gross outliers; optional narrow bump and
 * ridge on the part), plus a check grid of true points. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_opt.h"
#include "cf_part.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static unsigned long long g_rng = 0x243F6A8885A308D3ull;

static double urand(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return ((double)(g_rng >> 11) + 0.5) / 9007199254740992.0;
}

static double gauss(void)
{
    return sqrt(-2.0 * log(urand())) * cos(6.283185307179586 * urand());
}

/* "a,b,c[,d]": exactly n comma-separated finite numbers. */
static int numbers(const char *s, int n, double *out)
{
    char buf[256];
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    char *save = NULL, *t = strtok_r(buf, ",", &save);
    int k = 0;
    for (; t && k < n; t = strtok_r(NULL, ",", &save))
        if (cli_double(t, &out[k++]))
            return -1;
    return k == n && !t ? 0 : -1;
}

static int bump_arg(const char *v, void *dst)
{
    double *b = dst;
    return numbers(v, 4, b) || !(b[3] > 0) ? -1 : 0;
}

static int ridge_arg(const char *v, void *dst)
{
    double *r = dst;
    return numbers(v, 3, r) || !(r[2] > 0) ? -1 : 0;
}

int cmd_gen(int argc, char **argv)
{
    const char *dir = NULL;
    long nu = 40, nv = 30, deg = 3, m = 100000, seed = 1;
    double noise = 0.005, outliers = 0.0, spike = 5.0, bump[4] = {0, 0, 0, 1}, ridge[3] = {0, 0, 1};
    const cf_opt_t opts[] = {
        {.name = "dir",
         .kind = CF_OPT_STR,
         .dst = &dir,
         .arg = "DIR",
         .help = "where the files go (created if missing)",
         .req = 1},
        {.name = "nu",
         .kind = CF_OPT_LONG,
         .dst = &nu,
         .arg = "N",
         .help = "control points in u",
         .lo = 2,
         .hi = 100000},
        {.name = "nv",
         .kind = CF_OPT_LONG,
         .dst = &nv,
         .arg = "N",
         .help = "control points in v",
         .lo = 2,
         .hi = 100000},
        {.name = "degree",
         .kind = CF_OPT_LONG,
         .dst = &deg,
         .arg = "P",
         .help = "degree in u and v",
         .lo = 1,
         .hi = NF_MAX_DEGREE},
        {.name = "count",
         .kind = CF_OPT_LONG,
         .dst = &m,
         .arg = "M",
         .help = "measured points (a raster in u, v)",
         .lo = 1,
         .hi = 1e9},
        {.name = "noise",
         .kind = CF_OPT_DOUBLE,
         .dst = &noise,
         .arg = "MM",
         .help = "standard deviation of the Gaussian noise along z",
         .lo = 0,
         .hi = 1e308},
        {.name = "seed",
         .kind = CF_OPT_LONG,
         .dst = &seed,
         .arg = "S",
         .help = "random seed",
         .lo = 0,
         .hi = 4611686018427387904.0},
        {.name = "bump",
         .kind = CF_OPT_FUNC,
         .dst = bump,
         .arg = "H,X,Y,R",
         .help = "a Gaussian bump on the part: height H, centre (X, Y), radius R (mm)",
         .fn = bump_arg,
         .fn_what = "H,X,Y,R (mm, R > 0)",
         .def = "none"},
        {.name = "ridge",
         .kind = CF_OPT_FUNC,
         .dst = ridge,
         .arg = "H,X,W",
         .help = "a ridge on the part along y at x = X: height H, half-width W (mm)",
         .fn = ridge_arg,
         .fn_what = "H,X,W (mm, W > 0)",
         .def = "none"},
        {.name = "outliers",
         .kind = CF_OPT_DOUBLE,
         .dst = &outliers,
         .arg = "FRAC",
         .help = "fraction of the points made gross outliers",
         .lo = 0,
         .hi = 1},
        {.name = "spike",
         .kind = CF_OPT_DOUBLE,
         .dst = &spike,
         .arg = "MM",
         .help = "largest offset of an outlier along z",
         .lo = 0,
         .hi = 1e308},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "gen",
                          .summary = "write a synthetic part: nominal.igs, points.uvxyz (measured, "
                                     "with noise), check.uv and check.xyz (true points)",
                          .opts = opts};
    int rc = cf_opt_parse(&cmd, argc, argv, NULL, NULL);
    if (rc)
        return cf_opt_exit(rc);
    if (nu <= deg || nv <= deg)
        return cli_error("gen", CLI_USAGE, "net %ld x %ld too small for degree %ld", nu, nv, deg);
    if (mkdir(dir, 0777) && errno != EEXIST)
        return cli_error("gen", CLI_FAIL, "%s: cannot create the directory", dir);
    g_rng ^= (unsigned long long)seed * 0x9E3779B97F4A7C15ull;
    cf_part_t pt;
    cf_part_default(&pt);
    pt.bump_h = bump[0], pt.bump_x = bump[1], pt.bump_y = bump[2], pt.bump_r = bump[3];
    pt.ridge_h = ridge[0], pt.ridge_x = ridge[1], pt.ridge_w = ridge[2];
    nf_surf_t s;
    if (cf_surf_alloc(&s, (int)deg, (int)deg, (int)nu, (int)nv))
        return cli_error("gen", CLI_FAIL, "out of memory");
    cf_part_nominal(&pt, &s);
    char path[4096], msg[512];
    snprintf(path, sizeof path, "%s/nominal.igs", dir);
    if (cf_surfio_write(path, &s, "cellfit synthetic panel (nominal)", cf_version_string(), msg,
                        sizeof msg)) {
        cf_surf_free(&s);
        return cli_error("gen", CLI_FAIL, "%s", msg);
    }
    snprintf(path, sizeof path, "%s/points.uvxyz", dir);
    FILE *f = fopen(path, "w");
    if (!f) {
        cf_surf_free(&s);
        return cli_error("gen", CLI_FAIL, "%s: cannot write", path);
    }
    /* Raster order, as a scanner delivers: rows of constant v. */
    long rows = (long)floor(sqrt((double)m * pt.len_y / pt.len_x));
    rows = rows < 1 ? 1 : rows;
    long cols = (m + rows - 1) / rows;
    fprintf(f, "# u v x y z: %ld points on the real part, noise sigma %g mm along z\n", m, noise);
    if (outliers > 0)
        fprintf(f, "# outliers: a fraction %g of the points off by +/- %g mm along z\n", outliers,
                spike);
    for (long k = 0; k < m; k++) {
        long r = k / cols, c = k % cols;
        double u = (c + 0.5) / cols, v = (r + 0.5) / rows, P[3];
        cf_part_true_point(&pt, &s, u, v, P);
        P[2] += noise * gauss();
        /* Gross outliers (laser spikes): +/- spike, drawn only when asked so
         * that the default stream of noise stays the same. */
        if (outliers > 0 && urand() < outliers)
            P[2] += (urand() < 0.5 ? -spike : spike);
        fprintf(f, "%.9f %.9f %.6f %.6f %.6f\n", u, v, P[0], P[1], P[2]);
    }
    int bad = ferror(f);
    bad |= fclose(f);
    snprintf(path, sizeof path, "%s/check.uv", dir);
    FILE *cu = fopen(path, "w");
    snprintf(path, sizeof path, "%s/check.xyz", dir);
    FILE *cx = fopen(path, "w");
    if (!cu || !cx || bad) {
        if (cu)
            fclose(cu);
        if (cx)
            fclose(cx);
        cf_surf_free(&s);
        return cli_error("gen", CLI_FAIL, "cannot write into %s", dir);
    }
    for (int j = 0; j <= 40; j++)
        for (int i = 0; i <= 40; i++) {
            double u = 0.05 + 0.9 * i / 40.0, v = 0.05 + 0.9 * j / 40.0, P[3];
            cf_part_true_point(&pt, &s, u, v, P);
            fprintf(cu, "%.17g %.17g\n", u, v);
            fprintf(cx, "%.17g %.17g %.17g\n", P[0], P[1], P[2]);
        }
    bad = fclose(cu) | fclose(cx);
    cf_surf_free(&s);
    if (bad)
        return cli_error("gen", CLI_FAIL, "cannot write into %s", dir);
    printf("cellfit gen: %s/nominal.igs (%ld x %ld, degree %ld), %ld points in "
           "%s/points.uvxyz, check grid in %s/check.{uv,xyz}\n",
           dir, nu, nv, deg, m, dir, dir);
    return CLI_OK;
}
