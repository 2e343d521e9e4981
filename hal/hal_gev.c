/* SPDX-License-Identifier: MIT */
/* hal_gev.c: the GigE Vision profiler (hal_gev.h) on Aravis: open by
 * address, features, the stream with packet resend, frame ids unwrapped
 * and every lost frame counted. */
#include "hal_gev.h"
#if CF_HAVE_ARAVIS
#include "hal.h"
#include "hal_dl.h"
#include "hal_dl_libs.h"
#include <arv.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Aravis (and the GLib it brings), loaded by the first open (hal_dl.h):
 * only a profiler scan maps them. GObject's type macros call GLib
 * directly, so the type checks go through the table too (is_gv_stream). */
/* clang-format off */
#define ARV_SYMS(X) \
    X(arv_buffer_get_data) \
    X(arv_buffer_get_frame_id) \
    X(arv_buffer_get_status) \
    X(arv_buffer_get_timestamp) \
    X(arv_buffer_new) \
    X(arv_camera_create_stream) \
    X(arv_camera_get_device_serial_number) \
    X(arv_camera_get_payload) \
    X(arv_camera_get_region) \
    X(arv_camera_gv_set_packet_size_adjustment) \
    X(arv_camera_is_gv_device) \
    X(arv_camera_new) \
    X(arv_camera_set_acquisition_mode) \
    X(arv_camera_set_exposure_time) \
    X(arv_camera_set_frame_rate) \
    X(arv_camera_set_pixel_format) \
    X(arv_camera_set_region) \
    X(arv_camera_start_acquisition) \
    X(arv_camera_stop_acquisition) \
    X(arv_gv_stream_get_statistics) \
    X(arv_gv_stream_get_type) \
    X(arv_stream_get_statistics) \
    X(arv_stream_push_buffer) \
    X(arv_stream_timeout_pop_buffer) \
    X(g_error_free) \
    X(g_get_monotonic_time) \
    X(g_object_set) \
    X(g_object_unref) \
    X(g_type_check_instance_is_a)
/* clang-format on */
HAL_DL_TABLE(arv, ARV_SYMS)
static hal_dl_t arv_lib =
    HAL_DL_LIB(arv, HAL_DL_SONAME_ARAVIS, HAL_DL_PACKAGE_ARAVIS, "a GigE Vision profiler (gev:)");

/* ARV_IS_GV_STREAM, on the table. */
static int is_gv_stream(ArvStream *s)
{
    return arv.g_type_check_instance_is_a((GTypeInstance *)s, arv.arv_gv_stream_get_type());
}

struct hal_gev {
    ArvCamera *cam;
    ArvStream *stream;
    ArvBuffer *held; /* the frame last handed out, pushed back at the next call */
    size_t payload;
    int width, height, buffers;
    int any;          /* a frame id was seen */
    uint64_t last_id; /* highest unwrapped id delivered */
    uint64_t pending; /* frames lost since the last delivered one */
    hal_gev_stats_t st;
    char err[256];
};

static int fail(hal_gev_t *g, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(g->err, sizeof g->err, fmt, ap);
    va_end(ap);
    return code;
}

/* GError to our error text and code; frees it. */
static int gfail(hal_gev_t *g, int code, const char *what, GError *e)
{
    int rc = fail(g, code, "%s: %s", what, e ? e->message : "failed");
    if (e)
        arv.g_error_free(e);
    return rc;
}

