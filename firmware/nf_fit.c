/* SPDX-License-Identifier: MIT */
/* nf_fit.c: streaming assembly of the generalised normal equations (Eq. 7). */
#include "nf_isa_pass.h" /* first: this pass's names (nf_isa.h) */

#include "nf_basis.h"
#include "nf_err.h"
#include "nf_fit.h"
#include "nf_solve.h"
#include <stdint.h>

static int finite3(const double *x)
{
    return x[0] - x[0] == 0.0 && x[1] - x[1] == 0.0 && x[2] - x[2] == 0.0;
}

/* (u, v) in the domain within its rounding allowance; NaN fails. */
static inline int in_box(const nf_fit_t *f, double u, double v)
{
    return u >= f->dom[0] - f->dtol[0] && u <= f->dom[1] + f->dtol[0] &&
           v >= f->dom[2] - f->dtol[1] && v <= f->dom[3] + f->dtol[1];
}

/* Random order: a window of points is sorted by tiles of NF_TILE x NF_TILE
 * knot spans before it is accumulated, so that a tile's stripe rows
 * ((NF_TILE + q) (NF_TILE + p) rows, 72 KB bicubic) come from memory once
 * for all its points instead of once per point. Windows shorter than
 * NF_BIN_MIN points, or ordered (a raster), are accumulated as they come. */
#define NF_TILE 16
#define NF_BIN_MIN 1024
/* Points the general path takes after the row kernel stopped short. */
#define NF_ROW_RETRY 1024

#if NF_ISA_COLD
/* Lend the raster row buffers and the bins from arena room the solver uses
 * later (idle while points stream in): at most half the job's solver term
 * each for the job and for one shard, so nothing is added to the formula. */
static void take_lent(nf_fit_t *f, nf_arena_t *a)
{
    const nf_surf_t *s = f->base;
    f->row_mark = f->row_top = 0;
    f->bin_key = f->bin_idx = f->bin_cnt = 0;
    f->bin_cap = 0;
    long cap = (f->need_bytes - NF_BYTES_BASE(f->n, s->p, s->q) - NF_ARENA_SLACK) / 2 -
               8L * NF_ARENA_ALIGN;
    f->row_mark = nf_arena_mark(a);
    if (f->acc.fast && !f->acc.rational && cap >= 80L * s->nu) {
        double *G = nf_arena_doubles(a, (size_t)7 * s->nu),
               *Gq = nf_arena_doubles(a, (size_t)3 * s->nu);
        if (G && Gq) {
            nf_accum_rowbuf(&f->acc, G, Gq);
            cap -= 80L * s->nu + 2L * NF_ARENA_ALIGN;
        }
    }
    /* the reciprocals of every span (bicubic): no division per span change */
    if (f->acc.fast && cap >= 48L * (s->nu + s->nv)) {
        double *tu = nf_arena_doubles(a, (size_t)6 * s->nu),
               *tv = nf_arena_doubles(a, (size_t)6 * s->nv);
        if (tu && tv) {
            nf_accum_rtab(&f->acc, tu, tv);
            cap -= 48L * (s->nu + s->nv) + 2L * NF_ARENA_ALIGN;
        }
    }
    f->bin_tx = (s->nu - s->p + NF_TILE - 1) / NF_TILE;
    const long tiles = (long)f->bin_tx * ((s->nv - s->q + NF_TILE - 1) / NF_TILE);
    long w = (cap - 8 * (tiles + 1)) / 8; /* key and index per point */
    w = w > f->n ? f->n : w;
    w = w > 0xFFFFFFL ? 0xFFFFFFL : w; /* 24 bits of row index */
    if (w >= NF_BIN_MIN && tiles > 1) {
        /* two uint32 arrays of w and the counts, as doubles from the arena */
        double *k = nf_arena_doubles(a, (size_t)(w + 1) / 2),
               *x = nf_arena_doubles(a, (size_t)(w + 1) / 2),
               *c = nf_arena_doubles(a, (size_t)(tiles + 1));
        if (k && x && c) {
            f->bin_key = (uint32_t *)(void *)k;
            f->bin_idx = (uint32_t *)(void *)x;
            f->bin_cnt = (uint32_t *)(void *)c;
            f->bin_cap = w;
            f->bin_tiles = tiles;
        }
    }
    if (nf_arena_mark(a) != f->row_mark)
        f->row_top = nf_arena_mark(a);
}

