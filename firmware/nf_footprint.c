/* SPDX-License-Identifier: MIT */
/* nf_footprint.c: occupancy of the parameter domain by the data, and the
 * control points no data determine (issue 14, honest edges). */
#include "nf_footprint.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <string.h>

int nf_footprint_init(nf_footprint_t *fp, const nf_surf_t *s, void *mem, size_t bytes)
{
    if (!fp || !s || !mem || !s->U || !s->V)
        return NF_EARG;
    const long need = nf_footprint_bytes(s->nu, s->nv, s->p, s->q);
    if (need < 0)
        return NF_ESIZE;
    if ((size_t)need > bytes)
        return NF_EARENA;
    memset(mem, 0, (size_t)need);
    fp->s = s;
    fp->cu = NF_FP_SUB * (s->nu - s->p);
    fp->cv = NF_FP_SUB * (s->nv - s->q);
    fp->count = mem;
    fp->pin = (unsigned char *)mem + 4L * fp->cu * fp->cv;
    fp->points = 0;
    fp->hu = (s->nu - s->p) / (s->U[s->nu] - s->U[s->p]);
    fp->hv = (s->nv - s->q) / (s->V[s->nv] - s->V[s->q]);
    return NF_OK;
}

/* Cell index along one direction: the knot span (0-based from the first of
 * the domain) times NF_FP_SUB plus the sub-cell within it; h the spans per
 * unit (the uniform guess first: the binary search was most of the
 * footprint's cost, issue 20). */
static inline int cell_of(const double *K, int n, int p, double x, double h)
{
    const int l = nf_find_span_from(-1, n, p, x, K, h);
#if NF_FP_SUB == 2
    /* The upper half from its midpoint, without a division (2 (x - K_l) is
     * exact); the domain's end stays in the last cell. */
    const int sub = 2.0 * (x - K[l]) >= K[l + 1] - K[l];
#else
    int sub = (int)(NF_FP_SUB * (x - K[l]) / (K[l + 1] - K[l]));
    sub = sub < 0 ? 0 : (sub >= NF_FP_SUB ? NF_FP_SUB - 1 : sub);
#endif
    return (l - p) * NF_FP_SUB + sub;
}

/* Count a point of u (known finite, in the domain) in the cell row that
 * starts at row. */
static inline void mark(nf_footprint_t *fp, double u, long row)
{
    const nf_surf_t *s = fp->s;
    uint32_t *c = fp->count + cell_of(s->U, s->nu - 1, s->p, u, fp->hu) + row;
    *c += *c < UINT32_MAX; /* saturates: a count only needs to say "enough" */
}

static inline long cell_row(const nf_footprint_t *fp, double v)
{
    const nf_surf_t *s = fp->s;
    return (long)cell_of(s->V, s->nv - 1, s->q, v, fp->hv) * fp->cu;
}

int nf_footprint_add(nf_footprint_t *fp, double u, double v)
{
    const nf_surf_t *s = fp->s;
    if (!(u - u == 0.0 && v - v == 0.0))
        return NF_ENONFINITE;
    if (u < s->U[s->p] || u > s->U[s->nu] || v < s->V[s->q] || v > s->V[s->nv])
        return NF_EDOMAIN;
    mark(fp, u, cell_row(fp, v));
    fp->points++;
    return NF_OK;
}

int nf_footprint_merge(nf_footprint_t *a, const nf_footprint_t *b)
{
    if (!a || !b || a->s != b->s || a->cu != b->cu || a->cv != b->cv)
        return NF_EARG;
    const long n = (long)a->cu * a->cv;
    for (long i = 0; i < n; i++) {
        const uint64_t c = (uint64_t)a->count[i] + b->count[i];
        a->count[i] = c > UINT32_MAX ? UINT32_MAX : (uint32_t)c;
    }
    a->points += b->points;
    return NF_OK;
}

