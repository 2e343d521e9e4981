/* SPDX-License-Identifier: MIT */
/* nf_refine.c: knot insertion on NURBS surfaces (The NURBS Book, Sections
 * 5.2-5.3: A5.1/A5.3 for one knot inserted r times, A5.4/A5.5 for many
 * knots), on homogeneous control points so that weights are exact.
 *
 * Both algorithms run in place in out's storage: the input net is first
 * copied (as homogeneous points) into the low-index corner of out, then each
 * row (u) or column (v) is refined where it lies. That is safe because both
 * algorithms, with their copy loops run downwards, read an input point only
 * below every index they have written (Q[k-p-1] = P[i-p-1] with k > i in
 * A5.4; A5.1 reads all of P[k-p..k-s] into Rw first). Uniform refinement
 * uses it to refine u then v in one output array without scratch memory. */
#include "nf_refine.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <stddef.h>

/* One curve of the net inside out's storage: point m is at index
 * off + m * stride of cp (3 doubles, holding w x, w y, w z during the work)
 * and of w (NULL for a polynomial surface: w stays 1 and is not stored). */
typedef struct curve {
    double *cp, *w;
    long off, stride;
} curve_t;

static void hget(const curve_t *c, int m, double h[4])
{
    const long i = c->off + (long)m * c->stride;
    h[0] = c->cp[3 * i];
    h[1] = c->cp[3 * i + 1];
    h[2] = c->cp[3 * i + 2];
    h[3] = c->w ? c->w[i] : 1.0;
}

static void hput(const curve_t *c, int m, const double h[4])
{
    const long i = c->off + (long)m * c->stride;
    c->cp[3 * i] = h[0];
    c->cp[3 * i + 1] = h[1];
    c->cp[3 * i + 2] = h[2];
    if (c->w)
        c->w[i] = h[3];
}

static void hmove(const curve_t *c, int to, int from)
{
    double h[4];
    hget(c, from, h);
    hput(c, to, h);
}

/* The knots to insert: an array, or (X NULL) the midpoints of the non-empty
 * spans of U in order. A5.4 asks for them downwards, so the midpoint source
 * keeps the span of the last index asked and steps down from it: O(1) per
 * knot, O(n) only for a jump (the first two requests). */
typedef struct ksrc {
    const double *X;
    const double *U;
    int p;
    int cj, cs; /* knot cj is the midpoint of span cs; cj = -2: none yet */
} ksrc_t;

static void ksrc_init(ksrc_t *k, const double *X, const double *U, int p)
{
    k->X = X;
    k->U = U;
    k->p = p;
    k->cj = -2;
    k->cs = p;
}

static double kget(ksrc_t *k, int j)
{
    if (k->X)
        return k->X[j];
    const double *U = k->U;
    if (j != k->cj) {
        int s;
        if (j == k->cj - 1) {
            s = k->cs - 1;
            while (!(U[s] < U[s + 1]))
                s--;
        } else {
            s = k->p - 1;
            for (int c = -1; c < j;) {
                s++;
                c += U[s] < U[s + 1];
            }
        }
        k->cj = j;
        k->cs = s;
    }
    return 0.5 * U[k->cs] + 0.5 * U[k->cs + 1];
}

static int count_spans(int n, int p, const double *U)
{
    int c = 0;
    for (int i = p; i <= n; i++)
        c += U[i] < U[i + 1];
    return c;
}

/* Multiplicity of the interior value x in U (n+1 control points). */
static int mult(int n, int p, const double *U, double x)
{
    int k = nf_find_span(n, p, x, U), s = 0;
    while (k - s >= 0 && U[k - s] == x)
        s++;
    return s;
}

/* The r knots of src: finite, non-decreasing, strictly inside the domain
 * (a knot at an end would make it more than p+1 fold: no longer clamped),
 * and every value at most p-fold after insertion (Eq. 5.13 needs the
 * inserted knot's multiplicity s + r <= p; beyond p the curve would break). */
static int check_new_knots(int n, int p, const double *U, ksrc_t *src, int r)
{
    double prev = 0.0;
    int run = 0;
    for (int j = r - 1; j >= 0; j--) {
        double x = kget(src, j);
        if (!(U[p] < x && x < U[n + 1]))
            return NF_EKNOTS;
        if (j < r - 1 && x > prev)
            return NF_EKNOTS;
        run = (j < r - 1 && x == prev) ? run + 1 : 1;
        if (run + mult(n, p, U, x) > p)
            return NF_EKNOTS;
        prev = x;
    }
    return NF_OK;
}