int nf_fit_init(nf_fit_t *f, const nf_surf_t *base, const nf_fit_params_t *prm, nf_arena_t *a)
{
    if (!f || !base || !prm || !a)
        return NF_EARG;
    f->need_bytes = -1;
    f->bad_index = -1;
    int rc = nf_surf_check(base);
    if (rc == NF_EBUDGET)
        f->need_bytes = nf_fit_bytes(base->nu, base->nv, base->p, base->q, prm->solver);
    if (rc)
        return rc;
    if (!(prm->alpha >= 0.0) || !(prm->beta >= 0.0) || prm->alpha - prm->alpha != 0.0 ||
        prm->beta - prm->beta != 0.0)
        return NF_EARG;
    f->need_bytes = nf_fit_bytes(base->nu, base->nv, base->p, base->q, prm->solver);
    if (f->need_bytes < 0 || f->need_bytes > NF_ARENA_BYTES)
        return NF_EBUDGET;
    if ((size_t)f->need_bytes > nf_arena_room(a))
        return NF_EARENA;

    const long n = (long)base->nu * base->nv;
    const int K = NF_STRIPE_SLOTS(base->p, base->q);
    double *S = nf_arena_doubles(a, (size_t)(n * K));
    f->rhs = nf_arena_doubles(a, (size_t)(3 * n));
    f->P = nf_arena_doubles(a, (size_t)(3 * n));
    if (!S || !f->rhs || !f->P)
        return NF_EARENA; /* unreachable when the formula is right */
    nf_stripe_init(&f->A, base->nu, base->nv, base->p, base->q, S);
    nf_accum_init(&f->acc, base, &f->A, f->rhs);
    f->shard = 0;
    f->shard_mark = 0;
    for (long i = 0; i < 3 * n; i++)
        f->P[i] = base->cp[i]; /* P0: the nominal net is the start and the beta target */
    f->base = base;
    f->prm = *prm;
    f->arena = a;
    f->n = n;
    f->npoints = 0;
    f->sumw = 0.0;
    f->finished = 0;
    /* A store that fits in cache gains nothing from prefetching. */
    f->prefetch = (double)n * K * sizeof(double) > 8.0 * 1024 * 1024;
    f->pf_l = f->pf_k = -1;
    nf_surf_domain(base, &f->dom[0], &f->dom[1], &f->dom[2], &f->dom[3]);
    f->dtol[0] = 1e-12 * (f->dom[1] - f->dom[0]);
    f->dtol[1] = 1e-12 * (f->dom[3] - f->dom[2]);
    /* Row buffers for raster rows of one v (10 Nu doubles, at most 2.5 N
     * since Nv >= 4, against the smallest solver term 6N): returned at
     * nf_fit_finish, before any solve. */
    take_lent(f, a);
    return NF_OK;
}

int nf_fit_shard_init(nf_fit_t *sh, const nf_fit_t *f, nf_arena_t *a)
{
    if (!sh || !f || !a || f->shard || f->finished)
        return NF_EARG;
    const nf_surf_t *s = f->base;
    const long more = nf_fit_shard_bytes(s->nu, s->nv, s->p, s->q);
    if (more < 0 || f->need_bytes < 0 || more > NF_ARENA_BYTES - f->need_bytes)
        return NF_EBUDGET;
    if ((size_t)more > nf_arena_room(a))
        return NF_EARENA;
    *sh = *f;
    sh->shard = 1;
    sh->arena = a;
    sh->shard_mark = nf_arena_mark(a);
    double *S = nf_arena_doubles(a, (size_t)(f->n * f->A.K));
    sh->rhs = nf_arena_doubles(a, (size_t)(3 * f->n));
    if (!S || !sh->rhs) {
        nf_arena_release(a, sh->shard_mark);
        return NF_EARENA;
    }
    sh->P = 0;
    nf_stripe_init(&sh->A, s->nu, s->nv, s->p, s->q, S);
    nf_accum_init(&sh->acc, s, &sh->A, sh->rhs);
    sh->npoints = 0;
    sh->sumw = 0.0;
    sh->pf_l = sh->pf_k = -1;
    take_lent(sh, a); /* from room the job's solver uses later */
    return NF_OK;
}
#endif

