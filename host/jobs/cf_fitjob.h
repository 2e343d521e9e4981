/* SPDX-License-Identifier: MIT */
/* cf_fitjob.h: the fit job: every fit of measured points onto a nominal
 * runs here, whoever asks (`cellfit fit`, `journal fit`, `scan --fit`, the
 * cell's FIT and SCAN_FIT). Brujic et al. 2010: Eq. 7 accumulated one
 * point at a time into the stripes and solved; parameters given or by
 * projection onto the base, then reprojected onto the fit K times
 * (Section 2.2); optionally robust (Tukey weights, scale from the MAD of
 * the residuals); optionally to a tolerance: rounds of fit, check, knot
 * insertion (uniform or where the residuals are, cf_loop) until the share
 * of points within tol is reached or a limit says no (auto, the default:
 * nf_knotsel's knot lines where the misfit is and data lie on both sides,
 * never more control points than half the points, and nf_loopctl's rules:
 * met, no progress, data limit, max_cp, rounds). The best round is the
 * result: surface, statistics, rounds, timings, warnings, status. Every
 * K-th scan row can be held out of the fit and measured against it
 * (cf_holdout).
 *
 * Points come from a source (cf_fitsrc: points file or journal) read again
 * per pass; a live scan adds its points as they arrive (cf_fitjob_add), the
 * first pass, and hands its journal for the rest. Memory: the fitter's byte
 * formula for the largest net plus buffers of the net's size and a fixed
 * batch, never a function of the number of points, but for two holds of
 * at most CF_FITJOB_HOLD_ROWS points: a live scan's points, and the
 * tolerance loop's feet (u v per point, 16 bytes: the next round's fit
 * pass projects onto the last fit refined, the same surface, and starts
 * Newton at each point's foot on it instead of searching: half the loop's
 * projection work, the same feet). Progress and a stop
 * check between batches (the cell's ABORT and watchdog). */
#ifndef CF_FITJOB_H
#define CF_FITJOB_H

#include "cf_fitsrc.h"
#include "cf_loop.h"
#include "cf_stats.h"
#include "nf_fit.h"
#include <stddef.h>

/* Progress (0..100) and a cooperative stop check, both optional. */
typedef struct cf_job_ctl {
    void (*progress)(void *ctx, int pct);
    int (*should_stop)(void *ctx); /* non-zero: stop at the next batch */
    void *ctx;
} cf_job_ctl_t;

#define CF_FITJOB_MAX_ROUNDS 64
/* Live points the job holds (x y z, 24 bytes each: at most 24 MiB, grown
 * as they come): the passes after a live scan read them instead of
 * verifying and reading the journal back (the same points in the same
 * order: the same fit). A scan of more points lets the hold go at this
 * count and reads its source, as before (issue 19). */
#define CF_FITJOB_HOLD_ROWS (1L << 20)
#define CF_FITJOB_MAX_WARN 4
/* Newton from a kept foot stops at a step of this share of the domain and
 * takes it (the second-order Taylor foot): one derivative evaluation a
 * point saved in most, the distance off by 2e-6 mm at most (docs/loop.md). */
#define CF_FITJOB_WARM_TOL 1e-4

/* How a job ended (the cell's fit_status register, report.json). */
typedef enum cf_fitjob_status {
    CF_FITJOB_PLAIN = 0,              /* no tolerance loop asked */
    CF_FITJOB_MET = 1,                /* the share of points within tol reached */
    CF_FITJOB_NOT_MET_DATA_LIMIT = 2, /* no span with data on both sides left to split */
    CF_FITJOB_NOT_MET_MAX_CP = 3,     /* the next net exceeds max_cp, the board's points or bytes */
    CF_FITJOB_NOT_MET_NO_PROGRESS = 4 /* rounds stopped gaining (auto), or max_rounds used up */
} cf_fitjob_status_t;

/* The largest second accumulator (nf_fit_shard_bytes) a pass read in
 * halves takes (opts.cores): a few MiB, N up to about 1.8e4 control
 * points at degree 3 x 3; beyond, one reader, so memory does not grow
 * with the second core. */
#define CF_FITJOB_SHARD_MAX (4L << 20)

