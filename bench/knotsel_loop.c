/* SPDX-License-Identifier: MIT */
/* bench/knotsel_loop.c: the knot chooser's loop (nf_knotsel + nf_loopctl,
 * tests/ref_kloop.c) on a height field file, for bench/loop_bench.py.
 *
 *   knotsel_loop FIT.xyz --tol T [--within PCT] [--k K] [--min-rows R] [--ratio X] [--share X]
 *                [--max-cp N] [--max-rounds R] [--reparam] [--no-budget]
 *                [--holdout HOLD.xyz] [-v]
 *
 * Points are "x y z" lines; the parameters are x and y mapped to [0, 1]
 * over the fitted points' box (a height field's own parameters), the base a
 * bicubic plane with one span. Parameters stay fixed and d is |S(u, v) - Q|
 * (about the vertical distance), or with --reparam each check pass projects
 * the points onto the fit (nf_project from their last parameters): d is the
 * normal distance, as `cellfit fit` measures it, and the next round fits at
 * the new parameters. --no-budget: no nf_loopctl_budget. Prints
 * one JSON line: points, control points, net, share within T, rounds,
 * verdict, seconds, and with --holdout the held-out points' rms, p99 and
 * max distance. Measures, asserts nothing. */
#include "nf_basis.h"
#include "nf_err.h"
#include "ref_kloop.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Rows u v x y z of the file, u v from the box b (x0 x1 y0 y1; computed
 * when b[1] < b[0]). */
static double *load(const char *path, long *m, double b[4])
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "knotsel_loop: cannot open %s\n", path);
        exit(2);
    }
    long cap = 1 << 16, n = 0;
    double *r = malloc(sizeof(double) * 5 * (size_t)cap), x, y, z;
    while (r && fscanf(f, "%lf %lf %lf", &x, &y, &z) == 3) {
        if (n == cap) {
            double *g = realloc(r, sizeof(double) * 10 * (size_t)cap);
            if (!g)
                break;
            r = g;
            cap *= 2;
        }
        r[5 * n + 2] = x;
        r[5 * n + 3] = y;
        r[5 * n + 4] = z;
        n++;
    }
    fclose(f);
    if (!r || n == 0) {
        fprintf(stderr, "knotsel_loop: no points in %s\n", path);
        exit(2);
    }
    if (b[1] < b[0]) {
        b[0] = b[2] = HUGE_VAL;
        b[1] = b[3] = -HUGE_VAL;
        for (long k = 0; k < n; k++) {
            b[0] = fmin(b[0], r[5 * k + 2]);
            b[1] = fmax(b[1], r[5 * k + 2]);
            b[2] = fmin(b[2], r[5 * k + 3]);
            b[3] = fmax(b[3], r[5 * k + 3]);
        }
    }
    for (long k = 0; k < n; k++) {
        double u = (r[5 * k + 2] - b[0]) / (b[1] - b[0]), v = (r[5 * k + 3] - b[2]) / (b[3] - b[2]);
        r[5 * k] = fmin(1.0, fmax(0.0, u));
        r[5 * k + 1] = fmin(1.0, fmax(0.0, v));
    }
    *m = n;
    return r;
}

static int cmp_dbl(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
    const char *file = NULL, *hold = NULL;
    ref_kloop_cfg_t c;
    memset(&c, 0, sizeof c);
    c.within = 99.0;
    c.alpha = 0.1;
    c.beta = 1e-3;
    c.scale_alpha = 1;
    c.alpha_k = NF_LOOPCTL_ALPHA_K;
    c.progress = 1;
    c.budget = 1;
    c.max_rounds = 30;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : "";
        if (!strcmp(a, "--tol"))
            c.tol = atof(v), i++;
        else if (!strcmp(a, "--within"))
            c.within = atof(v), i++;
        else if (!strcmp(a, "--k"))
            c.alpha_k = atof(v), i++;
        else if (!strcmp(a, "--min-rows"))
            c.sel.min_rows = atoi(v), i++;
        else if (!strcmp(a, "--ratio"))
            c.sel.ratio = atof(v), i++;
        else if (!strcmp(a, "--share"))
            c.sel.share = atof(v), i++;
        else if (!strcmp(a, "--max-cp"))
            c.max_cp = atol(v), i++;
        else if (!strcmp(a, "--max-rounds"))
            c.max_rounds = atoi(v), i++;
        else if (!strcmp(a, "--holdout"))
            hold = v, i++;
        else if (!strcmp(a, "--reparam"))
            c.reparam = 1;
        else if (!strcmp(a, "--no-budget"))
            c.budget = 0;
        else if (!strcmp(a, "-v"))
            c.verbose = 1;
        else
            file = a;
    }
    if (!file || !(c.tol > 0)) {
        fprintf(stderr,
                "usage: knotsel_loop FIT.xyz --tol T [--within PCT] [--k K] [--min-rows R] "
                "[--ratio X] [--share X] [--max-cp N] [--max-rounds R] [--reparam] [--no-budget] "
                "[--holdout HOLD.xyz] [-v]\n");
        return 2;
    }
    double box[4] = {1, 0, 1, 0};
    long m, h = 0;
    double *pts = load(file, &m, box), *hp = hold ? load(hold, &h, box) : NULL;
    nf_surf_t base;
    ref_kloop_surf(&base, 3, 3, 4, 4);
    for (int i = 0; i < 8; i++)
        base.U[i] = base.V[i] = i < 4 ? 0.0 : 1.0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *p = base.cp + 3 * (i + 4 * j);
            p[0] = box[0] + (box[1] - box[0]) * nf_greville(i, 3, base.U);
            p[1] = box[2] + (box[3] - box[2]) * nf_greville(j, 3, base.V);
            p[2] = 0.0;
        }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    ref_kloop_out_t o;
    int rc = ref_kloop_run(&base, pts, m, &c, &o);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (rc) {
        printf("{\"error\": \"%s\"}\n", nf_strerror(rc));
        return 1;
    }
    printf("{\"points\": %ld, \"tol\": %.6g, \"control_points\": %ld, \"nu\": %d, \"nv\": %d, "
           "\"within_tol_pct\": %.4f, \"rms\": %.6g, \"max_abs\": %.6g, \"rounds\": %d, "
           "\"fit_status\": \"%s\", \"alpha_k\": %g, \"reparam\": %d, \"seconds\": %.4f",
           m, c.tol, o.cp, o.fit.nu, o.fit.nv, o.within_pct, o.rms, o.mx, o.rounds,
           nf_loopctl_str(o.verdict), c.alpha_k, c.reparam,
           (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    if (h > 0) {
        double *d = malloc(sizeof(double) * (size_t)h), ss = 0.0;
        for (long k = 0; k < h; k++) {
            d[k] = c.reparam ? ref_kloop_pdist(&o.fit, hp + 5 * k)
                             : ref_kloop_dist(&o.fit, hp + 5 * k);
            ss += d[k] * d[k];
        }
        qsort(d, (size_t)h, sizeof(double), cmp_dbl);
        printf(", \"holdout_points\": %ld, \"holdout_rms\": %.6g, \"holdout_p99\": %.6g, "
               "\"holdout_max\": %.6g",
               h, sqrt(ss / (double)h), d[(long)ceil(0.99 * (double)h) - 1], d[h - 1]);
        free(d);
    }
    printf("}\n");
    ref_kloop_free(&o);
    free(base.U);
    free(pts);
    free(hp);
    return 0;
}