int nf_fit_shard_merge(nf_fit_t *f, nf_fit_t *sh)
{
    if (!f || !sh || !sh->shard || f->shard || f->finished || sh->base != f->base)
        return NF_EARG;
    nf_accum_flush(&sh->acc);
    /* f's open run stays open: sums commute, only rounding order changes. */
    const long nS = f->n * f->A.K;
    for (long i = 0; i < nS; i++)
        f->A.S[i] += sh->A.S[i];
    for (long i = 0; i < 3 * f->n; i++)
        f->rhs[i] += sh->rhs[i];
    f->npoints += sh->npoints;
    f->sumw += sh->sumw;
    nf_accum_rowbuf(&sh->acc, 0, 0);
    nf_accum_rtab(&sh->acc, 0, 0);
    nf_arena_release(sh->arena, sh->shard_mark);
    sh->finished = 1;
    return NF_OK;
}

int nf_fit_add(nf_fit_t *f, double u, double v, const double xyz[3], double wgt)
{
    if (f->finished)
        return NF_ESTATE;
    if (!finite3(xyz) || u - u != 0.0 || v - v != 0.0 || !(wgt > 0.0) || wgt - wgt != 0.0)
        return NF_ENONFINITE;
    if (!in_box(f, u, v))
        return NF_EDOMAIN;
    u = u < f->dom[0] ? f->dom[0] : (u > f->dom[1] ? f->dom[1] : u);
    v = v < f->dom[2] ? f->dom[2] : (v > f->dom[3] ? f->dom[3] : v);
    nf_accum_point(&f->acc, u, v, xyz, wgt);
    f->npoints++;
    f->sumw += wgt;
    return NF_OK;
}

/* nf_fit_add_rows works in batches of NF_FIT_BATCH points: the spans of
 * batch i + 1 are found (and, when the store exceeds the cache, their stripe
 * rows prefetched) before batch i is accumulated with the spans it already
 * has, so that the loads of the next points overlap this batch's arithmetic
 * and no span is searched twice. */
#define NF_FIT_BATCH 8

typedef struct fit_batch {
    int n;
    int l[NF_FIT_BATCH], k[NF_FIT_BATCH]; /* -1: nf_fit_add checks and reports it */
    double u[NF_FIT_BATCH], v[NF_FIT_BATCH];
} fit_batch_t;

static void prefetch_rows(const nf_fit_t *f, int l, int k)
{
#if defined(__GNUC__)
    const nf_surf_t *s = f->base;
    const long base = (l - s->p) + (long)(k - s->q) * s->nu, K = f->A.K;
    const long bytes = (long)(s->p + 1) * K * (long)sizeof(double);
    for (int b = 0; b <= s->q; b++) {
        const char *a = (const char *)(f->A.S + (base + (long)b * s->nu) * K);
        for (long o = 0; o < bytes; o += 64)
            __builtin_prefetch(a + o, 1, 3);
        __builtin_prefetch(a + bytes - 1, 1, 3);
        const char *r = (const char *)(f->rhs + 3 * (base + (long)b * s->nu));
        __builtin_prefetch(r, 1, 3);
        __builtin_prefetch(r + 24 * (s->p + 1) - 1, 1, 3);
    }
#else
    (void)f;
    (void)l;
    (void)k;
#endif
}

