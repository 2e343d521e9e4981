/* SPDX-License-Identifier: MIT */
/* scan_otf.c: on-the-fly pairing of latched positions and streamed
 * readings by trigger number (scan_otf.h): a ring of SCAN_OTF_WINDOW slots
 * indexed by number, retired in number order. */
#include "scan_otf.h"
#include <math.h>
#include <string.h>

enum { HAVE_POS = 1, HAVE_RD = 2 };

int scan_otf_init(scan_otf_t *o, const scan_kin_t *kin, const scan_otf_enc_t *enc,
                  scan_otf_row_fn fn, void *ctx)
{
    if (!o || !kin || !enc || !fn)
        return RIG_EARG;
    memset(o, 0, sizeof *o);
    o->kin = *kin;
    o->enc = *enc;
    o->row_fn = fn;
    o->row_ctx = ctx;
    o->row = -1;
    return RIG_OK;
}

void scan_otf_set_gap(scan_otf_t *o, scan_otf_gap_fn fn)
{
    if (o)
        o->gap_fn = fn;
}

int scan_otf_row_begin(scan_otf_t *o, long row)
{
    if (!o || row < 0)
        return RIG_EARG;
    if (o->row >= 0 || o->err)
        return o->err ? o->err : RIG_ESTATE;
    o->row = row;
    o->base = 0;
    o->gp_count = 0;
    o->hi_trig = o->hi_read = 0;
    o->any_trig = o->any_read = 0;
    o->n_out = 0;
    o->has_end = o->end_seen = 0;
    o->has_start = o->st_have = 0;
    for (int i = 0; i < SCAN_OTF_WINDOW; i++)
        o->slot[i].state = 0;
    return RIG_OK;
}

int scan_otf_row_end_at(scan_otf_t *o, double x, double y, double tol)
{
    if (!o || !(tol > 0) || !isfinite(x) || !isfinite(y) || !isfinite(tol))
        return RIG_EARG;
    if (o->row < 0)
        return RIG_ESTATE;
    o->has_end = 1;
    o->end_xy[0] = x;
    o->end_xy[1] = y;
    o->end_tol = tol;
    return RIG_OK;
}

int scan_otf_row_start_at(scan_otf_t *o, double x, double y)
{
    if (!o || !isfinite(x) || !isfinite(y))
        return RIG_EARG;
    if (o->row < 0)
        return RIG_ESTATE;
    if (!o->has_end || o->base || o->any_trig || o->any_read)
        return RIG_ESTATE; /* after scan_otf_row_end_at (its tol), before any event */
    o->has_start = 1;
    o->start_xy[0] = x;
    o->start_xy[1] = y;
    return RIG_OK;
}

int scan_otf_end_seen(const scan_otf_t *o)
{
    return o && o->row >= 0 && o->end_seen;
}

/* Number num latched the row's end: it is the row's last, and whatever
 * the window already holds after it is dropped (arrival out of order). */
static void end_latched(scan_otf_t *o, uint64_t num)
{
    if (o->end_seen && num >= o->end_num)
        return;
    o->end_seen = 1;
    o->end_num = num;
    for (int i = 0; i < SCAN_OTF_WINDOW; i++) {
        scan_otf_slot_t *s = &o->slot[i];
        if (!s->state || s->num <= num)
            continue;
        if (s->state & HAVE_POS)
            o->c.trig--, o->c.past_end++;
        if (s->state & HAVE_RD)
            o->c.read--, o->c.past_end++;
        s->state = 0;
    }
}

static int past_end(const scan_otf_t *o, uint64_t num)
{
    return o->end_seen && num != UINT64_MAX && num > o->end_num;
}

/* The unwrapped number of a 16-bit one, against the stream's highest so
 * far: the nearest number with those low bits. */
static uint64_t unwrap(uint64_t hi, int any, uint16_t w)
{
    if (!any)
        return w;
    int16_t step = (int16_t)(uint16_t)(w - (uint16_t)hi);
    if (step < 0 && (uint64_t)(-step) > hi)
        return UINT64_MAX; /* before number 0: cannot be, taken as late */
    return hi + (uint64_t)(int64_t)step;
}

