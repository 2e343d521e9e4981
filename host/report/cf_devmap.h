/* SPDX-License-Identifier: MIT */
/* cf_devmap.h: the colour deviation map of an inspection report: a top view
 * of the measured points on a plane (by default the least-squares plane of
 * the points, i.e. the view that shows the part with the largest area), each
 * pixel coloured by the deviation of the points that fall in it, on the
 * segmented blue - green - red scale metrology software uses, with a labelled
 * colour bar, the share of points per colour, min/max flags, a scale bar and
 * a title with RMS, max and the tolerance. Written as PNG by cf_png.
 *
 * Memory is fixed by the raster (at most about 915 x 723 cells of 22 bytes,
 * 15 MB, allocated by cf_devmap_begin; a 64 KB histogram of |d| for the
 * scale; the image, 3.2 MB, while rendering),
 * never by the number of points: they stream through three passes the
 * caller drives,
 *     1. cf_devmap_plane_add  every point  -> cf_devmap_plane_fit (the view)
 *     2. cf_devmap_extent     every point  -> cf_devmap_begin     (the raster)
 *     3. cf_devmap_add        every point with its deviation
 * then cf_devmap_write_png. Pass 1 is skipped with a given plane
 * (cf_plane_from_axes), pass 2 with a given extent (cf_devmap_set_extent). */
#ifndef CF_DEVMAP_H
#define CF_DEVMAP_H

#include "cf_png.h"
#include "cf_stats.h"
#include <stddef.h>

/* A view plane: points map to u = (p - o).e1 (right), v = (p - o).e2 (up);
 * n = e1 x e2 points towards the viewer. */
typedef struct cf_plane {
    double o[3], e1[3], e2[3], n[3];
} cf_plane_t;

/* Streaming least-squares plane: mean and co-moment matrix of the points
 * (Welford's update, stable far from the origin). */
typedef struct cf_planefit {
    long long n;
    double mean[3];
    double c[6]; /* sum of (p - mean)(p - mean)^T: xx yy zz xy xz yz */
} cf_planefit_t;

void cf_devmap_plane_init(cf_planefit_t *pf);
void cf_devmap_plane_add(cf_planefit_t *pf, const double p[3]);

/* The least-squares plane of the points: through the centroid, normal n
 * along the smallest principal axis (eigenvectors of the covariance by
 * Jacobi rotations), so the view shows the part with its largest area; n
 * has its largest component positive (a part lying in XY is seen from +Z).
 * In-plane axes follow the machine's: when n is within 60 degrees of Z, e1
 * (right) is X projected onto the plane and e2 = n x e1 (up); otherwise (a
 * wall) e2 is Z projected and e1 = e2 x n. sd (optional): the
 * standard deviations of the points along the principal axes, largest
 * first (sd[2] is the RMS distance of the points from the plane). CF_EEMPTY
 * without points. */
int cf_devmap_plane_fit(const cf_planefit_t *pf, cf_plane_t *pl, double sd[3], char *msg,
                        size_t msglen);

/* A given view: e1 normalised, e2 made orthogonal to it and normalised,
 * n = e1 x e2. CF_EARG if e1 and e2 are (nearly) parallel or zero. */
int cf_plane_from_axes(cf_plane_t *pl, const double o[3], const double e1[3], const double e2[3],
                       char *msg, size_t msglen);

typedef enum cf_devmap_cell {
    CF_DEVMAP_MEAN = 0,  /* a cell shows the mean deviation of its points */
    CF_DEVMAP_MAXABS = 1 /* ... the deviation of largest magnitude (defects stand out) */
} cf_devmap_cell_t;

/* The colour scale is symmetric about 0: green within +/- tol (the band
 * marked on the legend), four steps each side out to the scale's end, one
 * colour each beyond. Its end is, in this order: the one
 * cf_devmap_set_scale fixed in mm; range * tol when range is not 0;
 * otherwise chosen from the data at render, the smallest end 1 + 4 k tol
 * (k a round multiple of 1/4: 0.25, 0.5, 1, 2, 2.5, 5, ... 200) covering
 * the 99th percentile of |d|, so that at most 1 % of the points fall off
 * the scale. A fixed end must lie in (tol, 1000 tol]. */