static void batch_prepare(nf_fit_t *f, const double *rows, int n, fit_batch_t *bt)
{
    bt->n = n;
    for (int t = 0; t < n; t++) {
        const double *r = rows + 5 * t;
        double u = r[0], v = r[1];
        bt->l[t] = bt->k[t] = -1;
        if (!finite3(r + 2) || !in_box(f, u, v))
            continue; /* nf_fit_add reports it, in order */
        u = u < f->dom[0] ? f->dom[0] : (u > f->dom[1] ? f->dom[1] : u);
        v = v < f->dom[2] ? f->dom[2] : (v > f->dom[3] ? f->dom[3] : v);
        int l, k;
        nf_accum_spans(&f->acc, u, v, f->pf_l, f->pf_k, &l, &k);
        /* A raster stays in the span or steps to the next in u, whose rows
         * follow in memory (the hardware prefetcher has them): only a jump
         * elsewhere is worth the prefetches. */
        if (f->prefetch && !(k == f->pf_k && (l == f->pf_l || l == f->pf_l + 1)))
            prefetch_rows(f, l, k);
        f->pf_l = l;
        f->pf_k = k;
        bt->l[t] = l;
        bt->k[t] = k;
        bt->u[t] = u;
        bt->v[t] = v;
    }
}

static int add_batched(nf_fit_t *f, const double *rows, long n, long *bad)
{
    fit_batch_t bt[2];
    int cur = 0;
    batch_prepare(f, rows, (int)(n < NF_FIT_BATCH ? n : NF_FIT_BATCH), &bt[0]);
    for (long i0 = 0; i0 < n; i0 += NF_FIT_BATCH, cur ^= 1) {
        const long next = i0 + NF_FIT_BATCH;
        if (next < n)
            batch_prepare(f, rows + 5 * next,
                          (int)(n - next < NF_FIT_BATCH ? n - next : NF_FIT_BATCH), &bt[cur ^ 1]);
        const fit_batch_t *b = &bt[cur];
        for (int t = 0; t < b->n; t++) {
            const double *r = rows + 5 * (i0 + t);
            if (b->l[t] >= 0) {
                nf_accum_point_at(&f->acc, b->u[t], b->v[t], b->l[t], b->k[t], r + 2, 1.0);
                f->npoints++;
                f->sumw += 1.0;
                continue;
            }
            int rc = nf_fit_add(f, r[0], r[1], r + 2, 1.0);
            if (rc) {
                if (bad)
                    *bad = i0 + t;
                return rc;
            }
        }
    }
    return NF_OK;
}

/* Spans of row r, clamped, or 0 when nf_fit_add must judge it. */
static inline int row_spans(nf_fit_t *f, const double *r, double *u, double *v, int *l, int *k)
{
    double a = r[0], b = r[1];
    if (!finite3(r + 2) || !in_box(f, a, b))
        return 0;
    *u = a < f->dom[0] ? f->dom[0] : (a > f->dom[1] ? f->dom[1] : a);
    *v = b < f->dom[2] ? f->dom[2] : (b > f->dom[3] ? f->dom[3] : b);
    nf_accum_spans(&f->acc, *u, *v, *l, *k, l, k);
    return 1;
}

/* Prefetch of a tile's stripe rows and right-hand side while the tile
 * before it is accumulated: its (NF_TILE + q) rows of control points, each
 * (NF_TILE + p) K doubles contiguous, walked a few cache lines a point so
 * that the loads from memory overlap the arithmetic (random order's first
 * touch of a row would otherwise wait for memory, ~8 lines a point). */
typedef struct tile_pf {
    const char *seg;   /* current segment (one control row of the tile) */
    long seg_len, off; /* its bytes and the next offset */
    int row, rows;     /* segment index, segments (2 per control row: S, rhs) */
    int per;           /* lines a point */
    const nf_fit_t *f;
    long pt0; /* first control point of the tile */
    long cols;
} tile_pf_t;

