/* SPDX-License-Identifier: MIT */
/* cmd_project.c: `cellfit project SURF.igs XYZFILE [--entity N]`: for each
 * measured point x y z, the parameters of its closest point on the surface
 * and the signed distance to it (Piegl & Tiller 2001, Section 3; NURBS Book
 * 6.1), one line "u v distance" (%.17g) per point. Start points come from
 * the quadrilateral decomposition (nf_quad, Section 3), or a 3-D grid of
 * seed samples where it cannot serve (cf_seedgrid); memory is that and one
 * read batch, whatever the number of points. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_seedgrid.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cmd.h"
#include "nf_err.h"
#include "nf_project.h"
#include <stdlib.h>
#include <string.h>

#define BATCH 4096
#define PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain */

int cmd_project(int argc, char **argv)
{
    const char *pos[2];
    long entity = 0;
    const cf_opt_t opts[] = {
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &entity,
         .arg = "DE",
         .help = "the surface's directory entry in SURF (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "project",
                          .args = "SURF.igs XYZFILE",
                          .summary = "\"u v distance\" (%.17g) of each point of XYZFILE projected "
                                     "onto SURF",
                          .opts = opts,
                          .min_pos = 2,
                          .max_pos = 2};
    int prc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (prc)
        return cf_opt_exit(prc);
    const char *surf = pos[0], *xyzf = pos[1];
    char msg[512];
    nf_surf_t s;
    if (cf_surfio_read(surf, (int)entity, &s, msg, sizeof msg))
        return cli_error("project", CLI_USAGE, "%s", msg);
    cf_points_t *r = NULL;
    if (cf_points_open(&r, xyzf, 3, msg, sizeof msg)) {
        cf_surf_free(&s);
        return cli_error("project", CLI_USAGE, "%s", msg);
    }
    cf_seedgrid_t g;
    double *buf = malloc(sizeof(double) * 3 * BATCH);
    int ec = CLI_OK;
    if (!buf || cf_seedgrid_init(&g, &s, 8)) {
        memset(&g, 0, sizeof g);
        ec = cli_error("project", CLI_FAIL, "out of memory");
        goto done;
    }
    long got, n = 0, lost = 0, first_lost = 0;
    while ((got = cf_points_read(r, buf, BATCH, msg, sizeof msg)) > 0) {
        for (long k = 0; k < got; k++) {
            nf_proj_t pr;
            int rc = cf_seedgrid_project(&g, buf + 3 * k, PROJ_TOL, &pr);
            n++;
            if (rc == NF_ENOCONV) { /* the nearest point found is still printed */
                first_lost = lost++ ? first_lost : n;
            } else if (rc != NF_OK) { /* the reader passes finite points only: a bug */
                fflush(stdout);
                ec = cli_error("project", CLI_FAIL, "%s: point %ld: %s", xyzf, n, nf_strerror(rc));
                goto done;
            }
            printf("%.17g %.17g %.17g\n", pr.u, pr.v, pr.dist);
        }
    }
    if (got < 0) {
        fflush(stdout);
        ec = cli_error("project", CLI_USAGE, "%s", msg);
    } else if (lost) {
        fflush(stdout);
        ec = cli_error("project", CLI_FAIL,
                       "%s: %ld point(s) did not converge in %d Newton steps (the first is point "
                       "%ld); the nearest point found is printed for them",
                       xyzf, lost, NF_PROJ_MAX_ITERS, first_lost);
    }
done:
    free(buf);
    cf_seedgrid_free(&g);
    cf_points_close(r);
    cf_surf_free(&s);
    return ec;
}
