/* SPDX-License-Identifier: MIT */
/* nf_quad.c: quadrilateral decomposition, maximum-area plane, 2-D grid
 * range search, projection onto quadrilaterals and thinning (Piegl &
 * Tiller 2001, Sections 3.1-3.4), with Newton point inversion after it.
 * Its set-up, start and Newton have a v3 copy (nf_quad_v3.c, nf_isa.h):
 * Newton's derivatives are most of a fitting loop's projections. */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_basis.h"
#include "nf_err.h"
#include "nf_quad.h"
#include "nf_vec3.h"
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* Offsets in a quadrilateral's NF_QUAD_QD doubles. */
enum { QD_C = 0, QD_E1 = 3, QD_E2 = 6, QD_B = 9, QD_BOX = 17 };

/* Smallest parameter interval the decomposition splits, relative to the
 * domain: below it a patch counts as flat (a pole, or a kink the tolerance
 * cannot resolve). 24 halvings per direction bound the stack depth. */
#define MIN_WIDTH (1.0 / 16777216.0)
#define STACK 64

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

/* ---- surface pieces used by the flatness test ---- */

/* Inverse of the Bernstein collocation matrix of degree p at the nodes
 * i / p (Gauss-Jordan; well conditioned up to NF_MAX_DEGREE): the Bezier
 * control points of a polynomial piece from its values at the nodes. */
static void bernstein_inverse(int p, double *inv)
{
    double a[NF_MAX_ORDER][2 * NF_MAX_ORDER];
    const int o = p + 1;
    for (int i = 0; i < o; i++) {
        const double t = (double)i / p;
        for (int k = 0; k < o; k++) {
            double b = 1.0; /* C(p, k) t^k (1 - t)^(p - k) */
            for (int m = 0; m < k; m++)
                b *= (double)(p - m) / (m + 1) * t;
            for (int m = 0; m < p - k; m++)
                b *= 1.0 - t;
            a[i][k] = b;
            a[i][o + k] = i == k;
        }
    }
    for (int c = 0; c < o; c++) {
        int piv = c;
        for (int r = c + 1; r < o; r++)
            if (fabs(a[r][c]) > fabs(a[piv][c]))
                piv = r;
        for (int k = 0; k < 2 * o; k++) {
            const double t = a[c][k];
            a[c][k] = a[piv][k];
            a[piv][k] = t;
        }
        const double d = a[c][c];
        for (int k = 0; k < 2 * o; k++)
            a[c][k] /= d;
        for (int r = 0; r < o; r++)
            if (r != c) {
                const double f = a[r][c];
                for (int k = 0; k < 2 * o; k++)
                    a[r][k] -= f * a[c][k];
            }
    }
    for (int i = 0; i < o; i++)
        for (int k = 0; k < o; k++)
            inv[i * o + k] = a[i][o + k];
}

typedef struct rect {
    double ua, ub, va, vb;
} rect_t;

/* Work of the decomposition: Bernstein inverses for the degrees. */
typedef struct dec {
    const nf_surf_t *s;
    double tol;
    double iu[NF_MAX_ORDER * NF_MAX_ORDER], iv[NF_MAX_ORDER * NF_MAX_ORDER];
} dec_t;

/* Bilinear point of the corners C[4] (00, 10, 01, 11) at (s, t), extended
 * linearly beyond [0, 1]^2. */
static void bilin(const double *C, double s, double t, double *B)
{
    for (int c = 0; c < 3; c++)
        B[c] = (1 - t) * ((1 - s) * C[c] + s * C[3 + c]) + t * ((1 - s) * C[6 + c] + s * C[9 + c]);
}

/* Span of the interval [a, b] of knot vector K: the last l with K[l] < b. */
static int span_end(int n, int p, double b, const double *K)
{
    int l = nf_find_span(n, p, b, K);
    while (l > p && K[l] >= b)
        l--;
    return l;
}

/* One direction of a patch's control net over [a, b]. Inside knot span l
 * (bez): the Bezier coefficients of the piece, T (o x o, o = p + 1)
 * applied to the control points from index l - p (T = Bernstein inverse
 * times the basis at the nodes a + (b - a) i / p), Greville parameters
 * a + (b - a) r / p. Over many spans (!bez): the o control points of s from
 * index first themselves, at their own Greville abscissae. */
typedef struct dir {
    int first, o, bez, p;
    double a, b;
    const double *K;
    double T[NF_MAX_ORDER * NF_MAX_ORDER];
} dir_t;

static void dir_init(dir_t *d, const double *K, int l, int p, double a, double b, const double *inv)
{
    const int o = p + 1;
    d->first = l - p;
    d->o = o;
    d->bez = 1;
    d->p = p;
    d->a = a;
    d->b = b;
    d->K = K;
    double Nn[NF_MAX_ORDER][NF_MAX_ORDER]; /* Nn[i][c]: basis c at node i */
    for (int i = 0; i < o; i++)
        nf_basis_funs(l, a + (b - a) * i / p, p, K, Nn[i]);
    for (int r = 0; r < o; r++)
        for (int c = 0; c < o; c++) {
            double t = 0.0;
            for (int i = 0; i < o; i++)
                t += inv[r * o + i] * Nn[i][c];
            d->T[r * o + c] = t;
        }
}

static void dir_whole(dir_t *d, const double *K, int la, int lb, int p)
{
    d->first = la - p;
    d->o = lb - la + p + 1;
    d->bez = 0;
    d->p = p;
    d->K = K;
}

/* Parameter of coefficient r. */
static double dir_param(const dir_t *d, int r)
{
    return d->bez ? d->a + (d->b - d->a) * r / d->p : nf_greville(d->first + r, d->p, d->K);
}

/* Control point (r, t) of the piece's net. */
static void net_pt(const nf_surf_t *s, const dir_t *du, const dir_t *dv, int r, int t, double *P)
{
    double h[4] = {0, 0, 0, 0};
    const int u0 = du->bez ? 0 : r, u1 = du->bez ? du->o : r + 1;
    const int v0 = dv->bez ? 0 : t, v1 = dv->bez ? dv->o : t + 1;
    for (int c2 = v0; c2 < v1; c2++) {
        const double fv = dv->bez ? dv->T[t * dv->o + c2] : 1.0;
        for (int c1 = u0; c1 < u1; c1++) {
            const double f = fv * (du->bez ? du->T[r * du->o + c1] : 1.0);
            const long i = (du->first + c1) + (long)(dv->first + c2) * s->nu;
            const double w = s->w ? s->w[i] : 1.0;
            h[0] += f * w * s->cp[3 * i];
            h[1] += f * w * s->cp[3 * i + 1];
            h[2] += f * w * s->cp[3 * i + 2];
            h[3] += f * w;
        }
    }
    for (int c = 0; c < 3; c++)
        P[c] = h[c] / h[3];
}

/* Spans a rectangle must cover in a direction for the control points of s
 * to serve as its net there: their Greville abscissae then lie within a
 * few spans of it and the bound stays tight; a narrower rectangle is taken
 * span by span. */
#define WIDE_SPANS 4

/* Direction to split r in (1: v): the larger chord deviation at the
 * midpoints of the sides running that way (curvature and uneven parametric
 * speed alike); on a tie the longer side, as the paper. */
