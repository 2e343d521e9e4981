/* SPDX-License-Identifier: MIT */
/* sim_gev.c: the simulated profiler (sim_gev.h): a map of the distances
 * the profiler sees over one pass of the part, computed once, and the fake
 * camera's fill-pattern callback that turns rows of it into Mono16 range
 * profiles with noise. The callback runs on the fake camera's thread; it
 * reads the map and owns the noise generator, nothing else. */
#include "sim_gev.h"
#if CF_HAVE_ARAVIS
#include <arv.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NOISE_TAB 65536 /* Gaussian samples drawn from cheaply per value */

struct sim_gev {
    ArvGvFakeCamera *cam;
    sim_gev_cfg_t c;
    double *map; /* profiles x width distances, NaN: no reading */
    float *noise;
    uint64_t rs; /* xorshift state, camera thread only */
};

/* Slope |grad z| at map cell (k, i) by central differences where they
 * exist; the flank test drops readings steeper than the flank angle. */
static double slope(const sim_gev_t *g, long k, long i)
{
    const sim_gev_cfg_t *c = &g->c;
    long P = c->profiles, W = c->width;
    const double *m = g->map;
    long k0 = k > 0 ? k - 1 : k, k1 = k < P - 1 ? k + 1 : k;
    long i0 = i > 0 ? i - 1 : i, i1 = i < W - 1 ? i + 1 : i;
    double gx = 0, gy = 0;
    if (k1 > k0 && !isnan(m[k1 * W + i]) && !isnan(m[k0 * W + i]))
        gx = (m[k1 * W + i] - m[k0 * W + i]) / ((double)(k1 - k0) * c->dx);
    if (i1 > i0 && !isnan(m[k * W + i1]) && !isnan(m[k * W + i0]))
        gy = (m[k * W + i1] - m[k * W + i0]) / ((double)(i1 - i0) * c->dy);
    return hypot(gx, gy);
}

static int build_map(sim_gev_t *g)
{
    sim_gev_cfg_t *c = &g->c;
    const sim_part_t *p = c->part;
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (int k = 0; k < p->ns * p->ns; k++) {
        const double *q = p->seed + 4 * k;
        xlo = fmin(xlo, q[0]);
        xhi = fmax(xhi, q[0]);
        ylo = fmin(ylo, q[1]);
        yhi = fmax(yhi, q[1]);
    }
    c->x0 = xlo;
    c->dx = (xhi - xlo) / (double)(c->profiles > 1 ? c->profiles - 1 : 1);
    c->y0 = ylo;
    c->dy = (yhi - ylo) / (double)(c->width > 1 ? c->width - 1 : 1);
    size_t n = (size_t)c->profiles * (size_t)c->width;
    g->map = malloc(n * sizeof *g->map);
    g->noise = malloc(NOISE_TAB * sizeof *g->noise);
    if (!g->map || !g->noise)
        return -1;
    for (long k = 0; k < c->profiles; k++) {
        double uv[2] = {NAN, NAN};
        for (long i = 0; i < c->width; i++) {
            double z, x = c->x0 + (double)k * c->dx, y = c->y0 + (double)i * c->dy;
            double *m = g->map + k * c->width + i;
            if (sim_part_z_near(p, x, y, uv, &z)) {
                *m = NAN;
                uv[0] = uv[1] = NAN; /* off the part: start afresh */
            } else
                *m = c->z0 - z;
        }
    }
    /* Flanks after the whole map (their slope needs the neighbours). */
    double tmax = tan(c->flank_deg * 3.14159265358979323846 / 180.0);
    unsigned char *drop = calloc(n, 1);
    if (!drop)
        return -1;
    for (long k = 0; k < c->profiles; k++)
        for (long i = 0; i < c->width; i++)
            drop[k * c->width + i] = !isnan(g->map[k * c->width + i]) && slope(g, k, i) > tmax;
    for (size_t j = 0; j < n; j++)
        if (drop[j])
            g->map[j] = NAN;
    free(drop);
    sim_rng_t r;
    sim_rng_seed(&r, c->seed, 7);
    for (int j = 0; j < NOISE_TAB; j++)
        g->noise[j] = (float)(c->noise * sim_gauss(&r));
    g->rs = c->seed * 2654435761u + 1;
    return 0;
}

