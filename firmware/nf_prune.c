/* SPDX-License-Identifier: MIT */
/* nf_prune.c: knot removal for the pruning stage (nf_prune.h). */
#include "nf_prune.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

/* Homogeneous point k of row r (dir 0: the row of fixed v index r, k
 * along u; dir 1: the column of fixed u index r, k along v). */
static void hpt(const nf_surf_t *s, int dir, int r, int k, double h[4])
{
    long i = dir == 0 ? k + (long)r * s->nu : r + (long)k * s->nu;
    double w = s->w ? s->w[i] : 1.0;
    for (int c = 0; c < 3; c++)
        h[c] = w * s->cp[3 * i + c];
    h[3] = w;
}

static void put(nf_surf_t *o, int dir, int r, int k, const double h[4])
{
    long i = dir == 0 ? k + (long)r * o->nu : r + (long)k * o->nu;
    for (int c = 0; c < 3; c++)
        o->cp[3 * i + c] = h[c] / h[3];
    if (o->w)
        o->w[i] = h[3];
}

/* The knot K[r] of n control points, degree p: interior and simple. */
static int simple_interior(const double *K, int n, int p, int r)
{
    return r > p && r < n && K[r - 1] < K[r] && K[r] < K[r + 1];
}

/* The window of the removal of K[r] from row `row` (n points, degree p,
 * knots K): W[k] = Q_{r-p-1+k}, k = 0 .. p, the coarse homogeneous points
 * that differ from the fine ones' copies (Q_i = P_i below the window,
 * Q_i = P_{i+1} above it); returns the mismatch of the equation left over.
 * Inserting x = K[r] into the coarse vector gives, for i = r-p .. r-1,
 *   P_i = a_i Q_i + (1 - a_i) Q_{i-1},  a_i = (x - K[i]) / (K[i+p+1] - K[i]),
 * with Q_{r-p-1} = P_{r-p-1} and Q_{r-1} = P_r: p equations, p-1 unknowns
 * Q_{r-p} .. Q_{r-2}, solved forward (the first f) and backward (the
 * rest), the middle one left to check (A5.8). */
static double window(const nf_surf_t *s, int dir, int row, int r, double (*W)[4])
{
    const int p = dir ? s->q : s->p, f = (p - 1) / 2, o = r - p - 1;
    const double *K = dir ? s->V : s->U, x = K[r];
    double P[4];
    hpt(s, dir, row, r - p - 1, W[0]);
    hpt(s, dir, row, r, W[p]);
    for (int i = r - p; i < r - p + f; i++) { /* forward: equation i gives Q_i */
        double a = (x - K[i]) / (K[i + p + 1] - K[i]);
        hpt(s, dir, row, i, P);
        for (int c = 0; c < 4; c++)
            W[i - o][c] = (P[c] - (1.0 - a) * W[i - 1 - o][c]) / a;
    }
    for (int i = r - 1; i > r - p + f; i--) { /* backward: equation i gives Q_{i-1} */
        double a = (x - K[i]) / (K[i + p + 1] - K[i]);
        hpt(s, dir, row, i, P);
        for (int c = 0; c < 4; c++)
            W[i - 1 - o][c] = (P[c] - a * W[i - o][c]) / (1.0 - a);
    }
    const int e = r - p + f; /* the equation left over */
    double a = (x - K[e]) / (K[e + p + 1] - K[e]), d2 = 0.0;
    hpt(s, dir, row, e, P);
    for (int c = 0; c < 4; c++) {
        double m = P[c] - (a * W[e - o][c] + (1.0 - a) * W[e - 1 - o][c]);
        d2 += m * m;
    }
    return sqrt(d2);
}

int nf_prune_remove(const nf_surf_t *s, int dir, int index, nf_surf_t *out, double *err)
{
    if (!s || !out || !err || (dir != 0 && dir != 1))
        return NF_EARG;
    int rc = nf_surf_check(s);
    if (rc)
        return rc;
    const int n = dir ? s->nv : s->nu, p = dir ? s->q : s->p, rows = dir ? s->nu : s->nv;
    const double *K = dir ? s->V : s->U;
    if (!simple_interior(K, n, p, index))
        return NF_EARG;
    if (out->p != s->p || out->q != s->q || out->nu != s->nu - (dir == 0) ||
        out->nv != s->nv - (dir == 1) || !out->U || !out->V || !out->cp)
        return NF_EARG;
    double worst = 0.0, W[NF_MAX_DEGREE + 1][4], h[4];
    for (int r = 0; r < rows; r++) {
        double m = window(s, dir, r, index, W);
        worst = m > worst ? m : worst;
        for (int k = 0; k < n - 1; k++) {
            if (k < index - p - 1)
                hpt(s, dir, r, k, h);
            else if (k >= index - 1)
                hpt(s, dir, r, k + 1, h);
            else
                memcpy(h, W[k - (index - p - 1)], sizeof h);
            put(out, dir, r, k, h);
        }
    }
    /* The knots: the removed one left out. */
    double *Ko = dir ? out->V : out->U, *Kko = dir ? out->U : out->V;
    const double *Kk = dir ? s->U : s->V;
    const int nk = n + p + 1, nkk = dir ? s->nu + s->p + 1 : s->nv + s->q + 1;
    for (int i = 0, o = 0; i < nk; i++)
        if (i != index)
            Ko[o++] = K[i];
    memcpy(Kko, Kk, sizeof(double) * (size_t)nkk);
    *err = worst;
    return NF_OK;
}

/* Times x occurs in K[0 .. nk-1]. */
static int mult(const double *K, int nk, double x)
{
    int m = 0;
    for (int i = 0; i < nk; i++)
        m += K[i] == x;
    return m;
}

/* The removal error of K[r] over the rows, as nf_prune_remove's. */
static double removal_error(const nf_surf_t *s, int dir, int r)
{
    const int rows = dir ? s->nu : s->nv;
    double W[NF_MAX_DEGREE + 1][4], worst = 0.0;
    for (int row = 0; row < rows; row++) {
        double m = window(s, dir, row, r, W);
        worst = m > worst ? m : worst;
    }
    return worst;
}

int nf_prune_rank(const nf_surf_t *s, const nf_surf_t *keep, nf_prune_cand_t *out, int cap, int *n)
{
    if (!s || !out || !n || cap < 0)
        return NF_EARG;
    int rc = nf_surf_check(s);
    if (rc)
        return rc;
    *n = 0;
    for (int dir = 0; dir < 2; dir++) {
        const int nn = dir ? s->nv : s->nu, p = dir ? s->q : s->p;
        const double *K = dir ? s->V : s->U;
        for (int r = p + 1; r < nn && *n < cap; r++) {
            if (!simple_interior(K, nn, p, r))
                continue;
            if (keep && mult(dir ? keep->V : keep->U,
                             dir ? keep->nv + keep->q + 1 : keep->nu + keep->p + 1, K[r]) > 0)
                continue; /* the start's knot: the loop did not insert it */
            nf_prune_cand_t c = {dir, r, K[r], removal_error(s, dir, r), 0.0};
            c.score = c.err / (double)(dir ? s->nu : s->nv);
            int i = *n;
            while (i > 0 && out[i - 1].score > c.score) { /* insertion, stable */
                out[i] = out[i - 1];
                i--;
            }
            out[i] = c;
            (*n)++;
        }
    }
    return NF_OK;
}
