/* SPDX-License-Identifier: MIT */
/* scan_bench.c: build/scan-bench, the scan benchmark (bench/scan.sh runs
 * it; one JSON line a run, nothing asserted):
 *   gev URI 'GEOMETRY' POINTS [RATE]  profiles from the profiler through
 *       hal_gev, each streamed as one row into a fit (nf_fit_add_rows) of
 *       the part's nominal net, until POINTS points were delivered; then
 *       nf_fit_finish and nf_fit_solve: the fit-ready time after the last
 *       profile. Points/s sustained, frames lost, peak RSS.
 *   otf-rig STAGE_URI PROBE_URI ROWS PERIOD_US NOISE  on the fly over
 *       cellsim's Modbus: each row the stage is sent across at its speed
 *       (no wait), the probe's streaming mode armed (its trigger simulated
 *       in cellsim, docs/rig-devices.md), the FIFO popped while it moves and
 *       drained after, the entries paired by scan_otf and streamed into the
 *       fit; every 37th point checked against the part itself. Exit 1 when
 *       a point is wrong or a loss is not accounted for.
 *   otf POINTS  on-the-fly pairing in one process: the stage runs raster
 *       rows (190 mm, 1 mm apart, 140 a pass) at constant speed, a trigger every SPACING mm latches both
 *       encoder counts, the probe's reading of the part at that position
 *       carries the trigger number; 0.5 % of readings and 0.2 % of trigger
 *       packets are dropped and 0.2 % of readings duplicated, delivered out
 *       of order in bursts; scan_otf pairs them and each row's points go
 *       into the fit. No wire: this bounds the firmware side of the cell,
 *       not a transport (docs/rig-profiler.md says why).
 * Parameters of a point: (u, v) by the part's footprint scaled to the
 * knot domain (the panel is a height field over x, y), so the figures are
 * those of the stream and the accumulation, not of projection. */
#include "hal_gev.h"
#include "hal_regmap.h"
#include "hal_rig.h"
#include "nf_fit.h"
#include "nf_solve.h"
#include "scan_otf.h"
#include "sim.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static long maxrss_kb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

/* The fit of the part's nominal net, and the footprint-to-domain map. */
typedef struct bfit {
    nf_fit_t f;
    nf_arena_t ar;
    void *mem;
    double x0, sx, y0, sy; /* u = dom_u0 + (x - x0) * sx, likewise v */
    double dom[4];
    double *rows; /* one row of points, u v x y z each */
    long cap, n, points, refused;
} bfit_t;

static int bfit_init(bfit_t *b, const sim_part_t *part, long cap)
{
    memset(b, 0, sizeof *b);
    const nf_surf_t *s = &part->s;
    long need = nf_fit_bytes(s->nu, s->nv, s->p, s->q, NF_SOLVER_AUTO);
    b->mem = malloc((size_t)need);
    b->rows = malloc((size_t)cap * 5 * sizeof(double));
    if (need <= 0 || !b->mem || !b->rows)
        return -1;
    nf_arena_init(&b->ar, b->mem, (size_t)need);
    nf_fit_params_t prm = {NF_ALPHA_DEFAULT, NF_BETA_DEFAULT, NF_SOLVER_AUTO};
    int rc = nf_fit_init(&b->f, s, &prm, &b->ar);
    if (rc)
        return rc;
    b->cap = cap;
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    for (int k = 0; k < part->ns * part->ns; k++) {
        const double *q = part->seed + 4 * k;
        xlo = fmin(xlo, q[0]);
        xhi = fmax(xhi, q[0]);
        ylo = fmin(ylo, q[1]);
        yhi = fmax(yhi, q[1]);
    }
    nf_surf_domain(s, &b->dom[0], &b->dom[1], &b->dom[2], &b->dom[3]);
    b->x0 = xlo;
    b->y0 = ylo;
    b->sx = (b->dom[1] - b->dom[0]) / (xhi - xlo);
    b->sy = (b->dom[3] - b->dom[2]) / (yhi - ylo);
    return 0;
}

static void bfit_point(bfit_t *b, double x, double y, double z)
{
    double *r = b->rows + 5 * b->n++;
    r[0] = fmin(fmax(b->dom[0] + (x - b->x0) * b->sx, b->dom[0]), b->dom[1]);
    r[1] = fmin(fmax(b->dom[2] + (y - b->y0) * b->sy, b->dom[2]), b->dom[3]);
    r[2] = x;
    r[3] = y;
    r[4] = z;
}

