/* SPDX-License-Identifier: MIT */
/* cf_surfio.h: surface files by extension: ".igs"/".iges" IGES entity 128
 * (cf_iges), ".stp"/".step" STEP AP242 (cf_step), case-insensitive. The one
 * place every reader and writer of a surface (fit --out, base --out,
 * convert, serve's EXPORT) should go through, so the extension chooses the
 * format everywhere. */
#ifndef CF_SURFIO_H
#define CF_SURFIO_H

#include "cf_trim.h"
#include "nf_surf.h"
#include <stddef.h>

typedef enum cf_surfio_fmt {
    CF_SURFIO_UNKNOWN = 0,
    CF_SURFIO_IGES = 1,
    CF_SURFIO_STEP = 2
} cf_surfio_fmt_t;

/* The format path's extension names. */
cf_surfio_fmt_t cf_surfio_format(const char *path);

/* Read the surface of path (which = 0: the first; otherwise IGES's DE
 * number or STEP's instance number) into out (cf_surf_free it). Without a
 * known extension the content decides (STEP starts "ISO-10303-21", anything
 * else is read as IGES); errors as cf_iges_read / cf_step_read. */
int cf_surfio_read(const char *path, long which, nf_surf_t *out, char *msg, size_t msglen);

/* Write s to path in the format its extension names (atomically: path.tmp,
 * then renamed). name: the product/surface name (may be NULL); version: the
 * cellfit version for STEP's FILE_NAME (may be NULL). Another extension is
 * written as IGES, the tools' format before STEP (`cellfit convert` alone
 * insists on a known one); errors as cf_iges_write / cf_step_write. */
int cf_surfio_write(const char *path, const nf_surf_t *s, const char *name, const char *version,
                    char *msg, size_t msglen);

/* The trim of the surface cf_surfio_read(path, which) reads, when it is a
 * trimmed face (IGES: a 144 over it, cf_iges_read_trim; STEP: the bounds
 * of its ADVANCED_FACE, cf_step_read_trim); t->nloops = 0 when it is not.
 * Errors as those. */
int cf_surfio_read_trim(const char *path, long which, cf_trim_t *t, char *msg, size_t msglen);

/* cf_surfio_write of s as the face t trims (t may be NULL or empty: the
 * whole surface): IGES 144/142/126 (cf_iges_write_trimmed_at), STEP
 * ADVANCED_FACE bounds (cf_step_write_trimmed_at). The trim must lie in s's
 * domain with closed loops (cf_trim_check, 1e-9 of the domain): the trim
 * curves are written as they are, only the 3-D edges are made on s.
 * *edge_err (may be NULL): their largest distance from S(c(t)), mm. */
int cf_surfio_write_trimmed(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                            const char *name, const char *version, double *edge_err, char *msg,
                            size_t msglen);

#endif
