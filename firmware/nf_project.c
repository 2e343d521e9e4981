/* SPDX-License-Identifier: MIT */
/* nf_project.c: point inversion on a NURBS surface (The NURBS Book, Section
 * 6.1, Eqs. 6.6-6.8), the step from measured points to their parameters
 * (Piegl & Tiller 2001, Section 3; Brujic et al. 2010, Section 2.2). */
#include "nf_project.h"
#include "nf_basis.h"
#include "nf_err.h"
#include "nf_vec3.h"
#include <float.h>
#include <math.h>

/* Offsets of the partial derivatives in nf_surf_derivs' skl[(k*3 + l)*3]. */
enum { D_S = 0, D_SV = 3, D_SVV = 6, D_SU = 9, D_SUV = 12, D_SUU = 18 };

/* The distance function at one parameter pair: r = S - Q, D = |r|^2 and the
 * half gradient (r . Su, r . Sv), the left-hand sides of Eq. 6.6. */
typedef struct pt {
    double u, v;
    double d[27];
    double r[3];
    double D, gu, gv;
} pt_t;

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}

static void pt_eval(const nf_surf_t *s, const double Q[3], double u, double v, pt_t *t)
{
    t->u = u;
    t->v = v;
    nf_surf_derivs(s, u, v, 2, t->d);
    for (int c = 0; c < 3; c++)
        t->r[c] = t->d[D_S + c] - Q[c];
    t->D = nf_dot3(t->r, t->r);
    t->gu = nf_dot3(t->r, t->d + D_SU);
    t->gv = nf_dot3(t->r, t->d + D_SV);
}

/* Level below which r . Su is rounding: r carries an absolute error of a few
 * ulps of the coordinates (S is a convex combination of control points, Q is
 * data), and the dot product adds a relative error of 3 ulps. */
static double grad_noise(const pt_t *t, const double Q[3], const double *Sx)
{
    double scale = 0.0;
    for (int c = 0; c < 3; c++) {
        scale = fmax(scale, fabs(Q[c]));
        scale = fmax(scale, fabs(t->d[D_S + c]));
    }
    return 8.0 * DBL_EPSILON * (scale + sqrt(t->D)) * sqrt(nf_dot3(Sx, Sx));
}

/* Bound constraints u in [u0, u1] (likewise v): a parameter on its bound is
 * held there when the distance decreases outward, i.e. the projected
 * gradient of the bound-constrained problem keeps only the other one. */
static int held(double x, double lo, double hi, double g)
{
    return (x <= lo && g > 0.0) || (x >= hi && g < 0.0);
}

/* The Newton step of Eq. 6.7/6.8 on the free parameters: J delta = -g with
 * J = [[|Su|^2 + r.Suu, Su.Sv + r.Suv], [Su.Sv + r.Suv, |Sv|^2 + r.Svv]].
 * Where J is not positive definite (Q beyond a centre of curvature, or a
 * saddle) the Gauss-Newton matrix (r = 0 in J) replaces it: it is positive
 * semi-definite, so its step still descends. A degenerate Gauss-Newton matrix
 * (Su parallel to Sv) falls back to scaled steepest descent per parameter.
 * Returns 1 for a true Newton step, 0 for a fallback (whose length is only
 * a guess). */
static int newton_step(const pt_t *t, int fu, int fv, double *du, double *dv)
{
    const double *Su = t->d + D_SU, *Sv = t->d + D_SV;
    const double euu = nf_dot3(Su, Su), euv = nf_dot3(Su, Sv), evv = nf_dot3(Sv, Sv);
    const double a = euu + nf_dot3(t->r, t->d + D_SUU);
    const double b = euv + nf_dot3(t->r, t->d + D_SUV);
    const double c = evv + nf_dot3(t->r, t->d + D_SVV);
    *du = *dv = 0.0;
    /* A parameter whose tangent vanishes (a collapsed edge, a pole) gets no
     * step: its Newton equation is 0 = 0 to rounding. */
    if (euu <= 1e-20 * evv)
        fu = 0;
    if (evv <= 1e-20 * euu)
        fv = 0;
    if (fu && fv) {
        double det = a * c - b * b;
        if (a > 0.0 && c > 0.0 && det > 1e-12 * a * c) {
            *du = (-t->gu * c + t->gv * b) / det;
            *dv = (t->gu * b - t->gv * a) / det;
            return 1;
        }
        det = euu * evv - euv * euv;
        if (det > 1e-12 * euu * evv) {
            *du = (-t->gu * evv + t->gv * euv) / det;
            *dv = (t->gu * euv - t->gv * euu) / det;
            return 0;
        }
        fu = fu && euu > 0.0;
        fv = fv && evv > 0.0;
        *du = fu ? -t->gu / euu : 0.0;
        *dv = fv ? -t->gv / evv : 0.0;
        return 0;
    }
    if (fu && euu > 0.0) { /* 1-D Newton in u (v held), or its fallback */
        *du = -t->gu / (a > 0.0 ? a : euu);
        return a > 0.0;
    }
    if (fv && evv > 0.0) {
        *dv = -t->gv / (c > 0.0 ? c : evv);
        return c > 0.0;
    }
    return 1;
}

/* At a collapsed edge (a pole: Su = 0 all along v = v0, say) the point is
 * the same for every u but the direction leaving it, Sv(u, v0), is not, and
 * Newton sees only the current u: it would stop on the pole when that one
 * direction climbs, or leave it along a poor one. The escape samples the
 * edge for the steepest descent into the domain (per unit length) and moves
 * there: the same point, with the best way out. 1 when it moved. */
