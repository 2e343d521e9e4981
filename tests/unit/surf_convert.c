/* SPDX-License-Identifier: MIT */
/* surf_convert.c: a test driver for tests/cli/step.sh until `cellfit
 * convert` exists in the command layer: reads a surface (IGES or STEP, by
 * extension, through cf_surfio) and writes it in the format OUT's extension
 * names. --rational SEED first gives the net pseudo-random weights in
 * [0.5, 2) (a rational surface from a plain one, the same in every output);
 * --id N reads that IGES DE or STEP instance.
 * Usage: surf_convert IN OUT [--rational SEED] [--id N] [--version V] */
#include "cf_err.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
    const char *in = NULL, *out = NULL, *version = "test";
    long id = 0;
    unsigned long seed = 0;
    int rational = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--rational") && i + 1 < argc) {
            seed = strtoul(argv[++i], NULL, 10);
            rational = 1;
        } else if (!strcmp(argv[i], "--id") && i + 1 < argc)
            id = strtol(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--version") && i + 1 < argc)
            version = argv[++i];
        else if (!in)
            in = argv[i];
        else if (!out)
            out = argv[i];
        else
            in = NULL, i = argc;
    }
    if (!in || !out) {
        fprintf(stderr, "usage: surf_convert IN OUT [--rational SEED] [--id N] [--version V]\n");
        return 2;
    }
    char msg[1024];
    nf_surf_t s;
    int rc = cf_surfio_read(in, id, &s, msg, sizeof msg);
    if (rc) {
        fprintf(stderr, "surf_convert: %s (%s)\n", msg, cf_strerror(rc));
        return 1;
    }
    if (rational) {
        unsigned long long x = 0x9E3779B97F4A7C15ULL ^ seed;
        for (long k = 0; k < (long)s.nu * s.nv; k++) {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            s.w[k] = 0.5 + 1.5 * (double)(x >> 11) * 0x1p-53;
        }
    }
    rc = cf_surfio_write(out, &s, "converted", version, msg, sizeof msg);
    cf_surf_free(&s);
    if (rc) {
        fprintf(stderr, "surf_convert: %s (%s)\n", msg, cf_strerror(rc));
        return 1;
    }
    return 0;
}
