/* SPDX-License-Identifier: MIT */
/* nf_knotsel.c: per-span misfit of the check pass and the knot lines chosen
 * from it (gain per control point added, data on both sides of each knot). */
#include "nf_knotsel.h"
#include "nf_basis.h"
#include "nf_err.h"
#include <math.h>
#include <stddef.h>

/* Offsets within a sub-bin and within a span slot. */
enum { B_N = 0, B_LO = 1, B_HI = 2, B_G = 3, B_GT = 4 };
enum { S_RSS = NF_KNOTSEL_BINS * NF_KNOTSEL_BIN, S_OUT = S_RSS + 1 };

int nf_knotsel_init(nf_knotsel_t *a, const nf_surf_t *s, double tol, double *mem)
{
    if (!a || !s || !mem || !(tol > 0.0))
        return NF_EARG;
    const long nsu = s->nu - s->p, nsv = s->nv - s->q;
    a->s = s;
    a->tol = tol;
    a->su = mem;
    a->sv = mem + NF_KNOTSEL_SPAN * nsu;
    for (long i = 0; i < nsu + nsv; i++) {
        double *sp = mem + NF_KNOTSEL_SPAN * i;
        for (int b = 0; b < NF_KNOTSEL_BINS; b++) {
            double *c = sp + NF_KNOTSEL_BIN * b;
            c[B_N] = c[B_G] = c[B_GT] = 0.0;
            c[B_LO] = HUGE_VAL;
            c[B_HI] = -HUGE_VAL;
        }
        sp[S_RSS] = sp[S_OUT] = 0.0;
    }
    a->n = a->out = 0;
    a->rss = a->g = 0.0;
    a->hu = (double)nsu / (s->U[s->nu] - s->U[s->p]);
    a->hv = (double)nsv / (s->V[s->nv] - s->V[s->q]);
    return NF_OK;
}

/* Span slot of t (clamped) in knots T (n + 1 control points, degree deg;
 * h spans per unit), and its sub-bin. The span is nf_find_span's, from
 * the uniform guess first (the binary search was a fifth of the check
 * pass's own work). */
static double *bin_of(double *slots, const double *T, int n, int deg, double t, double h, int *slot,
                      double **bin)
{
    const double lo = T[deg], hi = T[n + 1];
    t = t < lo ? lo : (t > hi ? hi : t);
    const int l = nf_find_span_from(-1, n, deg, t, T, h);
    const double a = T[l], w = T[l + 1] - a;
    int b = (int)((t - a) / w * NF_KNOTSEL_BINS);
    b = b < 0 ? 0 : (b >= NF_KNOTSEL_BINS ? NF_KNOTSEL_BINS - 1 : b);
    double *sp = slots + (long)NF_KNOTSEL_SPAN * (l - deg);
    *slot = l - deg;
    *bin = sp + NF_KNOTSEL_BIN * b;
    return sp;
}

static void take(double *sp, double *c, double t, double d2, int out)
{
    c[B_N] += 1.0;
    c[B_LO] = t < c[B_LO] ? t : c[B_LO];
    c[B_HI] = t > c[B_HI] ? t : c[B_HI];
    sp[S_RSS] += d2;
    if (out) {
        c[B_G] += d2;
        c[B_GT] += d2 * t;
        sp[S_OUT] += 1.0;
    }
}

void nf_knotsel_add(nf_knotsel_t *a, double u, double v, double d)
{
    if (!isfinite(u) || !isfinite(v))
        return;
    const nf_surf_t *s = a->s;
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    u = u < u0 ? u0 : (u > u1 ? u1 : u);
    v = v < v0 ? v0 : (v > v1 ? v1 : v);
    const int ok = isfinite(d), out = ok && fabs(d) > a->tol;
    const double d2 = ok ? d * d : 0.0;
    int slot;
    double *c;
    double *sp = bin_of(a->su, s->U, s->nu - 1, s->p, u, a->hu, &slot, &c);
    take(sp, c, u, d2, out);
    sp = bin_of(a->sv, s->V, s->nv - 1, s->q, v, a->hv, &slot, &c);
    take(sp, c, v, d2, out);
    a->n++;
    a->rss += d2;
    if (out) {
        a->out++;
        a->g += d2;
    }
}

static const double *span_slot(const nf_knotsel_t *a, int dir, int i)
{
    return (dir ? a->sv : a->su) + (long)NF_KNOTSEL_SPAN * i;
}

long nf_knotsel_span_points(const nf_knotsel_t *a, int dir, int i)
{
    const double *sp = span_slot(a, dir, i);
    double n = 0.0;
    for (int b = 0; b < NF_KNOTSEL_BINS; b++)
        n += sp[NF_KNOTSEL_BIN * b + B_N];
    return (long)n;
}