/* One row into the stripes; a refused point is counted and the rest go in. */
static void bfit_flush(bfit_t *b)
{
    long at = 0;
    while (at < b->n) {
        long bad = -1;
        int rc = nf_fit_add_rows(&b->f, b->rows + 5 * at, b->n - at, &bad);
        if (!rc) {
            b->points += b->n - at;
            break;
        }
        b->points += bad;
        b->refused++;
        at += bad + 1;
    }
    b->n = 0;
}

/* Finish and solve: the seconds it took (the fit-ready time). */
static double bfit_ready(bfit_t *b, int *rc)
{
    double t0 = now();
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    so.tol = 1e-8;
    nf_solve_stats_t st;
    *rc = nf_fit_finish(&b->f);
    if (!*rc)
        *rc = nf_fit_solve(&b->f, NF_SOLVER_AUTO, &so, &st);
    return now() - t0;
}

static void bfit_free(bfit_t *b)
{
    free(b->mem);
    free(b->rows);
}

static int run_gev(const sim_part_t *part, const char *uri, const char *geom, long want,
                   double rate)
{
    int width, height;
    long profiles;
    double x0, dx, y0, dy, z0, lo, scale;
    if (sscanf(geom,
               "width %d height %d profiles %ld x0 %lf dx %lf y0 %lf dy %lf z0 %lf lo %lf scale "
               "%lf",
               &width, &height, &profiles, &x0, &dx, &y0, &dy, &z0, &lo, &scale) != 10)
        return 2;
    hal_gev_t *g;
    char msg[512];
    hal_gev_opts_t o = {width, height, rate, 0, 32, 0};
    int rc = hal_gev_open(&g, uri, &o, msg, sizeof msg);
    if (rc) {
        fprintf(stderr, "scan-bench: %s\n", msg);
        return 1;
    }
    bfit_t b;
    if (bfit_init(&b, part, width)) {
        fprintf(stderr, "scan-bench: fit set-up failed\n");
        hal_gev_close(g);
        return 1;
    }
    rc = hal_gev_start(g);
    long got = 0, frames = 0, dropouts = 0;
    double t0 = 0, t_last = 0;
    uint64_t first = 0, last = 0;
    while (!rc && got < want) {
        hal_gev_frame_t f;
        rc = hal_gev_next(g, &f, 5000);
        if (rc)
            break;
        if (!frames) {
            t0 = now();
            first = f.id;
        }
        last = f.id;
        frames++;
        uint64_t wire = (f.id - 1) % 65535 + 1; /* the simulator's numbering (sim_gev.h) */
        for (int r = 0; r < f.height && got < want; r++) {
            uint64_t n = wire * (uint64_t)f.height + (uint64_t)r;
            double x = x0 + (double)(n % (uint64_t)profiles) * dx;
            const uint16_t *row = f.range + (size_t)r * (size_t)f.width;
            for (int i = 0; i < f.width; i++) {
                if (!row[i]) {
                    dropouts++;
                    continue;
                }
                bfit_point(&b, x, y0 + i * dy, z0 - (lo + row[i] * scale));
            }
            got += f.width;
            bfit_flush(&b); /* each profile one row into the stripes */
        }
        t_last = now();
    }
    hal_gev_stats_t st;
    hal_gev_stats(g, &st);
    hal_gev_stop(g);
    hal_gev_close(g);
    int frc = 0;
    double ready = rc ? 0 : bfit_ready(&b, &frc);
    double secs = t_last - t0;
    /* The first frame's points are not in the timed span (its arrival
     * starts the clock). */
    double pps = secs > 0 ? (double)(got - (long)width * height) / secs : 0;
    printf("{\"mode\": \"gev\", \"points\": %ld, \"fitted\": %ld, \"dropouts\": %ld, \"refused\": "
           "%ld, \"frames\": %ld, \"ids\": %llu, \"lost_frames\": %llu, \"lost_profiles\": %llu, "
           "\"bad_frames\": %llu, \"seconds\": %.3f, \"points_per_s\": %.0f, \"fit_ready_s\": "
           "%.3f, \"maxrss_kb\": %ld, \"rc\": %d, \"fit_rc\": %d}\n",
           got, b.points, dropouts, b.refused, frames, (unsigned long long)(last - first + 1),
           (unsigned long long)st.frames_gap, (unsigned long long)st.frames_gap * (unsigned)height,
           (unsigned long long)st.frames_bad, secs, pps, ready, maxrss_kb(), rc, frc);
    bfit_free(&b);
    return rc || frc ? 1 : 0;
}

/* --- on the fly, in process --- */

typedef struct otf_ctx {
    bfit_t *b;
} otf_ctx_t;