static void tile_pf_seg(tile_pf_t *pf)
{
    const nf_fit_t *f = pf->f;
    const long pt = pf->pt0 + (long)(pf->row / 2) * f->base->nu;
    if (pf->row % 2 == 0) {
        pf->seg = (const char *)(f->A.S + pt * f->A.K);
        pf->seg_len = pf->cols * f->A.K * (long)sizeof(double);
    } else {
        pf->seg = (const char *)(f->rhs + 3 * pt);
        pf->seg_len = pf->cols * 3 * (long)sizeof(double);
    }
    pf->off = 0;
}

static void tile_pf_start(const nf_fit_t *f, long T, uint32_t npts, tile_pf_t *pf)
{
    const nf_surf_t *s = f->base;
    pf->f = f;
    pf->rows = 0;
    if (T >= f->bin_tiles || npts == 0)
        return;
    const int c0 = (int)(T % f->bin_tx) * NF_TILE, r0 = (int)(T / f->bin_tx) * NF_TILE;
    const int c1 = c0 + NF_TILE + s->p > s->nu ? s->nu : c0 + NF_TILE + s->p;
    const int r1 = r0 + NF_TILE + s->q > s->nv ? s->nv : r0 + NF_TILE + s->q;
    pf->cols = c1 - c0;
    pf->pt0 = c0 + (long)r0 * s->nu;
    pf->rows = 2 * (r1 - r0);
    pf->row = 0;
    const long lines = (long)(r1 - r0) * (pf->cols * (f->A.K + 3) * 8 / 64 + 2);
    pf->per = (int)((lines + npts - 1) / npts);
    pf->per = pf->per > 32 ? 32 : pf->per;
    tile_pf_seg(pf);
}

/* pf->per lines of the current segment (a prefetch past its end is
 * harmless: prefetches never fault), then the next segment when done. */
static inline void tile_pf_step(tile_pf_t *pf)
{
#if defined(__GNUC__)
    if (pf->row >= pf->rows)
        return;
    const char *a = pf->seg + pf->off;
    for (int i = 0; i < pf->per; i++)
        __builtin_prefetch(a + 64 * i, 1, 2);
    pf->off += 64L * pf->per;
    if (pf->off >= pf->seg_len + 63 && ++pf->row < pf->rows)
        tile_pf_seg(pf);
#else
    (void)pf;
#endif
}

/* n <= bin_cap rows: the valid prefix counting-sorted by tile and
 * accumulated tile by tile (Eq. 9's sums in another order), unless it is
 * ordered already; then the first bad row, if any, is reported. */