double nf_knotsel_span_rss(const nf_knotsel_t *a, int dir, int i)
{
    return span_slot(a, dir, i)[S_RSS];
}

int nf_knotsel_merge(nf_knotsel_t *a, const nf_knotsel_t *b)
{
    if (!a || !b || a->s != b->s || a->tol != b->tol)
        return NF_EARG;
    const long slots = (a->s->nu - a->s->p) + (a->s->nv - a->s->q);
    for (long i = 0; i < slots; i++) { /* su and sv are one run (nf_knotsel_init) */
        double *d = a->su + NF_KNOTSEL_SPAN * i;
        const double *e = b->su + NF_KNOTSEL_SPAN * i;
        for (int k = 0; k < NF_KNOTSEL_BINS; k++) {
            double *c = d + NF_KNOTSEL_BIN * k;
            const double *x = e + NF_KNOTSEL_BIN * k;
            c[B_N] += x[B_N];
            c[B_LO] = x[B_LO] < c[B_LO] ? x[B_LO] : c[B_LO];
            c[B_HI] = x[B_HI] > c[B_HI] ? x[B_HI] : c[B_HI];
            c[B_G] += x[B_G];
            c[B_GT] += x[B_GT];
        }
        d[S_RSS] += e[S_RSS];
        d[S_OUT] += e[S_OUT];
    }
    a->n += b->n;
    a->out += b->out;
    a->rss += b->rss;
    a->g += b->g;
    return NF_OK;
}

int nf_knotsel_merge_span(nf_knotsel_t *a, const nf_knotsel_t *b, int dir, int i)
{
    if (!a || !b || a->s != b->s || i < 0 || i >= (dir ? a->s->nv - a->s->q : a->s->nu - a->s->p))
        return NF_EARG;
    double *d = (dir ? a->sv : a->su) + (long)NF_KNOTSEL_SPAN * i;
    const double *e = span_slot(b, dir, i);
    double g = 0.0;
    for (int k = 0; k < NF_KNOTSEL_BINS; k++) {
        d[NF_KNOTSEL_BIN * k + B_G] += e[NF_KNOTSEL_BIN * k + B_G];
        d[NF_KNOTSEL_BIN * k + B_GT] += e[NF_KNOTSEL_BIN * k + B_GT];
        g += e[NF_KNOTSEL_BIN * k + B_G];
    }
    d[S_OUT] += e[S_OUT];
    d[S_RSS] += g;
    /* The totals: a direction's spans hold every point once. */
    if (dir == 0) {
        a->g += g;
        a->out += (long)e[S_OUT];
        a->rss += g;
    }
    return NF_OK;
}

const char *nf_knotsel_status_str(int status)
{
    switch (status) {
    case NF_KNOTSEL_INSERT: return "insert";
    case NF_KNOTSEL_NONE_OUT: return "none_out";
    case NF_KNOTSEL_DATA: return "data_limit";
    case NF_KNOTSEL_HALF_PTS: return "half_points";
    case NF_KNOTSEL_MAX_CP: return "max_cp";
    default: return "unknown status";
    }
}

/* Data rows a sub-bin proves: none, one value, or at least two. */
static int rows_of(const double *c)
{
    return c[B_N] > 0.0 ? (c[B_HI] > c[B_LO] ? 2 : 1) : 0;
}

/* The best knot among the boundaries jmin .. jmax of the sub-bins b0 ..
 * b1 - 1 of span sp (t0 its start, w a sub-bin's width): of those where
 * both sides, within b0 .. b1 - 1, hold min_pts points and min_rows rows,
 * the one nearest the centroid of the misfit there (fpknot places its knot
 * by the residual too, and only between data points). 1 and *x, *jx, with
 * *g the misfit of b0 .. b1 - 1, or 0 (*g still set). */
static int best_split(const double *sp, double t0, double t1, int b0, int b1, int jmin, int jmax,
                      int min_pts, int min_rows, double *x, int *jx, double *g)
{
    const double w = (t1 - t0) / NF_KNOTSEL_BINS;
    double gs = 0.0, gt = 0.0, ntot = 0.0;
    int rtot = 0;
    for (int b = b0; b < b1; b++) {
        const double *c = sp + NF_KNOTSEL_BIN * b;
        gs += c[B_G];
        gt += c[B_GT];
        ntot += c[B_N];
        rtot += rows_of(c);
    }
    *g = gs;
    if (!(gs > 0.0))
        return 0;
    const double mid = gt / gs;
    double nl = 0.0, best = HUGE_VAL;
    int rl = 0, found = 0;
    for (int j = b0 + 1; j < b1; j++) {
        const double *c = sp + NF_KNOTSEL_BIN * (j - 1);
        nl += c[B_N];
        rl += rows_of(c);
        if (j < jmin || j > jmax)
            continue;
        if (nl < min_pts || ntot - nl < min_pts || rl < min_rows || rtot - rl < min_rows)
            continue;
        const double xj = t0 + w * j;
        if (fabs(xj - mid) < best) {
            best = fabs(xj - mid);
            *x = xj;
            *jx = j;
            found = 1;
        }
    }
    /* A boundary so close to t0 or t1 in floating point that it rounds
     * onto a knot would make no new span. */
    return found && t0 < *x && *x < t1;
}

