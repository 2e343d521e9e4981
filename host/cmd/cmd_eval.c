/* cmd_eval.c: `cellfit eval SURF.igs UVFILE`: x y z (%.17g) for each u v line. */
#include "cf_cli.h"
#include "cmd.h"
#include "cf_iges.h"
#include "cf_points.h"
#include "cf_surf.h"
#include <string.h>

int cmd_eval(int argc, char **argv)
{
    const char *surf = NULL, *uvf = NULL;
    long entity = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--entity")) {
            if (i + 1 >= argc || cli_int(argv[i + 1], 1, 9999999, &entity))
                return cli_error("eval", CLI_USAGE, "--entity needs a DE number");
            i++;
        } else if (argv[i][0] == '-' && argv[i][1])
            return cli_error("eval", CLI_USAGE, "unknown option '%s'", argv[i]);
        else if (!surf)
            surf = argv[i];
        else if (!uvf)
            uvf = argv[i];
        else
            return cli_error("eval", CLI_USAGE, "unexpected argument '%s'", argv[i]);
    }
    if (!surf || !uvf)
        return cli_error("eval", CLI_USAGE, "usage: cellfit eval SURF.igs UVFILE");
    char msg[512];
    nf_surf_t s;
    if (cf_iges_read(surf, (int)entity, &s, msg, sizeof msg))
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
