/* SPDX-License-Identifier: MIT */
/* test_scan_otf.c: on-the-fly pairing (scan_otf.h) against the truth of a
 * generated stream: every trigger number has its own position and its own
 * distance, so a reading paired with any other position gives a point that
 * differs from the closed-form one. Losses, duplicates, late readings,
 * overruns and cut rows are injected by number and each must be counted
 * exactly; arrival is out of order within and between the two streams. */
#include "cf_test.h"
#include "scan_otf.h"
#include <stdlib.h>
#include <string.h>

static const scan_kin_t kin = {120.0, {0.5, -0.25, 0.125}};
static const scan_otf_enc_t enc = {{10.0, -20.0}, {0.001, 0.0005}};

/* Truth of trigger number k. */
static int32_t enc_x(uint64_t k)
{
    return (int32_t)(7 * k + 3);
}
static int32_t enc_y(uint64_t k)
{
    return (int32_t)(40000 + (k % 13) * 17);
}
static double dist(uint64_t k)
{
    return 30.0 + 1e-3 * (double)(k % 9973) + 1e-7 * (double)(k / 9973);
}

/* Deterministic generator for the injections (xorshift64*). */
static uint64_t rs = 88172645463325252ull;
static double urand(void)
{
    rs ^= rs >> 12;
    rs ^= rs << 25;
    rs ^= rs >> 27;
    return (double)((rs * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

typedef struct sink {
    long chunks, lasts, points;
    uint64_t prev;
    int any;
    long bad; /* points not equal to their number's truth */
    long disorder;
    int fail_at;  /* chunk that returns an error (0 never) */
    uint8_t *gap; /* with a gap callback: the kind recorded per number (0 none) */
    long ngap, gap_bad, gap_calls;
    uint64_t first;         /* the first point's number */
    long start_at, stop_at; /* the plan's standing stage (plan_t), for the positions' truth */
} sink_t;

/* The number whose position number k latched: the stage stands at
 * start_at's position until it, and at stop_at's from it on (plan_t). */
static uint64_t pos_of(long start_at, long stop_at, long k)
{
    return (uint64_t)(k < start_at ? start_at : stop_at > 0 && k > stop_at ? stop_at : k);
}

static int on_row(void *ctx, long row, const double *xyz, const uint64_t *trig, long n, int last)
{
    sink_t *s = ctx;
    (void)row;
    s->chunks++;
    s->lasts += last;
    assert_true(n <= SCAN_OTF_ROW_MAX);
    for (long i = 0; i < n; i++) {
        uint64_t k = trig[i];
        double x = enc.org[0] + enc_x(k) * enc.mm_per_count[0];
        double y = enc.org[1] + enc_y(k) * enc.mm_per_count[1];
        /* scan.h's model, written out: (x + cx, y + cy, z0 - d + cz) */
        if (xyz[3 * i] != x + kin.cal[0] || xyz[3 * i + 1] != y + kin.cal[1] ||
            xyz[3 * i + 2] != kin.z0 - dist(k) + kin.cal[2])
            s->bad++;
        if (s->any && k <= s->prev)
            s->disorder++;
        if (!s->points)
            s->first = k;
        s->prev = k;
        s->any = 1;
        s->points++;
    }
    if (s->fail_at && s->chunks == s->fail_at)
        return -999;
    return 0;
}

/* The gap callback: each number's kind, once; a position only with a
 * reading lost, and then the true one it latched; in number order with the
 * points (the row callback's prev). */
static int on_gap(void *ctx, long row, int kind, uint64_t num, uint64_t count, const double *xy)
{
    sink_t *s = ctx;
    (void)row;
    s->gap_calls++;
    if (s->any && num <= s->prev)
        s->disorder++;
    uint64_t at = pos_of(s->start_at, s->stop_at, (long)num);
    if ((kind == JNL_GAP_NO_READING) != (xy != NULL) || count == 0 ||
        (xy && (count != 1 || xy[0] != enc.org[0] + enc_x(at) * enc.mm_per_count[0] ||
                xy[1] != enc.org[1] + enc_y(at) * enc.mm_per_count[1])))
        s->gap_bad++;
    for (uint64_t k = num; k < num + count; k++) {
        if (s->gap[k])
            s->gap_bad++;
        s->gap[k] = (uint8_t)kind;
        s->ngap++;
    }
    s->prev = num + count - 1;
    s->any = 1;
    return 0;
}

/* What to do to number k on each side. */
typedef struct plan {
    long n;
    uint8_t *drop_t, *drop_r, *dup_t, *dup_r, *nosurf, *overrun, *late;
    long stop_at;  /* > 0: the stage stands from this number on (its position latched again) */
    long start_at; /* > 0: the stage stands at this number's position until it */
} plan_t;

static void plan_alloc(plan_t *p, long n)
{
    memset(p, 0, sizeof *p);
    p->n = n;
    uint8_t **f[] = {&p->drop_t, &p->drop_r,  &p->dup_t, &p->dup_r,
                     &p->nosurf, &p->overrun, &p->late};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
        *f[i] = calloc((size_t)n, 1);
        assert_non_null(*f[i]);
    }
}

static void plan_free(plan_t *p)
{
    free(p->drop_t);
    free(p->drop_r);
    free(p->dup_t);
    free(p->dup_r);
    free(p->nosurf);
    free(p->overrun);
    free(p->late);
}

/* The losses t_injected, t_gaps and t_end_at inject at number k: 1 % of
 * the readings, 1 % of the triggers, 0.5 % both; the draw is returned so a
 * caller can add its own faults above 0.025. */
static double plan_loss(plan_t *p, long k)
{
    double r = urand();
    if (r < 0.01)
        p->drop_r[k] = 1;
    else if (r < 0.02)
        p->drop_t[k] = 1;
    else if (r < 0.025)
        p->drop_t[k] = p->drop_r[k] = 1;
    return r;
}

/* Numbers [from, to) lost on both sides. */
static void plan_lose_both(plan_t *p, long from, long to)
{
    for (long k = from; k < to; k++)
        p->drop_t[k] = p->drop_r[k] = 1;
}

/* Deliver the plan: triggers in random batches, readings lagging by up to
 * lag numbers and shuffled within each batch; a late reading comes more
 * than a window after its number. */
static void deliver(scan_otf_t *o, const plan_t *p, long lag)
{
    long nt = 0, nr = 0;
    long *late_q = calloc((size_t)p->n, sizeof(long));
    long nlate = 0, late_next = 0, last_t = 0;
    assert_non_null(late_q);
    while (nt < p->n || nr < p->n || late_next < nlate) {
        rig_trig_event_t ev[8];
        size_t ne = 0;
        long batch = 1 + (long)(urand() * 6);
        int catchup = 0;
        for (; nt < p->n && (long)ne < batch; nt++) {
            if (p->drop_t[nt])
                continue;
            if (nt - last_t > SCAN_OTF_WINDOW / 2 && nr < nt) {
                /* A gap in the triggers moves the window on: readings still
                 * lagging behind it would be late, which is not this test's
                 * injection, so they catch up first. */
                catchup = 1;
                break;
            }
            last_t = nt;
            uint64_t at = pos_of(p->start_at, p->stop_at, nt);
            rig_trig_event_t e = {(uint16_t)nt,
                                  p->overrun[nt] ? RIG_TRIG_F_OVERRUN : 0,
                                  (uint32_t)(nt * 50),
                                  {enc_x(at), enc_y(at)}};
            ev[ne++] = e;
            if (p->dup_t[nt] && ne < 8) {
                e.enc[0] += 1000; /* a duplicate must not replace the first */
                ev[ne++] = e;
            }
        }
        assert_int_equal(scan_otf_trig(o, ev, ne), RIG_OK);
        rig_reading_t rd[32] = {{0}}, dups[16] = {{0}};
        size_t nrd = 0, ndup = 0;
        long upto = nt - (long)(urand() * (double)lag);
        if (nt >= p->n)
            upto = p->n;
        if (catchup)
            upto = nt;
        for (; nr < upto && nrd < 12; nr++) {
            if (p->drop_r[nr])
                continue;
            if (p->late[nr]) {
                late_q[nlate++] = nr;
                continue;
            }
            rig_reading_t r = {(uint16_t)nr, p->nosurf[nr] ? RIG_RD_NOSURF : RIG_RD_VALID,
                               dist((uint64_t)nr)};
            rd[nrd++] = r;
            if (p->dup_r[nr]) {
                r.d += 5.0; /* a repeat, after the first: it must not replace it */
                dups[ndup++] = r;
            }
        }
        /* Shuffle the batch: order within the stream must not matter. */
        for (size_t i = nrd; i > 1; i--) {
            size_t j = (size_t)(urand() * (double)i);
            rig_reading_t t = rd[i - 1];
            rd[i - 1] = rd[j];
            rd[j] = t;
        }
        for (size_t i = 0; i < ndup; i++)
            rd[nrd++] = dups[i];
        assert_int_equal(scan_otf_read(o, rd, nrd), RIG_OK);
        /* Late ones: once the window has passed them. */
        while (late_next < nlate && late_q[late_next] + 3 * SCAN_OTF_WINDOW < nt) {
            long k = late_q[late_next++];
            rig_reading_t r = {(uint16_t)k, RIG_RD_VALID, dist((uint64_t)k)};
            assert_int_equal(scan_otf_read(o, &r, 1), RIG_OK);
        }
        if (nt >= p->n && nr >= p->n && late_next < nlate) {
            long k = late_q[late_next++]; /* the row's tail: still behind the window */
            rig_reading_t r = {(uint16_t)k, RIG_RD_VALID, dist((uint64_t)k)};
            if (k + 2 * SCAN_OTF_WINDOW + 16 < p->n)
                assert_int_equal(scan_otf_read(o, &r, 1), RIG_OK);
            else
                ((plan_t *)p)->late[k] = 2; /* near the end: never sent */
        }
    }
    free(late_q);
}

static void check_counts(const scan_otf_t *o, const plan_t *p, const sink_t *s)
{
    uint64_t e_trig = 0, e_read = 0, e_paired = 0, e_nosurf = 0, e_tnr = 0, e_rnt = 0, e_both = 0;
    uint64_t e_dupt = 0, e_dupr = 0, e_late = 0, e_over = 0, e_before = 0;
    for (long k = 0; k < p->n; k++) {
        int t = !p->drop_t[k], r = !p->drop_r[k] && !p->late[k];
        e_trig += (uint64_t)t;
        e_read += (uint64_t)r;
        e_dupt += (uint64_t)(t && p->dup_t[k]);
        e_dupr += (uint64_t)(r && p->dup_r[k]);
        e_late += (uint64_t)(!p->drop_r[k] && p->late[k] == 1);
        e_over += (uint64_t)(t && p->overrun[k]);
        if (t && r && k < p->start_at) { /* a pair at the standing start, before its last */
            e_trig--, e_read--, e_before += 2;
            continue;
        }
        if (t && r && p->nosurf[k])
            e_nosurf++;
        else if (t && r)
            e_paired++;
        else if (t)
            e_tnr++;
        else if (r)
            e_rnt++;
        else
            e_both++;
    }
    assert_int_equal(o->c.trig, e_trig);
    assert_int_equal(o->c.read, e_read);
    assert_int_equal(o->c.paired, e_paired);
    assert_int_equal(o->c.nosurf, e_nosurf);
    assert_int_equal(o->c.trig_no_read, e_tnr);
    assert_int_equal(o->c.read_no_trig, e_rnt);
    assert_int_equal(o->c.both_lost, e_both);
    assert_int_equal(o->c.dup_trig, e_dupt);
    assert_int_equal(o->c.dup_read, e_dupr);
    assert_int_equal(o->c.late, e_late);
    assert_int_equal(o->c.overrun, e_over);
    assert_int_equal(o->c.before_start, e_before);
    assert_int_equal(s->points, (long)e_paired);
    assert_int_equal(s->bad, 0);
    assert_int_equal(s->disorder, 0);
    assert_int_equal(s->lasts, 1);
}

/* A clean row past the 16-bit wrap: every number paired, in order. */
static void t_clean_wraps(void **state)
{
    (void)state;
    static scan_otf_t o;
    sink_t s = {0};
    plan_t p;
    plan_alloc(&p, 150000);
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
    deliver(&o, &p, SCAN_OTF_WINDOW / 2);
    assert_int_equal(scan_otf_row_end(&o, 0, (uint64_t)p.n), RIG_OK);
    check_counts(&o, &p, &s);
    assert_int_equal(o.c.paired, 150000);
    assert_true(s.chunks >= 150000 / SCAN_OTF_ROW_MAX);
    plan_free(&p);
}

/* Every kind of fault at once, by number; each counted exactly, and no
 * reading paired with a wrong position. */
static void t_injected(void **state)
{
    (void)state;
    static scan_otf_t o;
    plan_t p;
    plan_alloc(&p, 100000);
    for (long k = 0; k < p.n; k++) {
        double r = plan_loss(&p, k);
        if (r >= 0.025 && r < 0.03)
            p.late[k] = 1;
        p.dup_t[k] = urand() < 0.01;
        p.dup_r[k] = urand() < 0.01;
        p.nosurf[k] = urand() < 0.02;
        p.overrun[k] = urand() < 0.001;
    }
    /* A run of 3 windows lost on both sides, and the last 5 triggers. */
    plan_lose_both(&p, 50000, 50000 + 3 * SCAN_OTF_WINDOW);
    plan_lose_both(&p, p.n - 5, p.n);
    for (int pass = 0; pass < 2; pass++) {
        sink_t s = {0};
        assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
        assert_int_equal(scan_otf_row_begin(&o, 3), RIG_OK);
        deliver(&o, &p, pass ? 8 : SCAN_OTF_WINDOW - 16);
        assert_int_equal(scan_otf_row_end(&o, 0, (uint64_t)p.n), RIG_OK);
        check_counts(&o, &p, &s);
        assert_true(o.c.late > 0 && o.c.dup_read > 0 && o.c.dup_trig > 0 && o.c.overrun > 0);
        assert_int_equal(o.c.rows, 1);
        assert_int_equal(o.c.rows_cut, 0);
        for (long k = 0; k < p.n; k++)
            if (p.late[k] == 2)
                p.late[k] = 1;
    }
    plan_free(&p);
}

/* A row cut short by the stage: the triggers it never reached are not
 * losses; those it reached are settled as usual. */
static void t_cut_row(void **state)
{
    (void)state;
    static scan_otf_t o;
    sink_t s = {0};
    plan_t p;
    plan_alloc(&p, 3000);
    p.drop_r[100] = 1;
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
    deliver(&o, &p, 16);
    assert_int_equal(scan_otf_row_end(&o, 1, 10000), RIG_OK);
    assert_int_equal(o.c.rows_cut, 1);
    assert_int_equal(o.c.both_lost, 0);
    assert_int_equal(o.c.trig_no_read, 1);
    assert_int_equal(o.c.paired, 2999);
    /* The same row not cut: the 7000 never fired are losses on both sides. */
    sink_t s2 = {0};
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s2), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
    deliver(&o, &p, 16);
    assert_int_equal(scan_otf_row_end(&o, 0, 10000), RIG_OK);
    assert_int_equal(o.c.both_lost, 7000);
    plan_free(&p);
}

/* Rows in turn restart the numbering; calls out of order and a failing
 * callback are refused with their codes. */
static void t_rows_and_errors(void **state)
{
    (void)state;
    static scan_otf_t o;
    sink_t s = {0};
    rig_trig_event_t e = {0, 0, 0, {1, 2}};
    rig_reading_t r = {0, RIG_RD_VALID, 31.0};
    assert_int_equal(scan_otf_init(&o, &kin, &enc, NULL, &s), RIG_EARG);
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    assert_int_equal(scan_otf_trig(&o, &e, 1), RIG_ESTATE);
    assert_int_equal(scan_otf_read(&o, &r, 1), RIG_ESTATE);
    assert_int_equal(scan_otf_row_end(&o, 0, 0), RIG_ESTATE);
    for (long row = 0; row < 3; row++) {
        plan_t p;
        plan_alloc(&p, 500 + 100 * row);
        assert_int_equal(scan_otf_row_begin(&o, row), RIG_OK);
        assert_int_equal(scan_otf_row_begin(&o, row), RIG_ESTATE);
        s.any = 0; /* numbering restarts per row */
        deliver(&o, &p, 4);
        assert_int_equal(scan_otf_row_end(&o, 0, (uint64_t)p.n), RIG_OK);
        plan_free(&p);
    }
    assert_int_equal(o.c.rows, 3);
    assert_int_equal(o.c.paired, 1800);
    assert_int_equal(s.points, 1800);
    assert_int_equal(s.lasts, 3);
    assert_int_equal(s.bad, 0);
    /* A row with nothing at all still hands on its (empty) last chunk. */
    assert_int_equal(scan_otf_row_begin(&o, 9), RIG_OK);
    assert_int_equal(scan_otf_row_end(&o, 0, 0), RIG_OK);
    assert_int_equal(s.lasts, 4);
    /* The callback's code stops the pairing and stays. */
    sink_t f = {0};
    f.fail_at = 2;
    plan_t p;
    plan_alloc(&p, 4 * SCAN_OTF_ROW_MAX);
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &f), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
    int rc = RIG_OK;
    for (long k = 0; k < p.n && !rc; k++) {
        rig_trig_event_t ek = {(uint16_t)k, 0, 0, {enc_x((uint64_t)k), enc_y((uint64_t)k)}};
        rig_reading_t rk = {(uint16_t)k, RIG_RD_VALID, dist((uint64_t)k)};
        rc = scan_otf_trig(&o, &ek, 1);
        if (!rc)
            rc = scan_otf_read(&o, &rk, 1);
    }
    assert_int_equal(rc, -999);
    assert_int_equal(scan_otf_read(&o, &r, 1), -999);
    assert_int_equal(scan_otf_row_end(&o, 0, 0), -999);
    assert_int_equal(f.chunks, 2);
    plan_free(&p);
}

