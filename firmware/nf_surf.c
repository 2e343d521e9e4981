/* SPDX-License-Identifier: MIT */
/* nf_surf.c: NURBS surface validation and evaluation (Eq. 1; NURBS Book A4.3, A4.4). */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_basis.h"
#include "nf_err.h"
#include "nf_surf.h"

#if NF_ISA_COLD
void nf_surf_wire(nf_surf_t *s, int p, int q, int nu, int nv, double *mem)
{
    long n = (long)nu * nv;
    s->p = p;
    s->q = q;
    s->nu = nu;
    s->nv = nv;
    s->U = mem;
    s->V = s->U + nu + p + 1;
    s->cp = s->V + nv + q + 1;
    s->w = s->cp + 3 * n;
    for (long i = 0; i < n; i++)
        s->w[i] = 1.0;
}

int nf_surf_check(const nf_surf_t *s)
{
    if (!s || !s->U || !s->V || !s->cp)
        return NF_EARG;
    if (s->p < 1 || s->q < 1 || s->p > NF_MAX_DEGREE || s->q > NF_MAX_DEGREE)
        return NF_EDEGREE;
    if (s->nu < s->p + 1 || s->nv < s->q + 1)
        return NF_ESIZE;
    if (s->nu > NF_MAX_CP / s->nv) /* nu * nv > NF_MAX_CP without overflow */
        return NF_EBUDGET;
    if (nf_knots_check(s->nu - 1, s->p, s->U) || nf_knots_check(s->nv - 1, s->q, s->V))
        return NF_EKNOTS;
    long n = (long)s->nu * s->nv;
    for (long i = 0; i < 3 * n; i++)
        if (!(s->cp[i] - s->cp[i] == 0.0))
            return NF_ENONFINITE;
    if (s->w)
        for (long i = 0; i < n; i++)
            if (!(s->w[i] > 0.0) || !(s->w[i] - s->w[i] == 0.0))
                return NF_EWEIGHT;
    return NF_OK;
}

void nf_surf_domain(const nf_surf_t *s, double *u0, double *u1, double *v0, double *v1)
{
    *u0 = s->U[s->p];
    *u1 = s->U[s->nu];
    *v0 = s->V[s->q];
    *v1 = s->V[s->nv];
}
#endif

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

int nf_surf_rbasis(const nf_surf_t *s, double u, double v, int *l, int *k, double *R)
{
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER];
    const int p = s->p, q = s->q, o = p + 1;
    u = clampd(u, s->U[p], s->U[s->nu]);
    v = clampd(v, s->V[q], s->V[s->nv]);
    /* the span from uniform spacing first: no binary search on even knots */
    *l = nf_find_span_from(-1, s->nu - 1, p, u, s->U, (s->nu - p) / (s->U[s->nu] - s->U[p]));
    *k = nf_find_span_from(-1, s->nv - 1, q, v, s->V, (s->nv - q) / (s->V[s->nv] - s->V[q]));
    nf_basis_funs(*l, u, p, s->U, Nu);
    nf_basis_funs(*k, v, q, s->V, Nv);
    if (!s->w) {
        for (int b = 0; b <= q; b++)
            for (int a = 0; a <= p; a++)
                R[a + b * o] = Nu[a] * Nv[b];
        return o * (q + 1);
    }
    double W = 0.0;
    const double *w = s->w + (*l - p) + (long)(*k - q) * s->nu;
    for (int b = 0; b <= q; b++)
        for (int a = 0; a <= p; a++) {
            double r = Nu[a] * Nv[b] * w[a + (long)b * s->nu];
            R[a + b * o] = r;
            W += r;
        }
    double inv = 1.0 / W;
    for (int t = 0; t < o * (q + 1); t++)
        R[t] *= inv;
    return o * (q + 1);
}