/* The candidates of span slot i of direction dir into c (room for
 * per_span, at most 3), their count; 0 when the span has no misfit or no
 * admissible position (*blocked set when it has misfit). The first is at
 * the sub-bin boundary nearest the misfit's centroid, NF_KNOTSEL_BINS/4 ..
 * 3/4 of the way (a new span at least a quarter of the old). Then, as
 * FITPACK's fpknot does when it gives one interval several knots in one
 * iteration (each new interval keeps its share of the residual sum and
 * competes again), each side of it with misfit gets a knot at its own
 * misfit's centroid, no closer than a quarter side to the side's ends
 * (rounded up: at least one sub-bin), scored by that side's misfit (level
 * 1): a wide span with much misfit is split in up to four in one round, a
 * narrow feature bracketed, instead of one halving per round; only where
 * the misfit is deeper than depth tol (rms out of tolerance; depth <= 0:
 * always). */
static int candidates(const nf_knotsel_t *a, int dir, int i, int min_pts, int min_rows,
                      int per_span, double depth, double cost, nf_knotsel_cand_t *c, int *blocked)
{
    const nf_surf_t *s = a->s;
    const int deg = dir ? s->q : s->p;
    const double *T = dir ? s->V : s->U, *sp = span_slot(a, dir, i);
    const double t0 = T[deg + i], t1 = T[deg + i + 1];
    double x = 0.0, g = 0.0;
    int j = 0;
    *blocked = 0;
    if (!(t0 < t1))
        return 0;
    if (!best_split(sp, t0, t1, 0, NF_KNOTSEL_BINS, NF_KNOTSEL_BINS / 4, 3 * NF_KNOTSEL_BINS / 4,
                    min_pts, min_rows, &x, &j, &g)) {
        *blocked = g > 0.0;
        return 0;
    }
    c[0] = (nf_knotsel_cand_t){dir, i, x, g / cost, 0};
    int n = 1;
    /* Shallow misfit (rms out of tolerance at most depth tol): bisection
     * mends it; sides would crowd a broad feature (NF_KNOTSEL_SIDE_DEPTH). */
    if (depth > 0.0 && !(g > depth * depth * a->tol * a->tol * sp[S_OUT]))
        return n;
    /* The sides, the one holding more misfit first (per_span 2: that one). */
    double gl = 0.0;
    for (int b = 0; b < j; b++)
        gl += sp[NF_KNOTSEL_BIN * b + B_G];
    const int first = gl >= 0.5 * g ? 0 : 1;
    for (int k = 0; k < 2 && n < per_span; k++) {
        const int side = k ? !first : first;
        double x2 = 0.0, g2 = 0.0;
        int j2 = 0;
        const int b0 = side ? j : 0, b1 = side ? NF_KNOTSEL_BINS : j;
        /* A quarter of the side from its ends, as the first knot is from
         * the span's: spans stay balanced (at the side's own centroid,
         * unclamped, knots piled a sub-bin apart onto a peak). */
        const int qs = (b1 - b0 + 3) / 4;
        if (best_split(sp, t0, t1, b0, b1, b0 + qs, b1 - qs, min_pts, min_rows, &x2, &j2, &g2) &&
            x2 != x)
            c[n++] = (nf_knotsel_cand_t){dir, i, x2, g2 / cost, 1};
    }
    return n;
}

/* 1 when the first k picks hold the level-0 knot of span slot span of dir. */
static int taken(const nf_knotsel_cand_t *c, int k, int dir, int span)
{
    for (int i = 0; i < k; i++)
        if (c[i].dir == dir && c[i].span == span && c[i].level == 0)
            return 1;
    return 0;
}

/* c[i] ranks before c[j]: higher score, then u before v, then lower span
 * (a strict total order: the choice does not depend on the sort). */
static int before(const nf_knotsel_cand_t *x, const nf_knotsel_cand_t *y)
{
    if (x->score != y->score)
        return x->score > y->score;
    if (x->dir != y->dir)
        return x->dir < y->dir;
    return x->span < y->span;
}