int hal_gev_open(hal_gev_t **out, const char *uri, const hal_gev_opts_t *o, char *err, size_t len)
{
    hal_uri_t u;
    if (!out)
        return RIG_EARG;
    *out = NULL;
    int rc = hal_uri_parse(uri, &u, err, len);
    if (rc)
        return rc;
    if (u.kind != HAL_GEV) {
        snprintf(err, len, "%s: not a gev: URI", uri);
        return RIG_EARG;
    }
    if (hal_dl_load(&arv_lib)) {
        snprintf(err, len, "%s", hal_dl_error(&arv_lib));
        return RIG_EUNSUPPORTED;
    }
    hal_gev_t *g = calloc(1, sizeof *g);
    if (!g) {
        snprintf(err, len, "out of memory");
        return RIG_EARG;
    }
    hal_gev_opts_t d = {0};
    if (o)
        d = *o;
    g->buffers = d.buffers > 0 ? d.buffers : 16;
    GError *e = NULL;
    g->cam = arv.arv_camera_new(u.path, &e);
    if (!g->cam) {
        rc = gfail(g, RIG_EOPEN, u.path, e);
        goto out;
    }
    if (arv.arv_camera_is_gv_device(g->cam)) /* no test-packet probing at every stream */
        arv.arv_camera_gv_set_packet_size_adjustment(g->cam, ARV_GV_PACKET_SIZE_ADJUSTMENT_NEVER);
    if (u.serial[0]) {
        const char *sn = arv.arv_camera_get_device_serial_number(g->cam, &e);
        if (!sn) {
            rc = gfail(g, RIG_EOPEN, "serial number", e);
            goto out;
        }
        if (strcmp(sn, u.serial)) {
            rc = fail(g, RIG_EOPEN, "%s: serial %s, not %s", u.path, sn, u.serial);
            goto out;
        }
    }
    /* Range values are 16 bits a point; a profiler without Mono16 is not one. */
    arv.arv_camera_set_pixel_format(g->cam, ARV_PIXEL_FORMAT_MONO_16, &e);
    if (e) {
        rc = gfail(g, RIG_EUNSUPPORTED, "PixelFormat Mono16", e);
        goto out;
    }
    if (d.width > 0 || d.height > 0) {
        gint x, y, w, h;
        arv.arv_camera_get_region(g->cam, &x, &y, &w, &h, &e);
        if (!e)
            arv.arv_camera_set_region(g->cam, 0, 0, d.width > 0 ? d.width : w,
                                      d.height > 0 ? d.height : h, &e);
        if (e) {
            rc = gfail(g, RIG_EUNSUPPORTED, "Width/Height", e);
            goto out;
        }
    }
    if (d.exposure_us > 0)
        arv.arv_camera_set_exposure_time(g->cam, d.exposure_us, &e);
    if (!e && d.frame_rate > 0)
        arv.arv_camera_set_frame_rate(g->cam, d.frame_rate, &e);
    if (!e) {
        gint x, y;
        arv.arv_camera_get_region(g->cam, &x, &y, &g->width, &g->height, &e);
    }
    if (!e)
        g->payload = arv.arv_camera_get_payload(g->cam, &e);
    if (e) {
        rc = gfail(g, RIG_EUNSUPPORTED, "features", e);
        goto out;
    }
    if (g->payload < (size_t)g->width * (size_t)g->height * 2) {
        rc = fail(g, RIG_EPROTO, "payload %zu bytes for %d x %d Mono16", g->payload, g->width,
                  g->height);
        goto out;
    }
    *out = g;
    return RIG_OK;
out:
    snprintf(err, len, "%s", g->err);
    hal_gev_close(g);
    return rc;
}

