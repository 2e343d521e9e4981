/* SPDX-License-Identifier: MIT */
/* fuzz_iges.c: libFuzzer target for the IGES reader (cf_iges.c): the input
 * is a file, read as a surface (entity 128: the first, and DE 1) and as a
 * curve (entity 126: the first two). A refusal must be one line naming the
 * file; an acceptance must be a valid, finite surface or curve, which the
 * writer turns into a file that reads back bit for bit. */
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_surf.h"
#include "fuzz.h"
#include "nf_curve.h"
#include "nf_surf.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void finite_or_die(const double *x, long n, const char *what)
{
    for (long i = 0; i < n; i++)
        if (!isfinite(x[i])) {
            fprintf(stderr, "fuzz_iges: accepted a %s with a non-finite value\n", what);
            abort();
        }
}

static int same(const double *a, const double *b, long n)
{
    return !memcmp(a, b, sizeof(double) * (size_t)n);
}

/* Written (cf_iges_write_at) and read again: the same surface exactly. */
static void same_after_write(const nf_surf_t *s)
{
    char path[600], msg[1024];
    snprintf(path, sizeof path, "%s.out", fz_file("out.igs", NULL, 0));
    if (cf_iges_write_at(path, s, "fuzz", 0, msg, sizeof msg)) {
        fprintf(stderr, "fuzz_iges: cannot write an accepted surface: %s\n", msg);
        abort();
    }
    nf_surf_t t;
    if (cf_iges_read(path, 0, &t, msg, sizeof msg)) {
        fprintf(stderr, "fuzz_iges: the written surface does not read back: %s\n", msg);
        abort();
    }
    long n = (long)s->nu * s->nv;
    if (t.p != s->p || t.q != s->q || t.nu != s->nu || t.nv != s->nv ||
        !same(t.U, s->U, s->nu + s->p + 1) || !same(t.V, s->V, s->nv + s->q + 1) ||
        !same(t.cp, s->cp, 3 * n) || !same(t.w, s->w, n)) {
        fprintf(stderr, "fuzz_iges: the surface read back differs\n");
        abort();
    }
    cf_surf_free(&t);
    remove(path);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fz_file("in.igs", data, size);
    char msg[1024];
    for (int de = 0; de <= 1; de++) {
        nf_surf_t s;
        int rc = cf_iges_read(path, de, &s, msg, sizeof msg);
        if (rc) {
            fz_one_line(msg);
            fz_names(msg, path);
            continue;
        }
        if (nf_surf_check(&s))
            abort();
        finite_or_die(s.cp, 3L * s.nu * s.nv, "surface");
        finite_or_die(s.w, (long)s.nu * s.nv, "surface");
        same_after_write(&s);
        cf_surf_free(&s);
    }
    for (long nth = 0; nth <= 1; nth++) {
        nf_curve_t c;
        int rc = cf_iges_read_curve(path, 0, nth, &c, msg, sizeof msg);
        if (rc) {
            fz_one_line(msg);
            fz_names(msg, path);
            continue;
        }
        if (nf_curve_check(&c))
            abort();
        finite_or_die(c.cp, 3L * c.n, "curve");
        cf_curve_free(&c);
    }
    return 0;
}