static int add_binned(nf_fit_t *f, const double *rows, long n, long *bad)
{
    const nf_surf_t *s = f->base;
    int l = -1, k = -1, pl = -1, pk = -1;
    long m = 0, jumps = 0;
    for (; m < n; m++) {
        double u, v;
        if (!row_spans(f, rows + 5 * m, &u, &v, &l, &k))
            break;
        jumps += !(k == pk && (l == pl || l == pl + 1));
        pl = l;
        pk = k;
        f->bin_key[m] = (uint32_t)((l - s->p) / NF_TILE + ((k - s->q) / NF_TILE) * (long)f->bin_tx);
        /* the row, and its spans as offsets in the tile: 24 + 4 + 4 bits */
        const uint32_t dl = (uint32_t)((l - s->p) % NF_TILE), dk = (uint32_t)((k - s->q) % NF_TILE);
        f->bin_idx[m] = (uint32_t)m | dl << 24 | dk << 28;
    }
    const int p = s->p, q = s->q, tx = f->bin_tx;
    if (jumps * 4 < m) { /* a raster: its order is the better one; spans from key and idx */
        const uint32_t *key = f->bin_key, *idx = f->bin_idx;
        for (long t = 0; t < m; t++) {
            const double *r = rows + 5 * t;
            const uint32_t e = idx[t], T = key[t];
            double u = r[0], v = r[1];
            u = u < f->dom[0] ? f->dom[0] : (u > f->dom[1] ? f->dom[1] : u);
            v = v < f->dom[2] ? f->dom[2] : (v > f->dom[3] ? f->dom[3] : v);
            nf_accum_point_at(&f->acc, u, v, p + (int)(T % tx) * NF_TILE + (int)(e >> 24 & 15u),
                              q + (int)(T / tx) * NF_TILE + (int)(e >> 28), r + 2, 1.0);
        }
        f->npoints += m;
        f->sumw += (double)m;
    } else {
        /* Counting sort in place (American flag): cnt = tile starts,
         * nxt = next free slot of each tile; key and idx swap together. */
        uint32_t *cnt = f->bin_cnt, *nxt = f->bin_cnt + f->bin_tiles + 1, *key = f->bin_key,
                 *idx = f->bin_idx;
        for (long t = 0; t <= f->bin_tiles; t++)
            cnt[t] = 0;
        for (long t = 0; t < m; t++)
            cnt[key[t] + 1]++;
        for (long t = 0; t < f->bin_tiles; t++)
            cnt[t + 1] += cnt[t];
        for (long t = 0; t < f->bin_tiles; t++)
            nxt[t] = cnt[t];
        for (long T = 0; T < f->bin_tiles; T++)
            while (nxt[T] < cnt[T + 1]) {
                const uint32_t at = nxt[T], kt = key[at];
                if (kt == (uint32_t)T) {
                    nxt[T]++;
                    continue;
                }
                const uint32_t to = nxt[kt]++, e = idx[at];
                key[at] = key[to];
                idx[at] = idx[to];
                key[to] = kt;
                idx[to] = e;
            }
        long T1 = 0; /* the next tile with points: its stripe rows are prefetched meanwhile */
        while (T1 < f->bin_tiles && cnt[T1 + 1] == (T1 ? cnt[T1] : 0))
            T1++;
        for (long T = T1; T < f->bin_tiles; T = T1) {
            const int l0 = p + (int)(T % f->bin_tx) * NF_TILE,
                      k0 = q + (int)(T / f->bin_tx) * NF_TILE;
            for (T1 = T + 1; T1 < f->bin_tiles && cnt[T1 + 1] == cnt[T1]; T1++)
                ;
            tile_pf_t pf = {0};
            const uint32_t tb = T ? cnt[T] : 0;
            tile_pf_start(f, T1, cnt[T + 1] - tb, &pf);
            for (uint32_t t = tb; t < cnt[T + 1]; t++) {
                tile_pf_step(&pf);
                if (t + 16 < (uint32_t)m) {
                    const double *ra = rows + 5 * (long)(idx[t + 16] & 0xFFFFFFu);
                    __builtin_prefetch(ra);
                    __builtin_prefetch(ra + 4);
                }
                const uint32_t e = idx[t];
                const double *r = rows + 5 * (long)(e & 0xFFFFFFu);
                double u = r[0], v = r[1];
                u = u < f->dom[0] ? f->dom[0] : (u > f->dom[1] ? f->dom[1] : u);
                v = v < f->dom[2] ? f->dom[2] : (v > f->dom[3] ? f->dom[3] : v);
                nf_accum_lone33(&f->acc, u, v, l0 + (int)(e >> 24 & 15u), k0 + (int)(e >> 28),
                                r + 2);
            }
        }
        f->npoints += m;
        f->sumw += (double)m;
    }
    if (m < n) {
        int rc = nf_fit_add(f, rows[5 * m], rows[5 * m + 1], rows + 5 * m + 2, 1.0);
        if (bad)
            *bad = m;
        if (rc)
            return rc;
        long at = -1; /* nf_fit_add took it after all: go on */
        rc = add_binned(f, rows + 5 * (m + 1), n - m - 1, &at);
        if (rc && bad)
            *bad = m + 1 + at;
        return rc;
    }
    return NF_OK;
}

