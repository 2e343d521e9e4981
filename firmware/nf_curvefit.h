/* SPDX-License-Identifier: MIT */
/* nf_curvefit.h: least-squares fit of a clamped cubic B-spline curve with
 * uniform knots on [0, 1] to streamed points (t, Q), t their parameter:
 * the n x n normal equations N^T N P = N^T Q (one matrix, three right-hand
 * sides) accumulated one point at a time, then a Cholesky solve with a tiny
 * ridge toward the straight line between two given ends, so that a span with
 * few points stays defined. Boundary curves fitted from the data for a Coons
 * base (Piegl & Tiller 2001, Section 2). No heap: caller storage of
 * NF_CURVEFIT_DOUBLES(n) doubles, a function of n only. */
#ifndef NF_CURVEFIT_H
#define NF_CURVEFIT_H

#include "nf_curve.h"

#define NF_CURVEFIT_DEGREE 3
/* a sane bound for the dense n x n system */
#define NF_CURVEFIT_MAX_CP 256
/* knots, normal matrix, three right-hand sides, basis scratch */
#define NF_CURVEFIT_DOUBLES(n) ((long)(n) * (n) + 4L * (n) + 2L * (NF_CURVEFIT_DEGREE + 1))

typedef struct nf_curvefit {
    int n;      /* control points (>= 4) */
    double *U;  /* n + 4 uniform clamped knots on [0, 1] */
    double *A;  /* n x n normal matrix (upper triangle used) */
    double *b;  /* 3n: right-hand sides, x y z */
    double *N;  /* p + 1 basis values */
    long npts;  /* points accumulated */
    int solved; /* 1 after nf_curvefit_solve (A holds its factor) */
} nf_curvefit_t;

/* Start a fit of n control points in mem (len doubles). NF_ESIZE for n < 4,
 * NF_EARG for too little storage or a null pointer. */
int nf_curvefit_init(nf_curvefit_t *f, int n, double *mem, long len);

/* One point Q at parameter t (clamped to [0, 1]). NF_ENONFINITE for NaN or
 * Inf, NF_ESTATE after solve. */
int nf_curvefit_add(nf_curvefit_t *f, double t, const double Q[3]);

/* Solve; the control points into out (wired by the caller as degree 3, n
 * points; knots and unit weights written). ridge >= 0 is relative to the
 * mean diagonal of the normal matrix: it adds ridge * mean * |P - L|^2, L
 * the straight line from a to b at the Greville points. NF_ENODATA when
 * fewer points than control points were added, NF_ESINGULAR when the
 * system is not positive definite, NF_EARG for a wrong out. */
int nf_curvefit_solve(nf_curvefit_t *f, const double a[3], const double b[3], double ridge,
                      nf_curve_t *out);

#endif