typedef struct cf_devmap_opts {
    double tol;            /* mm, > 0: green is |d| <= tol */
    double range;          /* fixed end at +/- range * tol (> 1); 0: see above */
    cf_devmap_cell_t cell; /* what a cell shows */
    const char *title;     /* first line of the image; NULL: "Deviation map" */
} cf_devmap_opts_t;

typedef struct cf_devmap cf_devmap_t; /* opaque */

/* The map of a view. The title is copied (up to 160 bytes). CF_EARG, CF_ENOMEM. */
int cf_devmap_create(cf_devmap_t **m, const cf_plane_t *pl, const cf_devmap_opts_t *o, char *msg,
                     size_t msglen);
void cf_devmap_free(cf_devmap_t *m);

/* Fix the scale's end at +/- scale mm (`cellfit report --scale MM`), or with
 * scale = 0 choose it from the data (the default unless opts.range is
 * set). Any time before cf_devmap_render. CF_EARG unless tol < scale <=
 * 1000 tol (or 0). */
int cf_devmap_set_scale(cf_devmap_t *m, double scale, char *msg, size_t msglen);

/* Pass 2: grow the extent by one point (non-finite coordinates ignored). */
void cf_devmap_extent(cf_devmap_t *m, const double p[3]);

/* Or give the extent in plane coordinates, mm, and the number of points
 * expected (0: unknown), which sets how fine the raster is. */
void cf_devmap_set_extent(cf_devmap_t *m, double u0, double u1, double v0, double v1,
                          long long npts);

/* Fix the raster: image size from the extent's aspect ratio; cell size the
 * finer of one display pixel and the mean point spacing (so sparse points
 * do not leave a speckle of empty cells). CF_EEMPTY with an empty extent,
 * CF_ENOMEM. */
int cf_devmap_begin(cf_devmap_t *m, char *msg, size_t msglen);

/* Pass 3: one point and its signed deviation d (mm). Points outside the
 * extent are counted (cf_devmap_outside) and left out. CF_EARG before
 * cf_devmap_begin or for non-finite input (nothing counted). */
int cf_devmap_add(cf_devmap_t *m, const double p[3], double d);
long long cf_devmap_outside(const cf_devmap_t *m);

/* Marks of the data footprint (issue 14, honest edges; cf_fpmap): the
 * raster cell under p (a point of the surface) drawn hatched (NODATA: no
 * measured point on the surface there) or solid (OUTLINE: the footprint's
 * edge), over the deviations, with a key under the map. Points off the map
 * are left out. After cf_devmap_begin; CF_EARG before it, for another
 * what or non-finite p. */
#define CF_DEVMAP_NODATA 1
#define CF_DEVMAP_OUTLINE 2
int cf_devmap_mark(cf_devmap_t *m, const double p[3], int what);

/* The raster's cell size, mm (0 before cf_devmap_begin). */
double cf_devmap_pitch(const cf_devmap_t *m);

/* Draw the report image into im (allocated here; cf_image_free it). st, when
 * not NULL, supplies the title's figures (so they match the text report);
 * otherwise the map's own points do. CF_EARG before cf_devmap_begin,
 * CF_ENOMEM. */
int cf_devmap_render(cf_devmap_t *m, const cf_stats_t *st, cf_image_t *im, char *msg,
                     size_t msglen);

/* cf_devmap_render, then cf_png_write (atomic: path.tmp, then rename). */
int cf_devmap_write_png(cf_devmap_t *m, const cf_stats_t *st, const char *path, char *msg,
                        size_t msglen);

/* The colour a deviation gets on the scale (0xRRGGBB). A scale chosen from
 * the data is known after cf_devmap_render (3 tol before). */
uint32_t cf_devmap_colour(const cf_devmap_t *m, double d);

/* The scale's end, mm (see cf_devmap_opts_t; from the data: after render). */
double cf_devmap_scale_end(const cf_devmap_t *m);

/* Where point p lands in the rendered image (pixel column x, row y); 0 if it
 * is on the map, -1 if not (or before cf_devmap_begin). */
int cf_devmap_pixel(const cf_devmap_t *m, const double p[3], int *x, int *y);

/* The raster (cells across and down) and the image size, after begin. */
void cf_devmap_size(const cf_devmap_t *m, int *cells_w, int *cells_h, int *img_w, int *img_h);

#endif
