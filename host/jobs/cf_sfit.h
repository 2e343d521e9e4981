/* cf_sfit.h: the streaming fit of measured points as they arrive (from a
 * scan, or read back from a journal): each point's parameters by projection
 * onto the nominal (cf_seedgrid start, nf_project), one row into the
 * stripes (nf_fit_add), Eq. 7 solved at the end. Memory: the job's byte
 * formula plus the seed grid, whatever the number of points. Also the
 * identity of a nominal file (for the journal header) and the residual
 * pass over a journal. */
#ifndef CF_SFIT_H
#define CF_SFIT_H

#include "cf_seedgrid.h"
#include "jnl.h"
#include "nf_fit.h"
#include <stddef.h>
#include <stdint.h>

typedef struct cf_sfit {
    const nf_surf_t *nominal; /* the space (knots, weights) and P0 */
    const nf_surf_t *proj;    /* parameters by projection onto this (nominal, or a fit) */
    cf_seedgrid_t pj;
    nf_arena_t ar;
    nf_fit_t f;
    void *mem;
    long need;
    long points;
    double dev_ss, dev_max; /* normal distances to proj (|deviation|) */
} cf_sfit_t;

/* A job on nominal's space (knots, weights, P0), parameters by projection
 * onto proj (NULL: the nominal; a previous fit for a reparameterisation
 * pass, Section 2.2). Exit-code style errors: returns 0, or CLI_USAGE /
 * CLI_FAIL after printing one line for cmd. */
int cf_sfit_init(cf_sfit_t *s, const nf_surf_t *nominal, const nf_surf_t *proj, double alpha,
                 double beta, const char *cmd);
/* One point: 0, or an nf_err_t. */
int cf_sfit_add(cf_sfit_t *s, const double xyz[3]);
/* Solve into out->cp (out has nominal's shape). 0 or an exit code (message printed). */
int cf_sfit_solve(cf_sfit_t *s, nf_surf_t *out, nf_solve_stats_t *st, const char *cmd);
void cf_sfit_free(cf_sfit_t *s);

/* Residual pass: normal distance of every valid point of the journal to s. */
typedef struct cf_sfit_resid {
    long n;
    double rms, max;
} cf_sfit_resid_t;
int cf_sfit_residuals(const nf_surf_t *s, jnl_reader_t *rd, cf_sfit_resid_t *out);

/* FNV-1a 64 of a file's bytes and its base name, for jnl_header_t. CF_EIO. */
int cf_sfit_nominal_id(const char *path, uint64_t *hash, char name[JNL_NAME_LEN]);

#endif