static int split_dir(const nf_surf_t *s, const rect_t *r, const double *C)
{
    const double um = 0.5 * (r->ua + r->ub), vm = 0.5 * (r->va + r->vb);
    double M[4][3], e2u = 0.0, e2v = 0.0;
    nf_surf_eval(s, um, r->va, M[0]);
    nf_surf_eval(s, um, r->vb, M[1]);
    nf_surf_eval(s, r->ua, vm, M[2]);
    nf_surf_eval(s, r->ub, vm, M[3]);
    for (int c = 0; c < 3; c++) {
        const double a0 = M[0][c] - 0.5 * (C[c] + C[3 + c]),
                     a1 = M[1][c] - 0.5 * (C[6 + c] + C[9 + c]);
        const double b0 = M[2][c] - 0.5 * (C[c] + C[6 + c]),
                     b1 = M[3][c] - 0.5 * (C[3 + c] + C[9 + c]);
        e2u += fmax(a0 * a0, a1 * a1);
        e2v += fmax(b0 * b0, b1 * b1);
    }
    if (e2u != e2v)
        return e2v > e2u;
    else {
        double eu[3], ev[3];
        for (int c = 0; c < 3; c++) {
            eu[c] = C[3 + c] - C[c] + C[9 + c] - C[6 + c];
            ev[c] = C[6 + c] - C[c] + C[9 + c] - C[3 + c];
        }
        return nf_dot3(ev, ev) > nf_dot3(eu, eu);
    }
}

/* Flatness test (Section 3.1) of the patch over r, whose corner points are
 * C: the largest distance of the patch's control points from the bilinear
 * quadrilateral of the corners at the control points' Greville parameters.
 * The paper measures the distance from the mid-plane alone; in 3-D it also
 * bounds how far the start parameters are off (a flat patch whose
 * parametrisation bends inside the plane passes the plane test whole). For
 * a polynomial patch it bounds |S - B| everywhere: B has the control points
 * B(Greville) in the same basis, and the basis sums to one. Per direction,
 * a rectangle over WIDE_SPANS knot spans or more takes the control points
 * of s; a narrower one is taken piece by piece (one per knot span it
 * meets), each piece's own Bezier net extracted exactly from its values at
 * the nodes.
 * The scan stops at the first control point beyond the tolerance (then
 * the value returned is only known to exceed it), so that the large
 * rectangles at the top of the subdivision cost little.
 * *dirv: 1 to split in v (on a tie the longer side, as the paper). */
static double flat_dev(const dec_t *d, const rect_t *r, const double *C, int *dirv)
{
    const nf_surf_t *s = d->s;
    const int p = s->p, q = s->q;
    const int la = nf_find_span(s->nu - 1, p, r->ua, s->U),
              lb = span_end(s->nu - 1, p, r->ub, s->U);
    const int ka = nf_find_span(s->nv - 1, q, r->va, s->V),
              kb = span_end(s->nv - 1, q, r->vb, s->V);
    const int wide_u = lb - la + 1 >= WIDE_SPANS, wide_v = kb - ka + 1 >= WIDE_SPANS;
    double dev = 0.0;
    for (int k = ka; k <= (wide_v ? ka : kb); k++) {
        dir_t dv;
        if (wide_v)
            dir_whole(&dv, s->V, ka, kb, q);
        else if (s->V[k] < s->V[k + 1])
            dir_init(&dv, s->V, k, q, fmax(r->va, s->V[k]), fmin(r->vb, s->V[k + 1]), d->iv);
        else
            continue;
        for (int l = la; l <= (wide_u ? la : lb); l++) {
            dir_t du;
            if (wide_u)
                dir_whole(&du, s->U, la, lb, p);
            else if (s->U[l] < s->U[l + 1])
                dir_init(&du, s->U, l, p, fmax(r->ua, s->U[l]), fmin(r->ub, s->U[l + 1]), d->iu);
            else
                continue;
            for (int t = 0; t < dv.o; t++)
                for (int a = 0; a < du.o; a++) {
                    double P[3], B[3];
                    net_pt(s, &du, &dv, a, t, P);
                    bilin(C, (dir_param(&du, a) - r->ua) / (r->ub - r->ua),
                          (dir_param(&dv, t) - r->va) / (r->vb - r->va), B);
                    const double e[3] = {P[0] - B[0], P[1] - B[1], P[2] - B[2]};
                    dev = fmax(dev, sqrt(nf_dot3(e, e)));
                    if (dev > d->tol) /* not flat: the other pieces cannot change that */
                        goto direction;
                }
        }
    }
direction:
    /* Only a rectangle that is split needs the direction (four evaluations). */
    *dirv = dev > d->tol ? split_dir(s, r, C) : 0;
    return dev;
}

static void corners(const nf_surf_t *s, const rect_t *r, double *C)
{
    nf_surf_eval(s, r->ua, r->va, C);
    nf_surf_eval(s, r->ub, r->va, C + 3);
    nf_surf_eval(s, r->ua, r->vb, C + 6);
    nf_surf_eval(s, r->ub, r->vb, C + 9);
}

/* Insert x into the sorted list L of *n values (no duplicate); NF_EBUDGET
 * when the blanket would exceed maxq quadrilaterals. */
static int list_insert(double *L, int *n, int other, long maxq, double x)
{
    int k = *n;
    while (k > 0 && L[k - 1] > x)
        k--;
    if (k > 0 && L[k - 1] == x)
        return NF_OK;
    if ((long)(*n) * (other - 1) > maxq)
        return NF_EBUDGET;
    for (int i = *n; i > k; i--)
        L[i] = L[i - 1];
    L[k] = x;
    (*n)++;
    return NF_OK;
}

/* 1 when r may still be split in direction v (dirv) or u. */
static int splittable(const nf_quad_t *q, const rect_t *r, int dirv)
{
    return dirv ? r->vb - r->va > MIN_WIDTH * (q->dom[3] - q->dom[2])
                : r->ub - r->ua > MIN_WIDTH * (q->dom[1] - q->dom[0]);
}

/* The paper's crack-free scheme: a stack of parameter rectangles, each
 * non-flat one halved (in the direction of its larger curvature) and its
 * midpoint added to the sorted u or v list; the blanket is the tensor grid
 * of the lists, so neighbouring quadrilaterals share every vertex. */
static int decompose(nf_quad_t *q, const dec_t *d)
{
    rect_t st[STACK];
    int top = 0;
    st[top++] = (rect_t){q->dom[0], q->dom[1], q->dom[2], q->dom[3]};
    while (top > 0) {
        const rect_t r = st[--top];
        double C[12];
        int dirv;
        corners(q->s, &r, C);
        if (!(flat_dev(d, &r, C, &dirv) > q->tol))
            continue;
        if (!splittable(q, &r, dirv)) {
            dirv = !dirv;
            if (!splittable(q, &r, dirv))
                continue;
        }
        if (top + 2 > STACK)
            return NF_EBUDGET; /* cannot happen: depth <= 48 (MIN_WIDTH) */
        rect_t a = r, b = r;
        int rc;
        if (dirv) {
            const double m = 0.5 * (r.va + r.vb);
            a.vb = b.va = m;
            rc = list_insert(q->vl, &q->nv, q->nu, q->maxq, m);
        } else {
            const double m = 0.5 * (r.ua + r.ub);
            a.ub = b.ua = m;
            rc = list_insert(q->ul, &q->nu, q->nv, q->maxq, m);
        }
        if (rc)
            return rc;
        st[top++] = b;
        st[top++] = a;
    }
    return NF_OK;
}

/* The blanket's vertices S(ul[i], vl[j]) into q->xyz. */
static void vertices(nf_quad_t *q)
{
    for (int j = 0; j < q->nv; j++)
        for (int i = 0; i < q->nu; i++)
            nf_surf_eval(q->s, q->ul[i], q->vl[j], q->xyz + 3 * (i + (long)j * q->nu));
}

/* The blanket's quadrilaterals are sub-rectangles of flat ones, which
 * bounds their deviation by twice the tolerance only: every one is tested
 * again and the failing ones split (marks in scratch), until all pass.
 * Each pass evaluates the vertices once (not four corners a quadrilateral);
 * on return they are the final blanket's. */
