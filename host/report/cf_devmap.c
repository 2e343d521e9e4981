/* SPDX-License-Identifier: MIT */
/* cf_devmap.c: deviation map raster and its report image. Points are binned
 * into cells (sum, count, extreme); at render time the gaps the sampling
 * leaves between measured cells (scan lines, probe points) are closed, not
 * the part's outline or its holes, and the cell values are interpolated
 * bilinearly onto the image pixels, so colour boundaries come out as smooth
 * iso-deviation lines rather than a mosaic of cells. */
#include "cf_devmap.h"
#include "cf_err.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Image layout, pixels. Text is the 8x13 font at scale 1. */
#define DM_W 1200                 /* image width */
#define DM_M 20                   /* outer margin */
#define DM_TOP 84                 /* top of the map and of the colour bar panel */
#define DM_MAP_H 720              /* map height limit */
#define DM_GAP 40                 /* between the map area and the colour bar panel */
#define DM_FS 1                   /* font scale */
#define DM_TH (CF_FONT_H * DM_FS) /* text height */
#define DM_SEGS 4                 /* colour steps on each side between tol and range * tol */
#define DM_NCOL (2 * DM_SEGS + 3) /* below range, 4 blues, green, 4 warm, above range */
#define DM_SEG_H 30               /* colour bar box height */
#define DM_BOX_W 34               /* colour bar box width */
#define DM_CAP 34                 /* colour bar caption */
#define DM_BAR_H ((DM_NCOL + 1) * DM_SEG_H) /* the green box is two high */
/* The histogram of |d| / tol for the scale chosen from the data: bins of
 * a quarter tolerance up to DM_HMAX tolerances (bin b holds ((b-1)/4, b/4],
 * bin 0 exactly 0, the last everything beyond), so every segment edge the
 * automatic scale can choose (1 + k * step, step a multiple of 1/4) is a
 * bin edge and the share of points per colour is counted exactly. */
#define DM_HMAX 1000
#define DM_NBIN (4 * DM_HMAX + 2)
#define DM_GREY 0xD9D9D9    /* no data */
#define DM_INK 0x1A1A1A     /* text */
#define DM_HATCH 0x5A5A5A   /* footprint "no data" cells: diagonal hatch (cf_devmap_mark) */
#define DM_OUTLINE 0x000000 /* the footprint's outline */

/* Segmented diverging scale, from below -range * tol up to above it: the
 * metrology convention (blue short of material, green in tolerance, red
 * excess), with distinct colours for values off the scale. */
static const uint32_t palette[DM_NCOL] = {
    0x3C0078,                               /* < -range tol */
    0x0020C8, 0x0064FF, 0x00AAFF, 0x00E1EB, /* -range .. -tol */
    0x28BE46,                               /* within tolerance */
    0xEBEB00, 0xFFB400, 0xFF6E00, 0xDC1414, /* tol .. range */
    0x820032,                               /* > range tol */
};

struct cf_devmap {
    cf_plane_t pl;
    double tol, range;
    int autoscale;   /* range chosen from the data at render */
    double p99;      /* auto: the 99th percentile of |d| (bin upper edge), mm */
    long long *hist; /* DM_NBIN bins for d >= 0, then DM_NBIN for d < 0 */
    cf_devmap_cell_t cell;
    char title[161];
    /* extent of the points in plane coordinates, mm */
    double u0, u1, v0, v1;
    long long next;
    int have_ext;
    /* raster */
    int begun;
    int cw, ch;    /* cells across, down; row 0 at the top (largest v) */
    double U0, V0; /* lower-left corner of the raster, mm */
    double pitch;  /* cell size, mm */
    int fill_r;    /* render: closing radius, cells */
    int dw, dh;    /* map size in the image, px */
    int mx, my;    /* map's top-left pixel */
    int panel_x, pct_w, img_h, foot_y;
    double *sum;
    float *ext; /* deviation of largest magnitude */
    uint32_t *cnt;
    float *val;          /* render: cell values */
    unsigned char *flag; /* render: 0 empty, 1 measured, 2 filled (4, 8 while filling) */
    unsigned char *dist; /* render: chessboard distances */
    unsigned char *mark; /* CF_DEVMAP_NODATA | CF_DEVMAP_OUTLINE per cell (cf_devmap_mark) */
    int marked;          /* any mark: the legend shows the hatch */
    /* the points on the map */
    long long n, within, outside, seg[DM_NCOL];
    double sum_d, sq, dmin, dmax, at_min[2], at_max[2];
};

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Flip v so that its component of largest magnitude is positive. */
static void orient(double v[3])
{
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (fabs(v[i]) > fabs(v[k]))
            k = i;
    if (v[k] < 0)
        for (int i = 0; i < 3; i++)
            v[i] = -v[i];
}

/* ---- plane ---------------------------------------------------------------- */

void cf_devmap_plane_init(cf_planefit_t *pf)
{
    memset(pf, 0, sizeof *pf);
}

void cf_devmap_plane_add(cf_planefit_t *pf, const double p[3])
{
    if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
        return;
    double d[3], e[3];
    pf->n++;
    for (int i = 0; i < 3; i++) {
        d[i] = p[i] - pf->mean[i];
        pf->mean[i] += d[i] / (double)pf->n;
        e[i] = p[i] - pf->mean[i];
    }
    pf->c[0] += d[0] * e[0];
    pf->c[1] += d[1] * e[1];
    pf->c[2] += d[2] * e[2];
    pf->c[3] += d[0] * e[1];
    pf->c[4] += d[0] * e[2];
    pf->c[5] += d[1] * e[2];
}

/* Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations:
 * a becomes diagonal (the eigenvalues), the columns of v the eigenvectors.
 * Chosen over power iteration, which converges at the ratio of neighbouring
 * eigenvalues: near 1 for a square plate (equal in-plane variances) or, for
 * the normal by a shifted iteration, a long strip. Jacobi converges
 * quadratically whatever the spectrum, to rounding in a few sweeps. */
