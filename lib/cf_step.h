/* SPDX-License-Identifier: MIT */
/* cf_step.h: STEP AP242 (ISO 10303-21 exchange files) for NURBS surfaces,
 * read and written by our own code (the entity set is small).
 *
 * Written: one surface as the one face of a CAD model. The header names the
 * AP242 schema (AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIB_LF) and, in
 * FILE_NAME, the cellfit version; units are millimetres (LENGTH_UNIT
 * SI_UNIT(.MILLI.,.METRE.)). The surface is B_SPLINE_SURFACE_WITH_KNOTS, or
 * for unequal weights the complex entity with RATIONAL_B_SPLINE_SURFACE;
 * it is the geometry of an ADVANCED_FACE bounded by an EDGE_LOOP of its
 * four boundary curves (B-spline curves: the edge rows of the net, which
 * is clamped) between VERTEX_POINTs at the corners, in an OPEN_SHELL of a
 * SHELL_BASED_SURFACE_MODEL, the item of a
 * MANIFOLD_SURFACE_SHAPE_REPRESENTATION tied to a PRODUCT through the
 * usual product-definition chain. Numbers are %.17g, so reading back is
 * bit-exact.
 *
 * Read: a B_SPLINE_SURFACE_WITH_KNOTS (simple or as the rational complex
 * entity) with its CARTESIAN_POINTs, wherever it sits in the file; knot
 * multiplicities expanded. The file's length unit is applied (SI_UNIT with
 * any prefix; a CONVERSION_BASED_UNIT such as the inch is refused). */
#ifndef CF_STEP_H
#define CF_STEP_H

#include "cf_trim.h"
#include "nf_surf.h"
#include <stddef.h>

/* Write s to path as an AP242 file (to path.tmp, then renamed, so path is
 * complete or absent). name (may be NULL: "surface") names the product;
 * version (may be NULL) goes into FILE_NAME's originating_system, as
 * "cellfit VERSION". Timestamp: the current UTC time, or
 * SOURCE_DATE_EPOCH when that is set. CF_EARG, the nf_err_t of
 * nf_surf_check, CF_ENOMEM, CF_EIO; msg names the file. */
int cf_step_write(const char *path, const nf_surf_t *s, const char *name, const char *version,
                  char *msg, size_t msglen);

/* cf_step_write with an explicit timestamp (seconds since 1970, UTC). */
int cf_step_write_at(const char *path, const nf_surf_t *s, const char *name, const char *version,
                     long long utc, char *msg, size_t msglen);

/* Read the surface of instance #id (id = 0: the first B-spline surface with
 * knots in the file) into out (cf_surf_alloc'd, always with weights;
 * cf_surf_free it). CF_EIO, CF_EPARSE (msg: file and line), CF_ENOTFOUND,
 * CF_EUNSUPPORTED (a surface type or unit we do not take), CF_ENOMEM, or
 * the nf_err_t of nf_surf_check. On failure out is zeroed and owns
 * nothing. */
/* cf_step_write_at of s trimmed by t (t->nloops > 0): the ADVANCED_FACE's
 * bounds are t's loops (FACE_OUTER_BOUND first, then FACE_BOUNDs), each an
 * EDGE_LOOP of ORIENTED_EDGEs of EDGE_CURVEs between VERTEX_POINTs; an edge
 * is a SURFACE_CURVE: the 3-D B-spline cf_trim_edge3d makes on s, with the
 * trim curve as its PCURVE (2-D B-spline in a parametric context).
 * *edge_err (may be NULL): the largest 3-D edge error, mm. */
int cf_step_write_trimmed_at(const char *path, const nf_surf_t *s, const cf_trim_t *t,
                             const char *name, const char *version, long long utc, double *edge_err,
                             char *msg, size_t msglen);

int cf_step_read(const char *path, long id, nf_surf_t *out, char *msg, size_t msglen);

/* The trim of the surface cf_step_read(path, id) reads: the bounds of the
 * first ADVANCED_FACE over it, the FACE_OUTER_BOUND first (else the order
 * of the file), each EDGE_LOOP's edges as their PCURVEs on that surface
 * (2-D B-splines, plain or rational), turned to run as the face does
 * (bound, oriented edge and edge senses). out->nloops = 0 when no face
 * uses the surface, or when an edge has no B-spline PCURVE on it (3-D
 * curves only, as cellfit's untrimmed faces; LINE or other PCURVEs): the
 * surface is then taken whole. Errors as cf_step_read. */
int cf_step_read_trim(const char *path, long id, cf_trim_t *out, char *msg, size_t msglen);

#endif