static int verify(nf_quad_t *q, const dec_t *d, double *scratch)
{
    for (int pass = 0; pass < 64; pass++) {
        double *mu = scratch, *mv = scratch + q->nu;
        for (int i = 0; i < q->nu + q->nv; i++)
            scratch[i] = 0.0;
        vertices(q);
        int any = 0;
        for (int j = 0; j + 1 < q->nv; j++)
            for (int i = 0; i + 1 < q->nu; i++) {
                const rect_t r = {q->ul[i], q->ul[i + 1], q->vl[j], q->vl[j + 1]};
                const double *P00 = q->xyz + 3 * (i + (long)j * q->nu), *P01 = P00 + 3L * q->nu;
                double C[12];
                int dirv;
                for (int c = 0; c < 3; c++) {
                    C[c] = P00[c];
                    C[3 + c] = P00[3 + c];
                    C[6 + c] = P01[c];
                    C[9 + c] = P01[3 + c];
                }
                if (!(flat_dev(d, &r, C, &dirv) > q->tol))
                    continue;
                if (!splittable(q, &r, dirv))
                    dirv = !dirv;
                if (!splittable(q, &r, dirv))
                    continue;
                *(dirv ? &mv[j] : &mu[i]) = 1.0;
                any = 1;
            }
        if (!any)
            return NF_OK;
        /* Midpoints collected first (the lists move as they grow). */
        const int nu = q->nu, nv = q->nv;
        double *xu = scratch + nu + nv, *xv = xu + nu;
        int cu = 0, cv = 0;
        for (int i = 0; i + 1 < nu; i++)
            if (mu[i] != 0.0)
                xu[cu++] = 0.5 * (q->ul[i] + q->ul[i + 1]);
        for (int j = 0; j + 1 < nv; j++)
            if (mv[j] != 0.0)
                xv[cv++] = 0.5 * (q->vl[j] + q->vl[j + 1]);
        for (int k = 0; k < cu; k++)
            if (list_insert(q->ul, &q->nu, q->nv, q->maxq, xu[k]))
                return NF_EBUDGET;
        for (int k = 0; k < cv; k++)
            if (list_insert(q->vl, &q->nv, q->nu, q->maxq, xv[k]))
                return NF_EBUDGET;
    }
    vertices(q); /* the last pass split: the lists moved */
    return NF_OK;
}

/* ---- the maximum-area plane and the grid (Section 3.2) ---- */

/* Normal of the maximum-area plane: the dominant eigenvector of
 * sum A_k A_k^T over the quadrilaterals' area vectors A_k (half the cross
 * product of the diagonals), by power iteration; started from the largest
 * column (the paper's (1, 1, 1) can be orthogonal to the answer). */
static void max_area_plane(nf_quad_t *q)
{
    double M[9] = {0};
    for (int j = 0; j + 1 < q->nv; j++)
        for (int i = 0; i + 1 < q->nu; i++) {
            const double *P00 = q->xyz + 3 * (i + (long)j * q->nu), *P10 = P00 + 3,
                         *P01 = P00 + 3L * q->nu, *P11 = P01 + 3;
            double d1[3], d2[3], A[3];
            for (int c = 0; c < 3; c++) {
                d1[c] = P11[c] - P00[c];
                d2[c] = P01[c] - P10[c];
            }
            nf_cross3(d1, d2, A);
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    M[3 * a + b] += 0.25 * A[a] * A[b];
        }
    int col = 0;
    for (int c = 1; c < 3; c++)
        if (M[4 * c] > M[4 * col])
            col = c;
    double n[3] = {M[col], M[3 + col], M[6 + col]};
    if (!(nf_dot3(n, n) > 0.0))
        n[0] = n[1] = n[2] = 1.0; /* no area at all: any plane */
    for (int it = 0; it < 200; it++) {
        double m[3];
        for (int a = 0; a < 3; a++)
            m[a] = M[3 * a] * n[0] + M[3 * a + 1] * n[1] + M[3 * a + 2] * n[2];
        const double l = sqrt(nf_dot3(m, m)), l0 = sqrt(nf_dot3(n, n));
        if (!(l > 0.0))
            break;
        double ch = 0.0;
        for (int a = 0; a < 3; a++) {
            ch += fabs(m[a] / l - n[a] / l0);
            n[a] = m[a] / l;
        }
        if (ch < 1e-13)
            break;
    }
    const double l = sqrt(nf_dot3(n, n));
    for (int c = 0; c < 3; c++)
        q->N[c] = n[c] / l;
    /* Orientation: the summed area vector points along N; any quadrilateral
     * whose own area vector points against it faces away: a fold. */
    double sum = 0.0, tot = 0.0;
    for (int j = 0; j + 1 < q->nv; j++)
        for (int i = 0; i + 1 < q->nu; i++) {
            const double *P00 = q->xyz + 3 * (i + (long)j * q->nu), *P10 = P00 + 3,
                         *P01 = P00 + 3L * q->nu, *P11 = P01 + 3;
            double d1[3], d2[3], A[3];
            for (int c = 0; c < 3; c++) {
                d1[c] = P11[c] - P00[c];
                d2[c] = P01[c] - P10[c];
            }
            nf_cross3(d1, d2, A);
            const double a = nf_dot3(A, q->N);
            sum += a;
            tot += sqrt(nf_dot3(A, A));
        }
    if (sum < 0.0)
        for (int c = 0; c < 3; c++)
            q->N[c] = -q->N[c];
    q->folded = 0;
    for (int j = 0; j + 1 < q->nv && !q->folded; j++)
        for (int i = 0; i + 1 < q->nu; i++) {
            const double *P00 = q->xyz + 3 * (i + (long)j * q->nu), *P10 = P00 + 3,
                         *P01 = P00 + 3L * q->nu, *P11 = P01 + 3;
            double d1[3], d2[3], A[3];
            for (int c = 0; c < 3; c++) {
                d1[c] = P11[c] - P00[c];
                d2[c] = P01[c] - P10[c];
            }
            nf_cross3(d1, d2, A);
            if (nf_dot3(A, q->N) < -1e-9 * tot) {
                q->folded = 1;
                break;
            }
        }
    /* In-plane axes: e1 along the coordinate axis least aligned with N. */
    double t[3] = {0, 0, 0};
    int ax = 0;
    for (int c = 1; c < 3; c++)
        if (fabs(q->N[c]) < fabs(q->N[ax]))
            ax = c;
    t[ax] = 1.0;
    nf_cross3(q->N, t, q->e1);
    const double l1 = sqrt(nf_dot3(q->e1, q->e1));
    for (int c = 0; c < 3; c++)
        q->e1[c] /= l1;
    nf_cross3(q->N, q->e1, q->e2);
}

/* Per quadrilateral: the mid-plane (through the centroid, spanned by the
 * mid-rulings, Section 3.1), axes in it, the planar corners relative to
 * the centroid in the bilinear form b0 + s b1 + t b2 + s t b3, and the box
 * of the corners in the maximum-area plane, widened by the tolerance (the
 * surface lies within it of the quadrilateral). */