static void fill(ArvBuffer *b, void *data, guint32 exposure_us, guint32 gain, ArvPixelFormat fmt)
{
    sim_gev_t *g = data;
    const sim_gev_cfg_t *c = &g->c;
    (void)exposure_us;
    (void)gain;
    /* The fake camera checked the buffer against Width x Height at the
     * pixel format's size before calling (arv_buffer_get_data reports
     * what was received, 0 here). */
    uint16_t *out = (uint16_t *)(uintptr_t)arv_buffer_get_data(b, NULL);
    gint w = arv_buffer_get_image_width(b), h = arv_buffer_get_image_height(b);
    if (!out || w < 1 || h < 1 || fmt != ARV_PIXEL_FORMAT_MONO_16)
        return; /* not configured as a profiler: the client refuses such frames */
    /* Profiles are numbered by the frame id on the wire (1..65535, as
     * GigE Vision 1.x sends it), which both sides see alike however many
     * acquisitions came before. */
    uint64_t id = arv_buffer_get_frame_id(b);
    for (gint r = 0; r < h; r++) {
        uint64_t n = id * (uint64_t)h + (uint64_t)r;
        const double *m = g->map + (long)(n % (uint64_t)c->profiles) * c->width;
        uint16_t *row = out + (size_t)r * (size_t)w;
        for (gint i = 0; i < w; i++) {
            if (i >= c->width || isnan(m[i])) {
                row[i] = 0;
                continue;
            }
            g->rs ^= g->rs << 13;
            g->rs ^= g->rs >> 7;
            g->rs ^= g->rs << 17;
            double d = m[i] + g->noise[g->rs & (NOISE_TAB - 1)];
            double v = floor((d - c->lo) / c->scale + 0.5);
            row[i] = d <= c->lo || d > c->hi || v < 1 || v > 65535 ? 0 : (uint16_t)v;
        }
    }
}

int sim_gev_start(sim_gev_t **out, sim_gev_cfg_t *c, char *msg, size_t len)
{
    *out = NULL;
    if (!c->part || c->width < 2 || c->height < 1 || c->profiles < 2 || !(c->scale > 0) ||
        !(c->lo < c->hi) || c->loss < 0 || c->loss > 1) {
        snprintf(msg, len, "gev: bad configuration");
        return -1;
    }
    sim_gev_t *g = calloc(1, sizeof *g);
    if (!g) {
        snprintf(msg, len, "out of memory");
        return -1;
    }
    g->c = *c;
    if (build_map(g)) {
        snprintf(msg, len, "out of memory");
        sim_gev_stop(g);
        return -1;
    }
    *c = g->c;
    g->cam = arv_gv_fake_camera_new("127.0.0.1", c->serial);
    if (!g->cam || !arv_gv_fake_camera_is_running(g->cam)) {
        snprintf(msg, len,
                 "gev: the fake camera did not start on 127.0.0.1 (is the GigE Vision "
                 "control port 3956 taken by another profiler?)");
        sim_gev_stop(g);
        return -1;
    }
    g_object_set(g->cam, "gvsp-lost-ratio", c->loss, NULL);
    ArvFakeCamera *fc = arv_gv_fake_camera_get_fake_camera(g->cam);
    arv_fake_camera_write_register(fc, ARV_FAKE_CAMERA_REGISTER_WIDTH, (guint32)c->width);
    arv_fake_camera_write_register(fc, ARV_FAKE_CAMERA_REGISTER_HEIGHT, (guint32)c->height);
    arv_fake_camera_set_fill_pattern(fc, fill, g);
    *out = g;
    return 0;
}

void sim_gev_stop(sim_gev_t *g)
{
    if (!g)
        return;
    if (g->cam)
        g_object_unref(g->cam); /* joins the camera's thread */
    free(g->map);
    free(g->noise);
    free(g);
}

#else /* !CF_HAVE_ARAVIS: cellsim built without Aravis has no profiler. */
#include <stdio.h>

int sim_gev_start(sim_gev_t **g, sim_gev_cfg_t *c, char *msg, size_t len)
{
    (void)c;
    *g = NULL;
    snprintf(msg, len, "--gev: this cellsim is built without Aravis (libaravis-dev)");
    return -1;
}

void sim_gev_stop(sim_gev_t *g)
{
    (void)g;
}
#endif
