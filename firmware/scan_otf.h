/* SPDX-License-Identifier: MIT */
/* scan_otf.h: on-the-fly pairing: positions latched by the trigger box and
 * readings streamed by the probe (rig.h) are matched BY TRIGGER NUMBER in a
 * window of the last SCAN_OTF_WINDOW triggers, never by arrival order; each
 * pair becomes a point by the kinematic model (scan.h), and the points of a
 * row go to the caller in trigger order, in chunks of at most
 * SCAN_OTF_ROW_MAX (to be journalled and streamed into the fit row by row).
 *
 * What cannot be paired is counted, once each, never guessed:
 *   a trigger whose reading never came     -> trig_no_read (a lost reading)
 *   a reading whose position never came    -> read_no_trig (a lost trigger)
 *   the same number twice                  -> dup_read / dup_trig (ignored)
 *   a number lost on both sides            -> both_lost (seen as a gap)
 *   a number already behind the window     -> late (dropped)
 *   the box's overrun flag                 -> overrun
 *   a row ended by a stage fault           -> rows_cut
 *   an event numbered after the trigger that
 *   latched the row's end position          -> past_end (dropped)
 *   a pair at the row's start before the
 *   last position there                      -> before_start (dropped)
 * so that, once a row is ended, trig = paired + nosurf + errors +
 * trig_no_read and read = paired + nosurf + errors + read_no_trig, and every
 * number below the row's end is in exactly one of paired, nosurf, errors,
 * trig_no_read, read_no_trig, both_lost, or a pair dropped as before_start.
 *
 * Numbers are 16 bits on the wire; each stream is unwrapped against its own
 * highest number so far (a jump of 32768 or more cannot be told from a
 * step back). Memory: the struct alone, fixed by the two sizes below. */
#ifndef SCAN_OTF_H
#define SCAN_OTF_H

#include "rig.h"
#include "scan.h"
#include <stdint.h>

#ifndef SCAN_OTF_WINDOW
#define SCAN_OTF_WINDOW 256 /* triggers in flight at once: a power of two */
#endif
#ifndef SCAN_OTF_ROW_MAX
#define SCAN_OTF_ROW_MAX 1024 /* points per chunk handed to the caller */
#endif
_Static_assert((SCAN_OTF_WINDOW & (SCAN_OTF_WINDOW - 1)) == 0 && SCAN_OTF_WINDOW >= 2,
               "SCAN_OTF_WINDOW must be a power of two");

/* Encoder counts to stage millimetres: x = org[0] + enc[0] * mm_per_count[0]. */
typedef struct scan_otf_enc {
    double org[2];
    double mm_per_count[2];
} scan_otf_enc_t;

typedef struct scan_otf_counts {
    uint64_t trig, read;     /* unique events taken */
    uint64_t paired, nosurf; /* points handed on; pairs without a surface */
    uint64_t errors;         /* pairs whose reading reported a sensor error */
    uint64_t trig_no_read, read_no_trig, both_lost;
    uint64_t dup_trig, dup_read, late, overrun;
    uint64_t rows, rows_cut;
    uint64_t past_end;     /* events after the row's end trigger, each side counted */
    uint64_t before_start; /* events at the row's start before its last there, each side */
} scan_otf_counts_t;

/* A chunk of a row: n points (x y z each) in trigger order, their trigger
 * numbers (unwrapped), and last = 1 on the row's final chunk. A non-zero
 * return stops the pairing with that code. */
typedef int (*scan_otf_row_fn)(void *ctx, long row, const double *xyz, const uint64_t *trig, long n,
                               int last);

/* A loss at its numbers (issue 19), for the journal's gap records: kind
 * JNL_GAP_NO_READING (a position whose reading never came; xy its latched
 * stage position), JNL_GAP_NO_TRIGGER or JNL_GAP_BOTH (xy NULL), count
 * numbers from num on (runs of one kind without a position are joined).
 * The row's points before it are handed on first, so that the caller sees
 * points and gaps in number order. Non-zero stops the pairing. */
typedef int (*scan_otf_gap_fn)(void *ctx, long row, int kind, uint64_t num, uint64_t count,
                               const double *xy);