static void quad_data(nf_quad_t *q)
{
    for (int j = 0; j + 1 < q->nv; j++)
        for (int i = 0; i + 1 < q->nu; i++) {
            const double *P[4];
            P[0] = q->xyz + 3 * (i + (long)j * q->nu);
            P[1] = P[0] + 3;
            P[2] = P[0] + 3L * q->nu;
            P[3] = P[2] + 3;
            double *D = q->qd + NF_QUAD_QD * (i + (long)j * (q->nu - 1));
            double m1[3], m2[3], n[3];
            for (int c = 0; c < 3; c++) {
                D[QD_C + c] = 0.25 * (P[0][c] + P[1][c] + P[2][c] + P[3][c]);
                m1[c] = 0.5 * (P[1][c] + P[3][c] - P[0][c] - P[2][c]);
                m2[c] = 0.5 * (P[2][c] + P[3][c] - P[0][c] - P[1][c]);
            }
            nf_cross3(m1, m2, n);
            double ln = sqrt(nf_dot3(n, n)), l1 = sqrt(nf_dot3(m1, m1));
            if (!(ln > 1e-300) || !(l1 > 1e-300)) { /* degenerate: use the big plane */
                for (int c = 0; c < 3; c++) {
                    D[QD_E1 + c] = q->e1[c];
                    D[QD_E2 + c] = q->e2[c];
                }
            } else {
                double e2[3];
                for (int c = 0; c < 3; c++) {
                    n[c] /= ln;
                    D[QD_E1 + c] = m1[c] / l1;
                }
                nf_cross3(n, D + QD_E1, e2);
                for (int c = 0; c < 3; c++)
                    D[QD_E2 + c] = e2[c];
            }
            double x[4], y[4];
            for (int k = 0; k < 4; k++) {
                double r[3] = {P[k][0] - D[QD_C], P[k][1] - D[QD_C + 1], P[k][2] - D[QD_C + 2]};
                x[k] = nf_dot3(r, D + QD_E1);
                y[k] = nf_dot3(r, D + QD_E2);
            }
            D[QD_B + 0] = x[0];
            D[QD_B + 1] = y[0];
            D[QD_B + 2] = x[1] - x[0];
            D[QD_B + 3] = y[1] - y[0];
            D[QD_B + 4] = x[2] - x[0];
            D[QD_B + 5] = y[2] - y[0];
            D[QD_B + 6] = x[3] - x[2] - x[1] + x[0];
            D[QD_B + 7] = y[3] - y[2] - y[1] + y[0];
            double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY;
            for (int k = 0; k < 4; k++) {
                const double a = nf_dot3(P[k], q->e1), b = nf_dot3(P[k], q->e2);
                bx0 = fmin(bx0, a);
                bx1 = fmax(bx1, a);
                by0 = fmin(by0, b);
                by1 = fmax(by1, b);
            }
            D[QD_BOX + 0] = bx0 - q->tol;
            D[QD_BOX + 1] = bx1 + q->tol;
            D[QD_BOX + 2] = by0 - q->tol;
            D[QD_BOX + 3] = by1 + q->tol;
        }
}

static int cell_of(double x, double x0, double h, int n)
{
    const double f = floor((x - x0) / h);
    return f < 0 ? 0 : (f >= n ? n - 1 : (int)f);
}

/* The grid: cells of the paper's size sqrt(area / vertices), each holding
 * the quadrilaterals whose box meets it; coarsened until the cells and the
 * references fit the storage bound. */
static int build_grid(nf_quad_t *q, int *cstart, int *citem)
{
    const long nq = nf_quad_count(q);
    double xl = INFINITY, xr = -INFINITY, yb = INFINITY, yt = -INFINITY;
    for (long k = 0; k < nq; k++) {
        const double *B = q->qd + NF_QUAD_QD * k + QD_BOX;
        xl = fmin(xl, B[0]);
        xr = fmax(xr, B[1]);
        yb = fmin(yb, B[2]);
        yt = fmax(yt, B[3]);
    }
    const double xL = fmax(xr - xl, 1e-300), yL = fmax(yt - yb, 1e-300);
    double h = sqrt(xL * yL / (double)((long)q->nu * q->nv));
    h = fmax(h, fmax(xL, yL) / 65536.0);
    const long maxcells = 2 * q->maxq + 2, maxitems = (long)NF_QUAD_ITEMS * q->maxq;
    for (;;) {
        const double gx = floor(xL / h) + 1, gy = floor(yL / h) + 1;
        if (gx * gy <= (double)maxcells) {
            q->gx = (int)gx;
            q->gy = (int)gy;
            long items = 0;
            for (long k = 0; k < nq && items <= maxitems; k++) {
                const double *B = q->qd + NF_QUAD_QD * k + QD_BOX;
                items += (long)(cell_of(B[1], xl, h, q->gx) - cell_of(B[0], xl, h, q->gx) + 1) *
                         (cell_of(B[3], yb, h, q->gy) - cell_of(B[2], yb, h, q->gy) + 1);
            }
            if (items <= maxitems)
                break;
        }
        h *= 1.25;
    }
    q->x0 = xl;
    q->y0 = yb;
    q->cell = h;
    const long cells = (long)q->gx * q->gy;
    for (long c = 0; c <= cells; c++)
        cstart[c] = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (long k = 0; k < nq; k++) {
            const double *B = q->qd + NF_QUAD_QD * k + QD_BOX;
            const int i0 = cell_of(B[0], xl, h, q->gx), i1 = cell_of(B[1], xl, h, q->gx);
            const int j0 = cell_of(B[2], yb, h, q->gy), j1 = cell_of(B[3], yb, h, q->gy);
            for (int j = j0; j <= j1; j++)
                for (int i = i0; i <= i1; i++) {
                    const long c = i + (long)j * q->gx;
                    if (pass == 0)
                        cstart[c + 1]++;
                    else
                        citem[cstart[c]++] = (int)k;
                }
        }
        if (pass == 0)
            for (long c = 0; c < cells; c++)
                cstart[c + 1] += cstart[c];
        else /* the fill advanced every start to the next cell's: shift back */
            for (long c = cells; c > 0; c--)
                cstart[c] = cstart[c - 1];
    }
    cstart[0] = 0;
    q->cstart = cstart;
    q->citem = citem;
    return NF_OK;
}

static int has_crease(const double *K, int n, int p)
{
    for (int i = p + 1; i <= n; i++)
        if (K[i] < K[n + 1] && K[i + p - 1] == K[i] && K[i] > K[p])
            return 1;
    return 0;
}

/* What Newton reads (q->ru, q->rv carved): the reciprocals of every
 * span, the crease and rational flags. */
static void newton_setup(nf_quad_t *q, const nf_surf_t *s)
{
    for (int l = s->p; l < s->nu; l++)
        if (s->U[l] < s->U[l + 1])
            nf_basis_recip(l, s->p, s->U, q->ru + (long)l * NF_RECIP_LEN);
    for (int k = s->q; k < s->nv; k++)
        if (s->V[k] < s->V[k + 1])
            nf_basis_recip(k, s->q, s->V, q->rv + (long)k * NF_RECIP_LEN);
    q->creased = has_crease(s->U, s->nu - 1, s->p) || has_crease(s->V, s->nv - 1, s->q);
    /* Equal weights cancel: the surface is polynomial (the host's surfaces
     * carry weights 1), and Newton skips the quotient rule. */
    q->rational = 0;
    for (long k = 1; s->w && k < (long)s->nu * s->nv; k++)
        q->rational |= s->w[k] != s->w[0];
}

#if NF_ISA_COLD
int nf_quad_newton_init(nf_quad_t *q, const nf_surf_t *s, void *mem, size_t bytes)
{
    if (!q || !s || !mem)
        return NF_EARG;
    if (bytes < NF_QUAD_NEWTON_BYTES(s->nu, s->nv))
        return NF_EARENA;
    memset(q, 0, sizeof *q);
    q->s = s;
    nf_surf_domain(s, &q->dom[0], &q->dom[1], &q->dom[2], &q->dom[3]);
    unsigned char *base = (unsigned char *)mem;
    base += (64 - (uintptr_t)base % 64) % 64;
    q->ru = (double *)(void *)base;
    q->rv = q->ru + (long)(s->nu + 1) * NF_RECIP_LEN;
    newton_setup(q, s);
    return NF_OK;
}

long nf_quad_count(const nf_quad_t *q)
{
    return (long)(q->nu - 1) * (q->nv - 1);
}

#endif