static int pole_escape(const nf_surf_t *s, const double Q[3], const double dom[4], const pt_t *cur,
                       pt_t *out)
{
    const double *Su = cur->d + D_SU, *Sv = cur->d + D_SV;
    const double euu = nf_dot3(Su, Su), evv = nf_dot3(Sv, Sv);
    int along; /* 0: the edge runs in u (v on a bound), 1: in v */
    double side;
    if (evv > 0.0 && euu <= 1e-20 * evv && (cur->v == dom[2] || cur->v == dom[3])) {
        along = 0;
        side = cur->v == dom[2] ? 1.0 : -1.0;
    } else if (euu > 0.0 && evv <= 1e-20 * euu && (cur->u == dom[0] || cur->u == dom[1])) {
        along = 1;
        side = cur->u == dom[0] ? 1.0 : -1.0;
    } else {
        return 0;
    }
    const int cross = along == 0 ? D_SV : D_SU; /* derivative leaving the edge */
    const double lo = dom[2 * along], hi = dom[2 * along + 1];
    const double *T = cur->d + cross;
    double best = side * nf_dot3(cur->r, T) / sqrt(nf_dot3(T, T)),
           bx = along == 0 ? cur->u : cur->v;
    const double now = best;
    for (int i = 0; i <= 32; i++) {
        const double x = lo + (hi - lo) * i / 32;
        double d[27];
        nf_surf_derivs(s, along == 0 ? x : cur->u, along == 0 ? cur->v : x, 1, d);
        const double l = sqrt(nf_dot3(d + cross, d + cross));
        const double g = l > 0.0 ? side * nf_dot3(cur->r, d + cross) / l : 0.0;
        if (g < best) {
            best = g;
            bx = x;
        }
    }
    /* Worth it when the best way out descends, and beats the current one
     * beyond rounding. */
    const double noise = grad_noise(cur, Q, T) / sqrt(nf_dot3(T, T));
    if (!(best < -noise && best < now - noise))
        return 0;
    pt_eval(s, Q, along == 0 ? bx : cur->u, along == 0 ? cur->v : bx, out);
    return 1;
}

static void finish(const nf_surf_t *s, const double Q[3], const pt_t *t, int iters, nf_proj_t *out)
{
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    const double *Su = t->d + D_SU, *Sv = t->d + D_SV;
    out->u = t->u;
    out->v = t->v;
    for (int c = 0; c < 3; c++)
        out->foot[c] = t->d[D_S + c];
    out->iters = iters;
    /* Clamped: held on a bound by a gradient beyond rounding, so that the
     * foot is the boundary's answer, not a stationary point that happens to
     * lie on the boundary. */
    out->clamped = (held(t->u, u0, u1, t->gu) && fabs(t->gu) > grad_noise(t, Q, Su)) ||
                   (held(t->v, v0, v1, t->gv) && fabs(t->gv) > grad_noise(t, Q, Sv));
    double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                   Su[0] * Sv[1] - Su[1] * Sv[0]};
    double nn = sqrt(nf_dot3(n, n)), lu = sqrt(nf_dot3(Su, Su)), lv = sqrt(nf_dot3(Sv, Sv));
    /* |r| scaled, so that a point absurdly far (|Q| ~ 1e200) still gets a
     * finite distance where |r|^2 overflows. */
    const double m = fmax(fabs(t->r[0]), fmax(fabs(t->r[1]), fabs(t->r[2])));
    double dist = m > 0.0 && m < INFINITY
                      ? m * sqrt((t->r[0] / m) * (t->r[0] / m) + (t->r[1] / m) * (t->r[1] / m) +
                                 (t->r[2] / m) * (t->r[2] / m))
                      : m;
    /* The sign needs a normal: Su x Sv vanishes at a degenerate point (a
     * collapsed edge, a cusp), where it is rounding; measured against both
     * tangents, since on a pole one of them is itself rounding. */
    if (nn > 1e-12 * (lu * lu + lv * lv) && -nf_dot3(t->r, n) < 0.0)
        dist = -dist;
    out->dist = dist;
}

/* End of a step from x by dx, stopped on the first C0 knot line it would
 * cross (a knot of multiplicity >= p, every interior knot at degree 1):
 * across it the distance has a kink, Newton's model of it is wrong, and a
 * minimum on the crease is only found exactly by landing on the knot. */
static double step_end(const double *K, int n, int p, double x, double dx)
{
    const int k = nf_find_span(n, p, x, K); /* K[k] <= x < K[k+1] */
    if (dx > 0.0) {
        for (int i = k + 1; i <= n && K[i] < x + dx; i++)
            if (K[i + p - 1] == K[i]) /* first of a p-fold run */
                return K[i];
    } else if (dx < 0.0) {
        for (int i = k; K[i] > K[p] && K[i] > x + dx; i--)
            if (K[i] < x && K[i - p + 1] == K[i]) /* last of a p-fold run */
                return K[i];
    }
    return x + dx;
}

/* x moved onto a crease (C0 knot) that lies within tol of it. Where two
 * creases cross, the minimum is often their crossing; a step stopped on one
 * crease leaves the other parameter a little off its own, and without the
 * snap the iteration zigzags between the two towards the crossing. */
static double snap_crease(const double *K, int n, int p, double x, double tol)
{
    const int k = nf_find_span(n, p, x, K); /* K[k] <= x < K[k+1] */
    if (K[k] > K[p] && K[k - p + 1] == K[k] && x - K[k] <= tol)
        return K[k];
    if (K[k + 1] < K[n + 1] && K[k + p] == K[k + 1] && K[k + 1] - x <= tol)
        return K[k + 1];
    return x;
}

/* 1 when x is exactly a crease (an interior knot of multiplicity >= p). */
static int on_crease(const double *K, int n, int p, double x)
{
    const int k = nf_find_span(n, p, x, K);
    return K[k] == x && K[k] > K[p] && K[k - p + 1] == K[k];
}

/* Rounding level of D = |S - Q|^2, from the few-ulp error of r. */
static double d_noise(const pt_t *t, const double Q[3])
{
    double scale = 0.0;
    for (int c = 0; c < 3; c++)
        scale = fmax(scale, fmax(fabs(Q[c]), fabs(t->d[D_S + c])));
    return 16.0 * DBL_EPSILON * (scale + sqrt(t->D)) * sqrt(t->D);
}

/* Squared tangential part of r in the free parameters, (r.Su)^2/|Su|^2 +
 * (r.Sv)^2/|Sv|^2: zero at the foot, and first order in the distance to it
 * where D is second order and lost in rounding (thin or flat directions). */
static double tangential(const pt_t *t, int fu, int fv)
{
    const double uu = nf_dot3(t->d + D_SU, t->d + D_SU), vv = nf_dot3(t->d + D_SV, t->d + D_SV);
    return (fu && uu > 0.0 ? t->gu * t->gu / uu : 0.0) +
           (fv && vv > 0.0 ? t->gv * t->gv / vv : 0.0);
}

/* Acceptance of a trial point: D lower beyond rounding, or (where the
 * change of D is rounding) a smaller tangential residual. */
static int better(const pt_t *trial, const pt_t *cur, double noise, int fu, int fv)
{
    if (trial->D < cur->D - noise)
        return 1;
    return trial->D <= cur->D + noise && tangential(trial, fu, fv) < tangential(cur, fu, fv);
}