static int flush_out(scan_otf_t *o, int last)
{
    if (o->err)
        return o->err;
    if (!o->n_out && !last)
        return RIG_OK;
    int rc = o->row_fn(o->row_ctx, o->row, o->out, o->out_num, o->n_out, last);
    o->n_out = 0;
    if (rc)
        o->err = rc;
    return rc;
}

/* The run of losses held back, to the gap callback (after the points
 * before it). */
static int gap_emit(scan_otf_t *o)
{
    if (!o->gp_count)
        return RIG_OK;
    int rc = flush_out(o, 0);
    if (!rc && (rc = o->gap_fn(o->row_ctx, o->row, o->gp_kind, o->gp_num, o->gp_count,
                               o->gp_has_xy ? o->gp_xy : NULL)) != 0)
        o->err = rc;
    o->gp_count = 0;
    return rc;
}

/* count numbers from num lost (kind JNL_GAP_*; xy a position, or NULL):
 * joined to the run held back when it continues it, else that run is
 * handed on and this one held. */
static int gap_add(scan_otf_t *o, int kind, uint64_t num, uint64_t count, const double *xy)
{
    if (!o->gap_fn || !count)
        return RIG_OK;
    if (o->gp_count && o->gp_kind == kind && !xy && !o->gp_has_xy &&
        num == o->gp_num + o->gp_count) {
        o->gp_count += count;
        return RIG_OK;
    }
    int rc = gap_emit(o);
    if (rc)
        return rc;
    o->gp_kind = kind;
    o->gp_num = num;
    o->gp_count = count;
    o->gp_has_xy = xy != NULL;
    if (xy)
        o->gp_xy[0] = xy[0], o->gp_xy[1] = xy[1];
    return RIG_OK;
}

/* Settle slot s as number num (a point, or a loss counted). */
static int settle(scan_otf_t *o, const scan_otf_slot_t *s, uint64_t num)
{
    int rc = RIG_OK;
    if (s->state == (HAVE_POS | HAVE_RD) && s->num == num) {
        if (s->rst == RIG_RD_VALID) {
            if (o->gp_count && (rc = gap_emit(o)) != RIG_OK)
                return rc;
            scan_kin_point(&o->kin, s->x, s->y, s->d, o->out + 3 * o->n_out);
            o->out_num[o->n_out++] = s->num;
            o->c.paired++;
            if (o->n_out == SCAN_OTF_ROW_MAX)
                rc = flush_out(o, 0);
        } else if (s->rst == RIG_RD_NOSURF)
            o->c.nosurf++;
        else
            o->c.errors++;
    } else if (s->state == HAVE_POS) {
        o->c.trig_no_read++;
        const double xy[2] = {s->x, s->y};
        rc = gap_add(o, JNL_GAP_NO_READING, num, 1, xy);
    } else if (s->state == HAVE_RD) {
        o->c.read_no_trig++;
        rc = gap_add(o, JNL_GAP_NO_TRIGGER, num, 1, NULL);
    } else {
        o->c.both_lost++;
        rc = gap_add(o, JNL_GAP_BOTH, num, 1, NULL);
    }
    return rc;
}

static int near_xy(const scan_otf_t *o, double x, double y, const double at[2])
{
    return x - at[0] <= o->end_tol && at[0] - x <= o->end_tol && y - at[1] <= o->end_tol &&
           at[1] - y <= o->end_tol;
}

/* The start phase ends (at the first position latched away from the row's
 * start): the last position held there is settled first. */
static int start_done(scan_otf_t *o)
{
    int rc = RIG_OK;
    if (o->has_start && o->st_have)
        rc = settle(o, &o->stash, o->stash.num);
    o->has_start = o->st_have = 0;
    return rc;
}

/* A later position at the row's start is known: the one held back is not
 * the last there. Its pair is dropped (before_start); a position whose
 * reading never came is a loss as anywhere (settled now, in number order). */