int nf_quad_init(nf_quad_t *q, const nf_surf_t *s, const nf_quad_params_t *prm, long maxq,
                 void *mem, size_t bytes)
{
    if (!q || !s || !prm || !mem || maxq < 1)
        return NF_EARG;
    if (!(prm->rel_tol > 0.0 && prm->rel_tol < 1.0))
        return NF_EARG;
    if (bytes < (size_t)NF_QUAD_BYTES(maxq, s->nu, s->nv))
        return NF_EARENA;
    memset(q, 0, sizeof *q);
    q->s = s;
    q->maxq = maxq;
    nf_surf_domain(s, &q->dom[0], &q->dom[1], &q->dom[2], &q->dom[3]);
    /* Carve the storage: doubles first (aligned), then ints. */
    unsigned char *base = (unsigned char *)mem;
    base += (64 - (uintptr_t)base % 64) % 64;
    double *dm = (double *)(void *)base;
    q->ul = dm;
    q->vl = q->ul + maxq + 2;
    q->xyz = q->vl + maxq + 2;
    q->qd = q->xyz + 3 * (3 * maxq + 2);
    q->ru = q->qd + NF_QUAD_QD * maxq;
    q->rv = q->ru + (long)(s->nu + 1) * NF_RECIP_LEN;
    int *im = (int *)(void *)(base + sizeof(double) * (size_t)NF_QUAD_DOUBLES_(maxq, s->nu, s->nv));
    newton_setup(q, s);
    /* Size of the surface: the diagonal of its control net's box. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (long k = 0; k < (long)s->nu * s->nv; k++)
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], s->cp[3 * k + c]);
            hi[c] = fmax(hi[c], s->cp[3 * k + c]);
        }
    double diag[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    const double size = sqrt(nf_dot3(diag, diag));
    q->tol = prm->rel_tol * size;
    q->limit = prm->limit > 0.0 ? prm->limit : 0.05 * size;
    q->drop_far = prm->drop_far;
    dec_t d;
    d.s = s;
    d.tol = q->tol;
    bernstein_inverse(s->p, d.iu);
    bernstein_inverse(s->q, d.iv);
    q->ul[0] = q->dom[0];
    q->ul[1] = q->dom[1];
    q->vl[0] = q->dom[2];
    q->vl[1] = q->dom[3];
    q->nu = q->nv = 2;
    int rc = decompose(q, &d);
    if (!rc)
        rc = verify(q, &d, q->qd); /* the per-quadrilateral storage is free yet */
    if (rc)
        return rc;
    max_area_plane(q); /* verify left the vertices in q->xyz */
    quad_data(q);
    (void)nf_affine_init(&q->aff, s);
    return build_grid(q, im, im + 2 * maxq + 3);
}

/* ---- projection onto the quadrilaterals (Section 3.4) ---- */

/* Q onto the mid-plane of quadrilateral k, (s, t) by inverting the planar
 * bilinear map there (the quadratic of the two rulings through the point),
 * clamped to [0, 1]^2; returns |Q - B(s, t)|^2 with B the quadrilateral's
 * own (non-planar) bilinear point. */
static double quad_try(const nf_quad_t *q, long k, const double Q[3], double *ps, double *pt)
{
    const double *D = q->qd + NF_QUAD_QD * k;
    const double r[3] = {Q[0] - D[QD_C], Q[1] - D[QD_C + 1], Q[2] - D[QD_C + 2]};
    const double hx = nf_dot3(r, D + QD_E1) - D[QD_B], hy = nf_dot3(r, D + QD_E2) - D[QD_B + 1];
    const double ex = D[QD_B + 2], ey = D[QD_B + 3], fx = D[QD_B + 4], fy = D[QD_B + 5];
    const double gx = D[QD_B + 6], gy = D[QD_B + 7];
    /* h = s e + t f + s t g: k2 t^2 + k1 t + k0 = 0. */
    const double k2 = gx * fy - gy * fx;
    const double k1 = ex * fy - ey * fx + hx * gy - hy * gx;
    const double k0 = hx * ey - hy * ex;
    double ts[2];
    int nt;
    if (fabs(k2) <= 1e-12 * fabs(k1)) {
        ts[0] = -k0 / k1;
        nt = 1;
    } else {
        double disc = k1 * k1 - 4.0 * k0 * k2;
        disc = disc > 0.0 ? sqrt(disc) : 0.0;
        /* The stable pair of roots. */
        const double w = -0.5 * (k1 + (k1 >= 0 ? disc : -disc));
        ts[0] = w / k2;
        ts[1] = w != 0.0 ? k0 / w : ts[0];
        nt = 2;
    }
    double bs = 0.5, bt = 0.5, bv = INFINITY;
    for (int m = 0; m < nt; m++) {
        double t = ts[m];
        if (!(t - t == 0.0))
            t = 0.5;
        const double ax = ex + gx * t, ay = ey + gy * t;
        const double a2 = ax * ax + ay * ay;
        double sv = a2 > 0.0 ? ((hx - fx * t) * ax + (hy - fy * t) * ay) / a2 : 0.5;
        if (!(sv - sv == 0.0))
            sv = 0.5;
        /* How far outside [0, 1]^2 (plain compares: fmax is a libm call). */
        const double vs = sv < 0.0 ? -sv : sv - 1.0, vt = t < 0.0 ? -t : t - 1.0;
        const double viol = vs > vt ? vs : vt;
        if (viol < bv) {
            bv = viol;
            bs = sv;
            bt = t;
        }
    }
    bs = clampd(bs, 0.0, 1.0);
    bt = clampd(bt, 0.0, 1.0);
    const long i = k % (q->nu - 1), j = k / (q->nu - 1);
    const double *P00 = q->xyz + 3 * (i + j * q->nu);
    double B[3];
    for (int c = 0; c < 3; c++)
        B[c] = (1 - bt) * ((1 - bs) * P00[c] + bs * P00[3 + c]) +
               bt * ((1 - bs) * P00[3 * q->nu + c] + bs * P00[3 * q->nu + 3 + c]);
    *ps = bs;
    *pt = bt;
    const double e[3] = {Q[0] - B[0], Q[1] - B[1], Q[2] - B[2]};
    return nf_dot3(e, e);
}

/* The nearest quadrilateral among the references of cells [i0, i1] x
 * [j0, j1] whose box holds (x, y) when inbox, all of them otherwise. */
static void search_cells(const nf_quad_t *q, const double Q[3], double x, double y, int i0, int i1,
                         int j0, int j1, int inbox, double *best, long *bk, double *bs, double *bt)
{
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            const long c = i + (long)j * q->gx;
            for (int m = q->cstart[c]; m < q->cstart[c + 1]; m++) {
                const long k = q->citem[m];
                const double *B = q->qd + NF_QUAD_QD * k + QD_BOX;
                if (inbox && !(x >= B[0] && x <= B[1] && y >= B[2] && y <= B[3]))
                    continue;
                double s, t;
                const double d = quad_try(q, k, Q, &s, &t);
                if (d < *best) {
                    *best = d;
                    *bk = k;
                    *bs = s;
                    *bt = t;
                }
            }
        }
}

