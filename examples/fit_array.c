/* SPDX-License-Identifier: MIT */
/* fit_array.c: libcellfit from a program: fit a nominal surface's control
 * net to points held in an array, read the fitted surface back and write
 * it as IGES. The points lie on a surface of the nominal's own spline space
 * (the nominal with its control points moved), so the fit must reproduce
 * that surface exactly: the program checks it and exits 1 if not.
 * Build: cc fit_array.c $(pkg-config --cflags --libs cellfit) */
#include <cellfit.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define NU 7
#define NV 6
#define P 3

int main(int argc, char **argv)
{
    const char *out = argc > 1 ? argv[1] : "fitted.igs";
    int maj, min, pat;
    cellfit_version_numbers(&maj, &min, &pat);
    if (maj != CELLFIT_VERSION_MAJOR) {
        fprintf(stderr, "built for cellfit %d.x, running with %s\n", CELLFIT_VERSION_MAJOR,
                cellfit_version());
        return 1;
    }
    /* Clamped uniform knots on [0, 1], a 100 x 80 mm panel as the nominal. */
    double U[NU + P + 1], V[NV + P + 1], cp[3 * NU * NV], truth[3 * NU * NV];
    for (int i = 0; i < NU + P + 1; i++)
        U[i] = i <= P ? 0 : i >= NU ? 1 : (double)(i - P) / (NU - P);
    for (int i = 0; i < NV + P + 1; i++)
        V[i] = i <= P ? 0 : i >= NV ? 1 : (double)(i - P) / (NV - P);
    for (int j = 0; j < NV; j++)
        for (int i = 0; i < NU; i++) {
            double *c = cp + 3 * (i + j * NU), *t = truth + 3 * (i + j * NU);
            c[0] = t[0] = 100.0 * i / (NU - 1);
            c[1] = t[1] = 80.0 * j / (NV - 1);
            c[2] = 0;
            t[2] = 0.5 * sin(0.9 * i) * cos(0.7 * j); /* the measured part: warped */
        }
    cellfit_surface_t nominal = {P, P, NU, NV, U, V, cp, NULL};
    cellfit_surface_t part = {P, P, NU, NV, U, V, truth, NULL};

    /* The caller's memory: the public byte formula says how much. */
    cellfit_params_t prm;
    cellfit_params_default(&prm);
    prm.alpha = 0; /* exact reproduction needs the data term alone */
    prm.beta = 0;
    long need = cellfit_fit_bytes(&nominal, &prm);
    if (need < 0) {
        fprintf(stderr, "nominal: %s\n", cellfit_strerror((int)need));
        return 1;
    }
    void *mem = aligned_alloc(16, ((size_t)need + 15) / 16 * 16);
    cellfit_fit_t *fit;
    int rc = cellfit_fit_open(&fit, &nominal, &prm, mem, (size_t)need);
    if (rc) {
        fprintf(stderr, "open: %s\n", cellfit_strerror(rc));
        return 1;
    }
    /* 60 x 50 points u v x y z, fed in rows (any number of calls). */
    double row[5 * 60];
    for (int b = 0; b < 50 && !rc; b++) {
        for (int a = 0; a < 60; a++) {
            double u = (a + 0.5) / 60, v = (b + 0.5) / 50, *r = row + 5 * a;
            r[0] = u;
            r[1] = v;
            cellfit_surface_eval(&part, u, v, r + 2);
        }
        rc = cellfit_fit_add_uvxyz(fit, row, 60);
    }
    if (!rc)
        rc = cellfit_fit_solve(fit);
    if (rc) {
        fprintf(stderr, "fit: %s: %s\n", cellfit_strerror(rc), cellfit_fit_message(fit));
        cellfit_fit_close(fit);
        return 1;
    }
    cellfit_stats_t st;
    cellfit_surface_t s;
    cellfit_fit_stats(fit, &st);
    cellfit_fit_surface(fit, &s);
    double err = 0;
    for (int k = 0; k < 3 * NU * NV; k++)
        err = fmax(err, fabs(s.cp[k] - truth[k]));
    rc = cellfit_fit_write(fit, out);
    printf("cellfit %s: %ld points, %ld control points, %ld bytes, %d iterations, "
           "max control point error %.3g mm, largest move %.3g mm, wrote %s\n",
           cellfit_version(), st.points, st.control_points, st.bytes, st.iterations, err,
           st.max_move, rc ? "nothing" : out);
    if (rc)
        fprintf(stderr, "write: %s\n", cellfit_fit_message(fit));
    cellfit_fit_close(fit);
    free(mem);
    return rc || !(err < 1e-9) ? 1 : 0;
}
