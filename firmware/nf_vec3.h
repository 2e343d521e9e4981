/* SPDX-License-Identifier: MIT */
/* nf_vec3.h: the dot and cross products of 3-vectors that the projection
 * modules (nf_project, nf_quad, nf_affine, nf_fold) share; inline, so the
 * hot loops compile as with their former local copies. */
#ifndef NF_VEC3_H
#define NF_VEC3_H

static inline double nf_dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* c = a x b (c apart from a and b). */
static inline void nf_cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

#endif