void nf_quad_start(const nf_quad_t *q, const double Q[3], double *u0, double *v0)
{
    const double x = nf_dot3(Q, q->e1), y = nf_dot3(Q, q->e2);
    const int ci = cell_of(x, q->x0, q->cell, q->gx), cj = cell_of(y, q->y0, q->cell, q->gy);
    double best = INFINITY, bs = 0.5, bt = 0.5;
    long bk = 0;
    search_cells(q, Q, x, y, ci, ci, cj, cj, 1, &best, &bk, &bs, &bt);
    /* Outside every box (beyond the boundary in the plane, or far off a
     * tilted part): rings of cells around Q's until the nearest found is
     * nearer than the next ring (a quadrilateral first listed r + 1 cells
     * out is at least r cells away in the plane, hence in space). */
    const int rmax = q->gx > q->gy ? q->gx : q->gy;
    if (best == INFINITY) {
        for (int rr = 0; rr <= rmax && !(best < INFINITY && sqrt(best) <= (rr - 1) * q->cell);
             rr++) {
            const int i0 = ci - rr, i1 = ci + rr, j0 = cj - rr, j1 = cj + rr;
            for (int j = j0 < 0 ? 0 : j0; j <= (j1 >= q->gy ? q->gy - 1 : j1); j++) {
                if (j == j0 || j == j1) {
                    search_cells(q, Q, x, y, i0 < 0 ? 0 : i0, i1 >= q->gx ? q->gx - 1 : i1, j, j, 0,
                                 &best, &bk, &bs, &bt);
                } else {
                    if (i0 >= 0)
                        search_cells(q, Q, x, y, i0, i0, j, j, 0, &best, &bk, &bs, &bt);
                    if (i1 < q->gx && i1 != i0)
                        search_cells(q, Q, x, y, i1, i1, j, j, 0, &best, &bk, &bs, &bt);
                }
            }
        }
    }
    /* Walk: a foot on an edge of the quadrilateral may belong to the
     * neighbour across it (a tilted part seen in the plane). */
    const long nqu = q->nu - 1, nqv = q->nv - 1;
    for (int step = 0; step < 64; step++) {
        const long i = bk % nqu, j = bk / nqu;
        long nb[4];
        int n = 0;
        if (bs <= 0.0 && i > 0)
            nb[n++] = bk - 1;
        if (bs >= 1.0 && i + 1 < nqu)
            nb[n++] = bk + 1;
        if (bt <= 0.0 && j > 0)
            nb[n++] = bk - nqu;
        if (bt >= 1.0 && j + 1 < nqv)
            nb[n++] = bk + nqu;
        long next = -1;
        for (int m = 0; m < n; m++) {
            double s, t;
            const double d = quad_try(q, nb[m], Q, &s, &t);
            if (d < best) {
                best = d;
                next = nb[m];
                bs = s;
                bt = t;
            }
        }
        if (next < 0)
            break;
        bk = next;
    }
    const long i = bk % nqu, j = bk / nqu;
    *u0 = q->ul[i] + bs * (q->ul[i + 1] - q->ul[i]);
    *v0 = q->vl[j] + bt * (q->vl[j + 1] - q->vl[j]);
}

/* ---- Newton from the start (NURBS Book 6.1, Eqs. 6.6-6.8) ---- */

/* Inlined into the specialisations below, so that a constant degree
 * unrolls the loops (bicubic, the design degree, is the one that counts). */
#if defined(__GNUC__)
#define QINLINE static inline __attribute__((always_inline))
#define QUNROLL _Pragma("GCC unroll 4")
#else
#define QINLINE static inline
#define QUNROLL
#endif

/* Basis values and first and second derivatives on span l at u, from the
 * degree p-1 and p-2 values (N' of degree p = p (N_{i,p-1} / dU - N_{i+1,p-1}
 * / dU'), applied twice), every knot difference's reciprocal from the
 * span's table (nf_basis_recip): A2.3 without its divisions. */
/* Cox-de Boor from degree j - 1 to j on span l (A2.2's inner step). */
QINLINE void basis_up(double *t, int j, int l, double u, const double *U, const double *rc)
{
    double saved = 0.0;
    QUNROLL
    for (int r = 0; r < j; r++) {
        const double left = u - U[l + 1 - j + r], right = U[l + r + 1] - u;
        const double temp = t[r] * rc[j * (j - 1) / 2 + r];
        t[r] = saved + right * temp;
        saved = left * temp;
    }
    t[j] = saved;
}

QINLINE void ders2(int l, double u, const int p, const double *U, const double *rc,
                   double N[3][NF_MAX_ORDER])
{
    double t[NF_MAX_ORDER], t1[NF_MAX_ORDER] = {0}, t2[NF_MAX_ORDER] = {0};
    t[0] = 1.0;
    QUNROLL
    for (int j = 1; j <= p - 2; j++)
        basis_up(t, j, l, u, U, rc);
    QUNROLL
    for (int r = 0; r <= p - 2; r++) /* degree p - 2 */
        t2[r] = t[r];
    if (p >= 2)
        basis_up(t, p - 1, l, u, U, rc);
    QUNROLL
    for (int r = 0; r < p; r++) /* degree p - 1 */
        t1[r] = t[r];
    basis_up(t, p, l, u, U, rc);
    QUNROLL
    for (int a = 0; a <= p; a++)
        N[0][a] = t[a];
    /* D1[r] = N_{l-p+1+r, p-1} / (U[l+r+1] - U[l-p+r+1]), r = 0..p-1 */
    double D1[NF_MAX_ORDER + 1] = {0}, C1[NF_MAX_ORDER + 1] = {0}, D2[NF_MAX_ORDER + 1] = {0};
    QUNROLL
    for (int r = 0; r < p; r++)
        D1[r] = t1[r] * rc[p * (p - 1) / 2 + r]; /* 1 / (U[l+r+1] - U[l-p+r+1]) */
    QUNROLL
    for (int a = 0; a <= p; a++)
        N[1][a] = p * ((a >= 1 ? D1[a - 1] : 0.0) - (a < p ? D1[a] : 0.0));
    if (p < 2) {
        QUNROLL
        for (int a = 0; a <= p; a++)
            N[2][a] = 0.0;
        return;
    }
    /* N'_{l-p+1+r, p-1} = (p-1) (D2[r-1] - D2[r]), D2[r] = N_{l-p+2+r, p-2} /
     * (U[l+r+1] - U[l-p+2+r]), r = 0..p-2. */
    QUNROLL
    for (int r = 0; r <= p - 2; r++)
        D2[r] = t2[r] * rc[(p - 1) * (p - 2) / 2 + r]; /* 1 / (U[l+r+1] - U[l-p+2+r]) */
    QUNROLL
    for (int r = 0; r < p; r++)
        C1[r] = (p - 1) * ((r >= 1 ? D2[r - 1] : 0.0) - (r <= p - 2 ? D2[r] : 0.0)) *
                rc[p * (p - 1) / 2 + r];
    QUNROLL
    for (int a = 0; a <= p; a++)
        N[2][a] = p * ((a >= 1 ? C1[a - 1] : 0.0) - (a < p ? C1[a] : 0.0));
}

/* S, Su, Sv, Suu, Suv, Svv on spans (l, k) (quotient rule on the
 * homogeneous derivatives for a rational surface, A4.4 to order 2). */