/* A full step that left the domain: the rest of it was computed for a move
 * the bound forbids, and halving the clipped step would zigzag towards the
 * bound instead of reaching it (or away from it, when the clip of the other
 * parameter was the artefact). So a parameter the step clipped is put on
 * its bound with the other one given its own 1-D Newton step, or left
 * where it is (the projected Newton method's guess of the active bound). */
static int bound_steps(const nf_surf_t *s, const double Q[3], const double dom[4], const pt_t *cur,
                       double ue, double ve, int cu, int cv, double noise, int fu, int fv,
                       pt_t *trial)
{
    double du, dv, skip;
    newton_step(cur, 1, 0, &du, &skip);
    newton_step(cur, 0, 1, &skip, &dv);
    const double un = clampd(cur->u + du, dom[0], dom[1]), vn = clampd(cur->v + dv, dom[2], dom[3]);
    const double cand[4][2] = {{un, ve}, {cur->u, ve}, {ue, vn}, {ue, cur->v}};
    for (int k = cv ? 0 : 2; k < (cu ? 4 : 2); k++) {
        pt_eval(s, Q, cand[k][0], cand[k][1], trial);
        if (better(trial, cur, noise, fu, fv))
            return 1;
    }
    return 0;
}

/* A fallback step (Gauss-Newton or steepest descent, where J is not
 * positive definite) has no reliable length: near a saddle of the distance,
 * far from the surface, it is much too short and the iteration would crawl.
 * When the full step was accepted, it is doubled while that keeps
 * improving (within the domain and up to 2^10). */
static void expand(const nf_surf_t *s, const double Q[3], const double dom[4], const pt_t *cur,
                   double du, double dv, pt_t *trial)
{
    pt_t next;
    for (int k = 1; k <= 10; k++) {
        const double f = (double)(1 << k);
        const double un = cur->u + f * du, vn = cur->v + f * dv;
        if (un < dom[0] || un > dom[1] || vn < dom[2] || vn > dom[3])
            return;
        pt_eval(s, Q, un, vn, &next);
        if (!(next.D < trial->D))
            return;
        *trial = next;
    }
}

/* Step control on the step (du, dv) from cur: the projected step is halved
 * until the point is better (trial then holds it); a step that left the
 * domain also tries the bounds it met (bound_steps). A step already
 * below the tolerance at full length is Newton's last (quadratic
 * convergence: the point it reaches is better still) and is taken without
 * the test. */
enum { STEP_DESCENT, STEP_SMALL, STEP_CREASE, STEP_FAILED };

static int line_search(const nf_surf_t *s, const double Q[3], const double dom[4], double tu,
                       double tv, const pt_t *cur, int fu, int fv, double du, double dv, int newton,
                       pt_t *trial)
{
    if (!(du - du == 0.0 && dv - dv == 0.0)) /* overflow in J: no usable step */
        return STEP_FAILED;
    /* Stopped on the first crease either parameter meets, the step kept in
     * its direction (cutting one component alone would turn it). */
    double uf = step_end(s->U, s->nu - 1, s->p, cur->u, du);
    double vf = step_end(s->V, s->nv - 1, s->q, cur->v, dv);
    const double ku = uf != cur->u + du ? (uf - cur->u) / du : 1.0;
    const double kv = vf != cur->v + dv ? (vf - cur->v) / dv : 1.0;
    /* The other parameter, scaled with the cut step, is snapped onto its own
     * crease when that is within the tolerance. If it already lies on one,
     * staying there is tried too (stay_u / stay_v): where two creases
     * cross, the minimum is often the crossing, and the scaled steps would
     * zigzag towards it, landing on each crease in turn and leaving the
     * other. */
    int stay_u = 0, stay_v = 0;
    if (ku < kv) {
        vf = snap_crease(s->V, s->nv - 1, s->q, cur->v + ku * dv, tv);
        stay_v = vf != cur->v && on_crease(s->V, s->nv - 1, s->q, cur->v);
    } else if (kv < ku) {
        uf = snap_crease(s->U, s->nu - 1, s->p, cur->u + kv * du, tu);
        stay_u = uf != cur->u && on_crease(s->U, s->nu - 1, s->p, cur->u);
    }
    const double ue = clampd(uf, dom[0], dom[1]), ve = clampd(vf, dom[2], dom[3]);
    const int cu = ue != uf, cv = ve != vf;
    const double noise = d_noise(cur, Q);
    for (double t = 1.0;; t *= 0.5) {
        const double un = t == 1.0 ? ue : cur->u + t * (ue - cur->u);
        const double vn = t == 1.0 ? ve : cur->v + t * (ve - cur->v);
        const int small = fabs(un - cur->u) <= tu && fabs(vn - cur->v) <= tv;
        if (small && t < 1.0)
            return STEP_FAILED; /* no descent above the tolerance */
        pt_eval(s, Q, un, vn, trial);
        if (small) /* below the tolerance only because a crease cut it: no convergence */
            return ku < 1.0 || kv < 1.0 ? STEP_CREASE : STEP_SMALL;
        if (t == 1.0 && (stay_u || stay_v)) {
            pt_t alt;
            pt_eval(s, Q, stay_u ? cur->u : un, stay_v ? cur->v : vn, &alt);
            if (alt.D < trial->D)
                *trial = alt;
        }
        if (better(trial, cur, noise, fu, fv)) {
            if (t == 1.0 && !newton && !cu && !cv && ku == 1.0 && kv == 1.0)
                expand(s, Q, dom, cur, du, dv, trial);
            return STEP_DESCENT;
        }
        if (t == 1.0 && (cu || cv) &&
            bound_steps(s, Q, dom, cur, ue, ve, cu, cv, noise, fu, fv, trial))
            return STEP_DESCENT;
    }
}

/* Newton from (u0, v0) within the domain: the local minimum of the
 * distance in the valley of the start (arguments checked by the callers). */
