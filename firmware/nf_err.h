/* SPDX-License-Identifier: MIT */
/* nf_err.h: error codes of the fitter core; 0 is success, negatives errors.
 * Every value has one meaning and one string (nf_strerror). */
#ifndef NF_ERR_H
#define NF_ERR_H

typedef enum nf_err {
    NF_OK = 0,
    NF_EARG = -1,       /* caller bug: null pointer or impossible argument */
    NF_EBUDGET = -2,    /* job needs more bytes than the board allows */
    NF_EARENA = -3,     /* arena given is smaller than the job needs */
    NF_EDEGREE = -4,    /* degree below 1 or above the board's maximum */
    NF_EKNOTS = -5,     /* knot vector decreasing, wrong length or unclamped */
    NF_EWEIGHT = -6,    /* a weight is zero, negative or not finite */
    NF_EDOMAIN = -7,    /* parameter outside the knot domain */
    NF_ENONFINITE = -8, /* NaN or Inf in input coordinates */
    NF_ENODATA = -9,    /* a control point has no data and alpha = beta = 0 */
    NF_ESINGULAR = -10, /* normal equations numerically rank deficient */
    NF_ENOCONV = -11,   /* iterative solver hit its iteration limit */
    NF_ESOLVER = -12,   /* solver unknown or not possible within budget */
    NF_ESTATE = -13,    /* call out of order (e.g. point after finish) */
    NF_ESIZE = -14      /* net too small for the degree, or too large */
} nf_err_t;

#define NF_ERR_COUNT 15

/* A static string for any value above; "unknown error" otherwise. */
const char *nf_strerror(int err);

#endif