QINLINE void derivs_pq(const nf_quad_t *qd, int l, int k, double u, double v, const int p,
                       const int q, double d[6][3])
{
    const nf_surf_t *s = qd->s;
    double Nu[3][NF_MAX_ORDER], Nv[3][NF_MAX_ORDER];
    ders2(l, u, p, s->U, qd->ru + (long)l * NF_RECIP_LEN, Nu);
    ders2(k, v, q, s->V, qd->rv + (long)k * NF_RECIP_LEN, Nv);
    if (!qd->rational) {
        /* Polynomial: rows contracted with the u basis, then v; one
         * coordinate at a time, so that the sums stay in registers (all
         * three at once spilled them: a third of Newton's time). */
        for (int c = 0; c < 3; c++) {
            double S0 = 0.0, S1 = 0.0, S2 = 0.0, S3 = 0.0, S4 = 0.0, S5 = 0.0;
            QUNROLL
            for (int b = 0; b <= q; b++) {
                const double *P = s->cp + 3 * ((l - p) + (long)(k - q + b) * s->nu) + c;
                double r0 = 0.0, r1 = 0.0, r2 = 0.0;
                QUNROLL
                for (int a = 0; a <= p; a++) {
                    r0 += Nu[0][a] * P[3 * a];
                    r1 += Nu[1][a] * P[3 * a];
                    r2 += Nu[2][a] * P[3 * a];
                }
                S0 += Nv[0][b] * r0;
                S1 += Nv[0][b] * r1;
                S2 += Nv[1][b] * r0;
                S3 += Nv[0][b] * r2;
                S4 += Nv[1][b] * r1;
                S5 += Nv[2][b] * r0;
            }
            d[0][c] = S0;
            d[1][c] = S1;
            d[2][c] = S2;
            d[3][c] = S3;
            d[4][c] = S4;
            d[5][c] = S5;
        }
        return;
    }
    double A[6][4] = {{0}};
    QUNROLL
    for (int b = 0; b <= q; b++) {
        const long row = (l - p) + (long)(k - q + b) * s->nu;
        const double *P = s->cp + 3 * row, *w = s->w + row;
        double r[3][4] = {{0}};
        QUNROLL
        for (int a = 0; a <= p; a++) {
            const double h[4] = {P[3 * a] * w[a], P[3 * a + 1] * w[a], P[3 * a + 2] * w[a], w[a]};
            QUNROLL
            for (int m = 0; m < 3; m++)
                QUNROLL
            for (int c = 0; c < 4; c++)
                r[m][c] += Nu[m][a] * h[c];
        }
        QUNROLL
        for (int c = 0; c < 4; c++) {
            A[0][c] += Nv[0][b] * r[0][c];
            A[1][c] += Nv[0][b] * r[1][c]; /* u */
            A[2][c] += Nv[1][b] * r[0][c]; /* v */
            A[3][c] += Nv[0][b] * r[2][c]; /* uu */
            A[4][c] += Nv[1][b] * r[1][c]; /* uv */
            A[5][c] += Nv[2][b] * r[0][c]; /* vv */
        }
    }
    const double iw = 1.0 / A[0][3];
    QUNROLL
    for (int c = 0; c < 3; c++) {
        const double S = A[0][c] * iw;
        const double Su = (A[1][c] - A[1][3] * S) * iw, Sv = (A[2][c] - A[2][3] * S) * iw;
        d[0][c] = S;
        d[1][c] = Su;
        d[2][c] = Sv;
        d[3][c] = (A[3][c] - 2 * A[1][3] * Su - A[3][3] * S) * iw;
        d[4][c] = (A[4][c] - A[1][3] * Sv - A[2][3] * Su - A[4][3] * S) * iw;
        d[5][c] = (A[5][c] - 2 * A[2][3] * Sv - A[5][3] * S) * iw;
    }
}

#if NF_ISA_COLD
/* Taylor coefficients of the four cubic basis functions of span l at its
 * left knot: B[a][m] = N_{l-3+a}^(m)(U[l]) / m!. */
static void power_basis(int l, const double *U, double B[4][4])
{
    double d[4 * 4];
    nf_ders_basis_funs(l, U[l], 3, 3, U, d);
    static const double fact[4] = {1.0, 1.0, 2.0, 6.0};
    for (int a = 0; a < 4; a++)
        for (int m = 0; m < 4; m++)
            B[a][m] = d[m * 4 + a] / fact[m];
}

int nf_quad_power(nf_quad_t *q, double *pf, size_t bytes)
{
    if (!q || !q->s || !pf)
        return NF_EARG;
    const nf_surf_t *s = q->s;
    q->pf = NULL;
    if (s->p != 3 || s->q != 3 || q->rational)
        return NF_OK;
    if (bytes < NF_QUAD_POWER_BYTES(s->nu, s->nv))
        return NF_EARENA;
    const long su = s->nu - 3;
    for (int k = 3; k < s->nv; k++) {
        double Bv[4][4];
        if (s->V[k] < s->V[k + 1])
            power_basis(k, s->V, Bv);
        for (int l = 3; l < s->nu; l++) {
            double *C = pf + NF_QUAD_POWER_SPAN * ((l - 3) + (long)(k - 3) * su);
            for (int t = 0; t < NF_QUAD_POWER_SPAN; t++)
                C[t] = 0.0;
            if (!(s->U[l] < s->U[l + 1] && s->V[k] < s->V[k + 1]))
                continue;                          /* empty: Newton's spans are never empty */
            double Bu[4][4], R[4][4][3] = {{{0}}}; /* R[b][m]: row b in powers of s */
            power_basis(l, s->U, Bu);
            for (int b = 0; b < 4; b++)
                for (int a = 0; a < 4; a++) {
                    const double *P = s->cp + 3 * ((l - 3 + a) + (long)(k - 3 + b) * s->nu);
                    for (int m = 0; m < 4; m++)
                        for (int c = 0; c < 3; c++)
                            R[b][m][c] += Bu[a][m] * P[c];
                }
            for (int n = 0; n < 4; n++)
                for (int m = 0; m < 4; m++)
                    for (int c = 0; c < 3; c++) {
                        double t = 0.0;
                        for (int b = 0; b < 4; b++)
                            t += Bv[b][n] * R[b][m][c];
                        C[16 * n + 4 * m + c] = t;
                    }
        }
    }
    q->pf = pf;
    return NF_OK;
}
#endif

/* S and its derivatives to order 2 from span (l, k)'s power form: Horner in
 * s = u - U[l] per power of t, then in t = v - V[k]; x, y, z (and a zero)
 * side by side, which the v3 copy does four at a time. */
QINLINE void derivs_power(const nf_quad_t *qd, int l, int k, double u, double v, double d[6][3])
{
    const nf_surf_t *s = qd->s;
    const double *C = qd->pf + NF_QUAD_POWER_SPAN * ((l - 3) + (long)(k - 3) * (s->nu - 3));
    const double x = u - s->U[l], y = v - s->V[k];
    double r0[4][4], r1[4][4], r2[4][4];
    for (int n = 0; n < 4; n++) {
        const double *Cn = C + 16 * n;
        for (int c = 0; c < 4; c++) {
            const double c0 = Cn[c], c1 = Cn[4 + c], c2 = Cn[8 + c], c3 = Cn[12 + c];
            r0[n][c] = ((c3 * x + c2) * x + c1) * x + c0;
            r1[n][c] = (3.0 * c3 * x + 2.0 * c2) * x + c1;
            r2[n][c] = 6.0 * c3 * x + 2.0 * c2;
        }
    }
    double o[6][4];
    for (int c = 0; c < 4; c++) {
        o[0][c] = ((r0[3][c] * y + r0[2][c]) * y + r0[1][c]) * y + r0[0][c];
        o[1][c] = ((r1[3][c] * y + r1[2][c]) * y + r1[1][c]) * y + r1[0][c];
        o[2][c] = (3.0 * r0[3][c] * y + 2.0 * r0[2][c]) * y + r0[1][c];
        o[3][c] = ((r2[3][c] * y + r2[2][c]) * y + r2[1][c]) * y + r2[0][c];
        o[4][c] = (3.0 * r1[3][c] * y + 2.0 * r1[2][c]) * y + r1[1][c];
        o[5][c] = 6.0 * r0[3][c] * y + 2.0 * r0[2][c];
    }
    for (int e = 0; e < 6; e++)
        for (int c = 0; c < 3; c++)
            d[e][c] = o[e][c];
}

/* Span of x, trying the previous one first (Newton's iterates rarely
 * leave it), then the uniform guess (a new point's first step). */
static int span_hint(int n, int p, double x, const double *K, int *hint)
{
    const int h = *hint;
    if (h >= p && h <= n && K[h] <= x && (x < K[h + 1] || (h == n && x <= K[h + 1])))
        return h;
    if (!(x >= K[p] && x <= K[n + 1]))
        return *hint = nf_find_span(n, p, x, K); /* its clamping, as before */
    return *hint = nf_find_span_from(-1, n, p, x, K, (double)(n - p + 1) / (K[n + 1] - K[p]));
}

static void derivs(const nf_quad_t *qd, double u, double v, int *hl, int *hk, double d[6][3])
{
    const nf_surf_t *s = qd->s;
    const int l = span_hint(s->nu - 1, s->p, u, s->U, hl);
    const int k = span_hint(s->nv - 1, s->q, v, s->V, hk);
    if (qd->pf)
        derivs_power(qd, l, k, u, v, d);
    else if (s->p == 3 && s->q == 3)
        derivs_pq(qd, l, k, u, v, 3, 3, d);
    else
        derivs_pq(qd, l, k, u, v, s->p, s->q, d);
}

