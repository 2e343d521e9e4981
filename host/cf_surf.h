/* cf_surf.h: heap-owned NURBS surfaces for the host tools. */
#ifndef CF_SURF_H
#define CF_SURF_H

#include "nf_surf.h"

/* Allocate storage for a surface of this shape (weights 1, knots and points
 * zero). CF_ENOMEM on failure. Free with cf_surf_free. */
int cf_surf_alloc(nf_surf_t *s, int p, int q, int nu, int nv);
void cf_surf_free(nf_surf_t *s);
/* Deep copy of src into dst (allocated here). */
int cf_surf_copy(nf_surf_t *dst, const nf_surf_t *src);

#endif
