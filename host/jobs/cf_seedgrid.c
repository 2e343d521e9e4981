/* SPDX-License-Identifier: MIT */
/* cf_seedgrid.c: start points for projection: the quadrilateral
 * decomposition (nf_quad), else the nearest seed sample by a 3-D cell grid. */
#include "cf_seedgrid.h"
#include "cf_err.h"
#include "nf_err.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SG_MAX_DIM 512

static int clampi(long x, int hi)
{
    return x < 0 ? 0 : (x > hi ? hi : (int)x);
}

static long cell_index(const cf_seedgrid_t *g, double x, double y, double z)
{
    const int ix = clampi((long)floor((x - g->lo[0]) / g->cell), g->dim[0] - 1);
    const int iy = clampi((long)floor((y - g->lo[1]) / g->cell), g->dim[1] - 1);
    const int iz = clampi((long)floor((z - g->lo[2]) / g->cell), g->dim[2] - 1);
    return ix + (long)g->dim[0] * (iy + (long)g->dim[1] * iz);
}

int cf_seedgrid_init(cf_seedgrid_t *g, const nf_surf_t *s, int per_span)
{
    return cf_seedgrid_init_n(g, s, per_span, -1);
}

int cf_seedgrid_init_n(cf_seedgrid_t *g, const nf_surf_t *s, int per_span, long points)
{
    memset(g, 0, sizeof *g);
    g->seed.s = s;
    /* The quadrilaterals when the surface is projectable to a plane (the
     * paper's assumption, Section 3.2): over a fold two layers of the
     * surface share the plane's cells and the nearest quadrilateral in the
     * cell need not be the nearest in space, so the 3-D grid is kept. */
    const size_t qb = NF_QUAD_BYTES(CF_SEEDGRID_MAXQ, s->nu, s->nv);
    g->qmem = malloc(qb);
    /* the finer blanket for closer starts, the paper's when it does not fit
     * or when too few points follow to repay it */
    const nf_quad_params_t fine = {NF_QUAD_SEED_TOL, 0.0, 0}, paper = {NF_QUAD_REL_TOL, 0.0, 0};
    const int fine_first = !(points >= 0 && points < CF_SEEDGRID_FINE_POINTS);
    int rc = g->qmem ? nf_quad_init(&g->quad, s, fine_first ? &fine : &paper, CF_SEEDGRID_MAXQ,
                                    g->qmem, qb)
                     : NF_EARG;
    if (rc == NF_EBUDGET && fine_first)
        rc = nf_quad_init(&g->quad, s, &paper, CF_SEEDGRID_MAXQ, g->qmem, qb);
    if (g->qmem && rc == NF_OK && !g->quad.folded) {
        g->use_quad = 1;
        /* Without its memory Newton keeps the basis path: slower, the same feet. */
        const size_t pb = NF_QUAD_POWER_BYTES(s->nu, s->nv);
        g->pf = pb ? malloc(pb) : NULL;
        if (g->pf && nf_quad_power(&g->quad, g->pf, pb) != NF_OK) {
            free(g->pf);
            g->pf = NULL;
        }
        return CF_OK;
    }
    free(g->qmem);
    g->qmem = NULL;
    int spans = (s->nu - s->p) > (s->nv - s->q) ? (s->nu - s->p) : (s->nv - s->q);
    long ns = (long)per_span * spans + 1;
    ns = ns > 1024 ? 1024 : (ns < 16 ? 16 : ns);
    const long n2 = ns * ns;
    g->pts = malloc(sizeof(double) * 3 * (size_t)n2);
    g->next = malloc(sizeof(int) * (size_t)n2);
    if (!g->pts || !g->next) {
        cf_seedgrid_free(g);
        return CF_ENOMEM;
    }
    nf_seed_init(&g->seed, s, (int)ns, g->pts);
    const double *X = g->pts, *Y = X + n2, *Z = Y + n2;
    double hi[3];
    for (int c = 0; c < 3; c++) {
        g->lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (long k = 0; k < n2; k++) {
        const double P[3] = {X[k], Y[k], Z[k]};
        for (int c = 0; c < 3; c++) {
            g->lo[c] = fmin(g->lo[c], P[c]);
            hi[c] = fmax(hi[c], P[c]);
        }
    }
    /* About two samples per cell along the surface; no axis over SG_MAX_DIM
     * cells and no more cells than 4 per sample. */
    double ext = fmax(hi[0] - g->lo[0], fmax(hi[1] - g->lo[1], hi[2] - g->lo[2]));
    g->cell = ext > 0 ? 2.0 * ext / (double)(ns - 1) : 1.0;
    for (;;) {
        long cells = 1;
        for (int c = 0; c < 3; c++) {
            double d = floor((hi[c] - g->lo[c]) / g->cell) + 1;
            g->dim[c] = d > SG_MAX_DIM ? SG_MAX_DIM + 1 : (int)d;
            cells *= g->dim[c];
        }
        if (g->dim[0] <= SG_MAX_DIM && g->dim[1] <= SG_MAX_DIM && g->dim[2] <= SG_MAX_DIM &&
            cells <= 4 * n2)
            break;
        g->cell *= 1.5;
    }
    const long cells = (long)g->dim[0] * g->dim[1] * g->dim[2];
    g->head = malloc(sizeof(int) * (size_t)cells);
    if (!g->head) {
        cf_seedgrid_free(g);
        return CF_ENOMEM;
    }
    for (long i = 0; i < cells; i++)
        g->head[i] = -1;
    g->sreach = calloc((size_t)n2, sizeof(float));
    g->breach = calloc((size_t)cells, sizeof(float));
    g->rreach = calloc((size_t)g->dim[1] * (size_t)g->dim[2], sizeof(float));
    if (!g->sreach || !g->breach || !g->rreach) {
        cf_seedgrid_free(g);
        return CF_ENOMEM;
    }
    /* The local reach: a surface point of a grid cell is within twice its
     * longest edge chord of each corner (nf_seed's reach, cell by cell). */
    for (long j = 0; j + 1 < ns; j++)
        for (long i = 0; i + 1 < ns; i++) {
            const long c[4] = {i + j * ns, i + 1 + j * ns, i + (j + 1) * ns, i + 1 + (j + 1) * ns};
            static const int e[4][2] = {{0, 1}, {2, 3}, {0, 2}, {1, 3}};
            double h2 = 0.0;
            for (int t = 0; t < 4; t++) {
                const long a = c[e[t][0]], b = c[e[t][1]];
                const double dx = X[a] - X[b], dy = Y[a] - Y[b], dz = Z[a] - Z[b];
                h2 = fmax(h2, dx * dx + dy * dy + dz * dz);
            }
            /* up: a float rounds by at most 2^-24 of it */
            const float r = (float)(2.0 * sqrt(h2) * (1.0 + 1e-6));
            for (int t = 0; t < 4; t++)
                g->sreach[c[t]] = g->sreach[c[t]] > r ? g->sreach[c[t]] : r;
        }
    for (long k = n2 - 1; k >= 0; k--) {
        const long ci = cell_index(g, X[k], Y[k], Z[k]);
        g->next[k] = g->head[ci];
        g->head[ci] = (int)k;
        const float r = g->sreach[k];
        g->breach[ci] = g->breach[ci] > r ? g->breach[ci] : r;
        g->rreach[ci / g->dim[0]] = g->rreach[ci / g->dim[0]] > r ? g->rreach[ci / g->dim[0]] : r;
    }
    return CF_OK;
}

/* The sample nearest Q (exact), by cells in growing shells around Q's
 * cell c0; its squared distance in *d2. */
static long nearest(const cf_seedgrid_t *g, const double Q[3], const int c0[3], double *d2)
{
    const long n2 = (long)g->seed.ns * g->seed.ns;
    const double *X = g->pts, *Y = X + n2, *Z = Y + n2;
    const int rmax = g->dim[0] > g->dim[1] ? (g->dim[0] > g->dim[2] ? g->dim[0] : g->dim[2])
                                           : (g->dim[1] > g->dim[2] ? g->dim[1] : g->dim[2]);
    double best = INFINITY;
    long bk = 0;
    for (int r = 0; r <= rmax; r++) {
        for (int dz = -r; dz <= r; dz++) {
            int iz = c0[2] + dz;
            if (iz < 0 || iz >= g->dim[2])
                continue;
            for (int dy = -r; dy <= r; dy++) {
                int iy = c0[1] + dy;
                if (iy < 0 || iy >= g->dim[1])
                    continue;
                /* Only the shell: interior cells were searched at smaller r. */
                int step = (abs(dz) == r || abs(dy) == r) ? 1 : 2 * r;
                for (int dx = -r; dx <= r; dx += step ? step : 1) {
                    int ix = c0[0] + dx;
                    if (ix < 0 || ix >= g->dim[0])
                        continue;
                    long ci = ix + (long)g->dim[0] * (iy + (long)g->dim[1] * iz);
                    for (int k = g->head[ci]; k >= 0; k = g->next[k]) {
                        double dx3 = X[k] - Q[0], dy3 = Y[k] - Q[1], dz3 = Z[k] - Q[2];
                        double d = dx3 * dx3 + dy3 * dy3 + dz3 * dz3;
                        if (d < best) {
                            best = d;
                            bk = k;
                        }
                    }
                    if (r == 0)
                        break;
                }
            }
        }
        /* Cells beyond shell r are at least r cells from Q's cell. */
        if (best < INFINITY && sqrt(best) <= r * g->cell)
            break;
    }
    *d2 = best;
    return bk;
}

/* Distance from x to cell i's extent along axis c (0 inside; the first
 * and last cells open outward, as the clamped binning puts samples there),
 * less slack, at least 0. */
static double cell_gap(const cf_seedgrid_t *g, int c, int i, double x, double slack)
{
    const double a = g->lo[c] + g->cell * i, b = a + g->cell;
    double d = 0.0;
    if (i > 0 && x < a)
        d = a - x;
    else if (i < g->dim[c] - 1 && x > b)
        d = x - b;
    return d > slack ? d - slack : 0.0;
}

/* Steepest descent of the distance to Q over the sample grid from sample
 * k (squared distance *d): to the nearest 4-neighbour while one is
 * strictly nearer; the local minimum it ends on (nf_seed_local_min's). */
static long descend(const cf_seedgrid_t *g, long k, const double Q[3], double *d)
{
    const long ns = g->seed.ns, n2 = ns * ns;
    const double *X = g->pts, *Y = X + n2, *Z = Y + n2;
    for (;;) {
        const long i = k % ns, j = k / ns;
        const long nb[4] = {i > 0 ? k - 1 : -1, i + 1 < ns ? k + 1 : -1, j > 0 ? k - ns : -1,
                            j + 1 < ns ? k + ns : -1};
        long bk = k;
        for (int t = 0; t < 4; t++) {
            if (nb[t] < 0)
                continue;
            const double dx = X[nb[t]] - Q[0], dy = Y[nb[t]] - Q[1], dz = Z[nb[t]] - Q[2];
            const double e = dx * dx + dy * dy + dz * dz;
            if (e < *d) {
                *d = e;
                bk = nb[t];
            }
        }
        if (bk == k)
            return k;
        k = bk;
    }
}

/* Q's cell. */
static void cell_of(const cf_seedgrid_t *g, const double Q[3], int c0[3])
{
    for (int c = 0; c < 3; c++)
        c0[c] = clampi((long)floor((Q[c] - g->lo[c]) / g->cell), g->dim[c] - 1);
}

/* The starts of the valleys that may hold a foot no further than core
 * from Q (core: the distance to some point of the surface), after the
 * found ones in ks and bd (squared distances; first < NF_PROJ_STARTS):
 * up to NF_PROJ_STARTS in all, nearest first. Returns how many. */
static int band_starts(const cf_seedgrid_t *g, const double Q[3], const int c0[3], double core,
                       long *ks, double *bd, int found)
{
    const long n2 = (long)g->seed.ns * g->seed.ns;
    const double *X = g->pts, *Y = X + n2, *Z = Y + n2;
    const double band = core + g->seed.reach, band2 = band * band;
    /* A cell r cells from Q's cell is at least (r - 1) cells from Q. */
    const double rr = floor(band / g->cell) + 1;
    const int R = rr > SG_MAX_DIM ? SG_MAX_DIM : (int)rr;
    long key[NF_PROJ_STARTS]; /* (cell, sample): ties ordered as a scan by cells */
    for (int t = 0; t < found; t++)
        key[t] = -1;
    const int first = found; /* ks[0 .. first - 1] stay in front */
    /* Local bands: the valley of a foot no further than core has a corner
     * of the foot's grid cell within core + that cell's reach, and the
     * valley's start is where steepest descent over the grid from that
     * corner ends. So only samples within their own reach of the band's
     * core are descended from, and a cell whose box is further than its
     * largest reach is skipped: a long chord elsewhere (a stretched free
     * edge) no longer makes every search read every sample. */
    const double slack = 1e-9 * g->cell;
    for (int iz = c0[2] - R < 0 ? 0 : c0[2] - R; iz < g->dim[2] && iz <= c0[2] + R; iz++) {
        const double gz = cell_gap(g, 2, iz, Q[2], slack);
        for (int iy = c0[1] - R < 0 ? 0 : c0[1] - R; iy < g->dim[1] && iy <= c0[1] + R; iy++) {
            const double gy = cell_gap(g, 1, iy, Q[1], slack);
            const double rl = core + g->rreach[iy + (long)g->dim[1] * iz];
            if (gy * gy + gz * gz >= rl * rl)
                continue; /* the whole row is beyond its reach */
            for (int ix = c0[0] - R < 0 ? 0 : c0[0] - R; ix < g->dim[0] && ix <= c0[0] + R; ix++) {
                const long ci = ix + (long)g->dim[0] * (iy + (long)g->dim[1] * iz);
                if (g->head[ci] < 0)
                    continue;
                const double gx = cell_gap(g, 0, ix, Q[0], slack), lim = core + g->breach[ci];
                if (gx * gx + gy * gy + gz * gz >= lim * lim)
                    continue;
                for (int k = g->head[ci]; k >= 0; k = g->next[k]) {
                    const double dx3 = X[k] - Q[0], dy3 = Y[k] - Q[1], dz3 = Z[k] - Q[2];
                    double d = dx3 * dx3 + dy3 * dy3 + dz3 * dz3;
                    const double lk = core + g->sreach[k];
                    if (!(d < lk * lk))
                        continue;
                    const long m = descend(g, k, Q, &d);
                    if (!(d < band2))
                        continue;
                    const long kk = cell_index(g, X[m], Y[m], Z[m]) * n2 + m;
                    int dup = 0;
                    for (int t = 0; t < found; t++)
                        dup |= ks[t] == m;
                    if (dup || (found == NF_PROJ_STARTS &&
                                (d > bd[found - 1] || (d == bd[found - 1] && kk > key[found - 1]))))
                        continue;
                    int t = found < NF_PROJ_STARTS ? found++ : NF_PROJ_STARTS - 1;
                    for (; t > first && (bd[t - 1] > d || (bd[t - 1] == d && key[t - 1] > kk));
                         t--) {
                        bd[t] = bd[t - 1];
                        ks[t] = ks[t - 1];
                        key[t] = key[t - 1];
                    }
                    bd[t] = d;
                    ks[t] = m;
                    key[t] = kk;
                }
            }
        }
    }
    return found;
}

/* Up to NF_PROJ_STARTS starts, nearest first: the nearest sample, then the
 * other samples that are local minima of the distance over the sample grid
 * within the band sqrt(nearest) + reach (nf_seed_starts's rule: a valley
 * whose samples never come that near cannot hold the nearest foot). Over a
 * fold the nearest sample can lie on the wrong layer; the other layer's
 * valley is then among these. Returns how many (>= 1). */
static int grid_starts(const cf_seedgrid_t *g, const double Q[3], long *ks)
{
    int c0[3];
    cell_of(g, Q, c0);
    double best;
    ks[0] = nearest(g, Q, c0, &best);
    if (!(best < INFINITY))
        return 1;
    double bd[NF_PROJ_STARTS];
    bd[0] = best;
    return band_starts(g, Q, c0, sqrt(best), ks, bd, 1);
}

static void sample_uv(const cf_seedgrid_t *g, long k, double *u0, double *v0)
{
    double ua, ub, va, vb;
    nf_surf_domain(g->seed.s, &ua, &ub, &va, &vb);
    const long ns = g->seed.ns;
    long i = k % ns, j = k / ns;
    *u0 = i == ns - 1 ? ub : ua + (ub - ua) * (double)i / (double)(ns - 1);
    *v0 = j == ns - 1 ? vb : va + (vb - va) * (double)j / (double)(ns - 1);
}

void cf_seedgrid_start(const cf_seedgrid_t *g, const double Q[3], double *u0, double *v0)
{
    if (g->use_quad) {
        nf_quad_start(&g->quad, Q, u0, v0);
        return;
    }
    long ks[NF_PROJ_STARTS];
    grid_starts(g, Q, ks);
    sample_uv(g, ks[0], u0, v0);
}

int cf_seedgrid_project(cf_seedgrid_t *g, const double Q[3], double tol, nf_proj_t *out)
{
    if (g->use_quad)
        return nf_quad_project(&g->quad, Q, tol, out);
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    long ks[NF_PROJ_STARTS];
    double u0[NF_PROJ_STARTS], v0[NF_PROJ_STARTS];
    const int n = grid_starts(g, Q, ks);
    for (int t = 0; t < n; t++)
        sample_uv(g, ks[t], &u0[t], &v0[t]);
    return nf_project_starts(&g->seed, Q, u0, v0, n, tol, out);
}

int cf_seedgrid_nearer(const cf_seedgrid_t *g, const nf_quad_t *nq, const double Q[3], double tol,
                       nf_proj_t *io)
{
    if (g->use_quad || !(fabs(io->dist) < INFINITY))
        return NF_OK;
    if (!(Q[0] - Q[0] == 0.0 && Q[1] - Q[1] == 0.0 && Q[2] - Q[2] == 0.0))
        return NF_ENONFINITE;
    /* Every valley within the band, io's own too: two feet closer than a
     * sample spacing (a steep step) share a valley of the samples. */
    int c0[3];
    cell_of(g, Q, c0);
    long ks[NF_PROJ_STARTS];
    double bd[NF_PROJ_STARTS], u0[NF_PROJ_STARTS], v0[NF_PROJ_STARTS];
    const int n = band_starts(g, Q, c0, fabs(io->dist), ks, bd, 0);
    if (n == 0)
        return NF_OK;
    for (int t = 0; t < n; t++)
        sample_uv(g, ks[t], &u0[t], &v0[t]);
    nf_proj_t alt;
    int rc = NF_ENOCONV;      /* alt's: a foot Newton did not converge to is no start */
    if (!nq || nq->creased) { /* a crease: its mirror starts too */
        rc = nf_project_starts(&g->seed, Q, u0, v0, n, tol, &alt);
        if (rc != NF_OK && rc != NF_ENOCONV)
            return rc;
    } else
        for (int t = 0; t < n; t++) {
            /* Newton's interior foot, else nf_project's (its bound check) */
            double u = u0[t], v = v0[t];
            nf_proj_t p;
            int r = NF_OK;
            if (!nf_quad_newton(nq, Q, tol, &u, &v, &p))
                r = nf_project(g->seed.s, Q, u0[t], v0[t], tol, &p);
            if (r != NF_OK && r != NF_ENOCONV)
                return r;
            if (t == 0 || fabs(p.dist) < fabs(alt.dist)) {
                alt = p;
                rc = r;
            }
        }
    if (!(fabs(alt.dist) < fabs(io->dist)))
        return NF_OK;
    *io = alt;
    return rc;
}

void cf_seedgrid_free(cf_seedgrid_t *g)
{
    free(g->qmem);
    free(g->pf);
    free(g->pts);
    free(g->next);
    free(g->head);
    free(g->sreach);
    free(g->breach);
    free(g->rreach);
    memset(g, 0, sizeof *g);
}
