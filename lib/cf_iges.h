/* SPDX-License-Identifier: MIT */
/* cf_iges.h: IGES 5.3 entity 128 (rational B-spline surface), read and write.
 * Fixed-80-column ASCII IGES only; binary and compressed forms are refused. */
#ifndef CF_IGES_H
#define CF_IGES_H

#include "cf_trim.h"
#include "nf_curve.h"
#include "nf_surf.h"
#include <stddef.h>

/* Read one entity 128 from an IGES file into out (allocated with
 * cf_surf_alloc, always with weights; free with cf_surf_free). entity_de = 0
 * takes the first 128 in the Directory Entry section, otherwise the 128 whose
 * DE sequence number (odd D line number) is entity_de. A transformation
 * matrix (entity 124, chained) on the 128 itself is applied to the control
 * points; matrices of parents (144, 186, ...) are not.
 * Returns CF_OK, CF_EIO, CF_EPARSE, CF_ENOTFOUND, CF_EUNSUPPORTED, CF_ENOMEM,
 * or the nf_err_t of nf_surf_check; msg names the file and line/record. On
 * failure out is zeroed and owns nothing. */
int cf_iges_read(const char *path, int entity_de, nf_surf_t *out, char *msg, size_t msglen);

/* Write s as a complete IGES 5.3 file holding one entity 128 (form 0), with
 * every number in %.17g form so reading back is bit-exact. The file appears
 * at path only when complete: it is written to path.tmp and renamed. name
 * (may be NULL) goes into the Start and Global sections. The timestamp is
 * the current UTC time, or SOURCE_DATE_EPOCH when that is set. */
int cf_iges_write(const char *path, const nf_surf_t *s, const char *name, char *msg, size_t msglen);

/* cf_iges_write with an explicit timestamp (seconds since 1970, UTC), for
 * reproducible output and tests. */
int cf_iges_write_at(const char *path, const nf_surf_t *s, const char *name, long long utc,
                     char *msg, size_t msglen);

/* Entity 126 (rational B-spline curve), read like the 128: entity_de = 0
 * takes the nth (0-based) 126 of the Directory, otherwise the 126 at that
 * DE number; its own transformation matrices (124) and the Global unit are
 * applied. out is allocated (always with weights; cf_curve_free). Curves
 * whose parameter range V(0), V(1) is a part of the knot domain (trimmed)
 * are refused (CF_EUNSUPPORTED). Errors as cf_iges_read, plus
 * nf_curve_check's. */
int cf_iges_read_curve(const char *path, int entity_de, long nth, nf_curve_t *out, char *msg,
                       size_t msglen);

/* nc curves as entities 126 (form 0, DE 1, 3, 5, ...), %.17g numbers (bit
 * exact on reading back), written through path.tmp and renamed. The
 * timestamp follows SOURCE_DATE_EPOCH as cf_iges_write. */
int cf_iges_write_curves(const char *path, const nf_curve_t *c, int nc, const char *name, char *msg,
                         size_t msglen);

/* Heap storage for a curve of this shape (weights 1); CF_ENOMEM. */
int cf_curve_alloc(nf_curve_t *c, int p, int n);
void cf_curve_free(nf_curve_t *c);

/* The trim of the 128 cf_iges_read(path, entity_de) reads: the loops of the
 * first 144 (trimmed surface) over it, outer boundary first (the domain's
 * sides when N1 = 0), each from its 142's parameter-space curve (a 126, or a
 * 102 of 126s; the model-space curves are not read). out->nloops = 0 when
 * no 144 trims that surface. Errors as cf_iges_read; a 142 with no
 * parameter-space curve is CF_EUNSUPPORTED. */
int cf_iges_read_trim(const char *path, int entity_de, cf_trim_t *out, char *msg, size_t msglen);

/* cf_iges_write_at of s trimmed by t (t->nloops > 0): the 128, each loop's
 * curves in parameter space (126, form 0, use flag 05) and as 3-D edges on s
 * (126, cf_trim_edge3d), a 102 per loop side when a loop has more than one
 * curve, a 142 per loop and one 144 over them; everything but the 144
 * physically dependent. *edge_err (may be NULL): the largest 3-D edge error. */
int cf_iges_write_trimmed_at(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                             const char *name, long long utc, double *edge_err, char *msg,
                             size_t msglen);

#endif