int nf_fit_add_rows(nf_fit_t *f, const double *rows, long n, long *bad)
{
    if (n > 0 && f->finished) {
        if (bad)
            *bad = 0;
        return NF_ESTATE;
    }
    const double lim[4] = {f->dom[0] - f->dtol[0], f->dom[1] + f->dtol[0], f->dom[2] - f->dtol[1],
                           f->dom[3] + f->dtol[1]};
    for (long i = 0; i < n;) {
        /* Raster rows of one v first: the row kernel, while it applies. */
        const long took = nf_accum_rows33(&f->acc, rows + 5 * i, n - i, lim, f->dom);
        f->npoints += took;
        f->sumw += (double)took;
        i += took;
        if (i >= n)
            break;
        long w = n - i, at = -1;
        int rc;
        /* After a raster that ended in a short row or a bad point: the
         * general path for a while, then the kernel again. Fewer taken: not
         * a raster, the general path's whole window (random order bins). */
        if (took >= NF_ROW_RETRY && w > NF_ROW_RETRY)
            w = NF_ROW_RETRY;
        if (f->bin_cap > 0 && w >= NF_BIN_MIN) {
            w = w > f->bin_cap ? f->bin_cap : w;
            rc = add_binned(f, rows + 5 * i, w, &at);
        } else {
            rc = add_batched(f, rows + 5 * i, w, &at);
        }
        if (rc) {
            if (bad)
                *bad = i + at;
            return rc;
        }
        i += w;
    }
    return NF_OK;
}

/* The alpha criterion: row r of (B - I) is the rational basis at control
 * point r's Greville point minus 1 at column r. Greville point r lies in
 * [U[i+1], U[i+p]], inside the support of basis function i, so column r is
 * one of the row's (p+1)(q+1) non-zeros and the row has exactly the pattern
 * of a measured point's row of R (Eq. 9): (B - I)^T (B - I) fills the same
 * stripes as R^T R and adds nothing to the right-hand side. */
static void add_alpha(nf_fit_t *f)
{
    const nf_surf_t *s = f->base;
    const int p = s->p, q = s->q, o = p + 1;
    double Nu[NF_MAX_ORDER], Nv[NF_MAX_ORDER], R[NF_MAX_LOCAL];
    for (int j = 0; j < s->nv; j++) {
        double vg = nf_greville(j, q, s->V);
        int k = nf_find_span(s->nv - 1, q, vg, s->V);
        k = k < j ? j : (k > j + q ? j + q : k); /* keep column j in the span */
        k = k < q ? q : (k > s->nv - 1 ? s->nv - 1 : k);
        nf_basis_funs(k, vg, q, s->V, Nv);
        for (int i = 0; i < s->nu; i++) {
            double ug = nf_greville(i, p, s->U);
            int l = nf_find_span(s->nu - 1, p, ug, s->U);
            l = l < i ? i : (l > i + p ? i + p : l);
            l = l < p ? p : (l > s->nu - 1 ? s->nu - 1 : l);
            nf_basis_funs(l, ug, p, s->U, Nu);
            double W = 0.0;
            for (int b = 0; b <= q; b++)
                for (int a = 0; a <= p; a++) {
                    double w = s->w ? s->w[(l - p + a) + (long)(k - q + b) * s->nu] : 1.0;
                    R[a + b * o] = Nu[a] * Nv[b] * w;
                    W += R[a + b * o];
                }
            for (int t = 0; t < o * (q + 1); t++)
                R[t] /= W;
            R[(i - (l - p)) + (j - (k - q)) * o] -= 1.0;
            nf_stripe_add_outer(&f->A, (l - p) + (long)(k - q) * s->nu, R, f->prm.alpha);
        }
    }
}