/* Issue 19: every loss handed to the gap callback at its own number and of
 * its kind (a lost reading with its position), in order with the points;
 * runs lost on both sides joined (one in the middle longer than two
 * windows, one at the row's end). */
static void t_gaps(void **state)
{
    (void)state;
    static scan_otf_t o;
    plan_t p;
    plan_alloc(&p, 30000);
    for (long k = 0; k < p.n; k++)
        plan_loss(&p, k);
    plan_lose_both(&p, 12000, 12700); /* more than two windows: make_room's jump */
    plan_lose_both(&p, p.n - 5, p.n); /* the row's last, lost on both sides */
    sink_t s = {0};
    s.gap = calloc((size_t)p.n, 1);
    assert_non_null(s.gap);
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    scan_otf_set_gap(&o, on_gap);
    assert_int_equal(scan_otf_row_begin(&o, 2), RIG_OK);
    deliver(&o, &p, 8);
    assert_int_equal(scan_otf_row_end(&o, 0, (uint64_t)p.n), RIG_OK);
    long lost = 0, wrong = 0;
    for (long k = 0; k < p.n; k++) {
        int want = p.drop_t[k] && p.drop_r[k] ? JNL_GAP_BOTH
                   : p.drop_t[k]              ? JNL_GAP_NO_TRIGGER
                   : p.drop_r[k]              ? JNL_GAP_NO_READING
                                              : 0;
        lost += want != 0;
        wrong += s.gap[k] != want;
    }
    assert_int_equal(wrong, 0);
    assert_int_equal(s.gap_bad, 0);
    assert_int_equal(s.disorder, 0);
    assert_int_equal(s.bad, 0);
    assert_int_equal(s.ngap, lost);
    assert_int_equal((long)(o.c.trig_no_read + o.c.read_no_trig + o.c.both_lost), lost);
    assert_int_equal(s.points + lost, p.n);
    assert_true(s.gap_calls < lost - 700); /* the long run is one call */
    free(s.gap);
    plan_free(&p);
}