void nf_surf_eval(const nf_surf_t *s, double u, double v, double out[3])
{
    double R[NF_MAX_LOCAL];
    int l, k;
    nf_surf_rbasis(s, u, v, &l, &k, R);
    const int o = s->p + 1;
    out[0] = out[1] = out[2] = 0.0;
    for (int b = 0; b <= s->q; b++) {
        const double *P = s->cp + 3 * ((l - s->p) + (long)(k - s->q + b) * s->nu);
        for (int a = 0; a <= s->p; a++) {
            double r = R[a + b * o];
            out[0] += r * P[3 * a];
            out[1] += r * P[3 * a + 1];
            out[2] += r * P[3 * a + 2];
        }
    }
}

void nf_surf_derivs(const nf_surf_t *s, double u, double v, int d, double skl[27])
{
    /* Homogeneous derivatives Aw(k,l) of (wx, wy, wz, w), then the quotient
     * rule of A4.4 removes the weight. */
    double du[3 * NF_MAX_ORDER], dv[3 * NF_MAX_ORDER];
    double Aw[3][3][4] = {{{0}}};
    const int p = s->p, q = s->q;
    if (d > 2)
        d = 2;
    u = clampd(u, s->U[p], s->U[s->nu]);
    v = clampd(v, s->V[q], s->V[s->nv]);
    int l = nf_find_span_from(-1, s->nu - 1, p, u, s->U, (s->nu - p) / (s->U[s->nu] - s->U[p]));
    int k = nf_find_span_from(-1, s->nv - 1, q, v, s->V, (s->nv - q) / (s->V[s->nv] - s->V[q]));
    int du_n = d < p ? d : p, dv_n = d < q ? d : q;
    nf_ders_basis_funs(l, u, p, du_n, s->U, du);
    nf_ders_basis_funs(k, v, q, dv_n, s->V, dv);
    for (int b = 0; b <= q; b++) {
        for (int a = 0; a <= p; a++) {
            long idx = (l - p + a) + (long)(k - q + b) * s->nu;
            double w = s->w ? s->w[idx] : 1.0;
            const double *P = s->cp + 3 * idx;
            double hw[4] = {P[0] * w, P[1] * w, P[2] * w, w};
            for (int kk = 0; kk <= du_n; kk++)
                for (int ll = 0; ll <= dv_n && kk + ll <= d; ll++) {
                    double f = du[kk * (p + 1) + a] * dv[ll * (q + 1) + b];
                    for (int c = 0; c < 4; c++)
                        Aw[kk][ll][c] += f * hw[c];
                }
        }
    }
    static const double bin[3][3] = {{1, 0, 0}, {1, 1, 0}, {1, 2, 1}};
    double S[3][3][3] = {{{0}}};
    for (int kk = 0; kk <= d; kk++)
        for (int ll = 0; ll + kk <= d; ll++) {
            double v3[3] = {Aw[kk][ll][0], Aw[kk][ll][1], Aw[kk][ll][2]};
            for (int j = 1; j <= ll; j++)
                for (int c = 0; c < 3; c++)
                    v3[c] -= bin[ll][j] * Aw[0][j][3] * S[kk][ll - j][c];
            for (int i = 1; i <= kk; i++) {
                for (int c = 0; c < 3; c++)
                    v3[c] -= bin[kk][i] * Aw[i][0][3] * S[kk - i][ll][c];
                double v2[3] = {0, 0, 0};
                for (int j = 1; j <= ll; j++)
                    for (int c = 0; c < 3; c++)
                        v2[c] += bin[ll][j] * Aw[i][j][3] * S[kk - i][ll - j][c];
                for (int c = 0; c < 3; c++)
                    v3[c] -= bin[kk][i] * v2[c];
            }
            for (int c = 0; c < 3; c++)
                S[kk][ll][c] = v3[c] / Aw[0][0][3];
        }
    for (int kk = 0; kk < 3; kk++)
        for (int ll = 0; ll < 3; ll++)
            for (int c = 0; c < 3; c++)
                skl[(kk * 3 + ll) * 3 + c] = (kk + ll <= d) ? S[kk][ll][c] : 0.0;
}
