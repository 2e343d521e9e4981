/* SPDX-License-Identifier: MIT */
/* ref_job.c: the fit-job tests' shared run and surface gap (ref_job.h). */
#include "ref_job.h"
#include "cf_fitsrc.h"
#include "cf_points.h"
#include <math.h>

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