/* Ubar: U and the r new knots merged (the knot vector A5.4 builds as it
 * goes; built first here, since A5.4 only reads Ubar[k+l] above the index k
 * it is writing, which already hold their final values). */
static void merge_knots(int n, int p, const double *U, ksrc_t *src, int r, double *Ubar)
{
    int i = n + p + 1, j = r - 1;
    for (int k = n + p + 1 + r; k >= 0; k--) {
        if (j >= 0 && (i < 0 || kget(src, j) > U[i]))
            Ubar[k] = kget(src, j--);
        else
            Ubar[k] = U[i--];
    }
}

/* A5.4 RefineKnotVectCurve on one curve in place: points 0..n of c become
 * 0..n+r, knots U become Ubar (r = number of knots, the book's r + 1). */
static void refine_curve(const curve_t *c, int n, int p, const double *U, const double *Ubar,
                         ksrc_t *src, int r)
{
    const int last = r - 1;
    const int a = nf_find_span(n, p, kget(src, 0), U);
    const int b = nf_find_span(n, p, kget(src, last), U) + 1;
    for (int j = n; j >= b - 1; j--) /* downwards: the target is above the source */
        hmove(c, j + r, j);
    /* Points 0..a-p keep their places. */
    int i = b + p - 1, k = b + p + last;
    for (int j = last; j >= 0; j--) {
        const double x = kget(src, j);
        while (x <= U[i] && i > a) {
            hmove(c, k - p - 1, i - p - 1);
            k--;
            i--;
        }
        hmove(c, k - p - 1, k - p);
        for (int l = 1; l <= p; l++) {
            const int ind = k - p + l;
            double alfa = Ubar[k + l] - x;
            if (alfa == 0.0) {
                hmove(c, ind - 1, ind);
            } else {
                double q0[4], q1[4];
                alfa /= Ubar[k + l] - U[i - p + l];
                hget(c, ind - 1, q0);
                hget(c, ind, q1);
                for (int t = 0; t < 4; t++)
                    q0[t] = alfa * q0[t] + (1.0 - alfa) * q1[t];
                hput(c, ind - 1, q0);
            }
        }
        k--;
    }
}

/* A5.1 CurveKnotIns on one curve in place: x (in span k, multiplicity s)
 * inserted r times, r + s <= p; points 0..n become 0..n+r. */
static void insert_curve(const curve_t *c, int n, int p, const double *U, double x, int k, int s,
                         int r)
{
    double Rw[NF_MAX_ORDER][4];
    for (int i = 0; i <= p - s; i++)
        hget(c, k - p + i, Rw[i]);
    for (int i = n; i >= k - s; i--)
        hmove(c, i + r, i);
    int L = k - p;
    for (int j = 1; j <= r; j++) {
        L = k - p + j;
        for (int i = 0; i <= p - j - s; i++) {
            const double alpha = (x - U[L + i]) / (U[i + k + 1] - U[L + i]);
            for (int t = 0; t < 4; t++)
                Rw[i][t] = alpha * Rw[i + 1][t] + (1.0 - alpha) * Rw[i][t];
        }
        hput(c, L, Rw[0]);
        hput(c, k + r - j - s, Rw[p - j - s]);
    }
    for (int i = L + 1; i < k - s; i++)
        hput(c, i, Rw[i - L]);
}

int nf_refine_size(const nf_surf_t *in, int ru, int rv, int *nu, int *nv)
{
    if (!in || !nu || !nv || ru < 0 || rv < 0)
        return NF_EARG;
    if (in->nu < 1 || in->nv < 1)
        return NF_ESIZE;
    /* In long, whose 32 bits on the cross boards hold NF_MAX_CP and every
     * sum below it; the product is compared by division. */
    if (ru > NF_MAX_CP - in->nu || rv > NF_MAX_CP - in->nv)
        return NF_EBUDGET;
    const int mu = in->nu + ru, mv = in->nv + rv;
    if (mu > NF_MAX_CP / mv)
        return NF_EBUDGET;
    *nu = mu;
    *nv = mv;
    return NF_OK;
}

void nf_refine_spans(const nf_surf_t *in, int *su, int *sv)
{
    *su = count_spans(in->nu - 1, in->p, in->U);
    *sv = count_spans(in->nv - 1, in->q, in->V);
}

int nf_refine_uniform_size(const nf_surf_t *in, int *nu, int *nv)
{
    int rc = nf_surf_check(in);
    if (rc)
        return rc;
    int su, sv;
    nf_refine_spans(in, &su, &sv);
    return nf_refine_size(in, su, sv, nu, nv);
}