static int stash_drop(scan_otf_t *o)
{
    int rc = RIG_OK;
    if (o->st_have && o->stash.state == (HAVE_POS | HAVE_RD))
        o->c.trig--, o->c.read--, o->c.before_start += 2;
    else if (o->st_have)
        rc = settle(o, &o->stash, o->stash.num);
    o->st_have = 0;
    return rc;
}

/* Number base came without a position while the row is starting: does the
 * stage still stand at the start? The first position after it in the
 * window says so (the stage stands, then moves, never back); none there
 * yet (a window of losses): taken as moved. */
static int still_standing(const scan_otf_t *o)
{
    for (uint64_t k = o->base + 1; k < o->base + SCAN_OTF_WINDOW; k++) {
        const scan_otf_slot_t *s = &o->slot[k & (SCAN_OTF_WINDOW - 1)];
        if ((s->state & HAVE_POS) && s->num == k)
            return near_xy(o, s->x, s->y, o->start_xy);
    }
    return 0;
}

/* Settle the slot of number base and move the window on by one. While the
 * row is starting, a position at its start is held back instead, and the
 * one it replaces dropped (the stage stood there: only the last counts); a
 * number lost there is a loss and does not end the start. */
static int retire_one(scan_otf_t *o)
{
    scan_otf_slot_t *s = &o->slot[o->base & (SCAN_OTF_WINDOW - 1)];
    int rc = RIG_OK;
    int pos = (s->state & HAVE_POS) && s->num == o->base;
    if (o->has_start && pos && near_xy(o, s->x, s->y, o->start_xy)) {
        if ((rc = stash_drop(o)) == RIG_OK) {
            o->stash = *s;
            o->st_have = 1;
        }
    } else if (o->has_start && !pos && still_standing(o)) {
        if ((rc = stash_drop(o)) == RIG_OK)
            rc = settle(o, s, o->base);
    } else if ((rc = start_done(o)) == RIG_OK)
        rc = settle(o, s, o->base);
    s->state = 0;
    o->base++;
    return rc;
}

/* Make room for number num: retire everything more than a window behind. */
static int make_room(scan_otf_t *o, uint64_t num)
{
    while (num >= o->base + SCAN_OTF_WINDOW) {
        /* A long gap: the slots between are empty, skip them at once. */
        if (num - o->base > 2 * SCAN_OTF_WINDOW) {
            int rc = RIG_OK;
            for (int i = 0; i < SCAN_OTF_WINDOW && !rc; i++)
                rc = retire_one(o);
            if (!rc)
                rc = start_done(o); /* before the run's gap */
            if (rc)
                return rc;
            o->c.both_lost += num - SCAN_OTF_WINDOW + 1 - o->base;
            if ((rc = gap_add(o, JNL_GAP_BOTH, o->base, num - SCAN_OTF_WINDOW + 1 - o->base,
                              NULL)) != RIG_OK)
                return rc;
            o->base = num - SCAN_OTF_WINDOW + 1;
            continue;
        }
        int rc = retire_one(o);
        if (rc)
            return rc;
    }
    return RIG_OK;
}

/* Retire completed slots from the front, so points leave in number order
 * as soon as they can. */
static int advance(scan_otf_t *o)
{
    for (;;) {
        scan_otf_slot_t *s = &o->slot[o->base & (SCAN_OTF_WINDOW - 1)];
        if (s->state != (HAVE_POS | HAVE_RD) || s->num != o->base)
            return RIG_OK;
        int rc = retire_one(o);
        if (rc)
            return rc;
    }
}

/* The slot for num, or NULL when num is behind the window (late). */
static scan_otf_slot_t *slot_for(scan_otf_t *o, uint64_t num, int *rc)
{
    *rc = RIG_OK;
    if (num < o->base || num == UINT64_MAX) {
        o->c.late++;
        return NULL;
    }
    *rc = make_room(o, num);
    if (*rc)
        return NULL;
    scan_otf_slot_t *s = &o->slot[num & (SCAN_OTF_WINDOW - 1)];
    if (!s->state)
        s->num = num;
    return s;
}