static int newton(const nf_surf_t *s, const double Q[3], double u0, double v0, double tol,
                  nf_proj_t *out)
{
    double dom[4];
    nf_surf_domain(s, &dom[0], &dom[1], &dom[2], &dom[3]);
    const double tu = tol * (dom[1] - dom[0]), tv = tol * (dom[3] - dom[2]);
    pt_t cur, trial;
    pt_eval(s, Q, clampd(u0, dom[0], dom[1]), clampd(v0, dom[2], dom[3]), &cur);
    int escapes = 0;
    for (int it = 0; it < NF_PROJ_MAX_ITERS; it++) {
        if (escapes < 2 && pole_escape(s, Q, dom, &cur, &trial)) {
            escapes++;
            cur = trial;
        }
        const int fu = !held(cur.u, dom[0], dom[1], cur.gu);
        const int fv = !held(cur.v, dom[2], dom[3], cur.gv);
        /* Stationary within the free parameters (projected gradient zero to
         * rounding): the Karush-Kuhn-Tucker point of the clamped problem. */
        const int zu = !fu || fabs(cur.gu) <= grad_noise(&cur, Q, cur.d + D_SU);
        const int zv = !fv || fabs(cur.gv) <= grad_noise(&cur, Q, cur.d + D_SV);
        if (zu && zv) {
            finish(s, Q, &cur, it, out);
            return NF_OK;
        }
        /* The joint step first; if it finds no descent, the step in u alone
         * and in v alone. Those matter where the surface is only C0 (degree
         * 1, or a p-fold knot): on the crease the joint step cannot descend
         * while the parameter along the crease still can. */
        int res = STEP_FAILED, onto_crease = 0;
        for (int mode = 0; mode < 3; mode++) {
            if (mode > 0 && (!fu || !fv || (mode == 1 ? zu : zv)))
                continue;
            double du, dv;
            const int newton = newton_step(&cur, mode != 2 && fu, mode != 1 && fv, &du, &dv);
            res = line_search(s, Q, dom, tu, tv, &cur, fu, fv, du, dv, newton, &trial);
            if (res == STEP_DESCENT)
                break;
            /* A last small step is kept unless it is worse beyond rounding:
             * where D cannot tell, Newton's step is the better judge. So is a
             * short step onto a crease, and the iteration goes on from it. */
            if ((res == STEP_SMALL || res == STEP_CREASE) && trial.D <= cur.D + d_noise(&cur, Q)) {
                onto_crease = res == STEP_CREASE;
                cur = trial;
                if (onto_crease || mode == 0)
                    break; /* mode 0 small: Newton has converged */
            }
        }
        if (res == STEP_DESCENT)
            cur = trial;
        else if (!onto_crease) {
            finish(s, Q, &cur, it + 1, out);
            return NF_OK;
        }
    }
    finish(s, Q, &cur, NF_PROJ_MAX_ITERS, out);
    return NF_ENOCONV;
}

/* ---- the true foot at the boundary (issue 14) ---- */

/* Samples of the boundary curve per knot span, and in all at most. */
#define EDGE_PER_SPAN 4
#define EDGE_MAX_SAMPLES 256

/* Newton from (u, v), its foot kept in *out when it converged and is
 * nearer; only argument errors stop. */
static int try_start(const nf_surf_t *s, const double Q[3], double u, double v, double tol,
                     nf_proj_t *out)
{
    nf_proj_t p;
    const int r = newton(s, Q, u, v, tol, &p);
    if (r != NF_OK && r != NF_ENOCONV)
        return r;
    if (r == NF_OK && fabs(p.dist) < fabs(out->dist))
        *out = p;
    return NF_OK;
}

/* Knot spans (non-empty) of K over the domain. */
static int span_count(const double *K, int n, int p)
{
    int c = 0;
    for (int i = p; i <= n; i++)
        c += K[i] < K[i + 1];
    return c > 0 ? c : 1;
}

/* Samples of an iso-parameter curve, cheaply: the basis across it is fixed
 * (computed once), and on each knot span along it the p + 1 control points
 * of the curve (homogeneous: weight in the fourth lane) are formed once, so
 * that a sample costs one 1-D basis and p + 1 four-wide sums instead of a
 * surface evaluation. A span whose curve piece provably lies far from Q is
 * not sampled at all: the piece lies in the convex hull of its control
 * points (weights positive), so within the sphere around their centre that
 * holds them, and a sphere further than the band (out's distance plus two
 * radii, as generous as the band of the samples) holds no start. */
typedef struct iso {
    const nf_surf_t *s;
    const double *Q;
    int dir;          /* 0: u fixed, the curve runs in v; 1: v fixed */
    int pf, pv, nvv;  /* degree across, degree along, control points along */
    const double *Kv; /* knots along */
    int kf;           /* span across */
    double Nf[NF_MAX_ORDER];
    int l;   /* span along whose curve points are in C (-1: none) */
    int far; /* span l is beyond the band */
    double C[NF_MAX_ORDER][4];
    double recip[NF_RECIP_LEN]; /* of span l: its basis without a division */
} iso_t;

static void iso_init(iso_t *c, const nf_surf_t *s, const double Q[3], int dir, double e)
{
    c->s = s;
    c->Q = Q;
    c->dir = dir;
    const double *Kf = dir == 0 ? s->U : s->V;
    const int nf = dir == 0 ? s->nu : s->nv;
    c->pf = dir == 0 ? s->p : s->q;
    c->pv = dir == 0 ? s->q : s->p;
    c->nvv = dir == 0 ? s->nv : s->nu;
    c->Kv = dir == 0 ? s->V : s->U;
    c->kf = nf_find_span(nf - 1, c->pf, e, Kf);
    nf_basis_funs(c->kf, e, c->pf, Kf, c->Nf);
    c->l = -1;
    c->far = 0;
}

/* S at parameter x along the curve into P and 1, or 0 (P untouched) when
 * x's span is beyond the band around distance d. Calls come with x
 * increasing (the span is searched forward from the last one). */