int nf_knotsel_choose(const nf_knotsel_t *a, const nf_knotsel_opts_t *opts, nf_knotsel_cand_t *out,
                      int cap, int *n, int *status)
{
    if (!a || !out || !n || !status || cap < 0)
        return NF_EARG;
    const nf_surf_t *s = a->s;
    nf_knotsel_opts_t o = {0, 0, 0, 0.0, 0.0, 0, 0, 0, 0.0};
    if (opts)
        o = *opts;
    long max_cp = o.max_cp > 0 && o.max_cp < NF_MAX_CP ? o.max_cp : NF_MAX_CP;
    const long half = a->n / 2;
    const int min_rows = o.min_rows > 0 ? o.min_rows : NF_KNOTSEL_MIN_ROWS;
    const double ratio = o.ratio > 0.0 ? o.ratio : NF_KNOTSEL_RATIO;
    const double share = o.share > 0.0 ? o.share : NF_KNOTSEL_SHARE;
    *n = 0;
    *status = NF_KNOTSEL_NONE_OUT;
    if (!(a->g > 0.0))
        return NF_OK;

    /* Every admissible candidate, sorted by insertion (a span or two per
     * control point line: few). Room for the first of each span is the
     * caller's promise; a second knot without room waits a round. */
    const int per_span = o.per_span > 0 ? o.per_span : NF_KNOTSEL_PER_SPAN;
    const double depth = o.side_depth != 0.0 ? o.side_depth : NF_KNOTSEL_SIDE_DEPTH;
    int m = 0, blocked_any = 0, left = (s->nu - s->p) + (s->nv - s->q); /* spans to go */
    for (int dir = 0; dir < 2; dir++) {
        const int deg = dir ? s->q : s->p, ns = dir ? s->nv - s->q : s->nu - s->p;
        const int min_pts = o.min_pts > 0 ? o.min_pts : deg + 1;
        const double cost = dir ? s->nu : s->nv; /* control points one knot line adds */
        for (int i = 0; i < ns; i++) {
            nf_knotsel_cand_t cs[3];
            int blocked;
            const int nc = candidates(a, dir, i, min_pts, min_rows, per_span < 3 ? per_span : 3,
                                      depth, cost, cs, &blocked);
            blocked_any |= blocked;
            left--;
            for (int q = 0; q < nc; q++) {
                if (q == 0 && m >= cap)
                    return NF_EARG;
                if (q > 0 && m >= cap - left)
                    break; /* the room of the spans to go: their first knots */
                const nf_knotsel_cand_t c = cs[q];
                int j = m++;
                while (j > 0 && before(&c, &out[j - 1])) {
                    out[j] = out[j - 1];
                    j--;
                }
                out[j] = c;
            }
        }
    }
    if (m == 0) {
        *status = blocked_any ? NF_KNOTSEL_DATA : NF_KNOTSEL_NONE_OUT;
        return NF_OK;
    }

    /* Best first, within the ratio, the share per direction and the cap. */
    const double best = out[0].score;
    double got[2] = {0.0, 0.0};
    int r[2] = {0, 0}, k = 0, capped = 0;
    for (int i = 0; i < m; i++) {
        const nf_knotsel_cand_t c = out[i];
        if (c.score < ratio * best || (o.max_knots > 0 && k >= o.max_knots))
            break;
        /* A side's knot goes with its span's first (taken this round),
         * whatever the direction's share: it refines misfit already
         * counted; a first knot waits once the direction has its share. */
        if (c.level ? !taken(out, k, c.dir, c.span) : got[c.dir] >= share * a->g)
            continue;
        const long nu = s->nu + r[0] + (c.dir == 0), nv = s->nv + r[1] + (c.dir == 1);
        if (nu * nv > half || nu * nv > max_cp) {
            /* The smaller cap is the one that binds. */
            capped = half <= max_cp ? NF_KNOTSEL_HALF_PTS : NF_KNOTSEL_MAX_CP;
            continue;
        }
        if (k > 0 && o.max_add > 0 && nu * nv - (long)s->nu * s->nv > o.max_add)
            continue; /* the round's budget: a cheaper line may still fit */
        out[k++] = c;
        r[c.dir]++;
        /* A level-1 knot refines misfit its span's first knot counted. */
        got[c.dir] += c.level ? 0.0 : c.score * (c.dir ? s->nu : s->nv);
    }
    *n = k;
    *status = k > 0 ? NF_KNOTSEL_INSERT : capped;
    return NF_OK;
}

int nf_knotsel_split(const nf_knotsel_cand_t *c, int n, double *Xu, int maxu, int *ru, double *Xv,
                     int maxv, int *rv)
{
    if ((n > 0 && !c) || !ru || !rv || n < 0)
        return NF_EARG;
    *ru = *rv = 0;
    for (int i = 0; i < n; i++) {
        double *X = c[i].dir ? Xv : Xu;
        int *r = c[i].dir ? rv : ru;
        if (*r >= (c[i].dir ? maxv : maxu) || !X)
            return NF_EARG;
        int j = (*r)++;
        while (j > 0 && X[j - 1] > c[i].x) {
            X[j] = X[j - 1];
            j--;
        }
        X[j] = c[i].x;
    }
    return NF_OK;
}