/* Issue 19: the stage stands at the row's end while the box keeps firing
 * (the host sees the end late). With the end position given, the first
 * trigger latched there is the row's last: nothing after it becomes a
 * point (each would repeat the end's position with another reading) or a
 * loss, and everything up to it is settled as usual. Pass 1 loses the end
 * trigger itself: the next one, standing there too, ends the row. */
static void t_end_at(void **state)
{
    (void)state;
    static scan_otf_t o;
    const long end = 3000;
    const double ex = enc.org[0] + enc_x(end) * enc.mm_per_count[0];
    const double ey = enc.org[1] + enc_y(end) * enc.mm_per_count[1];
    for (int pass = 0; pass < 2; pass++) {
        plan_t p;
        plan_alloc(&p, 9000); /* 6000 triggers after the end, far more than a window */
        p.stop_at = end;
        for (long k = 0; k < p.n; k++)
            plan_loss(&p, k);
        p.drop_t[end] = p.drop_r[end] = (uint8_t)pass;
        p.drop_t[end + 1] = 0; /* so that pass 1 ends at end + 1 */
        sink_t s = {0};
        assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
        assert_int_equal(scan_otf_row_end_at(&o, ex, ey, 1e-3), RIG_ESTATE);
        assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
        assert_int_equal(scan_otf_row_end_at(&o, ex, ey, 0), RIG_EARG);
        /* x steps 7 um a number: only the stage standing is within 3 um */
        assert_int_equal(scan_otf_row_end_at(&o, ex, ey, 3e-3), RIG_OK);
        deliver(&o, &p, 8);
        assert_int_equal(scan_otf_end_seen(&o), 1);
        assert_int_equal(o.end_num, (uint64_t)(end + pass));
        /* the triggers expected past the end are no losses either */
        assert_int_equal(scan_otf_row_end(&o, 0, (uint64_t)p.n + 100), RIG_OK);
        uint64_t after = 0;
        for (long k = end + pass + 1; k < p.n; k++)
            after += (uint64_t)!p.drop_t[k] + (uint64_t)!p.drop_r[k];
        assert_int_equal(o.c.past_end, after);
        plan_t upto = p; /* the counts of numbers 0..end + pass only */
        upto.n = end + pass + 1;
        check_counts(&o, &upto, &s);
        assert_true(s.prev <= (uint64_t)(end + pass));
        plan_free(&p);
    }
    /* Out of order: number 8 (past the end) arrives before the end's
     * trigger 6 and is taken back out when 6 latches the end. */
    sink_t s = {0};
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 1), RIG_OK);
    assert_int_equal(scan_otf_row_end_at(&o, enc.org[0] + enc_x(6) * enc.mm_per_count[0],
                                         enc.org[1] + enc_y(6) * enc.mm_per_count[1], 3e-3),
                     RIG_OK);
    static const int order[][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}, {2, 0}, {2, 1}, {3, 0},
                                   {3, 1}, {4, 0}, {5, 0}, {4, 1}, {8, 0}, {8, 1}, {6, 0},
                                   {7, 0}, {7, 1}, {5, 1}, {6, 1}, {9, 0}};
    for (size_t i = 0; i < sizeof order / sizeof order[0]; i++) {
        uint64_t k = (uint64_t)order[i][0], at = k > 6 ? 6 : k;
        rig_trig_event_t e = {(uint16_t)k, 0, 0, {enc_x(at), enc_y(at)}};
        rig_reading_t r = {(uint16_t)k, RIG_RD_VALID, dist(k)};
        assert_int_equal(order[i][1] ? scan_otf_read(&o, &r, 1) : scan_otf_trig(&o, &e, 1), RIG_OK);
    }
    assert_int_equal(scan_otf_row_end(&o, 0, 0), RIG_OK);
    assert_int_equal(o.c.paired, 7);
    assert_int_equal(o.c.past_end, 5);
    assert_int_equal(o.c.trig, 7);
    assert_int_equal(o.c.read, 7);
    assert_int_equal(o.c.both_lost + o.c.trig_no_read + o.c.read_no_trig, 0);
    assert_int_equal(s.points, 7);
    assert_int_equal(s.bad, 0);
}