static int iso_eval(iso_t *c, double x, double d, double P[3])
{
    const nf_surf_t *s = c->s;
    /* Samples come in increasing x: the span only moves forward. */
    int l = c->l < 0 ? nf_find_span(c->nvv - 1, c->pv, x, c->Kv) : c->l;
    while (l < c->nvv - 1 && x >= c->Kv[l + 1])
        l++;
    if (l != c->l) {
        nf_basis_recip(l, c->pv, c->Kv, c->recip);
        double ctr[3] = {0.0, 0.0, 0.0};
        for (int a = 0; a <= c->pv; a++) {
            double h[4] = {0.0, 0.0, 0.0, 0.0};
            for (int b = 0; b <= c->pf; b++) {
                const int ia = l - c->pv + a, ib = c->kf - c->pf + b;
                const long k = c->dir == 0 ? ib + (long)ia * s->nu : ia + (long)ib * s->nu;
                const double w = s->w ? s->w[k] : 1.0, f = c->Nf[b] * w;
                h[0] += f * s->cp[3 * k];
                h[1] += f * s->cp[3 * k + 1];
                h[2] += f * s->cp[3 * k + 2];
                h[3] += f;
            }
            for (int m = 0; m < 4; m++)
                c->C[a][m] = h[m];
            for (int m = 0; m < 3; m++)
                ctr[m] += h[m] / h[3] / (c->pv + 1);
        }
        double r2 = 0.0;
        for (int a = 0; a <= c->pv; a++) {
            double e2 = 0.0;
            for (int m = 0; m < 3; m++)
                e2 += (c->C[a][m] / c->C[a][3] - ctr[m]) * (c->C[a][m] / c->C[a][3] - ctr[m]);
            r2 = fmax(r2, e2);
        }
        const double dq =
            sqrt((ctr[0] - c->Q[0]) * (ctr[0] - c->Q[0]) + (ctr[1] - c->Q[1]) * (ctr[1] - c->Q[1]) +
                 (ctr[2] - c->Q[2]) * (ctr[2] - c->Q[2]));
        c->far = dq - sqrt(r2) > d + 2.0 * sqrt(r2);
        c->l = l;
    }
    if (c->far)
        return 0;
    double N[NF_MAX_ORDER], h[4] = {0.0, 0.0, 0.0, 0.0};
    nf_basis_funs_r(l, x, c->pv, c->Kv, c->recip, N);
    for (int a = 0; a <= c->pv; a++)
        for (int m = 0; m < 4; m++)
            h[m] += N[a] * c->C[a][m];
    const double iw = 1.0 / h[3];
    for (int m = 0; m < 3; m++)
        P[m] = h[m] * iw;
    return 1;
}

/* Local minima of the samples kept per curve (the nearest ones). */
#define EDGE_MAX_STARTS 8

/* Newton from the local minima of the distance over samples of the
 * iso-parameter curve x = e (dir 0: u = e, the curve runs in v; dir 1:
 * v = e), EDGE_PER_SPAN per knot span along it (EDGE_MAX_SAMPLES at most),
 * the nearest converged foot kept in out. The curve passes through out's
 * foot at parameter f along it: the minimum within a sample spacing of it
 * is the foot's own valley and gets no restart. The others only when
 * within two chords (the longest between neighbouring samples) of out's
 * distance: a valley whose samples all lie further cannot be nearer
 * (the band of nf_seed_starts). Three samples in a sliding window find
 * the minima, the ends counting when below their one neighbour. */
static int curve_minima(const nf_surf_t *s, const double Q[3], int dir, double e, double f,
                        double tol, const double dom[4], nf_proj_t *out)
{
    const double *K = dir == 0 ? s->V : s->U;
    const int n = dir == 0 ? s->nv - 1 : s->nu - 1, p = dir == 0 ? s->q : s->p;
    const double a = dom[2 - 2 * dir], b = dom[3 - 2 * dir];
    int ns = EDGE_PER_SPAN * span_count(K, n, p) + 1;
    ns = ns > EDGE_MAX_SAMPLES ? EDGE_MAX_SAMPLES : ns;
    const double h = (b - a) / (ns - 1);
    double dprev = INFINITY, dcur = INFINITY, xcur = a, chord = 0.0, Pp[3] = {0, 0, 0};
    int havep = 0;
    double sd[EDGE_MAX_STARTS], sx[EDGE_MAX_STARTS];
    int nst = 0;
    iso_t iso;
    iso_init(&iso, s, Q, dir, e);
    const double d0 = fabs(out->dist);
    for (int i = 0; i <= ns; i++) {
        double dnext = INFINITY, x = 0.0;
        if (i < ns) {
            x = i == ns - 1 ? b : a + h * i;
            double P[3];
            if (iso_eval(&iso, x, d0, P)) {
                const double dx = P[0] - Q[0], dy = P[1] - Q[1], dz = P[2] - Q[2];
                dnext = dx * dx + dy * dy + dz * dz;
                if (havep) {
                    const double cx = P[0] - Pp[0], cy = P[1] - Pp[1], cz = P[2] - Pp[2];
                    chord = fmax(chord, cx * cx + cy * cy + cz * cz);
                }
                Pp[0] = P[0];
                Pp[1] = P[1];
                Pp[2] = P[2];
                havep = 1;
            } else {
                havep = 0; /* a span beyond the band: no sample, no start */
            }
        }
        if (i > 0 && dcur < INFINITY && dcur <= dprev && dcur <= dnext && fabs(xcur - f) > h) {
            /* Keep the EDGE_MAX_STARTS nearest minima, sorted. */
            int t = nst < EDGE_MAX_STARTS
                        ? nst++
                        : (dcur < sd[EDGE_MAX_STARTS - 1] ? EDGE_MAX_STARTS - 1 : -1);
            for (; t > 0 && sd[t - 1] > dcur; t--) {
                sd[t] = sd[t - 1];
                sx[t] = sx[t - 1];
            }
            if (t >= 0) {
                sd[t] = dcur;
                sx[t] = xcur;
            }
        }
        dprev = dcur;
        dcur = dnext;
        xcur = x;
    }
    const double c2 = 2.0 * sqrt(chord);
    for (int t = 0; t < nst; t++) {
        if (!(sqrt(sd[t]) < fabs(out->dist) + c2))
            break; /* sorted: the rest are further still */
        const int r = try_start(s, Q, dir == 0 ? e : sx[t], dir == 0 ? sx[t] : e, tol, out);
        if (r != NF_OK)
            return r;
    }
    return NF_OK;
}

static int edge_check(const nf_surf_t *s, const double Q[3], double tol, nf_proj_t *out)
{
    if (!out->clamped)
        return NF_OK;
    double dom[4];
    nf_surf_domain(s, &dom[0], &dom[1], &dom[2], &dom[3]);
    const nf_proj_t first = *out;
    for (int dir = 0; dir < 2; dir++) {
        const double x = dir == 0 ? first.u : first.v;
        const double lo = dom[2 * dir], hi = dom[2 * dir + 1];
        if (x != lo && x != hi)
            continue;
        /* (a) the boundary curve the foot lies on: its other minima (held
         * on the edge, Newton is the 1-D Newton along it; where the
         * distance falls inward it leaves the edge into that valley). */
        int r = curve_minima(s, Q, dir, x, dir == 0 ? first.v : first.u, tol, dom, out);
        /* (b) the curve across the edge through the foot: the interior
         * valleys beside the edge, also those a fold puts near in space but
         * far in parameter (a hem's plate under its free edge). */
        if (r == NF_OK)
            r = curve_minima(s, Q, 1 - dir, dir == 0 ? first.v : first.u, x, tol, dom, out);
        if (r != NF_OK)
            return r;
    }
    return NF_OK;
}