int nf_fit_finish(nf_fit_t *f)
{
    if (f->finished || f->shard)
        return NF_ESTATE;
    nf_accum_flush(&f->acc);
    if (f->row_top) { /* give the lent buffers back to the solver (take_lent) */
        nf_accum_rowbuf(&f->acc, 0, 0);
        nf_accum_rtab(&f->acc, 0, 0);
        f->bin_cap = 0;
        if (nf_arena_mark(f->arena) == f->row_top)
            nf_arena_release(f->arena, f->row_mark);
        f->row_top = 0;
    }
    const int K = f->A.K;
    if (f->prm.alpha == 0.0 && f->prm.beta == 0.0) {
        for (long i = 0; i < f->n; i++)
            if (f->A.S[i * K] == 0.0) { /* (R^T R)_ii = sum of R_ki^2 = 0: no data */
                f->bad_index = i;
                return NF_ENODATA;
            }
    }
    if (f->prm.alpha > 0.0)
        add_alpha(f);
    if (f->prm.beta > 0.0) {
        const double *P0 = f->base->cp;
        for (long i = 0; i < f->n; i++) {
            f->A.S[i * K] += f->prm.beta;
            f->rhs[3 * i] += f->prm.beta * P0[3 * i];
            f->rhs[3 * i + 1] += f->prm.beta * P0[3 * i + 1];
            f->rhs[3 * i + 2] += f->prm.beta * P0[3 * i + 2];
        }
    }
    f->finished = 1;
    return NF_OK;
}

#if NF_ISA_COLD /* not hot: one copy in the dispatched build (nf_isa_pass.h) */
int nf_fit_pin(nf_fit_t *f, long i, double beta)
{
    if (!f->finished || f->shard)
        return NF_ESTATE;
    if (i < 0 || i >= f->n || !(beta >= 0.0) || beta - beta != 0.0)
        return NF_EARG;
    return nf_fit_pin_to(f, i, beta, f->base->cp + 3 * i);
}

int nf_fit_pin_to(nf_fit_t *f, long i, double beta, const double q[3])
{
    if (!f->finished || f->shard)
        return NF_ESTATE;
    if (i < 0 || i >= f->n || !(beta >= 0.0) || beta - beta != 0.0 || !q)
        return NF_EARG;
    f->A.S[i * f->A.K] += beta;
    for (int c = 0; c < 3; c++)
        f->rhs[3 * i + c] += beta * q[c];
    return NF_OK;
}
#endif

int nf_fit_solve(nf_fit_t *f, nf_solver_t solver, const nf_solve_opts_t *opt, nf_solve_stats_t *st)
{
    if (!f->finished || f->shard)
        return NF_ESTATE;
    const nf_surf_t *s = f->base;
    if (solver == NF_SOLVER_AUTO)
        solver = nf_solver_pick(s->nu, s->nv, s->p, s->q);
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, solver);
    if (need < 0 || need > NF_ARENA_BYTES) {
        f->need_bytes = need;
        return NF_EBUDGET;
    }
    nf_solve_opts_t o = NF_SOLVE_OPTS_DEFAULT;
    if (opt)
        o = *opt;
    /* beta > 0 put beta I into A (nf_fit_finish, Eq. 7): A >= beta I is
     * positive definite, so the probe has no null space to find, and its
     * homogeneous solve cost twice the solve itself (issue 20). */
    if (f->prm.beta > 0.0)
        o.probe = 0;
    nf_solve_stats_t tmp;
    if (!st)
        st = &tmp;
    st->solver = solver;
    st->iterations = 0;
    st->rel_residual = 0.0;
    size_t mark = nf_arena_mark(f->arena);
    int rc;
    switch (solver) {
    case NF_SOLVER_GS:
        rc = nf_gs_solve(&f->A, f->rhs, f->P, &o, f->arena, st, &f->bad_index);
        break;
    case NF_SOLVER_CHOL:
        rc = nf_chol_solve(&f->A, f->rhs, f->P, f->arena, st, &f->bad_index);
        break;
    case NF_SOLVER_PCG:
        rc = nf_pcg_solve(&f->A, f->rhs, f->P, &o, f->arena, st, &f->bad_index);
        break;
    default: rc = NF_ESOLVER; break;
    }
    nf_arena_release(f->arena, mark);
    return rc;
}