/* The row's start and end positions, as cf_scanfast gives them. */
static void start_end_at(scan_otf_t *o, long start, long end)
{
    assert_int_equal(scan_otf_row_end_at(o, enc.org[0] + enc_x((uint64_t)end) * enc.mm_per_count[0],
                                         enc.org[1] + enc_y((uint64_t)end) * enc.mm_per_count[1],
                                         3e-3),
                     RIG_OK);
    assert_int_equal(
        scan_otf_row_start_at(o, enc.org[0] + enc_x((uint64_t)start) * enc.mm_per_count[0],
                              enc.org[1] + enc_y((uint64_t)start) * enc.mm_per_count[1]),
        RIG_OK);
}

/* The box armed before the stage moves (scan_otf_row_start_at): numbers
 * 0..399 fall on the stage standing at number 400's position; only 400,
 * the last there, is the row's first point, the rest dropped as
 * before_start; the row ends at 3000 as in t_end_at. Losses only while
 * moving here (t_start_lost: while standing). */
static void t_start_at(void **state)
{
    (void)state;
    static scan_otf_t o;
    const long start = 400, end = 3000;
    plan_t p;
    plan_alloc(&p, 5000);
    p.start_at = start;
    p.stop_at = end;
    for (long k = start + 1; k < end; k++)
        plan_loss(&p, k);
    sink_t s = {0};
    assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
    assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
    const double sx = enc.org[0] + enc_x(start) * enc.mm_per_count[0];
    const double sy = enc.org[1] + enc_y(start) * enc.mm_per_count[1];
    assert_int_equal(scan_otf_row_start_at(&o, sx, sy), RIG_ESTATE); /* its tol comes first */
    start_end_at(&o, start, end);
    deliver(&o, &p, 8);
    assert_int_equal(scan_otf_row_end(&o, 0, 0), RIG_OK);
    assert_int_equal(o.c.before_start, 2 * start);
    plan_t upto = p; /* the counts of numbers 0..end only */
    upto.n = end + 1;
    check_counts(&o, &upto, &s);
    assert_int_equal(s.first, start);
    assert_true(s.points > 0 && s.prev <= (uint64_t)end);
    plan_free(&p);
}