int nf_project_edge(const nf_surf_t *s, const double Q[3], double tol, nf_proj_t *out)
{
    if (!s || !Q || !out || !s->U || !s->V || !s->cp || !(tol > 0.0 && tol < 1.0))
        return NF_EARG;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    return edge_check(s, Q, tol, out);
}

/* Newton from the start, and a boundary foot checked against the edge's
 * other minima and the valleys beside it (the true foot, issue 14). A
 * start whose Newton did not converge keeps NF_ENOCONV unless the check
 * found a nearer foot (restarts keep converged feet only). */
int nf_project(const nf_surf_t *s, const double Q[3], double u0, double v0, double tol,
               nf_proj_t *out)
{
    if (!s || !Q || !out || !s->U || !s->V || !s->cp)
        return NF_EARG;
    if (!(tol > 0.0 && tol < 1.0) || !(u0 - u0 == 0.0) || !(v0 - v0 == 0.0))
        return NF_EARG;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    int rc = newton(s, Q, u0, v0, tol, out);
    if (rc != NF_OK && rc != NF_ENOCONV)
        return rc;
    if (out->clamped) {
        const nf_proj_t first = *out;
        const int r = edge_check(s, Q, tol, out);
        if (r != NF_OK)
            return r;
        if (fabs(out->dist) < fabs(first.dist))
            rc = NF_OK; /* a restart's converged foot */
    }
    return rc;
}

/* Parameter of sample i of n over [a, b]: uniform, both ends exact. */
static double sample_at(int i, int n, double a, double b)
{
    if (n == 1)
        return 0.5 * a + 0.5 * b;
    return i == n - 1 ? b : a + (b - a) * i / (n - 1);
}

/* u samples whose bases a chunk keeps for all rows, and the control point
 * columns a chunk may span (at least one sample's p + 1 always fit). */
#define SEED_CHUNK 16
#define SEED_COLS (SEED_CHUNK + NF_MAX_ORDER)

/* The grid as a tensor product, evaluated separably: the u bases and spans
 * of a chunk of u samples once for all rows, per row the v basis once and
 * the chunk's columns contracted with it (homogeneous for a rational
 * surface), then each sample a (p + 1)-term sum. nf_surf_eval per sample
 * found both spans and both bases every time. Bounded stack, no heap. */
static void seed_eval(const nf_surf_t *s, int nsu, int nsv, double *pts)
{
    const int p = s->p, q = s->q, rat = s->w ? 1 : 0;
    const long n2 = (long)nsu * nsv;
    double ua, ub, va, vb;
    nf_surf_domain(s, &ua, &ub, &va, &vb);
    const double hu = (s->nu - p) / (ub - ua), hv = (s->nv - q) / (vb - va);
    double Nu[SEED_CHUNK][NF_MAX_ORDER], Nv[NF_MAX_ORDER], H[SEED_COLS][4];
    int lu[SEED_CHUNK];
    int l = -1;
    for (int i0 = 0; i0 < nsu;) {
        int n = 0;
        for (; n < SEED_CHUNK && i0 + n < nsu; n++) {
            const double u = clampd(sample_at(i0 + n, nsu, ua, ub), ua, ub);
            const int ln = nf_find_span_from(l, s->nu - 1, p, u, s->U, hu);
            if (n > 0 && ln - lu[0] + p + 1 > SEED_COLS)
                break; /* the next chunk starts with it */
            l = lu[n] = ln;
            nf_basis_funs(ln, u, p, s->U, Nu[n]);
        }
        const int c0 = lu[0] - p, nc = lu[n - 1] - c0 + 1;
        int k = -1;
        for (int j = 0; j < nsv; j++) {
            const double v = clampd(sample_at(j, nsv, va, vb), va, vb);
            k = nf_find_span_from(k, s->nv - 1, q, v, s->V, hv);
            nf_basis_funs(k, v, q, s->V, Nv);
            for (int c = 0; c < nc; c++)
                H[c][0] = H[c][1] = H[c][2] = H[c][3] = 0.0;
            for (int b = 0; b <= q; b++) {
                const long row = (long)(k - q + b) * s->nu + c0;
                const double *P = s->cp + 3 * row;
                for (int c = 0; c < nc; c++) {
                    const double f = rat ? Nv[b] * s->w[row + c] : Nv[b];
                    H[c][0] += f * P[3 * c];
                    H[c][1] += f * P[3 * c + 1];
                    H[c][2] += f * P[3 * c + 2];
                    H[c][3] += f;
                }
            }
            for (int t = 0; t < n; t++) {
                const double(*h)[4] = H + (lu[t] - p - c0);
                double X[4] = {0.0, 0.0, 0.0, 0.0};
                for (int a = 0; a <= p; a++)
                    for (int c = 0; c < 4; c++)
                        X[c] += Nu[t][a] * h[a][c];
                const double inv = rat ? 1.0 / X[3] : 1.0;
                const long kk = i0 + t + (long)j * nsu;
                pts[kk] = X[0] * inv;
                pts[n2 + kk] = X[1] * inv;
                pts[2 * n2 + kk] = X[2] * inv;
            }
        }
        i0 += n;
    }
}

void nf_seed_init_uv(nf_seed_t *g, const nf_surf_t *s, int nsu, int nsv, double *pts)
{
    nsu = nsu < 1 ? 1 : (nsu > NF_SEED_MAX_NS ? NF_SEED_MAX_NS : nsu);
    nsv = nsv < 1 ? 1 : (nsv > NF_SEED_MAX_NS ? NF_SEED_MAX_NS : nsv);
    g->s = s;
    g->ns = nsu == nsv ? nsu : 0;
    g->nsu = nsu;
    g->nsv = nsv;
    g->pts = pts;
    const long n2 = (long)nsu * nsv;
    seed_eval(s, nsu, nsv, pts);
    double h2 = 0.0;
    for (long k = 0; k < n2; k++) {
        const int i = (int)(k % nsu);
        const long nb[2] = {i + 1 < nsu ? k + 1 : -1, k + nsu < n2 ? k + nsu : -1};
        for (int t = 0; t < 2; t++) {
            if (nb[t] < 0)
                continue;
            const double dx = pts[nb[t]] - pts[k], dy = pts[n2 + nb[t]] - pts[n2 + k],
                         dz = pts[2 * n2 + nb[t]] - pts[2 * n2 + k];
            h2 = fmax(h2, dx * dx + dy * dy + dz * dz);
        }
    }
    g->reach = 2.0 * sqrt(h2);
}

void nf_seed_init(nf_seed_t *g, const nf_surf_t *s, int ns, double *pts)
{
    nf_seed_init_uv(g, s, ns, ns, pts);
}