static void jacobi3(double a[3][3], double v[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            v[i][j] = i == j;
    for (int sweep = 0; sweep < 64; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off == 0 || off <= 1e-18 * diag)
            break;
        static const int pq[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (int r = 0; r < 3; r++) {
            int p = pq[r][0], q = pq[r][1];
            if (a[p][q] == 0)
                continue;
            double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
            double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1));
            double c = 1 / sqrt(t * t + 1), s = t * c;
            for (int k = 0; k < 3; k++) { /* a = a P */
                double akp = a[k][p], akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for (int k = 0; k < 3; k++) { /* a = P^T a */
                double apk = a[p][k], aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for (int k = 0; k < 3; k++) { /* v = v P */
                double vkp = v[k][p], vkq = v[k][q];
                v[k][p] = c * vkp - s * vkq;
                v[k][q] = s * vkp + c * vkq;
            }
            a[p][q] = a[q][p] = 0;
        }
    }
}

int cf_devmap_plane_fit(const cf_planefit_t *pf, cf_plane_t *pl, double sd[3], char *msg,
                        size_t msglen)
{
    if (!pf || !pl)
        return cf_fail(msg, msglen, CF_EARG, "cf_devmap_plane_fit: NULL argument");
    if (pf->n < 1)
        return cf_fail(msg, msglen, CF_EEMPTY, "no points to fit a view plane to");
    double a[3][3] = {{pf->c[0], pf->c[3], pf->c[4]},
                      {pf->c[3], pf->c[1], pf->c[5]},
                      {pf->c[4], pf->c[5], pf->c[2]}},
           v[3][3];
    jacobi3(a, v);
    int ord[3] = {0, 1, 2}; /* eigenvalues, descending */
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (a[ord[j]][ord[j]] > a[ord[i]][ord[i]]) {
                int t = ord[i];
                ord[i] = ord[j];
                ord[j] = t;
            }
    for (int i = 0; i < 3; i++) {
        pl->o[i] = pf->mean[i];
        pl->n[i] = v[i][ord[2]];
    }
    orient(pl->n);
    /* Axes as in the measuring machine, not the principal axes (which the
     * outline of a part with cut-outs would turn any way): a part facing
     * up (within 60 degrees of +Z) has X projected to the right, so one
     * lying in XY is seen with X right and Y up; a wall has Z projected up. */
    if (fabs(pl->n[2]) >= 0.5) {
        double len = sqrt(1 - pl->n[0] * pl->n[0]);
        for (int i = 0; i < 3; i++)
            pl->e1[i] = ((i == 0) - pl->n[0] * pl->n[i]) / len;
        cross3(pl->n, pl->e1, pl->e2);
    } else {
        double len = sqrt(1 - pl->n[2] * pl->n[2]);
        for (int i = 0; i < 3; i++)
            pl->e2[i] = ((i == 2) - pl->n[2] * pl->n[i]) / len;
        cross3(pl->e2, pl->n, pl->e1);
    }
    if (sd)
        for (int i = 0; i < 3; i++) {
            double lam = a[ord[i]][ord[i]];
            sd[i] = pf->n > 1 && lam > 0 ? sqrt(lam / (double)(pf->n - 1)) : 0.0;
        }
    return CF_OK;
}

int cf_plane_from_axes(cf_plane_t *pl, const double o[3], const double e1[3], const double e2[3],
                       char *msg, size_t msglen)
{
    double l1 = sqrt(dot3(e1, e1));
    if (!(l1 > 0) || !isfinite(l1))
        return cf_fail(msg, msglen, CF_EARG, "view axis e1 is zero or not finite");
    for (int i = 0; i < 3; i++) {
        pl->o[i] = o[i];
        pl->e1[i] = e1[i] / l1;
    }
    double k = dot3(e2, pl->e1);
    for (int i = 0; i < 3; i++)
        pl->e2[i] = e2[i] - k * pl->e1[i];
    double l2 = sqrt(dot3(pl->e2, pl->e2));
    if (!(l2 > 1e-9 * sqrt(dot3(e2, e2))) || !isfinite(l2))
        return cf_fail(msg, msglen, CF_EARG, "view axes e1 and e2 are parallel or e2 is zero");
    for (int i = 0; i < 3; i++)
        pl->e2[i] /= l2;
    cross3(pl->e1, pl->e2, pl->n);
    return CF_OK;
}

/* ---- raster --------------------------------------------------------------- */

int cf_devmap_create(cf_devmap_t **out, const cf_plane_t *pl, const cf_devmap_opts_t *o, char *msg,
                     size_t msglen)
{
    if (!out || !pl || !o)
        return cf_fail(msg, msglen, CF_EARG, "cf_devmap_create: NULL argument");
    *out = NULL;
    if (!(o->tol > 0) || !isfinite(o->tol))
        return cf_fail(msg, msglen, CF_EARG, "deviation map: tolerance must be > 0");
    /* A fixed range in tolerances, else from the data (3 tolerances until
     * the data are in). */
    double range = o->range != 0 ? o->range : 3.0;
    if (!(range > 1) || !(range <= DM_HMAX))
        return cf_fail(msg, msglen, CF_EARG,
                       "deviation map: the scale (%g mm) must lie above the tolerance (%g mm) "
                       "and within %d tolerances",
                       range * o->tol, o->tol, DM_HMAX);
    cf_devmap_t *m = calloc(1, sizeof *m);
    long long *hist = calloc(2 * DM_NBIN, sizeof *hist);
    if (!m || !hist) {
        free(m);
        free(hist);
        return cf_fail(msg, msglen, CF_ENOMEM, "deviation map: out of memory");
    }
    m->hist = hist;
    m->autoscale = o->range == 0;
    m->pl = *pl;
    m->tol = o->tol;
    m->range = range;
    m->cell = o->cell;
    snprintf(m->title, sizeof m->title, "%s", o->title ? o->title : "Deviation map");
    *out = m;
    return CF_OK;
}

static int seg_of_t(const cf_devmap_t *m, double t);

int cf_devmap_set_scale(cf_devmap_t *m, double scale, char *msg, size_t msglen)
{
    if (!m)
        return cf_fail(msg, msglen, CF_EARG, "cf_devmap_set_scale: NULL map");
    if (scale == 0) {
        m->autoscale = 1;
        m->range = 3.0;
        return CF_OK;
    }
    double range = scale / m->tol;
    if (!(range > 1) || !(range <= DM_HMAX))
        return cf_fail(msg, msglen, CF_EARG,
                       "deviation map: the scale (%g mm) must lie above the tolerance (%g mm) "
                       "and within %d tolerances",
                       scale, m->tol, DM_HMAX);
    /* The points added so far were counted on no fixed scale: count them
     * from the histogram (to a quarter tolerance) when the scale changes
     * late; before the first point this is exact. */
    m->autoscale = 0;
    m->range = range;
    memset(m->seg, 0, sizeof m->seg);
    for (int b = 0; b < DM_NBIN; b++) {
        m->seg[seg_of_t(m, b / 4.0)] += m->hist[b];
        m->seg[seg_of_t(m, -b / 4.0)] += m->hist[DM_NBIN + b];
    }
    return CF_OK;
}

void cf_devmap_free(cf_devmap_t *m)
{
    if (!m)
        return;
    free(m->sum);
    free(m->ext);
    free(m->cnt);
    free(m->val);
    free(m->flag);
    free(m->dist);
    free(m->mark);
    free(m->hist);
    free(m);
}

static void to_plane(const cf_devmap_t *m, const double p[3], double *u, double *v)
{
    double d[3] = {p[0] - m->pl.o[0], p[1] - m->pl.o[1], p[2] - m->pl.o[2]};
    *u = dot3(d, m->pl.e1);
    *v = dot3(d, m->pl.e2);
}

void cf_devmap_extent(cf_devmap_t *m, const double p[3])
{
    double u, v;
    to_plane(m, p, &u, &v);
    if (!isfinite(u) || !isfinite(v))
        return;
    if (!m->have_ext) {
        m->u0 = m->u1 = u;
        m->v0 = m->v1 = v;
        m->have_ext = 1;
    }
    m->u0 = fmin(m->u0, u);
    m->u1 = fmax(m->u1, u);
    m->v0 = fmin(m->v0, v);
    m->v1 = fmax(m->v1, v);
    m->next++;
}

void cf_devmap_set_extent(cf_devmap_t *m, double u0, double u1, double v0, double v1,
                          long long npts)
{
    m->u0 = fmin(u0, u1);
    m->u1 = fmax(u0, u1);
    m->v0 = fmin(v0, v1);
    m->v1 = fmax(v0, v1);
    m->next = npts > 0 ? npts : 0;
    m->have_ext = isfinite(u0) && isfinite(u1) && isfinite(v0) && isfinite(v1);
}

/* Colour segment of t = d / tol: 0 below the scale, DM_SEGS + 1 within
 * tolerance, DM_NCOL - 1 above. */
static int seg_of_t(const cf_devmap_t *m, double t)
{
    double a = fabs(t);
    if (t > m->range)
        return DM_NCOL - 1;
    if (t < -m->range)
        return 0;
    if (a <= 1)
        return DM_SEGS + 1;
    int k = (int)ceil((a - 1) / ((m->range - 1) / DM_SEGS));
    k = k < 1 ? 1 : k > DM_SEGS ? DM_SEGS : k;
    return t > 0 ? DM_SEGS + 1 + k : DM_SEGS + 1 - k;
}

static int seg_of(const cf_devmap_t *m, double d)
{
    return seg_of_t(m, d / m->tol);
}

/* The scale from the data: the smallest range 1 + 4 step (step a "round"
 * multiple of a quarter tolerance) reaching the 99th percentile of |d|, so
 * at most 1 % of the points fall off the scale and the colours spread over
 * the deviations there are; then the share of points per colour from the
 * histogram (exact: the edges are bin edges). */
static void auto_scale(cf_devmap_t *m)
{
    static const double steps[] = {0.25, 0.5, 1, 2, 2.5, 5, 10, 20, 25, 50, 100, 200};
    const long long *pos = m->hist, *neg = m->hist + DM_NBIN;
    long long need = (99 * m->n + 99) / 100, cum = 0;
    int b99 = 0;
    for (int b = 0; b < DM_NBIN && m->n; b++) {
        cum += pos[b] + neg[b];
        if (cum >= need) {
            b99 = b;
            break;
        }
    }
    double a99 = b99 / 4.0;
    size_t k = 0;
    while (k + 1 < sizeof steps / sizeof steps[0] && 1 + DM_SEGS * steps[k] < a99)
        k++;
    m->range = 1 + DM_SEGS * steps[k];
    m->p99 = a99 * m->tol;
    memset(m->seg, 0, sizeof m->seg);
    for (int b = 0; b < DM_NBIN; b++) {
        m->seg[seg_of_t(m, b / 4.0)] += pos[b];
        m->seg[seg_of_t(m, -b / 4.0)] += neg[b];
    }
}

/* The deviation at the edge between segments i and i + 1. */
static double edge_value(const cf_devmap_t *m, int i)
{
    double step = (m->range - 1) / DM_SEGS;
    if (i <= DM_SEGS)
        return -(1 + (DM_SEGS - i) * step) * m->tol;
    return (1 + (i - DM_SEGS - 1) * step) * m->tol;
}

uint32_t cf_devmap_colour(const cf_devmap_t *m, double d)
{
    return palette[seg_of(m, d)];
}

double cf_devmap_scale_end(const cf_devmap_t *m)
{
    return m->range * m->tol;
}

static void edge_label(const cf_devmap_t *m, int i, char *buf, size_t n)
{
    snprintf(buf, n, "%+.*f", cf_stats_decimals(m->tol), edge_value(m, i));
}

int cf_devmap_begin(cf_devmap_t *m, char *msg, size_t msglen)
{
    if (m->begun)
        return CF_OK;
    if (!m->have_ext)
        return cf_fail(msg, msglen, CF_EEMPTY, "deviation map: no points");
    double eu = m->u1 - m->u0, ev = m->v1 - m->v0, big = fmax(eu, ev);
    double cu = 0.5 * (m->u0 + m->u1), cv = 0.5 * (m->v0 + m->v1);
    if (!(big > 1e-9)) /* all points at one spot: show 1 mm around it */
        eu = ev = big = 1.0;
    /* A line of points still gets a strip of 2 % of its length. */
    eu = fmax(eu, 0.02 * big);
    ev = fmax(ev, 0.02 * big);
    m->u0 = cu - 0.5 * eu;
    m->u1 = cu + 0.5 * eu;
    m->v0 = cv - 0.5 * ev;
    m->v1 = cv + 0.5 * ev;
    /* Panel width from its widest label, the map takes the rest. */
    char lab[64];
    int lw = 0;
    double keep = m->range;
    if (m->autoscale) /* the labels of the widest scale it may choose */
        m->range = 1 + DM_SEGS * 200.0;
    for (int i = 0; i < DM_NCOL - 1; i++) {
        edge_label(m, i, lab, sizeof lab);
        int w = cf_text_width(lab, DM_FS);
        lw = w > lw ? w : lw;
    }
    m->range = keep;
    m->pct_w = cf_text_width("100.0%", DM_FS);
    int panel_w = m->pct_w + 8 + DM_BOX_W + 10 + lw;
    if (panel_w < cf_text_width("deviation, mm", DM_FS))
        panel_w = cf_text_width("deviation, mm", DM_FS);
    /* The scale's note under the bar, at its widest. */
    snprintf(lab, sizeof lab, "99%% of |d| <= %.*f", cf_stats_decimals(m->tol), DM_HMAX * m->tol);
    if (panel_w < cf_text_width(lab, DM_FS))
        panel_w = cf_text_width(lab, DM_FS);
    m->panel_x = DM_W - DM_M - panel_w;
    int aw = m->panel_x - DM_GAP - DM_M, ah = DM_MAP_H;
    /* Cells: no finer than a pixel of the map with a 3 % margin round the
     * part, no finer than the points are spaced (sparse points would
     * otherwise leave a speckle of empty cells). */
    double pad = 0.03 * fmax(eu, ev);
    double f = fmin(aw / (eu + 2 * pad), ah / (ev + 2 * pad)); /* pixels per mm */
    double spacing = m->next > 0 ? sqrt(eu * ev / (double)m->next) : 0.0;
    m->pitch = fmax(1.0 / f, 0.5 * spacing);
    /* Whole cells of margin, and the data cells starting at the points'
     * lower edge: cells on the part's outline are then as full as any. The
     * +1 keeps the upper edge strictly inside the last data cell. Hence at
     * most aw + 3 cells across, whatever the number of points. */
    int k = (int)ceil(pad / m->pitch - 1e-9);
    k = k < 1 ? 1 : k;
    m->cw = (int)floor(eu / m->pitch) + 1 + 2 * k;
    m->ch = (int)floor(ev / m->pitch) + 1 + 2 * k;
    m->U0 = m->u0 - k * m->pitch;
    m->V0 = m->v0 - k * m->pitch;
    double fw = fmin(aw / (m->cw * m->pitch), ah / (m->ch * m->pitch));
    m->dw = (int)fmin(fmax(round(m->cw * m->pitch * fw), 1), aw);
    m->dh = (int)fmin(fmax(round(m->ch * m->pitch * fw), 1), ah);
    m->mx = DM_M + (aw - m->dw) / 2;
    m->my = DM_TOP;
    int panel_h = DM_CAP + DM_BAR_H + 3 * DM_TH + 8; /* the bar, then the scale's note */
    int body = m->dh + 44 > panel_h ? m->dh + 44 : panel_h;
    m->foot_y = DM_TOP + body + 10;
    m->img_h = m->foot_y + DM_TH + DM_M;
    size_t nc = (size_t)m->cw * (size_t)m->ch;
    m->sum = calloc(nc, sizeof *m->sum);
    m->ext = calloc(nc, sizeof *m->ext);
    m->cnt = calloc(nc, sizeof *m->cnt);
    m->val = calloc(nc, sizeof *m->val);
    m->flag = calloc(nc, 1);
    m->dist = calloc(nc, 1);
    m->mark = calloc(nc, 1);
    if (!m->sum || !m->ext || !m->cnt || !m->val || !m->flag || !m->dist || !m->mark)
        return cf_fail(msg, msglen, CF_ENOMEM, "deviation map: out of memory for %d x %d cells",
                       m->cw, m->ch);
    m->begun = 1;
    return CF_OK;
}

int cf_devmap_add(cf_devmap_t *m, const double p[3], double d)
{
    if (!m->begun || !isfinite(d))
        return CF_EARG;
    double u, v;
    to_plane(m, p, &u, &v);
    if (!isfinite(u) || !isfinite(v))
        return CF_EARG;
    double x = floor((u - m->U0) / m->pitch), y = floor((v - m->V0) / m->pitch);
    if (!(x >= 0 && x < m->cw && y >= 0 && y < m->ch)) {
        m->outside++;
        return CF_OK;
    }
    int i = (int)x, j = m->ch - 1 - (int)y;
    size_t c = (size_t)j * (size_t)m->cw + (size_t)i;
    if (!m->cnt[c]++ || fabs(d) > fabs((double)m->ext[c]))
        m->ext[c] = (float)d;
    m->sum[c] += d;
    if (!m->n || d < m->dmin) {
        m->dmin = d;
        m->at_min[0] = u;
        m->at_min[1] = v;
    }
    if (!m->n || d > m->dmax) {
        m->dmax = d;
        m->at_max[0] = u;
        m->at_max[1] = v;
    }
    m->n++;
    m->sum_d += d;
    m->sq += d * d;
    m->within += fabs(d) <= m->tol;
    double t = d / m->tol, b = ceil(fabs(t) * 4);
    m->hist[(t < 0 ? DM_NBIN : 0) + (b < DM_NBIN - 1 ? (int)b : DM_NBIN - 1)]++;
    if (!m->autoscale)
        m->seg[seg_of_t(m, t)]++;
    return CF_OK;
}

long long cf_devmap_outside(const cf_devmap_t *m)
{
    return m->outside;
}

int cf_devmap_mark(cf_devmap_t *m, const double p[3], int what)
{
    if (!m->begun || (what & ~(CF_DEVMAP_NODATA | CF_DEVMAP_OUTLINE)))
        return CF_EARG;
    double u, v;
    to_plane(m, p, &u, &v);
    if (!isfinite(u) || !isfinite(v))
        return CF_EARG;
    double x = floor((u - m->U0) / m->pitch), y = floor((v - m->V0) / m->pitch);
    if (!(x >= 0 && x < m->cw && y >= 0 && y < m->ch))
        return CF_OK; /* off the map: counted by the caller, not drawn */
    m->mark[(size_t)(m->ch - 1 - (int)y) * (size_t)m->cw + (size_t)x] |= (unsigned char)what;
    m->marked = 1;
    return CF_OK;
}

double cf_devmap_pitch(const cf_devmap_t *m)
{
    return m->begun ? m->pitch : 0.0;
}

void cf_devmap_size(const cf_devmap_t *m, int *cells_w, int *cells_h, int *img_w, int *img_h)
{
    if (cells_w)
        *cells_w = m->begun ? m->cw : 0;
    if (cells_h)
        *cells_h = m->begun ? m->ch : 0;
    if (img_w)
        *img_w = m->begun ? DM_W : 0;
    if (img_h)
        *img_h = m->begun ? m->img_h : 0;
}

/* Image position of plane point (u, v), fractional pixels. */
static void uv_to_px(const cf_devmap_t *m, double u, double v, double *x, double *y)
{
    *x = m->mx + (u - m->U0) / (m->cw * m->pitch) * m->dw;
    *y = m->my + (m->V0 + m->ch * m->pitch - v) / (m->ch * m->pitch) * m->dh;
}

int cf_devmap_pixel(const cf_devmap_t *m, const double p[3], int *x, int *y)
{
    if (!m->begun)
        return -1;
    double u, v, fx, fy;
    to_plane(m, p, &u, &v);
    uv_to_px(m, u, v, &fx, &fy);
    if (!(fx >= m->mx && fx < m->mx + m->dw && fy >= m->my && fy < m->my + m->dh))
        return -1;
    *x = (int)fx;
    *y = (int)fy;
    return 0;
}

/* Gap length (empty cells between two measured ones along a row or a
 * column) that 95 % of the gaps do not exceed, when gaps are everywhere (at
 * least one per five measured cells: scan lines, sparse probing); 1 when
 * they are not (a dense scan, whose longer gaps are holes in the part). */
static int typical_gap(const cf_devmap_t *m)
{
    enum { GMAX = 64 };
    long long hist[GMAX + 2] = {0}, runs = 0, measured = 0;
    for (int pass = 0; pass < 2; pass++) {
        int nl = pass ? m->cw : m->ch, len = pass ? m->ch : m->cw;
        for (int l = 0; l < nl; l++) {
            int last = -1;
            for (int t = 0; t < len; t++) {
                size_t c = pass ? (size_t)t * m->cw + l : (size_t)l * m->cw + t;
                if (!(m->flag[c] & 1))
                    continue;
                measured += !pass;
                if (last >= 0 && t - last > 1) {
                    int g = t - last - 1;
                    hist[g > GMAX ? GMAX + 1 : g]++;
                    runs++;
                }
                last = t;
            }
        }
    }
    if (runs < measured / 5)
        return 1;
    long long c = 0;
    for (int g = 1; g <= GMAX; g++)
        if ((c += hist[g]) >= runs - runs / 20)
            return g;
    return GMAX;
}

/* Chessboard distance from every cell to the nearest cell with bit set in
 * flag (outside the raster counts as set when outside_set), capped at 255,
 * into m->dist: the classic two raster scans. */
static void chess_distance(cf_devmap_t *m, unsigned char bit, int outside_set)
{
    int cw = m->cw, ch = m->ch, out = outside_set ? 0 : 255;
    unsigned char *d = m->dist;
    for (int j = 0; j < ch; j++)
        for (int i = 0; i < cw; i++) {
            size_t c = (size_t)j * cw + i;
            if (m->flag[c] & bit) {
                d[c] = 0;
                continue;
            }
            int b = i > 0 ? d[c - 1] : out;
            if (j > 0) {
                b = d[c - cw] < b ? d[c - cw] : b;
                b = i > 0 && d[c - cw - 1] < b ? d[c - cw - 1] : b;
                b = i + 1 < cw && d[c - cw + 1] < b ? d[c - cw + 1] : b;
            } else
                b = out < b ? out : b;
            if (i == 0 || i + 1 == cw)
                b = out < b ? out : b;
            d[c] = (unsigned char)(b < 254 ? b + 1 : 255);
        }
    for (int j = ch - 1; j >= 0; j--)
        for (int i = cw - 1; i >= 0; i--) {
            size_t c = (size_t)j * cw + i;
            int b = i + 1 < cw ? d[c + 1] : out;
            if (j + 1 < ch) {
                b = d[c + cw] < b ? d[c + cw] : b;
                b = i + 1 < cw && d[c + cw + 1] < b ? d[c + cw + 1] : b;
                b = i > 0 && d[c + cw - 1] < b ? d[c + cw - 1] : b;
            } else
                b = out < b ? out : b;
            if (b + 1 < d[c])
                d[c] = (unsigned char)(b + 1);
        }
}

/* Value for an empty cell: inverse-square-distance mean of the nearest
 * measured cell in each quadrant around it, searched ring by ring. */
static float fill_value(const cf_devmap_t *m, int i, int j, int rmax)
{
    double best[4] = {0, 0, 0, 0}, val[4] = {0, 0, 0, 0};
    int found = 0;
    for (int r = 1; r <= rmax && found != 15; r++)
        for (int y = j - r; y <= j + r; y++) {
            int step = (y == j - r || y == j + r) ? 1 : 2 * r; /* the ring only */
            for (int x = i - r; x <= i + r; x += step) {
                if (x < 0 || y < 0 || x >= m->cw || y >= m->ch)
                    continue;
                size_t c = (size_t)y * m->cw + x;
                if (!(m->flag[c] & 1))
                    continue;
                int dx = x - i, dy = y - j;
                int q = dx > 0 && dy >= 0 ? 0 : dx <= 0 && dy > 0 ? 1 : dx < 0 && dy <= 0 ? 2 : 3;
                double d2 = (double)(dx * dx + dy * dy);
                if (!(found >> q & 1) || d2 < best[q]) {
                    best[q] = d2;
                    val[q] = m->val[c];
                }
                found |= 1 << q;
            }
        }
    double acc = 0, ws = 0;
    for (int q = 0; q < 4; q++)
        if (found >> q & 1) {
            acc += val[q] / best[q];
            ws += 1 / best[q];
        }
    return (float)(acc / ws);
}

/* Cell values, then the gaps filled. The cells to fill are the morphological
 * closing of the measured ones (dilate by R, erode by R, square element):
 * it bridges gaps up to 2R cells wide between scan lines or probe points,
 * but leaves a straight or convex outline where it is and holes wider than
 * 2R open. R is half the typical gap, so the closing follows the sampling. */
static void cell_values(cf_devmap_t *m)
{
    int cw = m->cw, ch = m->ch;
    size_t nc = (size_t)cw * (size_t)ch;
    for (size_t c = 0; c < nc; c++) {
        m->flag[c] = m->cnt[c] > 0;
        m->val[c] = !m->cnt[c]                    ? 0.0f
                    : m->cell == CF_DEVMAP_MAXABS ? m->ext[c]
                                                  : (float)(m->sum[c] / m->cnt[c]);
    }
    int g = typical_gap(m), R = (g + 1) / 2;
    R = R < 1 ? 1 : R > 16 ? 16 : R;
    m->fill_r = R;
    chess_distance(m, 1, 0); /* dilation: within R of a measured cell */
    for (size_t c = 0; c < nc; c++)
        if (m->dist[c] <= R)
            m->flag[c] |= 4;
    /* erosion: more than R from any cell outside the dilation */
    for (size_t c = 0; c < nc; c++)
        m->flag[c] ^= 4; /* bit 4 now marks the cells outside the dilation */
    chess_distance(m, 4, 1);
    for (size_t c = 0; c < nc; c++) {
        m->flag[c] &= 3;
        if (!m->flag[c] && m->dist[c] > R)
            m->flag[c] = 8; /* to fill */
    }
    for (int j = 0; j < ch; j++)
        for (int i = 0; i < cw; i++) {
            size_t c = (size_t)j * cw + i;
            if (m->flag[c] == 8) {
                m->val[c] = fill_value(m, i, j, 2 * R + 1);
                m->flag[c] = 2;
            }
        }
}

/* The map pixels: grey where the cell under the pixel has no data, else the
 * colour of the bilinear interpolation of the neighbouring cells with data. */
static void draw_map(cf_devmap_t *m, cf_image_t *im)
{
    int cw = m->cw, ch = m->ch;
    for (int y = 0; y < m->dh; y++) {
        double cy = (y + 0.5) * ch / m->dh, gy = cy - 0.5;
        int cj = (int)cy < ch ? (int)cy : ch - 1, j0 = (int)floor(gy);
        double fy = gy - j0;
        for (int x = 0; x < m->dw; x++) {
            double cx = (x + 0.5) * cw / m->dw, gx = cx - 0.5;
            int ci = (int)cx < cw ? (int)cx : cw - 1, i0 = (int)floor(gx);
            uint32_t col = DM_GREY;
            if (m->flag[(size_t)cj * cw + ci]) {
                double fx = gx - i0, acc = 0, ws = 0;
                for (int b = 0; b < 2; b++)
                    for (int a = 0; a < 2; a++) {
                        int i = i0 + a, j = j0 + b;
                        if (i < 0 || j < 0 || i >= cw || j >= ch || !m->flag[(size_t)j * cw + i])
                            continue;
                        double w = (a ? fx : 1 - fx) * (b ? fy : 1 - fy);
                        acc += w * m->val[(size_t)j * cw + i];
                        ws += w;
                    }
                col = palette[seg_of(m, ws > 0 ? acc / ws : m->val[(size_t)cj * cw + ci])];
            }
            /* The footprint's marks over it: its outline solid, the cells
             * no point reached hatched (what shows there is not measured). */
            unsigned char mk = m->mark[(size_t)cj * cw + ci];
            if (mk & CF_DEVMAP_OUTLINE)
                col = DM_OUTLINE;
            else if ((mk & CF_DEVMAP_NODATA) && (x + y) % 6 < 2)
                col = DM_HATCH;
            cf_image_set(im, m->mx + x, m->my + y, col);
        }
    }
    cf_image_box(im, m->mx - 1, m->my - 1, m->dw + 2, m->dh + 2, 0x707070);
}

static void text_bold(cf_image_t *im, int x, int y, uint32_t rgb, const char *s)
{
    cf_image_text(im, x, y, DM_FS, rgb, s);
    cf_image_text(im, x + 1, y, DM_FS, rgb, s);
}

/* A ring around the min or max point (open, so the point's own colour stays
 * visible), its value in a box beside it: right of the ring, or left when
 * the map area ends, and moved down (or up) off the box in avoid[4] (x, y,
 * w, h; w = 0: none). The box drawn is returned in box[4]. */
static void flag_point(const cf_devmap_t *m, cf_image_t *im, const double at[2], const char *s,
                       const int avoid[4], int box[4])
{
    double fx, fy;
    uv_to_px(m, at[0], at[1], &fx, &fy);
    int px = (int)fx, py = (int)fy;
    for (int dy = -9; dy <= 9; dy++)
        for (int dx = -9; dx <= 9; dx++) {
            double r = sqrt((double)(dx * dx + dy * dy));
            if (r >= 5.5 && r <= 7.5)
                cf_image_set(im, px + dx, py + dy, 0x000000);
            else if (r > 7.5 && r <= 9.0)
                cf_image_set(im, px + dx, py + dy, 0xFFFFFF);
        }
    int area_r = m->panel_x - DM_GAP / 2; /* labels may leave the map, not the map area */
    int bw = cf_text_width(s, DM_FS) + 8, bh = DM_TH + 8;
    int bx = px + 12 + bw <= area_r ? px + 12 : px - 12 - bw, by = py - bh / 2;
    bx = bx < DM_M / 2 ? DM_M / 2 : bx;
    by = by < m->my ? m->my : by;
    if (avoid[2] && bx < avoid[0] + avoid[2] && avoid[0] < bx + bw && by < avoid[1] + avoid[3] &&
        avoid[1] < by + bh)
        by =
            avoid[1] + avoid[3] + bh <= m->my + m->dh ? avoid[1] + avoid[3] + 2 : avoid[1] - bh - 2;
    cf_image_fill(im, bx, by, bw, bh, 0xFFFFFF);
    cf_image_box(im, bx, by, bw, bh, 0x000000);
    cf_image_text(im, bx + 4, by + 4, DM_FS, 0x000000, s);
    box[0] = bx;
    box[1] = by;
    box[2] = bw;
    box[3] = bh;
}

/* Top pixel row of colour bar segment seg (DM_NCOL - 1 at the top; seg -1:
 * the bar's bottom). The tolerance band is twice as tall as the others: it
 * is the one that matters, and it holds the 0 label. */
static int seg_top(int seg)
{
    int k = DM_NCOL - 1 - seg; /* boxes above it */
    return DM_TOP + DM_CAP + k * DM_SEG_H + (seg < DM_SEGS + 1 ? DM_SEG_H : 0);
}

/* The colour bar: boxes from the top (above the scale) down, deviation
 * labels at the box edges (the tolerance limits bold, with a heavy line),
 * the share of points in each colour on the left. */
static void draw_bar(const cf_devmap_t *m, cf_image_t *im)
{
    int x = m->panel_x, bx = x + m->pct_w + 8, lx = bx + DM_BOX_W + 10, y0 = seg_top(DM_NCOL - 1);
    char s[64];
    text_bold(im, x, DM_TOP, DM_INK, "deviation, mm");
    for (int seg = 0; seg < DM_NCOL; seg++) {
        int y = seg_top(seg), h = seg_top(seg - 1) - y;
        cf_image_fill(im, bx, y, DM_BOX_W, h, palette[seg]);
        double pct = m->n ? 100.0 * (double)m->seg[seg] / (double)m->n : 0.0;
        snprintf(s, sizeof s, "%.1f%%", pct);
        cf_image_text(im, x + m->pct_w - cf_text_width(s, DM_FS), y + (h - DM_TH) / 2, DM_FS,
                      0x404040, s);
    }
    cf_image_box(im, bx - 1, y0 - 1, DM_BOX_W + 2, DM_BAR_H + 2, 0x303030);
    for (int i = 0; i < DM_NCOL - 1; i++) {
        int y = seg_top(i);
        int tol_edge = i == DM_SEGS || i == DM_SEGS + 1;
        edge_label(m, i, s, sizeof s);
        if (tol_edge) {
            cf_image_fill(im, bx - 6, y - 1, DM_BOX_W + 12, 3, 0x000000);
            text_bold(im, lx, y - DM_TH / 2, 0x000000, s);
        } else {
            cf_image_fill(im, bx + DM_BOX_W, y, 6, 1, 0x303030);
            cf_image_text(im, lx, y - DM_TH / 2, DM_FS, DM_INK, s);
        }
    }
    /* 0 in the middle of the green box, between the tolerance labels, and
     * the band marked as the tolerance beside it. */
    int yz = seg_top(DM_SEGS + 1) + DM_SEG_H;
    cf_image_fill(im, bx + DM_BOX_W, yz, 6, 1, 0x303030);
    cf_image_text(im, lx, yz - DM_TH / 2, DM_FS, DM_INK, " 0");
    cf_image_text(im, x + m->pct_w - cf_text_width("tol", DM_FS), yz - DM_TH / 2 + DM_TH + 2, DM_FS,
                  0x000000, "tol");
    /* How the scale was set: by the data (its 99th percentile) or fixed. */
    int dp = cf_stats_decimals(m->tol), yn = seg_top(-1) + 10;
    if (m->autoscale) {
        text_bold(im, x, yn, DM_INK, "scale from data:");
        snprintf(s, sizeof s, "99%% of |d| <= %.*f", dp, m->p99);
    } else {
        text_bold(im, x, yn, DM_INK, "fixed scale:");
        snprintf(s, sizeof s, "\xC2\xB1%.*f mm", dp, m->range * m->tol);
    }
    cf_image_text(im, x, yn + DM_TH + 3, DM_FS, DM_INK, s);
}

/* Scale bar under the map, about 160 pixels of a round length, then the
 * key to the grey of cells without data. */
static void draw_scale(const cf_devmap_t *m, cf_image_t *im)
{
    double mm_per_px = m->cw * m->pitch / m->dw, target = 160 * mm_per_px;
    double dec = pow(10.0, floor(log10(target))), len = dec;
    if (5 * dec <= target)
        len = 5 * dec;
    else if (2 * dec <= target)
        len = 2 * dec;
    int px = (int)round(len / mm_per_px), x = m->mx, y = m->my + m->dh + 18;
    x = x + px + 200 > m->panel_x ? DM_M : x; /* a narrow map: start at the margin */
    cf_image_fill(im, x, y, px, 3, 0x000000);
    cf_image_fill(im, x, y - 5, 2, 13, 0x000000);
    cf_image_fill(im, x + px - 2, y - 5, 2, 13, 0x000000);
    char s[48];
    snprintf(s, sizeof s, "%g mm", len);
    int kx = x + px + 10 + cf_image_text(im, x + px + 10, y + 1 - DM_TH / 2, DM_FS, DM_INK, s) + 40;
    cf_image_fill(im, kx, y - 7, 18, 16, DM_GREY);
    cf_image_box(im, kx, y - 7, 18, 16, 0x707070);
    int w = cf_image_text(im, kx + 26, y + 1 - DM_TH / 2, DM_FS, DM_INK, "no data");
    if (!m->marked)
        return;
    /* The hatch of the footprint's "no data" cells (cf_devmap_mark). */
    kx += 26 + w + 24;
    for (int j = 0; j < 16; j++)
        for (int i = 0; i < 18; i++)
            cf_image_set(im, kx + i, y - 7 + j, (kx + i + y - 7 + j) % 6 < 2 ? DM_HATCH : DM_GREY);
    cf_image_box(im, kx, y - 7, 18, 16, DM_OUTLINE);
    cf_image_text(im, kx + 26, y + 1 - DM_TH / 2, DM_FS, DM_INK, "surface cells without points");
}

int cf_devmap_render(cf_devmap_t *m, const cf_stats_t *st, cf_image_t *im, char *msg, size_t msglen)
{
    if (!m || !im || !m->begun)
        return cf_fail(msg, msglen, CF_EARG, "deviation map: render before cf_devmap_begin");
    int ec = cf_image_init(im, DM_W, m->img_h, 0xFFFFFF, msg, msglen);
    if (ec)
        return ec;
    if (m->autoscale)
        auto_scale(m);
    cell_values(m);
    draw_map(m, im);
    int dp = cf_stats_decimals(m->tol);
    char s[320], num[2][40];
    /* Flags on the extremes that are out of tolerance (in tolerance they
     * would only clutter the picture; the title gives them anyway). */
    int box[4] = {0, 0, 0, 0};
    if (m->n && m->dmin < -m->tol) {
        snprintf(num[0], sizeof num[0], "min %+.*f", dp, m->dmin);
        static const int none[4] = {0, 0, 0, 0};
        flag_point(m, im, m->at_min, num[0], none, box);
    }
    if (m->n && m->dmax > m->tol) {
        int first[4] = {box[0], box[1], box[2], box[3]};
        snprintf(num[1], sizeof num[1], "max %+.*f", dp, m->dmax);
        flag_point(m, im, m->at_max, num[1], first, box);
    }
    draw_bar(m, im);
    draw_scale(m, im);
    /* Title: the caller's line, then the figures. */
    text_bold(im, DM_M, 18, 0x000000, m->title);
    long long n = st ? st->n : m->n;
    double rms = st ? cf_stats_rms(st) : m->n ? sqrt(m->sq / (double)m->n) : NAN;
    double mean = st ? cf_stats_mean(st) : m->n ? m->sum_d / (double)m->n : NAN;
    double dmin = st ? st->min : m->n ? m->dmin : NAN, dmax = st ? st->max : m->n ? m->dmax : NAN;
    double inpct = st     ? cf_stats_within_pct(st)
                   : m->n ? 100.0 * (double)m->within / (double)m->n
                          : NAN;
    if (n) {
        snprintf(s, sizeof s,
                 "RMS %.*f  mean %+.*f  min %+.*f  max %+.*f mm  %.1f %% within "
                 "\xC2\xB1%.*f mm  %lld points",
                 dp, rms, dp, mean, dp, dmin, dp, dmax, inpct, dp, m->tol, n);
        if (cf_text_width(s, DM_FS) > DM_W - 2 * DM_M) /* too long: the figures that matter */
            snprintf(s, sizeof s, "RMS %.*f  min %+.*f  max %+.*f mm  %.1f %% in \xC2\xB1%.*f mm",
                     dp, rms, dp, dmin, dp, dmax, inpct, dp, m->tol);
    } else
        snprintf(s, sizeof s, "no points   tolerance \xC2\xB1%.*f mm", dp, m->tol);
    cf_image_text(im, DM_M, 46, DM_FS, DM_INK, s);
    cf_image_fill(im, DM_M, 70, DM_W - 2 * DM_M, 1, 0xB0B0B0);
    /* Footer: the view, so that the picture can be related to the part. */
    double a[3], b[3];
    for (int i = 0; i < 3; i++) { /* no "-0.000" */
        a[i] = fabs(m->pl.e1[i]) < 5e-4 ? 0.0 : m->pl.e1[i];
        b[i] = fabs(m->pl.e2[i]) < 5e-4 ? 0.0 : m->pl.e2[i];
    }
    int k = snprintf(s, sizeof s,
                     "view: right (%+.3f %+.3f %+.3f)  up (%+.3f %+.3f %+.3f)  cell %.3g mm", a[0],
                     a[1], a[2], b[0], b[1], b[2], m->pitch);
    if (m->outside && k > 0 && (size_t)k < sizeof s)
        snprintf(s + k, sizeof s - (size_t)k, "  %lld off the map", m->outside);
    cf_image_text(im, DM_M, m->foot_y, DM_FS, 0x505050, s);
    return CF_OK;
}

int cf_devmap_write_png(cf_devmap_t *m, const cf_stats_t *st, const char *path, char *msg,
                        size_t msglen)
{
    cf_image_t im;
    int ec = cf_devmap_render(m, st, &im, msg, msglen);
    if (ec)
        return ec;
    ec = cf_png_write_image(path, &im, msg, msglen);
    cf_image_free(&im);
    return ec;
}