/* Numbers lost while the stage stands at the row's start (the review of
 * round 4): each is a loss of its kind, with its gap record in number
 * order, and the start goes on, so the points are still exactly the
 * numbers start..end that were paired (the first is start's) and every
 * pair before it is before_start. Pass 0: the first number's trigger
 * lost, a reading, a run of 5 on both sides, the trigger just before the
 * start's and the one just after it (the stage moving); pass 1: 20 % of
 * the standing numbers lost at random. */
static void t_start_lost(void **state)
{
    (void)state;
    static scan_otf_t o;
    const long start = 400, end = 3000;
    for (int pass = 0; pass < 2; pass++) {
        plan_t p;
        plan_alloc(&p, 4000);
        p.start_at = start;
        p.stop_at = end;
        if (pass == 0) {
            p.drop_t[0] = 1;
            p.drop_r[50] = 1;
            p.drop_t[100] = 1;
            plan_lose_both(&p, 200, 205);
            p.drop_t[start - 1] = 1;
            p.drop_t[start + 1] = 1;
        } else {
            for (long k = 0; k < start; k++) {
                double r = urand();
                p.drop_r[k] = r < 0.07 || (r >= 0.14 && r < 0.2);
                p.drop_t[k] = r >= 0.07 && r < 0.2;
            }
        }
        for (long k = start + 2; k < end; k++)
            plan_loss(&p, k);
        sink_t s = {0};
        s.start_at = start;
        s.stop_at = end;
        s.gap = calloc((size_t)p.n, 1);
        assert_non_null(s.gap);
        assert_int_equal(scan_otf_init(&o, &kin, &enc, on_row, &s), RIG_OK);
        scan_otf_set_gap(&o, on_gap);
        assert_int_equal(scan_otf_row_begin(&o, 0), RIG_OK);
        start_end_at(&o, start, end);
        deliver(&o, &p, 8);
        assert_int_equal(scan_otf_row_end(&o, 0, 0), RIG_OK);
        plan_t upto = p;
        upto.n = end + 1;
        check_counts(&o, &upto, &s);
        assert_int_equal(s.first, start);
        long lost = 0, wrong = 0, standing = 0;
        for (long k = 0; k <= end; k++) {
            int want = p.drop_t[k] && p.drop_r[k] ? JNL_GAP_BOTH
                       : p.drop_t[k]              ? JNL_GAP_NO_TRIGGER
                       : p.drop_r[k]              ? JNL_GAP_NO_READING
                                                  : 0;
            lost += want != 0;
            standing += want != 0 && k < start;
            wrong += s.gap[k] != want;
        }
        assert_true(standing >= 8);
        assert_int_equal(wrong, 0);
        assert_int_equal(s.ngap, lost);
        assert_int_equal(s.gap_bad, 0);
        free(s.gap);
        plan_free(&p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(t_clean_wraps), cmocka_unit_test(t_injected),
        cmocka_unit_test(t_cut_row),     cmocka_unit_test(t_rows_and_errors),
        cmocka_unit_test(t_gaps),        cmocka_unit_test(t_end_at),
        cmocka_unit_test(t_start_at),    cmocka_unit_test(t_start_lost),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