static int clampi(double x, int lo, int hi)
{
    return x < lo ? lo : (x > hi ? hi : (int)x);
}

void nf_seed_size(const nf_surf_t *s, long cap, int *nsu, int *nsv)
{
    int su = 0, sv = 0;
    for (int i = s->p; i < s->nu; i++)
        su += s->U[i] < s->U[i + 1];
    for (int j = s->q; j < s->nv; j++)
        sv += s->V[j] < s->V[j + 1];
    /* Mean lengths of the control polygons of the rows and of the columns:
     * how long the surface is in u and in v (the polygon bounds the curve). */
    double lu = 0.0, lv = 0.0;
    for (int j = 0; j < s->nv; j++)
        for (int i = 0; i < s->nu; i++) {
            const double *P = s->cp + 3 * (i + (long)j * s->nu);
            double du = 0.0, dv = 0.0;
            for (int c = 0; c < 3 && i + 1 < s->nu; c++)
                du += (P[3 + c] - P[c]) * (P[3 + c] - P[c]);
            for (int c = 0; c < 3 && j + 1 < s->nv; c++)
                dv += (P[3L * s->nu + c] - P[c]) * (P[3L * s->nu + c] - P[c]);
            lu += sqrt(du);
            lv += sqrt(dv);
        }
    lu /= s->nv;
    lv /= s->nu;
    /* At most 8 samples per knot span and direction, and at most cap. */
    double budget = (8.0 * su + 1.0) * (8.0 * sv + 1.0);
    budget = budget < (double)cap ? budget : (double)cap;
    if (budget < 4.0) {
        *nsu = *nsv = 1;
        return;
    }
    /* Spread the samples evenly in space (nsu / nsv = lu / lv), so that a
     * long thin surface is sampled along its length finely enough for the
     * start to land in the right valley, but keep 4 samples per span (and
     * at least 2) across it to resolve its shape that way too. */
    const double root = sqrt(budget);
    const int lo_u = clampi(4.0 * su + 1.0, 2, (int)root),
              lo_v = clampi(4.0 * sv + 1.0, 2, (int)root);
    const double ratio = (lu > 0.0 && lv > 0.0) ? lu / lv : 1.0;
    const int hi_u = clampi(budget / lo_v, lo_u, NF_SEED_MAX_NS);
    *nsu = clampi(floor(sqrt(budget * ratio) + 0.5), lo_u, hi_u);
    *nsv = clampi(floor(budget / *nsu), lo_v, NF_SEED_MAX_NS);
}

static double sample_d2(const nf_seed_t *g, long k, const double Q[3])
{
    const long n2 = (long)g->nsu * g->nsv;
    const double dx = g->pts[k] - Q[0], dy = g->pts[n2 + k] - Q[1], dz = g->pts[2 * n2 + k] - Q[2];
    return dx * dx + dy * dy + dz * dz;
}

/* No grid neighbour (4-neighbourhood) of sample k is strictly nearer. */
static int grid_local_min(const nf_seed_t *g, long k, double d, const double Q[3])
{
    const int i = (int)(k % g->nsu), j = (int)(k / g->nsu);
    return !((i > 0 && sample_d2(g, k - 1, Q) < d) ||
             (i + 1 < g->nsu && sample_d2(g, k + 1, Q) < d) ||
             (j > 0 && sample_d2(g, k - g->nsu, Q) < d) ||
             (j + 1 < g->nsv && sample_d2(g, k + g->nsu, Q) < d));
}

int nf_seed_local_min(const nf_seed_t *g, long k, const double Q[3])
{
    return grid_local_min(g, k, sample_d2(g, k, Q), Q);
}

/* The samples are searched tile by tile, SEED_TILE x SEED_TILE samples
 * around a centre sample c: every sample of the tile is within
 * SEED_TILE / 2 reach of c (at most SEED_TILE grid steps of at most
 * reach / 2), so a tile whose centre is further than that beyond the band
 * below cannot hold a candidate and is skipped unread. The search stays
 * exact (the nearest sample and every local minimum within the band are
 * found) and reads a few tiles instead of the whole grid. */
#define SEED_TILE 8

/* Index of the centre sample of tile (ti, tj). */
static long tile_centre(const nf_seed_t *g, int ti, int tj)
{
    const int i =
        ti * SEED_TILE + SEED_TILE / 2 < g->nsu ? ti * SEED_TILE + SEED_TILE / 2 : g->nsu - 1;
    const int j =
        tj * SEED_TILE + SEED_TILE / 2 < g->nsv ? tj * SEED_TILE + SEED_TILE / 2 : g->nsv - 1;
    return i + (long)j * g->nsu;
}

typedef struct seed_search {
    const nf_seed_t *g;
    const double *Q;
    int k, found;
    double best, thr;
    double bd[NF_SEED_MAX_STARTS];
    long bk[NF_SEED_MAX_STARTS];
} seed_search_t;

/* The band: only a valley whose samples come within reach of the nearest
 * sample's distance can hold the nearest foot (its own nearest sample is
 * within reach of it). */
static void search_thr(seed_search_t *ss)
{
    const double band = sqrt(ss->best) + ss->g->reach;
    ss->thr = band * band;
    if (ss->found == ss->k && ss->bd[ss->k - 1] < ss->thr)
        ss->thr = ss->bd[ss->k - 1];
}

static void search_sample(seed_search_t *ss, long i, double d)
{
    if (!(d < ss->thr))
        return;
    if (d < ss->best) {
        ss->best = d;
        search_thr(ss);
    }
    if (!grid_local_min(ss->g, i, d, ss->Q))
        return;
    int t = ss->found < ss->k ? ss->found : ss->k - 1;
    for (; t > 0 && ss->bd[t - 1] > d; t--) {
        ss->bd[t] = ss->bd[t - 1];
        ss->bk[t] = ss->bk[t - 1];
    }
    ss->bd[t] = d;
    ss->bk[t] = i;
    ss->found += ss->found < ss->k;
    search_thr(ss);
}

static void search_tile(seed_search_t *ss, int ti, int tj)
{
    const nf_seed_t *g = ss->g;
    const int i1 = ti * SEED_TILE + SEED_TILE < g->nsu ? ti * SEED_TILE + SEED_TILE : g->nsu;
    const int j1 = tj * SEED_TILE + SEED_TILE < g->nsv ? tj * SEED_TILE + SEED_TILE : g->nsv;
    for (int j = tj * SEED_TILE; j < j1; j++)
        for (int i = ti * SEED_TILE; i < i1; i++) {
            const long k = i + (long)j * g->nsu;
            search_sample(ss, k, sample_d2(g, k, ss->Q));
        }
}

