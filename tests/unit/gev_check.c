/* SPDX-License-Identifier: MIT */
/* gev_check.c: build/gev-check, the client side of tests/cli/profiler.sh:
 * opens the simulated profiler through hal_gev, receives frames, and checks
 * them against the part itself (sim_part_z from a fresh seed search, not
 * the simulator's map): sampled range values within the noise, dropouts
 * only where there is no surface or a steep flank, and every frame id from
 * the first to the last accounted exactly once (delivered, arrived bad, or
 * never seen). Prints one line of figures; exit 0 when every check holds. */
#include "hal_gev.h"
#include "sim.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct geom {
    int width, height;
    long profiles;
    double x0, dx, y0, dy, z0, lo, scale;
} geom_t;

/* The geometry from cellsim's "gev ..." line (its words after the serial). */
static int parse_geom(const char *s, geom_t *g)
{
    return sscanf(s,
                  "width %d height %d profiles %ld x0 %lf dx %lf y0 %lf dy %lf z0 %lf lo %lf scale "
                  "%lf",
                  &g->width, &g->height, &g->profiles, &g->x0, &g->dx, &g->y0, &g->dy, &g->z0,
                  &g->lo, &g->scale) == 10
               ? 0
               : -1;
}

/* Slope of the part at (x, y) by central differences of step h. */
static double part_slope(const sim_part_t *p, double x, double y, double h)
{
    double a, b, c, d;
    if (sim_part_z(p, x + h, y, &a) || sim_part_z(p, x - h, y, &b) || sim_part_z(p, x, y + h, &c) ||
        sim_part_z(p, x, y - h, &d))
        return INFINITY; /* at the edge: as good as a flank */
    return hypot((a - b) / (2 * h), (c - d) / (2 * h));
}

static int usage(void)
{
    fprintf(stderr, "usage: gev-check URI FRAMES 'GEOMETRY' NOISE FLANK_DEG [RATE [SAMPLES "
                    "[expect-loss]]]\n");
    return 2;
}

int main(int argc, char **argv)
{
    if (argc < 6)
        return usage();
    const char *uri = argv[1];
    long frames = atol(argv[2]);
    geom_t g;
    double noise = atof(argv[4]), flank = atof(argv[5]);
    double rate = argc > 6 ? atof(argv[6]) : 50;
    long samples = argc > 7 ? atol(argv[7]) : 200;
    int expect_loss = argc > 8 && !strcmp(argv[8], "expect-loss");
    if (frames < 1 || parse_geom(argv[3], &g))
        return usage();
    sim_part_t part;
    char msg[512];
    if (sim_part_builtin(&part, msg, sizeof msg)) {
        fprintf(stderr, "gev-check: %s\n", msg);
        return 1;
    }
    hal_gev_t *cam;
    hal_gev_opts_t o = {g.width, g.height, rate, 0, 16, 0};
    int rc = hal_gev_open(&cam, uri, &o, msg, sizeof msg);
    if (rc) {
        fprintf(stderr, "gev-check: %s: %s\n", uri, msg);
        sim_part_free(&part);
        return 1;
    }
    int w, h;
    hal_gev_size(cam, &w, &h);
    if (w != g.width || h != g.height) {
        fprintf(stderr, "gev-check: profiler is %d x %d, asked %d x %d\n", w, h, g.width, g.height);
        hal_gev_close(cam);
        sim_part_free(&part);
        return 1;
    }
    rc = hal_gev_start(cam);
    long got = 0, checked = 0, wrong = 0, drops = 0, bad_drops = 0, gaps = 0;
    uint64_t first = 0, last = 0;
    double worst = 0, tol = 6 * noise + g.scale, tmax = tan(flank * 3.14159265358979323846 / 180);
    uint64_t rs = 12345;
    while (!rc && got < frames) {
        hal_gev_frame_t f;
        rc = hal_gev_next(cam, &f, 5000);
        if (rc)
            break;
        if (!got)
            first = f.id;
        else
            gaps += (long)f.gap_before;
        last = f.id;
        got++;
        for (long s = 0; s < samples; s++) {
            rs = rs * 6364136223846793005ull + 1442695040888963407ull;
            int r = (int)((rs >> 33) % (uint64_t)h), i = (int)((rs >> 13) % (uint64_t)w);
            uint64_t wire = (f.id - 1) % 65535 + 1; /* the id the simulator numbers by */
            uint64_t n = wire * (uint64_t)h + (uint64_t)r;
            double x = g.x0 + (double)(n % (uint64_t)g.profiles) * g.dx, y = g.y0 + i * g.dy, z;
            uint16_t raw = f.range[(size_t)r * (size_t)w + (size_t)i];
            int off = sim_part_z(&part, x, y, &z);
            checked++;
            if (!raw) {
                drops++;
                /* No reading: off the part, outside the range, or a flank. */
                double d = off ? 0 : g.z0 - z;
                if (!off && d > g.lo + tol &&
                    part_slope(&part, x, y, fmin(g.dx, g.dy)) < 0.8 * tmax)
                    bad_drops++;
                continue;
            }
            double e = off ? INFINITY : fabs(g.lo + raw * g.scale - (g.z0 - z));
            if (e > worst)
                worst = e;
            if (!(e <= tol))
                wrong++;
        }
    }
    hal_gev_stats_t st;
    hal_gev_stats(cam, &st);
    hal_gev_stop(cam);
    hal_gev_close(cam);
    sim_part_free(&part);
    if (rc) {
        fprintf(stderr, "gev-check: after %ld frames: %s\n", got, rig_strerror(rc));
        return 1;
    }
    uint64_t span = last - first + 1;
    uint64_t lost = st.frames_gap;
    /* Losses before the first delivered frame are outside the span. */
    /* Every bad frame popped after the first delivered one and before the
     * last (all of them here: nothing is popped after) is one of the lost. */
    int accounted =
        (uint64_t)got + (uint64_t)gaps == span && (uint64_t)gaps == lost && st.frames_bad <= lost;
    printf("gev-check: frames %ld ids %llu..%llu span %llu lost %llu (of which arrived bad %llu; "
           "bad before the first %llu) gaps %ld "
           "packets missing %llu resent %llu; values checked %ld wrong %ld worst %.4g mm "
           "(tol %.4g) dropouts %ld unexplained %ld\n",
           got, (unsigned long long)first, (unsigned long long)last, (unsigned long long)span,
           (unsigned long long)lost, (unsigned long long)st.frames_bad,
           (unsigned long long)st.frames_bad_before, gaps, (unsigned long long)st.packets_missing,
           (unsigned long long)st.packets_resent, checked, wrong, worst, tol, drops, bad_drops);
    int ok = accounted && !wrong && !bad_drops && (expect_loss ? gaps > 0 : gaps == 0);
    if (!accounted)
        printf("gev-check: FAIL %ld delivered + %ld lost in gaps != span %llu, or more bad "
               "(%llu) than lost\n",
               got, gaps, (unsigned long long)span, (unsigned long long)st.frames_bad);
    return ok ? 0 : 1;
}