int hal_gev_start(hal_gev_t *g)
{
    if (!g || g->stream)
        return g ? fail(g, RIG_ESTATE, "already started") : RIG_EARG;
    GError *e = NULL;
    g->stream = arv.arv_camera_create_stream(g->cam, NULL, NULL, &e);
    if (!g->stream)
        return gfail(g, RIG_EOPEN, "stream", e);
    if (is_gv_stream(g->stream))
        arv.g_object_set(g->stream, "packet-resend", ARV_GV_STREAM_PACKET_RESEND_ALWAYS,
                         "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, NULL);
    for (int i = 0; i < g->buffers; i++)
        arv.arv_stream_push_buffer(g->stream, arv.arv_buffer_new(g->payload, NULL));
    arv.arv_camera_set_acquisition_mode(g->cam, ARV_ACQUISITION_MODE_CONTINUOUS, &e);
    if (!e)
        arv.arv_camera_start_acquisition(g->cam, &e);
    if (e)
        return gfail(g, RIG_EOPEN, "start acquisition", e);
    g->any = 0;
    g->pending = 0;
    return RIG_OK;
}

/* The unwrapped id of a wire id. GigE Vision 1.x ids run 1..65535 and
 * wrap skipping 0; an unwrapped id U has the wire id ((U - 1) mod 65535) + 1
 * and each new one is the first at or after the last with its wire id.
 * Extended (64-bit) ids are taken as they are. */
static uint64_t unwrap(const hal_gev_t *g, uint64_t w)
{
    if (!g->any || w > 0xFFFF || w == 0)
        return w;
    return g->last_id + ((w + 65535 - 1) - (g->last_id - 1) % 65535) % 65535;
}

/* Account a delivered frame's id: the ids skipped since the last
 * delivered one are lost frames (arrived bad or never at all). The ids of
 * bad frames are not trusted (a lost leader leaves them unknown). */
static void seen(hal_gev_t *g, uint64_t id)
{
    if (g->any && id > g->last_id + 1) {
        g->st.frames_gap += id - g->last_id - 1;
        g->pending += id - g->last_id - 1;
    }
    if (!g->any || id > g->last_id)
        g->last_id = id;
    g->any = 1;
}

int hal_gev_next(hal_gev_t *g, hal_gev_frame_t *f, int timeout_ms)
{
    if (!g || !f)
        return RIG_EARG;
    if (!g->stream)
        return fail(g, RIG_ESTATE, "not started");
    if (g->held) {
        arv.arv_stream_push_buffer(g->stream, g->held);
        g->held = NULL;
    }
    gint64 end = arv.g_get_monotonic_time() + (gint64)timeout_ms * 1000;
    for (;;) {
        gint64 left = end - arv.g_get_monotonic_time();
        if (left <= 0)
            return fail(g, RIG_ETIMEOUT, "no frame in %d ms", timeout_ms);
        ArvBuffer *b = arv.arv_stream_timeout_pop_buffer(g->stream, (guint64)left);
        if (!b)
            continue;
        size_t n = 0;
        const void *data = arv.arv_buffer_get_data(b, &n);
        if (arv.arv_buffer_get_status(b) != ARV_BUFFER_STATUS_SUCCESS ||
            n < (size_t)g->width * (size_t)g->height * 2) {
            /* Its id shows up as a gap at the next good frame; before the
             * first one delivered it is no loss of this scan (the numbering
             * starts there), so it is counted apart, or bad would exceed
             * lost (profiler.sh saw 53 bad of 52 lost). */
            if (g->any)
                g->st.frames_bad++;
            else
                g->st.frames_bad_before++;
            arv.arv_stream_push_buffer(g->stream, b);
            continue;
        }
        uint64_t id = unwrap(g, arv.arv_buffer_get_frame_id(b));
        seen(g, id);
        g->st.frames++;
        f->id = id;
        f->timestamp_ns = arv.arv_buffer_get_timestamp(b);
        f->gap_before = g->pending;
        g->pending = 0;
        f->width = g->width;
        f->height = g->height;
        f->range = data;
        g->held = b;
        return RIG_OK;
    }
}

int hal_gev_stop(hal_gev_t *g)
{
    if (!g)
        return RIG_EARG;
    GError *e = NULL;
    if (g->stream) {
        arv.arv_camera_stop_acquisition(g->cam, &e);
        if (e)
            arv.g_error_free(e);
    }
    return RIG_OK;
}

void hal_gev_stats(const hal_gev_t *g, hal_gev_stats_t *s)
{
    if (!g || !s)
        return;
    *s = g->st;
    if (g->stream) {
        guint64 done = 0, failures = 0, underruns = 0;
        arv.arv_stream_get_statistics(g->stream, &done, &failures, &underruns);
        s->underruns = underruns;
        if (is_gv_stream(g->stream)) {
            guint64 resent = 0, missing = 0;
            arv.arv_gv_stream_get_statistics((ArvGvStream *)g->stream, &resent, &missing);
            s->packets_resent = resent;
            s->packets_missing = missing;
        }
    }
}

void hal_gev_size(const hal_gev_t *g, int *width, int *height)
{
    if (width)
        *width = g ? g->width : 0;
    if (height)
        *height = g ? g->height : 0;
}

const char *hal_gev_error(const hal_gev_t *g)
{
    return g ? g->err : "no profiler";
}

void hal_gev_close(hal_gev_t *g)
{
    if (!g)
        return;
    if (g->held && g->stream)
        arv.arv_stream_push_buffer(g->stream, g->held);
    g->held = NULL;
    if (g->stream) {
        hal_gev_stop(g);
        arv.g_object_unref(g->stream);
    }
    if (g->cam)
        arv.g_object_unref(g->cam);
    free(g);
}

#else /* !CF_HAVE_ARAVIS: a build without Aravis (e.g. a cross build whose
       * target has no libaravis-dev): every call says so. */
#include "rig_err.h"
#include <stdio.h>
#include <string.h>

int hal_gev_open(hal_gev_t **g, const char *uri, const hal_gev_opts_t *o, char *err, size_t len)
{
    (void)uri;
    (void)o;
    if (g)
        *g = NULL;
    if (err && len)
        snprintf(err, len, "this cellfit is built without Aravis (libaravis-dev): no GigE Vision");
    return RIG_EUNSUPPORTED;
}

int hal_gev_start(hal_gev_t *g)
{
    (void)g;
    return RIG_EUNSUPPORTED;
}

int hal_gev_next(hal_gev_t *g, hal_gev_frame_t *f, int timeout_ms)
{
    (void)g;
    (void)f;
    (void)timeout_ms;
    return RIG_EUNSUPPORTED;
}

int hal_gev_stop(hal_gev_t *g)
{
    (void)g;
    return RIG_EUNSUPPORTED;
}

void hal_gev_stats(const hal_gev_t *g, hal_gev_stats_t *s)
{
    (void)g;
    memset(s, 0, sizeof *s);
}

void hal_gev_size(const hal_gev_t *g, int *width, int *height)
{
    (void)g;
    *width = *height = 0;
}

const char *hal_gev_error(const hal_gev_t *g)
{
    (void)g;
    return "built without Aravis";
}

void hal_gev_close(hal_gev_t *g)
{
    (void)g;
}
#endif
