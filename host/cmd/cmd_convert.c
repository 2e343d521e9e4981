/* SPDX-License-Identifier: MIT */
/* cmd_convert.c: `cellfit convert IN OUT`: a surface from one neutral
 * format to another, chosen by the file names' extensions (.igs/.iges IGES
 * entity 128, .stp/.step STEP AP242), the same surface to the last bit. */
#include "cf_cli.h"
#include "cf_opt.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "cmd.h"

int cmd_convert(int argc, char **argv)
{
    const char *pos[2];
    long entity = 0;
    const char *name = "converted";
    const cf_opt_t opts[] = {
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &entity,
         .arg = "N",
         .help = "the surface to read: IGES DE number or STEP instance #N (0: the first)",
         .lo = 0,
         .hi = 99999999},
        {.name = "name",
         .kind = CF_OPT_STR,
         .dst = &name,
         .arg = "TEXT",
         .help = "the surface's name in the output file"},
        {0}};
    const cf_cmd_t cmd = {
        .prog = "cellfit",
        .name = "convert",
        .args = "IN OUT",
        .summary = "convert a surface between IGES (.igs, .iges) and STEP AP242 (.stp, .step)",
        .descr = "The formats are chosen by the extensions. The knots, weights and control "
                 "points are kept exactly; STEP gets the surface as one face of a shell, in mm.",
        .opts = opts,
        .min_pos = 2,
        .max_pos = 2};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    if (cf_surfio_format(pos[1]) == CF_SURFIO_UNKNOWN)
        return cli_error(
            "convert", CLI_USAGE,
            "%s: unknown surface format (the extension must be .igs, .iges, .stp or .step)",
            pos[1]);
    char msg[1024];
    nf_surf_t s;
    if ((rc = cf_surfio_read(pos[0], entity, &s, msg, sizeof msg)))
        return cli_error("convert", CLI_USAGE, "%s", msg);
    cf_trim_t trim; /* a trimmed face stays one */
    if ((rc = cf_surfio_read_trim(pos[0], entity, &trim, msg, sizeof msg))) {
        cf_surf_free(&s);
        return cli_error("convert", CLI_USAGE, "%s", msg);
    }
    rc = cf_surfio_write_trimmed(pos[1], &s, &trim, name, cf_version_string(), NULL, msg,
                                 sizeof msg);
    cf_trim_free(&trim);
    cf_surf_free(&s);
    if (rc)
        return cli_error("convert", CLI_FAIL, "%s", msg);
    return CLI_OK;
}