int nf_seed_starts(const nf_seed_t *g, const double Q[3], int k, double *u0, double *v0)
{
    seed_search_t ss;
    ss.g = g;
    ss.Q = Q;
    ss.k = k < 1 ? 1 : (k > NF_SEED_MAX_STARTS ? NF_SEED_MAX_STARTS : k);
    ss.found = 0;
    ss.best = ss.thr = INFINITY;
    for (int t = 0; t < ss.k; t++) {
        ss.bd[t] = INFINITY;
        ss.bk[t] = 0;
    }
    const int ntu = (g->nsu + SEED_TILE - 1) / SEED_TILE,
              ntv = (g->nsv + SEED_TILE - 1) / SEED_TILE;
    const double rad = SEED_TILE / 2 * g->reach;
    /* The tile with the nearest centre first: a tight band early. */
    double dc = INFINITY;
    int ci = 0, cj = 0;
    for (int tj = 0; tj < ntv; tj++)
        for (int ti = 0; ti < ntu; ti++) {
            const double d = sample_d2(g, tile_centre(g, ti, tj), Q);
            if (d < dc) {
                dc = d;
                ci = ti;
                cj = tj;
            }
        }
    search_tile(&ss, ci, cj);
    for (int tj = 0; tj < ntv; tj++)
        for (int ti = 0; ti < ntu; ti++) {
            if (ti == ci && tj == cj)
                continue;
            const double d = sqrt(sample_d2(g, tile_centre(g, ti, tj), Q));
            if (d - rad < sqrt(ss.thr)) /* else no sample of the tile is inside the band */
                search_tile(&ss, ti, tj);
        }
    /* Starts found before the nearest sample was met may lie beyond its band. */
    const double band = sqrt(ss.bd[0]) + g->reach;
    int found = ss.found;
    while (found > 1 && !(ss.bd[found - 1] < band * band))
        found--;
    if (!found) /* every distance overflowed (or Q is not finite) */
        found = 1;
    double ua, ub, va, vb;
    nf_surf_domain(g->s, &ua, &ub, &va, &vb);
    for (int t = 0; t < found; t++) {
        u0[t] = sample_at((int)(ss.bk[t] % g->nsu), g->nsu, ua, ub);
        v0[t] = sample_at((int)(ss.bk[t] / g->nsu), g->nsv, va, vb);
    }
    return found;
}

void nf_seed_start(const nf_seed_t *g, const double Q[3], double *u0, double *v0)
{
    nf_seed_starts(g, Q, 1, u0, v0);
}

/* The crease (C0 knot) nearest x within h, in *c; 0 when there is none. */
static int crease_near(const double *K, int n, int p, double x, double h, double *c)
{
    const int k = nf_find_span(n, p, x, K);
    double dbest = INFINITY;
    for (int i = k; i > p && x - K[i] <= h; i--) /* below (or at) x: last of a p-fold run */
        if (K[i] > K[p] && K[i - p + 1] == K[i]) {
            *c = K[i];
            dbest = x - K[i];
            break;
        }
    for (int i = k + 1; i <= n && K[i] - x <= h; i++) /* above x: first of a p-fold run */
        if (K[i + p - 1] == K[i]) {
            if (K[i] - x < dbest) {
                *c = K[i];
                dbest = K[i] - x;
            }
            break;
        }
    return dbest < INFINITY;
}

/* Keep p in *out when it is the better result (nearer; converged first). */
static void keep_best(const nf_proj_t *p, int r, nf_proj_t *out, int *rc, int first)
{
    if (first || (r == NF_OK && *rc != NF_OK) ||
        ((r == NF_OK || *rc != NF_OK) && fabs(p->dist) < fabs(out->dist))) {
        *out = *p;
        *rc = r;
    }
}

int nf_project_seeded(const nf_seed_t *g, const double Q[3], double tol, nf_proj_t *out)
{
    if (!g || !g->s || !g->pts || !Q || !out)
        return NF_EARG;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    double u0[NF_PROJ_STARTS], v0[NF_PROJ_STARTS];
    const int n = nf_seed_starts(g, Q, NF_PROJ_STARTS, u0, v0);
    return nf_project_starts(g, Q, u0, v0, n, tol, out);
}

int nf_project_starts(const nf_seed_t *g, const double Q[3], const double *u0, const double *v0,
                      int n, double tol, nf_proj_t *out)
{
    if (!g || !g->s || !Q || !u0 || !v0 || n < 1 || !out)
        return NF_EARG;
    const nf_surf_t *s = g->s;
    int rc = NF_ENOCONV;
    for (int t = 0; t < n; t++) {
        nf_proj_t p;
        const int r = nf_project(s, Q, u0[t], v0[t], tol, &p);
        if (r != NF_OK && r != NF_ENOCONV)
            return r;
        keep_best(&p, r, out, &rc, t == 0);
    }
    /* A foot within a sample spacing of a crease: over a valley crease the
     * distance has a minimum on each side, and the samples (a spacing
     * apart) cannot tell which valley is deeper. Newton is started once
     * more across the crease, at the mirror image of the foot. */
    double ua, ub, va, vb;
    nf_surf_domain(s, &ua, &ub, &va, &vb);
    const double hu = (ub - ua) / (g->nsu > 1 ? g->nsu - 1 : 1);
    const double hv = (vb - va) / (g->nsv > 1 ? g->nsv - 1 : 1);
    const double fu = out->u, fv = out->v;
    for (int dir = 0; dir < 2; dir++) {
        const double f = dir == 0 ? fu : fv;
        double c;
        if (!(dir == 0 ? crease_near(s->U, s->nu - 1, s->p, fu, hu, &c)
                       : crease_near(s->V, s->nv - 1, s->q, fv, hv, &c)))
            continue;
        /* On the crease itself: a start a tenth of a spacing to either side. */
        const double h = dir == 0 ? hu : hv;
        for (int side = 0; side < (c == f ? 2 : 1); side++) {
            const double m = c == f ? f + (side ? 0.1 : -0.1) * h : 2.0 * c - f;
            nf_proj_t p;
            const int r = nf_project(s, Q, dir == 0 ? m : fu, dir == 0 ? fv : m, tol, &p);
            if (r != NF_OK && r != NF_ENOCONV)
                return r;
            keep_best(&p, r, out, &rc, 0);
        }
    }
    return rc;
}