int scan_otf_trig(scan_otf_t *o, const rig_trig_event_t *ev, size_t n)
{
    if (!o || (n && !ev))
        return RIG_EARG;
    if (o->err)
        return o->err;
    if (o->row < 0)
        return RIG_ESTATE;
    for (size_t i = 0; i < n; i++) {
        uint64_t num = unwrap(o->hi_trig, o->any_trig, ev[i].seq);
        if (past_end(o, num)) {
            o->hi_trig = num > o->hi_trig ? num : o->hi_trig; /* unwrapping goes on */
            o->any_trig = 1;
            o->c.past_end++;
            continue;
        }
        int rc;
        scan_otf_slot_t *s = slot_for(o, num, &rc);
        if (rc)
            return rc;
        if (!s)
            continue;
        if (s->state & HAVE_POS) {
            o->c.dup_trig++;
            continue;
        }
        if (!o->any_trig || num > o->hi_trig)
            o->hi_trig = num;
        o->any_trig = 1;
        o->c.trig++;
        if (ev[i].flags & RIG_TRIG_F_OVERRUN) /* once per event, not per copy */
            o->c.overrun++;
        s->state |= HAVE_POS;
        s->x = o->enc.org[0] + (double)ev[i].enc[0] * o->enc.mm_per_count[0];
        s->y = o->enc.org[1] + (double)ev[i].enc[1] * o->enc.mm_per_count[1];
        if (o->has_end && near_xy(o, s->x, s->y, o->end_xy))
            end_latched(o, num);
    }
    return advance(o);
}

int scan_otf_read(scan_otf_t *o, const rig_reading_t *r, size_t n)
{
    if (!o || (n && !r))
        return RIG_EARG;
    if (o->err)
        return o->err;
    if (o->row < 0)
        return RIG_ESTATE;
    for (size_t i = 0; i < n; i++) {
        uint64_t num = unwrap(o->hi_read, o->any_read, r[i].seq);
        if (past_end(o, num)) {
            o->hi_read = !o->any_read || num > o->hi_read ? num : o->hi_read;
            o->any_read = 1;
            o->c.past_end++;
            continue;
        }
        int rc;
        scan_otf_slot_t *s = slot_for(o, num, &rc);
        if (rc)
            return rc;
        if (!s)
            continue;
        if (s->state & HAVE_RD) {
            o->c.dup_read++; /* the first one stands: never overwritten */
            continue;
        }
        if (!o->any_read || num > o->hi_read)
            o->hi_read = num;
        o->any_read = 1;
        o->c.read++;
        s->state |= HAVE_RD;
        s->rst = r[i].status <= RIG_RD_ERROR ? r[i].status : RIG_RD_ERROR;
        s->d = r[i].d;
    }
    return advance(o);
}

int scan_otf_row_end(scan_otf_t *o, int stage_fault, uint64_t expected)
{
    if (!o)
        return RIG_EARG;
    if (o->err)
        return o->err;
    if (o->row < 0)
        return RIG_ESTATE;
    uint64_t end =
        o->any_trig || o->any_read ? (o->hi_trig > o->hi_read ? o->hi_trig : o->hi_read) + 1 : 0;
    if (o->end_seen && end > o->end_num + 1)
        end = o->end_num + 1; /* what came after the end trigger was dropped */
    int rc = RIG_OK;
    while (!rc && o->base < end)
        rc = retire_one(o);
    if (!rc)
        rc = start_done(o);
    if (!rc && !stage_fault && !o->end_seen &&
        expected > o->base) { /* the last triggers, lost on both sides */
        o->c.both_lost += expected - o->base;
        rc = gap_add(o, JNL_GAP_BOTH, o->base, expected - o->base, NULL);
    }
    if (!rc)
        rc = gap_emit(o);
    if (!rc)
        rc = flush_out(o, 1);
    o->c.rows++;
    if (stage_fault)
        o->c.rows_cut++;
    o->row = -1;
    return rc;
}
