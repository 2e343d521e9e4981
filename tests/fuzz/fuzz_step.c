/* SPDX-License-Identifier: MIT */
/* fuzz_step.c: libFuzzer target for the STEP reader (cf_step_read.c): the
 * input is a file, read as a surface (the first B-spline surface, and
 * instance #20). A refusal must be one line naming the file; an acceptance
 * must be a valid, finite surface, which cf_step_write turns into a file
 * that reads back bit for bit. */
#include "cf_err.h"
#include "cf_step.h"
#include "cf_surf.h"
#include "fuzz.h"
#include "nf_surf.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int same(const double *a, const double *b, long n)
{
    return !memcmp(a, b, sizeof(double) * (size_t)n);
}

/* Written (cf_step_write_at) and read again: the same surface exactly. */
static void same_after_write(const nf_surf_t *s)
{
    char path[600], msg[1024];
    snprintf(path, sizeof path, "%s.out.stp", fz_file("out.stp", NULL, 0));
    if (cf_step_write_at(path, s, "fuzz", "fuzz", 0, msg, sizeof msg)) {
        fprintf(stderr, "fuzz_step: cannot write an accepted surface: %s\n", msg);
        abort();
    }
    nf_surf_t t;
    if (cf_step_read(path, 0, &t, msg, sizeof msg)) {
        fprintf(stderr, "fuzz_step: the written surface does not read back: %s\n", msg);
        abort();
    }
    long n = (long)s->nu * s->nv;
    if (t.p != s->p || t.q != s->q || t.nu != s->nu || t.nv != s->nv ||
        !same(t.U, s->U, s->nu + s->p + 1) || !same(t.V, s->V, s->nv + s->q + 1) ||
        !same(t.cp, s->cp, 3 * n) || !same(t.w, s->w, n)) {
        fprintf(stderr, "fuzz_step: the surface read back differs\n");
        abort();
    }
    cf_surf_free(&t);
    remove(path);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fz_file("in.stp", data, size);
    char msg[1024];
    static const long ids[2] = {0, 20};
    for (int k = 0; k < 2; k++) {
        nf_surf_t s;
        int rc = cf_step_read(path, ids[k], &s, msg, sizeof msg);
        if (rc) {
            fz_one_line(msg);
            fz_names(msg, path);
            if (s.U || s.cp) /* refused: nothing owned */
                abort();
            continue;
        }
        if (nf_surf_check(&s))
            abort();
        for (long i = 0; i < 3L * s.nu * s.nv; i++)
            if (!isfinite(s.cp[i]))
                abort();
        same_after_write(&s);
        cf_surf_free(&s);
    }
    return 0;
}
