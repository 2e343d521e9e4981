/* SPDX-License-Identifier: MIT */
/* cf_surfio.c: surface read and write dispatched on the file's extension. */
#include "cf_surfio.h"
#include "cf_atomic.h"
#include "cf_err.h"
#include "cf_iges.h"
#include "cf_step.h"
#include "nf_err.h"
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int ext_is(const char *ext, const char *want)
{
    for (; *ext && *want; ext++, want++)
        if (tolower((unsigned char)*ext) != *want)
            return 0;
    return !*ext && !*want;
}

cf_surfio_fmt_t cf_surfio_format(const char *path)
{
    const char *dot = path ? strrchr(path, '.') : NULL, *slash = path ? strrchr(path, '/') : NULL;
    if (!dot || (slash && dot < slash))
        return CF_SURFIO_UNKNOWN;
    dot++;
    if (ext_is(dot, "igs") || ext_is(dot, "iges"))
        return CF_SURFIO_IGES;
    if (ext_is(dot, "stp") || ext_is(dot, "step"))
        return CF_SURFIO_STEP;
    return CF_SURFIO_UNKNOWN;
}

/* A name without a known extension: STEP if the file starts as one (its
 * ISO 10303-21 exchange-structure line), otherwise IGES. */
static cf_surfio_fmt_t sniff(const char *path)
{
    char head[16] = {0};
    FILE *f = path ? fopen(path, "rb") : NULL;
    if (f) {
        size_t n = fread(head, 1, sizeof head - 1, f);
        head[n] = '\0';
        fclose(f);
    }
    return !strncmp(head, "ISO-10303-21", 12) ? CF_SURFIO_STEP : CF_SURFIO_IGES;
}

int cf_surfio_read(const char *path, long which, nf_surf_t *out, char *msg, size_t msglen)
{
    cf_surfio_fmt_t fmt = cf_surfio_format(path);
    if (fmt == CF_SURFIO_UNKNOWN && path)
        fmt = sniff(path);
    switch (fmt) {
    case CF_SURFIO_IGES:
        if (which < 0 || which > 9999999)
            return cf_fail(msg, msglen, CF_EARG, "%s: IGES DE number %ld", path, which);
        return cf_iges_read(path, (int)which, out, msg, msglen);
    case CF_SURFIO_STEP: return cf_step_read(path, which, out, msg, msglen);
    default:
        return cf_fail(msg, msglen, CF_EUNSUPPORTED,
                       "%s: unknown surface format (use .igs, .iges, .stp or .step)",
                       path ? path : "(null)");
    }
}

int cf_surfio_write(const char *path, const nf_surf_t *s, const char *name, const char *version,
                    char *msg, size_t msglen)
{
    cf_surfio_fmt_t fmt = cf_surfio_format(path);
    if (fmt == CF_SURFIO_UNKNOWN && path && *path)
        fmt = CF_SURFIO_IGES; /* the tools' format before STEP: names like x.igs.replay */
    switch (fmt) {
    case CF_SURFIO_IGES: return cf_iges_write(path, s, name, msg, msglen);
    case CF_SURFIO_STEP: return cf_step_write(path, s, name, version, msg, msglen);
    default:
        return cf_fail(msg, msglen, CF_EUNSUPPORTED,
                       "%s: unknown surface format (use .igs, .iges, .stp or .step)",
                       path ? path : "(null)");
    }
}

int cf_surfio_read_trim(const char *path, long which, cf_trim_t *t, char *msg, size_t msglen)
{
    cf_surfio_fmt_t fmt = cf_surfio_format(path);
    memset(t, 0, sizeof *t);
    if (fmt == CF_SURFIO_UNKNOWN && path)
        fmt = sniff(path);
    if (fmt == CF_SURFIO_STEP)
        return cf_step_read_trim(path, which, t, msg, msglen);
    if (fmt != CF_SURFIO_IGES)
        return CF_OK;
    if (which < 0 || which > 9999999)
        return cf_fail(msg, msglen, CF_EARG, "%s: IGES DE number %ld", path, which);
    return cf_iges_read_trim(path, (int)which, t, msg, msglen);
}

int cf_surfio_write_trimmed(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                            const char *name, const char *version, double *edge_err, char *msg,
                            size_t msglen)
{
    if (edge_err)
        *edge_err = 0.0;
    if (!t || t->nloops == 0)
        return cf_surfio_write(path, s, name, version, msg, msglen);
    if (!s || nf_surf_check(s))
        return cf_surfio_write(path, s, name, version, msg, msglen); /* its error */
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    char why[400];
    if (cf_trim_check(t, s, 1e-9 * fmax(u1 - u0, v1 - v0), why, sizeof why))
        return cf_fail(msg, msglen, CF_EARG, "%s: not written: %s", path, why);
    cf_surfio_fmt_t fmt = cf_surfio_format(path);
    if (fmt == CF_SURFIO_STEP)
        return cf_step_write_trimmed_at(path, s, t, name, version, cf_atomic_stamp(), edge_err, msg,
                                        msglen);
    return cf_iges_write_trimmed_at(path, s, t, name, cf_atomic_stamp(), edge_err, msg, msglen);
}
