/* cmd_gen.c: `cellfit gen`: write the synthetic part's nominal surface and
 * points measured on the real part (raster in the nominal's parameters,
 * Gaussian noise along z, optional gross outliers; optional narrow bump and
 * ridge on the part), plus a check grid of true points. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_part.h"
#include "cf_surf.h"
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

int cmd_gen(int argc, char **argv)
{
    const char *dir = NULL;
    long nu = 40, nv = 30, deg = 3, m = 100000, seed = 1;
    double noise = 0.005, outliers = 0.0, spike = 5.0, bump[4] = {0, 0, 0, 1}, ridge[3] = {0, 0, 1};
    for (int i = 1; i < argc; i += 2) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v)
            return cli_error("gen", CLI_USAGE, "option %s needs a value", a);
        if (!strcmp(a, "--dir"))
            dir = v;
        else if (!strcmp(a, "--nu")) {
            if (cli_int(v, 2, 100000, &nu))
                return cli_error("gen", CLI_USAGE, "--nu '%s'", v);
        } else if (!strcmp(a, "--nv")) {
            if (cli_int(v, 2, 100000, &nv))
                return cli_error("gen", CLI_USAGE, "--nv '%s'", v);
        } else if (!strcmp(a, "--degree")) {
            if (cli_int(v, 1, NF_MAX_DEGREE, &deg))
                return cli_error("gen", CLI_USAGE, "--degree '%s': 1..%d", v, NF_MAX_DEGREE);
        } else if (!strcmp(a, "--points")) {
            if (cli_int(v, 1, 1000000000L, &m))
                return cli_error("gen", CLI_USAGE, "--points '%s'", v);
        } else if (!strcmp(a, "--seed")) {
            if (cli_int(v, 0, 1L << 62, &seed))
                return cli_error("gen", CLI_USAGE, "--seed '%s'", v);
        } else if (!strcmp(a, "--noise")) {
            if (cli_double(v, &noise) || noise < 0)
                return cli_error("gen", CLI_USAGE, "--noise '%s': need >= 0 (mm)", v);
        } else if (!strcmp(a, "--bump")) {
            if (numbers(v, 4, bump) || !(bump[3] > 0))
                return cli_error("gen", CLI_USAGE, "--bump '%s': need H,X,Y,R (mm, R > 0)", v);
        } else if (!strcmp(a, "--ridge")) {
            if (numbers(v, 3, ridge) || !(ridge[2] > 0))
                return cli_error("gen", CLI_USAGE, "--ridge '%s': need H,X,W (mm, W > 0)", v);
        } else if (!strcmp(a, "--outliers")) {
            if (cli_double(v, &outliers) || outliers < 0 || outliers > 1)
                return cli_error("gen", CLI_USAGE, "--outliers '%s': need a fraction 0..1", v);
        } else if (!strcmp(a, "--spike")) {
            if (cli_double(v, &spike) || spike < 0)
                return cli_error("gen", CLI_USAGE, "--spike '%s': need >= 0 (mm)", v);
        } else
            return cli_error("gen", CLI_USAGE, "unknown option '%s'", a);
    }
    if (!dir)
        return cli_error("gen", CLI_USAGE,
                         "usage: cellfit gen --dir DIR [--nu N --nv N "
                         "--degree P --points M --noise SIGMA --seed S --bump H,X,Y,R "
                         "--ridge H,X,W --outliers FRAC --spike MM]");
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
    if (cf_iges_write(path, &s, "cellfit synthetic panel (nominal)", msg, sizeof msg)) {
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
