/* SPDX-License-Identifier: MIT */
/* cmd_eval.c: `cellfit eval SURF UVFILE`: x y z (%.17g) for each u v line. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_opt.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cmd.h"

int cmd_eval(int argc, char **argv)
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
                          .name = "eval",
                          .args = "SURF UVFILE",
                          .summary = "x y z (%.17g) of SURF at each \"u v\" line of UVFILE",
                          .opts = opts,
                          .min_pos = 2,
                          .max_pos = 2};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    const char *surf = pos[0], *uvf = pos[1];
    char msg[512];
    nf_surf_t s;
    if (cf_surfio_read(surf, (int)entity, &s, msg, sizeof msg))
        return cli_error("eval", CLI_USAGE, "%s", msg);
    cf_points_t *r = NULL;
    if (cf_points_open(&r, uvf, 2, msg, sizeof msg)) {
        cf_surf_free(&s);
        return cli_error("eval", CLI_USAGE, "%s", msg);
    }
    double u0, u1, v0, v1, buf[2];
    nf_surf_domain(&s, &u0, &u1, &v0, &v1);
    long got;
    int ec = CLI_OK;
    /* One point per read so that an error can name its line exactly. */
    while ((got = cf_points_read(r, buf, 1, msg, sizeof msg)) > 0) {
        double u = buf[0], v = buf[1], P[3];
        if (u < u0 || u > u1 || v < v0 || v > v1) {
            fflush(stdout);
            ec = cli_error("eval", CLI_USAGE,
                           "%s:%ld: (%.17g, %.17g) outside the domain [%.17g, %.17g] x "
                           "[%.17g, %.17g]",
                           uvf, cf_points_line(r), u, v, u0, u1, v0, v1);
            goto done;
        }
        nf_surf_eval(&s, u, v, P);
        printf("%.17g %.17g %.17g\n", P[0], P[1], P[2]);
    }
    if (got < 0)
        ec = cli_error("eval", CLI_USAGE, "%s", msg);
done:
    cf_points_close(r);
    cf_surf_free(&s);
    return ec;
}