typedef struct cf_fitjob_opts {
    double alpha, beta; /* Eq. 7's weights */
    nf_solver_t solver;
    double solve_tol; /* relative residual of the iterative solvers */
    long max_iter;
    int probe;        /* 1: the iterative solvers check that the data determine the net */
    int threads;      /* accumulating cores: 1, or 2 (a second accumulator, cf_accum; its
                       * bytes checked at open and per pass, not by the loop's max_cp) */
    int cores;        /* 2: a pass of given parameters (u v x y z) over a points file read
                       * in halves on two threads, each its reader and (fit) its
                       * accumulator, when that second accumulator is small
                       * (CF_FITJOB_SHARD_MAX); and a pass's projections (the
                       * feet) of each batch in halves, summed in order, and a
                       * fit pass's halves of projected points accumulated at
                       * once (their grouping is one core's too): the same fit;
                       * 1: the present one reader, one thread */
    int net_u, net_v; /* 0: the base's net; else the base refined to it first */
    long reparam;     /* reprojection passes per round (Section 2.2) */
    double far;       /* projected points farther than this are counted (mm; 0: 5 % of the net) */
    int drop_far;     /* 1: and left out of the fit */
    double tol;       /* deviation tolerance, mm (0: none): the within count, the loop's goal */
    int loop;         /* 1: rounds of knot insertion until `within` % are within tol */
    double within;    /* percent */
    long max_cp, max_rounds;
    cf_refine_t refine;
    int robust; /* Tukey reweighting passes after each fit */
    long robust_iters;
    int stats;        /* 1: signed normal deviations of the points into cf_stats (tol > 0) */
    double min_gain;  /* auto: least gain of a round, points of percent (nf_loopctl) */
    double noise;     /* robust: the probe's noise, mm, a floor under the scale */
    long holdout;     /* >= 2: every holdout-th scan row left out and measured (cf_holdout) */
    int free_edges;   /* 1: no pins; else (issue 14) control points with no point in their
                       * support follow the nominal (cf_edges) */
    double stats_tol; /* the statistics' tolerance when it is not the loop's (0: tol); the
                       * cell's verdict tolerance beside its fit loop's goal */
    long prune;       /* auto, once met: at most this many trial fits with one knot line
                       * the loop inserted taken out again (nf_prune), each kept only if
                       * it still meets the tolerance; 0: none */
} cf_fitjob_opts_t;

/* Pruning trials by default (opts.prune): each costs about one round
 * (docs/loop.md, "Pruning the knot lines"). The stage also ends after
 * CF_FITJOB_PRUNE_MISSES trials in a row were undone: the next line ranks
 * worse still, and on none of the benchmark's eight fields did a trial
 * after an undone one succeed (one round less on four of them). */
#define CF_FITJOB_PRUNE_TRIALS 4
#define CF_FITJOB_PRUNE_MISSES 1
/* A line is tried only when it holds at least 1 / this of the net's control
 * points: on a fine net (the narrow ridge's 3,420, lines of 57) a trial
 * costs as much as the loop's last round (0.4 s) and saves 2 %. */
#define CF_FITJOB_PRUNE_MIN_LINE 32

/* The robust scale's floor as a share of tol: max(noise, this tol). Points
 * keep weight > 0 up to NF_ROBUST_CUT floors (1.5 tol): a fit short of the
 * tolerance never rejects the data it has yet to reach. */
#define CF_FITJOB_FLOOR_TOL 0.25

/* The shell's defaults: alpha, beta of the paper, solver auto, 1e-12 and
 * 20000 iterations with the probe, one core, within 100 %, max_cp the
 * board's, 12 rounds, auto refinement with min_gain NF_LOOPCTL_MIN_GAIN, 3
 * robust passes, CF_FITJOB_PRUNE_TRIALS pruning trials; everything else off. */
void cf_fitjob_defaults(cf_fitjob_opts_t *o);