typedef struct scan_otf_slot {
    uint64_t num;  /* unwrapped trigger number held, when state != 0 */
    uint8_t state; /* bit 0 position, bit 1 reading */
    uint8_t rst;   /* reading status RIG_RD_* */
    double x, y, d;
} scan_otf_slot_t;

typedef struct scan_otf {
    scan_kin_t kin;
    scan_otf_enc_t enc;
    scan_otf_row_fn row_fn;
    void *row_ctx;
    long row;         /* current row, -1 between rows */
    uint64_t base;    /* lowest trigger number still in the window */
    uint64_t hi_trig; /* highest unwrapped number seen, per stream */
    uint64_t hi_read;
    int any_trig, any_read;
    int err; /* the callback's code once it failed */
    scan_otf_counts_t c;
    scan_otf_slot_t slot[SCAN_OTF_WINDOW];
    long n_out;
    double out[3 * SCAN_OTF_ROW_MAX];
    uint64_t out_num[SCAN_OTF_ROW_MAX];
    /* The gap callback and the run of losses not yet handed to it. */
    scan_otf_gap_fn gap_fn;
    int gp_kind, gp_has_xy;
    uint64_t gp_num, gp_count;
    double gp_xy[2];
    /* The row's end (scan_otf_row_end_at): once a position within end_tol
     * of end_xy is latched, end_num is its number and the row's last. */
    int has_end, end_seen;
    double end_xy[2], end_tol;
    uint64_t end_num;
    /* The row's start (scan_otf_row_start_at): the last position retired
     * there is held back (stash) until a number past it is. */
    int has_start, st_have;
    double start_xy[2];
    scan_otf_slot_t stash;
} scan_otf_t;

/* Errors beyond rig_err_t's: none; RIG_EARG for a bad call, RIG_ESTATE for
 * events outside a row, or the callback's own code. */
int scan_otf_init(scan_otf_t *o, const scan_kin_t *kin, const scan_otf_enc_t *enc,
                  scan_otf_row_fn fn, void *ctx);

/* Hand every loss to fn too (NULL: counts only, the default); after
 * scan_otf_init, with the row callback's ctx. */
void scan_otf_set_gap(scan_otf_t *o, scan_otf_gap_fn fn);

/* A row starts (the box and the probe were armed for it: numbering from 0). */
int scan_otf_row_begin(scan_otf_t *o, long row);

/* The row ends at stage position (x, y): the first trigger (by number)
 * whose latched position lies within tol (mm, each axis) of it is the
 * row's last. The box keeps firing until the host stops it, at a stage
 * standing at the end; those events (numbered after it) are dropped and
 * counted as past_end, never paired nor counted as losses, so that a
 * host late to see the row's end adds no point (issue 19). After
 * scan_otf_row_begin; without it a row ends at scan_otf_row_end only. */
int scan_otf_row_end_at(scan_otf_t *o, double x, double y, double tol);

/* The row starts at stage position (x, y) (within scan_otf_row_end_at's
 * tol; after it, before any event): the box is armed before the stage
 * moves, so the triggers fire first at a standing stage; of the
 * positions latched there only the last is the row's first point, the
 * pairs before it dropped and counted as before_start (each side). A
 * number lost there is a loss of its kind as anywhere, and does not end
 * the start: a number without a position is taken as standing when the
 * next position in the window is at the start. The start ends at the first
 * position away from it (or a window of numbers without one), so a row's
 * point count does not depend on how long it stood, nor on its losses. */
int scan_otf_row_start_at(scan_otf_t *o, double x, double y);

/* 1 once the row's end position has been latched (the triggers can stop). */
int scan_otf_end_seen(const scan_otf_t *o);

/* Events as they arrive, in any order and in batches of any size. */
int scan_otf_trig(scan_otf_t *o, const rig_trig_event_t *ev, size_t n);
int scan_otf_read(scan_otf_t *o, const rig_reading_t *r, size_t n);

/* The row ends: everything still in the window is settled (counted or
 * paired) and the final chunk handed on. expected: the triggers the row
 * should have fired (its length over the spacing; 0 unknown), so triggers
 * lost at its end on both sides are counted too. stage_fault != 0 counts
 * the row as cut short by the stage (its points so far are kept, and the
 * triggers it never reached are not losses; nor are those after the end
 * trigger of scan_otf_row_end_at). */
int scan_otf_row_end(scan_otf_t *o, int stage_fault, uint64_t expected);

#endif