long nf_footprint_add_rows(nf_footprint_t *fp, const double *rows, long n, int stride)
{
    const nf_surf_t *s = fp->s;
    const double u0 = s->U[s->p], u1 = s->U[s->nu], v0 = s->V[s->q], v1 = s->V[s->nv];
    long m = 0, row = 0;
    double last = NAN; /* no v yet (v0 - 1 would equal v0 at |v0| >= 2^53) */
    for (long k = 0; k < n; k++, rows += stride) {
        const double u = rows[0], v = rows[1];
        if (!(u >= u0 && u <= u1 && v >= v0 && v <= v1)) /* true for NaN as well */
            continue;
        if (v != last) { /* a scanner's row shares its v: its cell row once */
            last = v;
            row = cell_row(fp, v);
        }
        mark(fp, u, row);
        m++;
    }
    fp->points += m;
    return m;
}

long nf_footprint_cell(const nf_footprint_t *fp, int i, int j)
{
    return (long)fp->count[i + (long)j * fp->cu];
}

void nf_footprint_cell_box(const nf_footprint_t *fp, int i, int j, double box[4])
{
    const nf_surf_t *s = fp->s;
    const int l = s->p + i / NF_FP_SUB, k = s->q + j / NF_FP_SUB;
    const double du = (s->U[l + 1] - s->U[l]) / NF_FP_SUB, dv = (s->V[k + 1] - s->V[k]) / NF_FP_SUB;
    box[0] = s->U[l] + du * (i % NF_FP_SUB);
    box[1] = box[0] + du;
    box[2] = s->V[k] + dv * (j % NF_FP_SUB);
    box[3] = box[2] + dv;
}

/* Cells of an empty knot span (repeated knots) cover nothing. */
static int cell_real(const nf_footprint_t *fp, int i, int j)
{
    const nf_surf_t *s = fp->s;
    const int l = s->p + i / NF_FP_SUB, k = s->q + j / NF_FP_SUB;
    return s->U[l] < s->U[l + 1] && s->V[k] < s->V[k + 1];
}

long nf_footprint_pin(nf_footprint_t *fp, long min_points)
{
    const nf_surf_t *s = fp->s;
    long pinned = 0;
    for (int b = 0; b < s->nv; b++)
        for (int a = 0; a < s->nu; a++) {
            /* Control point (a, b) is non-zero on spans a..a+p x b..b+q
             * (NURBS Book P2.1), those of the domain: p..nu-1, q..nv-1. */
            const int l0 = a > s->p ? a : s->p, l1 = a + s->p < s->nu - 1 ? a + s->p : s->nu - 1;
            const int k0 = b > s->q ? b : s->q, k1 = b + s->q < s->nv - 1 ? b + s->q : s->nv - 1;
            long n = 0;
            for (int j = (k0 - s->q) * NF_FP_SUB; j < (k1 - s->q + 1) * NF_FP_SUB; j++)
                for (int i = (l0 - s->p) * NF_FP_SUB; i < (l1 - s->p + 1) * NF_FP_SUB; i++)
                    n += fp->count[i + (long)j * fp->cu];
            const int pin = n < min_points;
            fp->pin[a + (long)b * s->nu] = (unsigned char)pin;
            pinned += pin;
        }
    return pinned;
}

int nf_footprint_cell_pinned(const nf_footprint_t *fp, int i, int j)
{
    const nf_surf_t *s = fp->s;
    const int l = s->p + i / NF_FP_SUB, k = s->q + j / NF_FP_SUB;
    for (int b = k - s->q; b <= k; b++)
        for (int a = l - s->p; a <= l; a++)
            if (!fp->pin[a + (long)b * s->nu])
                return 0;
    return 1;
}

void nf_footprint_stats(const nf_footprint_t *fp, nf_footprint_stats_t *st)
{
    memset(st, 0, sizeof *st);
    for (int j = 0; j < fp->cv; j++)
        for (int i = 0; i < fp->cu; i++) {
            if (!cell_real(fp, i, j))
                continue;
            st->cells++;
            if (!nf_footprint_cell(fp, i, j)) {
                st->empty++;
                continue;
            }
            st->filled++;
            const int nb[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
            for (int t = 0; t < 4; t++) {
                const int a = nb[t][0], b = nb[t][1];
                if (a >= 0 && a < fp->cu && b >= 0 && b < fp->cv && cell_real(fp, a, b) &&
                    !nf_footprint_cell(fp, a, b)) {
                    st->outline++;
                    break;
                }
            }
        }
    for (long k = 0; k < (long)fp->s->nu * fp->s->nv; k++)
        st->pinned += fp->pin[k];
}