static int otf_row(void *ctx, long row, const double *xyz, const uint64_t *trig, long n, int last)
{
    bfit_t *b = ((otf_ctx_t *)ctx)->b;
    (void)row;
    (void)trig;
    (void)last;
    for (long i = 0; i < n; i++)
        bfit_point(b, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    bfit_flush(b);
    return 0;
}

static uint64_t rs = 0x2545F4914F6CDD1Dull;
static double urand(void)
{
    rs ^= rs << 13;
    rs ^= rs >> 7;
    rs ^= rs << 17;
    return (double)(rs >> 11) / 9007199254740992.0;
}

static int run_otf(const sim_part_t *part, long want)
{
    /* The probe: z0 50 over the stage frame, no calibration offset; the
     * encoders count 1 um; a trigger every 0.1 mm along x, rows 1 mm apart. */
    const scan_kin_t kin = {50.0, {0, 0, 0}};
    const scan_otf_enc_t enc = {{0, 0}, {0.001, 0.001}};
    const double spacing = 0.1, pitch = 1.0, len = 190.0, x_start = 5.0, y_start = 5.0;
    const long per_row = (long)(len / spacing) + 1;
    static scan_otf_t o;
    bfit_t b;
    if (bfit_init(&b, part, SCAN_OTF_ROW_MAX)) {
        fprintf(stderr, "scan-bench: fit set-up failed\n");
        return 1;
    }
    otf_ctx_t cx = {&b};
    scan_otf_init(&o, &kin, &enc, otf_row, &cx);
    sim_rng_t noise;
    sim_rng_seed(&noise, 3, 4);
    long made = 0, rows = 0;
    long inj_read = 0, inj_trig = 0, inj_dup = 0;
    double t_gen = 0, t0 = now();
    int rc = 0;
    while (made < want && !rc) {
        rc = scan_otf_row_begin(&o, rows);
        double y = y_start + (double)(rows % 140) * pitch; /* pass after pass over the part */
        double uv[2] = {NAN, NAN};
        rig_trig_event_t ev[16];
        rig_reading_t rd[24];
        size_t ne = 0, nr = 0;
        for (long k = 0; k < per_row && !rc; k++) {
            double tg = now();
            /* The stage at constant speed: trigger k at x_start + k spacing
             * (serpentine rows run back). */
            double x =
                rows % 2 ? x_start + len - (double)k * spacing : x_start + (double)k * spacing;
            double z;
            int off = sim_part_z_near(part, x, y, uv, &z);
            if (off)
                uv[0] = uv[1] = NAN;
            rig_trig_event_t e = {(uint16_t)k,
                                  0,
                                  (uint32_t)(k * 50),
                                  {(int32_t)lround(x / enc.mm_per_count[0]),
                                   (int32_t)lround(y / enc.mm_per_count[1])}};
            rig_reading_t r = {(uint16_t)k, off ? RIG_RD_NOSURF : RIG_RD_VALID,
                               off ? 0 : kin.z0 - z + 0.002 * sim_gauss(&noise)};
            double u = urand();
            if (u < 0.002)
                inj_trig++;
            else
                ev[ne++] = e;
            if (u >= 0.002 && u < 0.007)
                inj_read++;
            else {
                rd[nr++] = r;
                if (urand() < 0.002) {
                    rd[nr++] = r;
                    inj_dup++;
                }
            }
            t_gen += now() - tg;
            /* Bursts: 16 positions, then the readings, reversed. */
            if (ne == 16 || k == per_row - 1) {
                rc = scan_otf_trig(&o, ev, ne);
                for (size_t i = 0; i < nr / 2; i++) {
                    rig_reading_t t = rd[i];
                    rd[i] = rd[nr - 1 - i];
                    rd[nr - 1 - i] = t;
                }
                if (!rc)
                    rc = scan_otf_read(&o, rd, nr);
                ne = nr = 0;
            }
        }
        if (!rc)
            rc = scan_otf_row_end(&o, 0, (uint64_t)per_row);
        made += per_row;
        rows++;
    }
    double secs = now() - t0 - t_gen; /* the part model's cost is the simulator's */
    int frc = 0;
    double ready = rc ? 0 : bfit_ready(&b, &frc);
    const scan_otf_counts_t *c = &o.c;
    int accounted = c->trig_no_read == (uint64_t)(inj_read) &&
                    c->read_no_trig == (uint64_t)inj_trig && c->dup_read == (uint64_t)inj_dup;
    printf("{\"mode\": \"otf\", \"triggers\": %ld, \"rows\": %ld, \"paired\": %llu, \"nosurf\": "
           "%llu, \"fitted\": %ld, \"lost_readings\": %llu, \"injected_lost_readings\": %ld, "
           "\"lost_triggers\": %llu, \"injected_lost_triggers\": %ld, \"dup\": %llu, "
           "\"injected_dup\": %ld, \"both_lost\": %llu, \"accounted\": %d, \"seconds\": %.3f, "
           "\"sim_seconds\": %.3f, \"points_per_s\": %.0f, \"fit_ready_s\": %.3f, \"maxrss_kb\": "
           "%ld, \"rc\": %d}\n",
           made, rows, (unsigned long long)c->paired, (unsigned long long)c->nosurf, b.points,
           (unsigned long long)c->trig_no_read, inj_read, (unsigned long long)c->read_no_trig,
           inj_trig, (unsigned long long)c->dup_read, inj_dup, (unsigned long long)c->both_lost,
           accounted, secs, t_gen, secs > 0 ? (double)c->paired / secs : 0, ready, maxrss_kb(),
           rc ? rc : frc);
    bfit_free(&b);
    return rc || frc || !accounted ? 1 : 0;
}

/* --- on the fly over cellsim's Modbus: the stage and the probe's FIFO --- */

/* A non-blocking move: target and command in one write (registers 0-4 are
 * applied in order: an atomic move, docs/rig-devices.md). */
static int move_start(hal_t *h, double x, double y)
{
    int32_t tx = (int32_t)lround(x * 1e3), ty = (int32_t)lround(y * 1e3);
    uint16_t r[5] = {(uint16_t)((uint32_t)tx >> 16), (uint16_t)((uint32_t)tx & 0xFFFFu),
                     (uint16_t)((uint32_t)ty >> 16), (uint16_t)((uint32_t)ty & 0xFFFFu),
                     STG_CMD_MOVE};
    return hal_write_regs(h, STG_TARGET_X, 5, r);
}

typedef struct mb_ctx {
    bfit_t *b;
    const sim_part_t *part;
    double noise;
    long checked, wrong;
    double worst;
} mb_ctx_t;

/* Each point into the fit; every 37th checked against the part itself:
 * a reading paired with another trigger's position would be off by the
 * part's change over the stage's travel between them. */
static int mb_row(void *ctx, long row, const double *xyz, const uint64_t *trig, long n, int last)
{
    mb_ctx_t *m = ctx;
    (void)row;
    (void)last;
    for (long i = 0; i < n; i++) {
        bfit_point(m->b, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
        double z;
        if (trig[i] % 37 == 0 && !sim_part_z(m->part, xyz[3 * i], xyz[3 * i + 1], &z)) {
            double e = fabs(xyz[3 * i + 2] - z);
            m->checked++;
            m->worst = e > m->worst ? e : m->worst;
            /* noise, and the latched position rounded to 1 um on a slope */
            if (!(e <= 6 * m->noise + 0.002))
                m->wrong++;
        }
    }
    bfit_flush(m->b);
    return 0;
}

static int run_otf_mb(const sim_part_t *part, const char *stage_uri, const char *probe_uri,
                      long rows_n, long period_us, double noise)
{
    hal_opts_t ho = HAL_OPTS_DEFAULT;
    hal_rig_t *rig;
    char msg[512];
    int rc = hal_rig_open(stage_uri, probe_uri, &ho, &rig, msg, sizeof msg);
    if (rc) {
        fprintf(stderr, "scan-bench: %s\n", msg);
        return 1;
    }
    /* The probe at z0 50 over the stage frame, no offset: scan.h's model
     * with the latched positions in um. */
    const scan_kin_t kin = {50.0, {0, 0, 0}};
    const scan_otf_enc_t enc = {{0, 0}, {0.001, 0.001}};
    static scan_otf_t o;
    bfit_t b;
    if (bfit_init(&b, part, SCAN_OTF_ROW_MAX)) {
        fprintf(stderr, "scan-bench: fit set-up failed\n");
        hal_rig_close(rig);
        return 1;
    }
    mb_ctx_t m = {&b, part, noise, 0, 0, 0};
    scan_otf_init(&o, &kin, &enc, mb_row, &m);
    unsigned long dropped = 0;
    double t_stream = 0;
    const double xa = 10, xb = 190;
    uint32_t bits = 0;
    rc = rig->stage.ops->status(rig->stage.ctx, &bits);
    if (!rc && !(bits & RIG_ST_HOMED))
        rc = rig->stage.ops->home(rig->stage.ctx);
    for (long row = 0; row < rows_n && !rc; row++) {
        double y = 10 + (double)(row % 130);
        double x0 = row % 2 ? xb : xa, x1 = row % 2 ? xa : xb;
        rc = rig->stage.ops->move_to(rig->stage.ctx, x0, y);
        double t0 = now();
        if (!rc)
            rc = scan_otf_row_begin(&o, row);
        if (!rc)
            rc = move_start(rig->st.h, x1, y);
        if (!rc)
            rc = hal_probe_stream_start(&rig->pr, (uint32_t)period_us);
        int moving = 1;
        while (!rc) {
            rig_reading_t rd[256];
            rig_trig_event_t pos[256];
            size_t n = 0;
            rc = hal_probe_stream_read(&rig->pr, rd, pos, 256, &n, &dropped);
            if (!rc && n)
                rc = scan_otf_trig(&o, pos, n);
            if (!rc && n)
                rc = scan_otf_read(&o, rd, n);
            if (rc || (!moving && !n && !rig->pr.streaming))
                break;
            if (moving && n < 256) {
                uint16_t st;
                rc = hal_read_regs(rig->st.h, 'h', STG_STATUS, 1, &st);
                if (!rc && !(st & RIG_ST_BUSY)) {
                    moving = 0; /* the row's end: stop the triggers, drain the FIFO */
                    rc = hal_probe_stream_stop(&rig->pr);
                }
            }
        }
        if (!rc)
            rc = scan_otf_row_end(&o, 0, 0);
        t_stream += now() - t0;
    }
    int frc = 0;
    double ready = rc ? 0 : bfit_ready(&b, &frc);
    const scan_otf_counts_t *c = &o.c;
    /* Entries the probe dropped on a full FIFO are numbers lost on both
     * sides: the two counts must agree. */
    int accounted = c->both_lost == dropped && !c->trig_no_read && !c->read_no_trig;
    printf("{\"mode\": \"otf-rig\", \"rows\": %ld, \"period_us\": %ld, \"triggers\": %llu, "
           "\"paired\": %llu, \"nosurf\": %llu, \"fitted\": %ld, \"dropped_by_probe\": %lu, "
           "\"both_lost\": %llu, \"lost_readings\": %llu, \"lost_triggers\": %llu, \"dup\": "
           "%llu, \"late\": %llu, \"accounted\": %d, \"checked\": %ld, \"wrong\": %ld, "
           "\"worst_mm\": %.4f, \"seconds\": %.3f, \"points_per_s\": %.0f, \"fit_ready_s\": "
           "%.3f, \"maxrss_kb\": %ld, \"rc\": %d}\n",
           rows_n, period_us, (unsigned long long)c->trig, (unsigned long long)c->paired,
           (unsigned long long)c->nosurf, b.points, dropped, (unsigned long long)c->both_lost,
           (unsigned long long)c->trig_no_read, (unsigned long long)c->read_no_trig,
           (unsigned long long)(c->dup_read + c->dup_trig), (unsigned long long)c->late, accounted,
           m.checked, m.wrong, m.worst, t_stream,
           t_stream > 0 ? (double)(c->paired + c->nosurf) / t_stream : 0, ready, maxrss_kb(),
           rc ? rc : frc);
    if (rc)
        fprintf(stderr, "scan-bench: %s (%s; %s)\n", rig_strerror(rc), hal_stage_error(&rig->st),
                hal_probe_error(&rig->pr));
    bfit_free(&b);
    hal_rig_close(rig);
    return rc || frc || !accounted || m.wrong || !m.checked ? 1 : 0;
}

int main(int argc, char **argv)
{
    sim_part_t part;
    char msg[512];
    if (argc < 3 ||
        (strcmp(argv[1], "gev") && strcmp(argv[1], "otf") && strcmp(argv[1], "otf-rig")) ||
        (!strcmp(argv[1], "gev") && argc < 5) || (!strcmp(argv[1], "otf-rig") && argc < 7)) {
        fprintf(stderr, "usage: scan-bench gev URI 'GEOMETRY' POINTS [RATE] | otf POINTS |\n"
                        "       otf-rig STAGE_URI PROBE_URI ROWS PERIOD_US NOISE\n");
        return 2;
    }
    if (sim_part_builtin(&part, msg, sizeof msg)) {
        fprintf(stderr, "scan-bench: %s\n", msg);
        return 1;
    }
    int rc;
    if (!strcmp(argv[1], "gev"))
        rc = run_gev(&part, argv[2], argv[3], atol(argv[4]), argc > 5 ? atof(argv[5]) : 100);
    else if (!strcmp(argv[1], "otf"))
        rc = run_otf(&part, atol(argv[2]));
    else
        rc = run_otf_mb(&part, argv[2], argv[3], atol(argv[4]), atol(argv[5]), atof(argv[6]));
    sim_part_free(&part);
    return rc;
}