/* Checks shared by every entry point: in valid, the new net within budget,
 * out wired to it. */
static int check_io(const nf_surf_t *in, int ru, int rv, const nf_surf_t *out)
{
    int rc = nf_surf_check(in);
    if (rc)
        return rc;
    int nu, nv;
    if ((rc = nf_refine_size(in, ru, rv, &nu, &nv)) != NF_OK)
        return rc;
    if (!out || !out->U || !out->V || !out->cp || (in->w && !out->w))
        return NF_EARG;
    if (out->p != in->p || out->q != in->q || out->nu != nu || out->nv != nv)
        return NF_EARG;
    return NF_OK;
}

/* in's net, as homogeneous points, into the first in->nu columns and
 * in->nv rows of out (row length out->nu); knots the caller sets. */
static void copy_net(const nf_surf_t *in, nf_surf_t *out)
{
    for (int j = 0; j < in->nv; j++)
        for (int i = 0; i < in->nu; i++) {
            const long s = i + (long)j * in->nu, d = i + (long)j * out->nu;
            const double w = in->w ? in->w[s] : 1.0;
            for (int t = 0; t < 3; t++)
                out->cp[3 * d + t] = in->cp[3 * s + t] * w;
            if (out->w)
                out->w[d] = w;
        }
}

/* Back from homogeneous points: divide by the weights. */
static void finish_net(const nf_surf_t *in, nf_surf_t *out)
{
    const long n = (long)out->nu * out->nv;
    if (!in->w) { /* polynomial: cp never scaled; weights 1 (out's storage may be reused) */
        for (long i = 0; out->w && i < n; i++)
            out->w[i] = 1.0;
        return;
    }
    for (long i = 0; i < n; i++) {
        const double inv = 1.0 / out->w[i];
        for (int t = 0; t < 3; t++)
            out->cp[3 * i + t] *= inv;
    }
}

static void copy_knots(const double *src, int len, double *dst)
{
    for (int i = 0; i < len; i++)
        dst[i] = src[i];
}

/* Curve j of direction dir (0: row j, refined in u; 1: column j, in v). */
static curve_t curve_of(const nf_surf_t *in, nf_surf_t *out, int dir, int j)
{
    curve_t c;
    c.cp = out->cp;
    c.w = in->w ? out->w : NULL;
    c.off = dir == 0 ? (long)j * out->nu : j;
    c.stride = dir == 0 ? 1 : out->nu;
    return c;
}

/* A5.5 in one direction: the r knots of src into every row (dir 0) or
 * column (dir 1) of out, which already holds in's net in its corner. */
static void refine_dir(const nf_surf_t *in, nf_surf_t *out, int dir, ksrc_t *src, int r)
{
    const int n = dir == 0 ? in->nu - 1 : in->nv - 1, p = dir == 0 ? in->p : in->q;
    const double *K = dir == 0 ? in->U : in->V;
    double *Kbar = dir == 0 ? out->U : out->V;
    const int ncurves = dir == 0 ? in->nv : out->nu;
    merge_knots(n, p, K, src, r, Kbar);
    if (r == 0)
        return;
    for (int j = 0; j < ncurves; j++) {
        curve_t c = curve_of(in, out, dir, j);
        refine_curve(&c, n, p, K, Kbar, src, r);
    }
}

static int refine(const nf_surf_t *in, const double *X, int r, nf_surf_t *out, int dir)
{
    if (!in || r < 0 || (r > 0 && !X))
        return NF_EARG;
    int rc = check_io(in, dir == 0 ? r : 0, dir == 0 ? 0 : r, out);
    if (rc)
        return rc;
    ksrc_t src;
    ksrc_init(&src, X, dir == 0 ? in->U : in->V, dir == 0 ? in->p : in->q);
    if (dir == 0 && (rc = check_new_knots(in->nu - 1, in->p, in->U, &src, r)) != NF_OK)
        return rc;
    if (dir == 1 && (rc = check_new_knots(in->nv - 1, in->q, in->V, &src, r)) != NF_OK)
        return rc;
    copy_net(in, out);
    if (dir == 0)
        copy_knots(in->V, in->nv + in->q + 1, out->V);
    else
        copy_knots(in->U, in->nu + in->p + 1, out->U);
    refine_dir(in, out, dir, &src, r);
    finish_net(in, out);
    return NF_OK;
}