/* Plain Newton for an interior foot: accepted when a full step below the
 * tolerance is reached with the distance never rising beyond rounding and
 * every iterate strictly inside the domain. 0 when it gave up (a bound, a
 * Jacobian that is not positive definite, no progress): *u, *v then hold
 * the nearest iterate, for nf_project to finish from. */
static int newton_fast(const nf_quad_t *q, const double Q[3], double tol, double *u, double *v,
                       nf_proj_t *out)
{
    const double tu = tol * (q->dom[1] - q->dom[0]), tv = tol * (q->dom[3] - q->dom[2]);
    double cu = *u, cv = *v, best = INFINITY;
    int hl = -1, hk = -1;
    for (int it = 0; it < 12; it++) {
        double d[6][3];
        derivs(q, cu, cv, &hl, &hk, d);
        const double r[3] = {d[0][0] - Q[0], d[0][1] - Q[1], d[0][2] - Q[2]};
        const double D = nf_dot3(r, r);
        const double a0 = fabs(Q[0]), a1 = fabs(Q[1]), a2 = fabs(Q[2]);
        const double scale = (a0 > a1 ? (a0 > a2 ? a0 : a2) : (a1 > a2 ? a1 : a2)) + sqrt(D);
        if (D > best + 64.0 * DBL_EPSILON * scale * scale)
            return 0;
        if (D < best) {
            best = D;
            *u = cu;
            *v = cv;
        }
        const double gu = nf_dot3(r, d[1]), gv = nf_dot3(r, d[2]);
        const double a = nf_dot3(d[1], d[1]) + nf_dot3(r, d[3]);
        const double b = nf_dot3(d[1], d[2]) + nf_dot3(r, d[4]);
        const double c = nf_dot3(d[2], d[2]) + nf_dot3(r, d[5]);
        const double det = a * c - b * b;
        if (!(a > 0.0 && c > 0.0 && det > 1e-12 * a * c))
            return 0;
        const double du = (-gu * c + gv * b) / det, dv = (gu * b - gv * a) / det;
        const double nu = cu + du, nv = cv + dv;
        if (!(nu > q->dom[0] && nu < q->dom[1] && nv > q->dom[2] && nv < q->dom[3]))
            return 0;
        if (fabs(du) <= tu && fabs(dv) <= tv) {
            /* Newton's last step: its end is the foot to second order in
             * the step, so the point there is taken from the Taylor
             * expansion to second order (its error of the step's third
             * order) instead of a further evaluation. */
            out->u = nu;
            out->v = nv;
            for (int m = 0; m < 3; m++)
                out->foot[m] = d[0][m] + d[1][m] * du + d[2][m] * dv +
                               0.5 * (d[3][m] * du * du + d[5][m] * dv * dv) + d[4][m] * du * dv;
            const double e[3] = {Q[0] - out->foot[0], Q[1] - out->foot[1], Q[2] - out->foot[2]};
            double n[3];
            nf_cross3(d[1], d[2], n);
            const double dist = sqrt(nf_dot3(e, e));
            out->dist = nf_dot3(e, n) < 0.0 ? -dist : dist;
            out->clamped = 0;
            out->iters = it + 1;
            return 1;
        }
        cu = nu;
        cv = nv;
    }
    return 0;
}

int nf_quad_newton(const nf_quad_t *q, const double Q[3], double tol, double *u, double *v,
                   nf_proj_t *out)
{
    return !q->creased && newton_fast(q, Q, tol, u, v, out);
}

int nf_quad_project(nf_quad_t *q, const double Q[3], double tol, nf_proj_t *out)
{
    if (!q || !Q || !out)
        return NF_EARG;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    if (!(tol > 0.0 && tol < 1.0))
        return NF_EARG;
    int rc = NF_OK;
    double u0, v0;
    if (q->aff.ok)
        (void)nf_affine_project(&q->aff, Q, out); /* Q is finite: NF_OK */
    else
        nf_quad_start(q, Q, &u0, &v0);
    if (!q->aff.ok && (q->creased || !newton_fast(q, Q, tol, &u0, &v0, out))) {
        q->n_slow++;
        rc = nf_project(q->s, Q, u0, v0, tol, out);
        if (rc != NF_OK && rc != NF_ENOCONV)
            return rc;
    }
    q->n_clamped += out->clamped != 0;
    if (fabs(out->dist) > q->limit) {
        q->n_far++;
        if (q->drop_far)
            return NF_QUAD_DROPPED;
    }
    return rc;
}

#if NF_ISA_COLD
/* ---- thinning (Section 3.3) ---- */

long nf_thin_verts(const nf_thin_t *t)
{
    return (long)t->q->nu * t->q->nv;
}

int nf_thin_init(nf_thin_t *t, const nf_quad_t *q, double r, double *best, long *idx)
{
    if (!t || !q || !best || !idx || !(r > 0.0) || !(r < INFINITY))
        return NF_EARG;
    t->q = q;
    t->r = r;
    t->best = best;
    t->idx = idx;
    for (long k = 0; k < nf_thin_verts(t); k++) {
        best[4 * k] = INFINITY;
        best[4 * k + 1] = best[4 * k + 2] = best[4 * k + 3] = 0.0;
        idx[k] = -1;
    }
    return NF_OK;
}

/* The vertices within r of P are corners of quadrilaterals whose boxes
 * (in the maximum-area plane) meet the square of half-side r around P's
 * image there: the cells covering that square list them all. */
int nf_thin_add(nf_thin_t *t, const double P[3], long k)
{
    if (!(P[0] - P[0] == 0.0 && P[1] - P[1] == 0.0 && P[2] - P[2] == 0.0))
        return NF_ENONFINITE;
    const nf_quad_t *q = t->q;
    const double x = nf_dot3(P, q->e1), y = nf_dot3(P, q->e2), r = t->r, r2 = r * r;
    if (x + r < q->x0 || y + r < q->y0 || x - r > q->x0 + q->gx * q->cell ||
        y - r > q->y0 + q->gy * q->cell)
        return NF_OK;
    const int i0 = cell_of(x - r, q->x0, q->cell, q->gx),
              i1 = cell_of(x + r, q->x0, q->cell, q->gx);
    const int j0 = cell_of(y - r, q->y0, q->cell, q->gy),
              j1 = cell_of(y + r, q->y0, q->cell, q->gy);
    const long nqu = q->nu - 1;
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            const long c = i + (long)j * q->gx;
            for (int m = q->cstart[c]; m < q->cstart[c + 1]; m++) {
                const long qk = q->citem[m];
                const double *B = q->qd + NF_QUAD_QD * qk + QD_BOX;
                if (x + r < B[0] || x - r > B[1] || y + r < B[2] || y - r > B[3])
                    continue;
                const long vi = qk % nqu, vj = qk / nqu;
                const long vk[4] = {vi + vj * q->nu, vi + 1 + vj * q->nu, vi + (vj + 1) * q->nu,
                                    vi + 1 + (vj + 1) * q->nu};
                for (int m2 = 0; m2 < 4; m2++) {
                    const double *V = q->xyz + 3 * vk[m2];
                    const double e[3] = {P[0] - V[0], P[1] - V[1], P[2] - V[2]};
                    const double d = nf_dot3(e, e);
                    double *b = t->best + 4 * vk[m2];
                    if (d <= r2 && (d < b[0] || (d == b[0] && k < t->idx[vk[m2]]))) {
                        b[0] = d;
                        b[1] = P[0];
                        b[2] = P[1];
                        b[3] = P[2];
                        t->idx[vk[m2]] = k;
                    }
                }
            }
        }
    return NF_OK;
}
#endif
