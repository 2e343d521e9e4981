/* SPDX-License-Identifier: MIT */
/* ref_job.c: the fit-job tests' shared run and surface gap (ref_job.h). */
#include "ref_job.h"
#include "cf_fitsrc.h"
#include "cf_points.h"
#include "cf_surf.h"
#include <math.h>
#include <stdio.h>
#include <string.h>

int ref_job_file(cf_fitjob_t *j, const char *path, int cols, cf_fitjob_result_t *r, char *m,
                 size_t ml)
{
    return ref_job_file_cache(j, path, cols, 0, r, m, ml);
}

int ref_job_file_cache(cf_fitjob_t *j, const char *path, int cols, size_t cache,
                       cf_fitjob_result_t *r, char *m, size_t ml)
{
    cf_points_t *pr = NULL;
    int rc = cf_points_open(&pr, path, cols, m, ml);
    if (!rc) {
        cf_fitsrc_t src;
        cf_fitsrc_points_t pc;
        cf_fitsrc_points(&src, &pc, pr, path);
        if (cache)
            cf_fitsrc_points_cache(&pc, cache);
        rc = cf_fitjob_run(j, &src, NULL, 0, 100, r, m, ml);
        cf_fitsrc_points_free(&pc);
    }
    cf_points_close(pr);
    return rc;
}

int ref_job_star(nf_surf_t *star, nf_surf_t *base, const char *path5, const char *path3)
{
    if (cf_surf_alloc(star, 3, 3, REF_JOB_SU, REF_JOB_SV) || cf_surf_alloc(base, 3, 3, 4, 4))
        return -1;
    static const double KU[] = {0, 0, 0, 0, 0.5, 1, 1, 1, 1}, K4[] = {0, 0, 0, 0, 1, 1, 1, 1};
    memcpy(star->U, KU, sizeof KU), memcpy(star->V, K4, sizeof K4);
    memcpy(base->U, K4, sizeof K4), memcpy(base->V, K4, sizeof K4);
    for (int j = 0; j < REF_JOB_SV; j++)
        for (int i = 0; i < REF_JOB_SU; i++) {
            double *P = star->cp + 3 * (i + REF_JOB_SU * j);
            P[0] = 10.0 * i, P[1] = 10.0 * j, P[2] = 2.0 * sin(1.3 * i + 0.4 * j);
        }
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *P = base->cp + 3 * (i + 4 * j);
            P[0] = 50.0 * i / 3.0, P[1] = 40.0 * j / 3.0, P[2] = 0.0;
        }
    FILE *f = fopen(path5, "w"), *g = fopen(path3, "w");
    if (!f || !g) {
        if (f)
            fclose(f);
        if (g)
            fclose(g);
        return -1;
    }
    for (int j = 0; j < 48; j++)
        for (int i = 0; i < 48; i++) {
            double u = (i + 0.5) / 48.0, v = (j + 0.5) / 48.0, P[3];
            nf_surf_eval(star, u, v, P);
            fprintf(f, "%.17g %.17g %.17g %.17g %.17g\n", u, v, P[0], P[1], P[2]);
            fprintf(g, "%.17g %.17g %.17g\n", P[0], P[1], P[2]);
        }
    return (fclose(f) | fclose(g)) ? -1 : 0;
}

double ref_job_gap(const nf_surf_t *a, const nf_surf_t *b)
{
    double worst = 0;
    for (int j = 0; j <= 20; j++)
        for (int i = 0; i <= 20; i++) {
            double A[3], B[3];
            nf_surf_eval(a, i / 20.0, j / 20.0, A);
            nf_surf_eval(b, i / 20.0, j / 20.0, B);
            for (int c = 0; c < 3; c++)
                worst = fmax(worst, fabs(A[c] - B[c]));
        }
    return worst;
}