int nf_refine_u(const nf_surf_t *in, const double *X, int r, nf_surf_t *out)
{
    return refine(in, X, r, out, 0);
}

int nf_refine_v(const nf_surf_t *in, const double *X, int r, nf_surf_t *out)
{
    return refine(in, X, r, out, 1);
}

/* A5.3 SurfaceKnotIns: A5.1 on every row (u) or column (v). */
static int insert(const nf_surf_t *in, double x, int times, nf_surf_t *out, int dir)
{
    if (!in || times < 0)
        return NF_EARG;
    int rc = check_io(in, dir == 0 ? times : 0, dir == 0 ? 0 : times, out);
    if (rc)
        return rc;
    const int n = dir == 0 ? in->nu - 1 : in->nv - 1, p = dir == 0 ? in->p : in->q;
    const double *K = dir == 0 ? in->U : in->V;
    if (!(K[p] < x && x < K[n + 1]))
        return NF_EKNOTS;
    const int k = nf_find_span(n, p, x, K), s = mult(n, p, K, x);
    if (s + times > p)
        return NF_EKNOTS;
    copy_net(in, out);
    double *Kbar = dir == 0 ? out->U : out->V;
    for (int i = 0; i <= k; i++)
        Kbar[i] = K[i];
    for (int i = 1; i <= times; i++)
        Kbar[k + i] = x;
    for (int i = k + 1; i <= n + p + 1; i++)
        Kbar[i + times] = K[i];
    if (dir == 0)
        copy_knots(in->V, in->nv + in->q + 1, out->V);
    else
        copy_knots(in->U, in->nu + in->p + 1, out->U);
    const int ncurves = dir == 0 ? in->nv : in->nu;
    for (int j = 0; times > 0 && j < ncurves; j++) {
        curve_t c = curve_of(in, out, dir, j);
        insert_curve(&c, n, p, K, x, k, s, times);
    }
    finish_net(in, out);
    return NF_OK;
}

int nf_refine_insert_u(const nf_surf_t *in, double x, int times, nf_surf_t *out)
{
    return insert(in, x, times, out, 0);
}

int nf_refine_insert_v(const nf_surf_t *in, double x, int times, nf_surf_t *out)
{
    return insert(in, x, times, out, 1);
}

int nf_refine_uniform(const nf_surf_t *in, nf_surf_t *out)
{
    int rc = nf_surf_check(in);
    if (rc)
        return rc;
    int su, sv;
    nf_refine_spans(in, &su, &sv);
    if ((rc = check_io(in, su, sv, out)) != NF_OK)
        return rc;
    ksrc_t xu, xv;
    ksrc_init(&xu, NULL, in->U, in->p);
    ksrc_init(&xv, NULL, in->V, in->q);
    /* Midpoints of spans only a few ulps wide can round onto an end knot. */
    if ((rc = check_new_knots(in->nu - 1, in->p, in->U, &xu, su)) != NF_OK ||
        (rc = check_new_knots(in->nv - 1, in->q, in->V, &xv, sv)) != NF_OK)
        return rc;
    copy_net(in, out);
    /* u on the in->nv rows (row length out->nu), then v on every column of
     * the widened net; the second pass reads the first pass's rows in place. */
    refine_dir(in, out, 0, &xu, su);
    refine_dir(in, out, 1, &xv, sv);
    finish_net(in, out);
    return NF_OK;
}

/* The breakpoints are K[deg..n] merged with the knots chosen so far (both
 * sorted), walked by merge each time: no buffer, O(r (n + r)) work. */
int nf_refine_widest(const double *K, int n, int deg, int r, double *X)
{
    if (r < 0 || (r > 0 && (!K || !X)))
        return NF_EARG;
    for (int t = 0; t < r; t++) {
        /* One merge walk over K's breakpoints and the t knots chosen so far:
         * the first widest gap between consecutive distinct values. */
        int i = deg, k = 0, have = 0, at = 0;
        double prev = 0.0, lo = 0.0, hi = 0.0;
        while (i <= n || k < t) {
            double x = k >= t || (i <= n && K[i] <= X[k]) ? K[i++] : X[k++];
            if (have && x > prev && (at == 0 || x - prev > hi - lo)) {
                lo = prev;
                hi = x;
                at = 1;
            }
            prev = x;
            have = 1;
        }
        double m = 0.5 * (lo + hi);
        int j = t;
        while (j > 0 && X[j - 1] > m) { /* sorted insertion */
            X[j] = X[j - 1];
            j--;
        }
        X[j] = m;
    }
    return NF_OK;
}
