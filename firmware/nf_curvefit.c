/* SPDX-License-Identifier: MIT */
/* nf_curvefit.c: streamed least-squares fit of a cubic B-spline curve (normal
 * equations, Cholesky, ridge toward a straight line). */
#include "nf_curvefit.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

#define P3 NF_CURVEFIT_DEGREE

int nf_curvefit_init(nf_curvefit_t *f, int n, double *mem, long len)
{
    if (!f || !mem)
        return NF_EARG;
    if (n < P3 + 1)
        return NF_ESIZE;
    if (len < NF_CURVEFIT_DOUBLES(n))
        return NF_EARG;
    memset(f, 0, sizeof *f);
    f->n = n;
    f->U = mem;
    f->A = f->U + n + P3 + 1;
    f->b = f->A + (long)n * n;
    f->N = f->b + 3L * n;
    memset(f->A, 0, sizeof(double) * (size_t)((long)n * n + 3L * n));
    for (int i = 0; i <= P3; i++) {
        f->U[i] = 0.0;
        f->U[n + i] = 1.0;
    }
    for (int i = P3 + 1; i < n; i++)
        f->U[i] = (double)(i - P3) / (n - P3);
    return NF_OK;
}

int nf_curvefit_add(nf_curvefit_t *f, double t, const double Q[3])
{
    if (f->solved)
        return NF_ESTATE;
    if (!(t - t == 0.0) || !(Q[0] - Q[0] == 0.0) || !(Q[1] - Q[1] == 0.0) || !(Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    int n = f->n, l = nf_find_span(n - 1, P3, t, f->U); /* its n: last index */
    nf_basis_funs(l, t, P3, f->U, f->N);
    /* Row N_{l-p..l}(t) of the overdetermined system: outer product into A. */
    for (int r = 0; r <= P3; r++) {
        int i = l - P3 + r;
        for (int s = r; s <= P3; s++)
            f->A[(long)i * n + (l - P3 + s)] += f->N[r] * f->N[s];
        for (int k = 0; k < 3; k++)
            f->b[3 * i + k] += f->N[r] * Q[k];
    }
    f->npts++;
    return NF_OK;
}

int nf_curvefit_solve(nf_curvefit_t *f, const double a[3], const double b[3], double ridge,
                      nf_curve_t *out)
{
    int n = f->n;
    if (!out || !out->U || !out->cp || out->p != P3 || out->n != n || !(ridge >= 0))
        return NF_EARG;
    if (f->solved)
        return NF_ESTATE;
    if (f->npts < n)
        return NF_ENODATA;
    double *A = f->A, *x = f->b, mean = 0.0;
    for (int i = 0; i < n; i++)
        mean += A[(long)i * n + i];
    double lam = ridge * mean / n;
    /* Ridge: minimise |N P - Q|^2 + lam |P - L|^2, L on the line a-b. */
    for (int i = 0; i < n; i++) {
        double g = nf_greville(i, P3, f->U);
        A[(long)i * n + i] += lam;
        for (int k = 0; k < 3; k++)
            x[3 * i + k] += lam * (a[k] + g * (b[k] - a[k]));
    }
    f->solved = 1;
    /* Cholesky A = R^T R in the upper triangle. */
    for (int j = 0; j < n; j++) {
        for (int i = 0; i <= j; i++) {
            double s = A[(long)i * n + j];
            for (int k = 0; k < i; k++)
                s -= A[(long)k * n + i] * A[(long)k * n + j];
            if (i < j)
                A[(long)i * n + j] = s / A[(long)i * n + i];
            else if (!(s > 1e-14 * (mean / n)))
                return NF_ESINGULAR;
            else
                A[(long)j * n + j] = sqrt(s);
        }
    }
    for (int k = 0; k < 3; k++) {
        for (int i = 0; i < n; i++) { /* R^T y = b */
            double s = x[3 * i + k];
            for (int m = 0; m < i; m++)
                s -= A[(long)m * n + i] * x[3 * m + k];
            x[3 * i + k] = s / A[(long)i * n + i];
        }
        for (int i = n - 1; i >= 0; i--) { /* R x = y */
            double s = x[3 * i + k];
            for (int m = i + 1; m < n; m++)
                s -= A[(long)i * n + m] * x[3 * m + k];
            x[3 * i + k] = s / A[(long)i * n + i];
        }
    }
    memcpy(out->U, f->U, sizeof(double) * (size_t)(n + P3 + 1));
    memcpy(out->cp, x, sizeof(double) * 3 * (size_t)n);
    if (out->w)
        for (int i = 0; i < n; i++)
            out->w[i] = 1.0;
    return NF_OK;
}