typedef struct cf_fitjob_result {
    nf_surf_t surf; /* the best fit (heap, cf_surf) */
    cf_fitjob_status_t status;
    char why[256];              /* the rule that stopped the loop, and why ("met: ...") */
    long points;                /* points read in a pass */
    long clamped, far, dropped; /* projection: feet on the boundary, beyond far, left out */
    double far_limit;
    double rms, max_abs;             /* distances of the points to the best fit */
    double within_pct;               /* of the points within tol (tol > 0) */
    double nominal_rms, nominal_max; /* the first pass's distances to the base */
    double sigma;                    /* robust scale of the best round (0: none) */
    long outliers;                   /* robust: points of weight 0 in its last pass */
    nf_solve_stats_t solve;
    long bytes;  /* fitter memory of the best round */
    int threads; /* 2: some pass read its halves on two threads (opts.cores) */
    cf_round_t rounds[CF_FITJOB_MAX_ROUNDS]; /* the loop's, then its pruning trials */
    int nrounds;
    int pruned; /* knot lines the pruning stage took out (rounds with prune 1) */
    double seconds, t_acc, t_solve;
    double t_rows, t_merge; /* of t_acc: inside the fitter's accumulation; the cores' merge */
    long store_bytes;       /* the stripes of Eq. 7's matrix, best round */
    cf_stats_t *stats;      /* heap, with opts.stats: deviations to the best fit */
    double robust_floor;    /* the scale's floor (robust) */
    /* The best round's data footprint (nf_footprint): cells of the knot
     * spans with points, without ("no data"), on the edge; fp_cells 0: none. */
    long fp_cells, fp_filled, fp_empty, fp_outline;
    long pinned; /* control points of the best fit pinned to the nominal (cf_edges) */
    /* Held-out rows (opts.holdout): points, rms, p99 (the histogram's
     * estimate, within NF_RHIST_RELERR) and max of their distances. */
    long ho_points;
    double ho_rms, ho_p99, ho_max;
    int nwarn;
    char warn[CF_FITJOB_MAX_WARN][160];
} cf_fitjob_result_t;

typedef struct cf_fitjob cf_fitjob_t; /* opaque */

/* A job on the nominal's space (copied; refined to net_u x net_v if asked),
 * checked against the board before any point: 0, or NF_EBUDGET (msg says
 * the bytes), CF_EARG (options, a net smaller than the nominal's, max_cp
 * below it), CF_ENOMEM. */
int cf_fitjob_open(cf_fitjob_t **j, const nf_surf_t *nominal, const cf_fitjob_opts_t *o, char *msg,
                   size_t ml);

/* The base the job fits in (the nominal refined), and its fitter bytes. */
const nf_surf_t *cf_fitjob_base(const cf_fitjob_t *j);
long cf_fitjob_bytes(const cf_fitjob_t *j);

/* A live point (x y z), the first pass of the first round: projected onto
 * the base and added as it arrives. 0, or an nf_err_t (msg). */
int cf_fitjob_add(cf_fitjob_t *j, const double xyz[3], char *msg, size_t ml);

/* 1 when every live point added so far is held (CF_FITJOB_HOLD_ROWS): the
 * run then reads the hold, not src, which may be NULL (a live scan need
 * not open its journal again). */
int cf_fitjob_held(const cf_fitjob_t *j);

/* Run the job: the first pass from the live points if any, else from src;
 * every later pass from src (from the hold when cf_fitjob_held). Progress over pct0..pct1 of ctl. 0 with *r
 * filled (cf_fitjob_result_free), also when the tolerance was not met
 * (r->status says so); RIG_EABORTED when ctl asked to stop; otherwise a
 * CF_E* / NF_E* / RIG_E* code with msg naming file and line or record. On
 * failure *r owns nothing. */
int cf_fitjob_run(cf_fitjob_t *j, const cf_fitsrc_t *src, const cf_job_ctl_t *ctl, int pct0,
                  int pct1, cf_fitjob_result_t *r, char *msg, size_t ml);

void cf_fitjob_close(cf_fitjob_t *j);
void cf_fitjob_result_free(cf_fitjob_result_t *r);

/* "plain", "met", "not_met_data_limit", "not_met_max_cp", "not_met_no_progress". */
const char *cf_fitjob_status_name(cf_fitjob_status_t s);

/* 1 when rc blames the input (points, nominal, options: exit 2), 0 when the
 * work failed (exit 1). */
int cf_fitjob_input_error(int rc);

#endif
