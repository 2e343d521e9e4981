/* SPDX-License-Identifier: MIT */
/* cellfit.h: the public C API of libcellfit: fit the control net of a
 * nominal NURBS surface to measured points (Brujic, Ainsworth & Ristic
 * 2010, Eq. 7: least squares with the Greville (alpha) and stay-near-nominal
 * (beta) terms), streamed in any number of calls, in memory that depends on
 * the control net alone; read the fitted surface, its statistics, write it
 * as IGES; read the points of a cell's journal.
 *
 * No global state: every call works on the handle it is given, so handles
 * may live in different threads (one thread per handle at a time). Errors
 * are negative CELLFIT_E* codes, with cellfit_strerror() for each and
 * cellfit_fit_message() for the detail of a handle's last failure.
 *
 * Memory: cellfit_fit_bytes() is the whole of what a fit needs (the
 * firmware's public byte formula plus this API's state). Pass a block of
 * that size to cellfit_fit_open() and nothing else is allocated for fits
 * of u v x y z points; x y z points are projected onto the nominal, whose
 * start-point grid is allocated on the first cellfit_fit_add_xyz(). With
 * mem NULL the library allocates the block itself.
 *
 * Link: pkg-config --cflags --libs cellfit. */
#ifndef CELLFIT_H
#define CELLFIT_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CELLFIT_VERSION_MAJOR 0
#define CELLFIT_VERSION_MINOR 13
#define CELLFIT_VERSION_PATCH 0

/* The library's version at run time ("0.13.0 (git revision)"), and its
 * numbers; compare with the CELLFIT_VERSION_* the caller was built with. */
const char *cellfit_version(void);
void cellfit_version_numbers(int *major, int *minor, int *patch);

enum cellfit_error {
    CELLFIT_OK = 0,
    CELLFIT_EARG = -1,    /* a NULL handle, bad sizes: a bug in the caller */
    CELLFIT_EIO = -2,     /* a file cannot be opened, read or written */
    CELLFIT_EFORMAT = -3, /* a file or surface is malformed or unsupported */
    CELLFIT_EBUDGET = -4, /* the net needs more memory than allowed or given */
    CELLFIT_ENOMEM = -5,  /* an allocation failed */
    CELLFIT_EDOMAIN = -6, /* a u v outside the surface's domain, or a non-finite value */
    CELLFIT_EDATA = -7,   /* the points do not determine the net (add alpha, beta or points) */
    CELLFIT_ESTATE = -8,  /* a call out of order (points after solve, a result before it) */
    CELLFIT_ESOLVE = -9   /* the solver did not converge */
};

/* A static string for every code above. */
const char *cellfit_strerror(int code);

/* A NURBS surface, read only: degrees p (u) and q (v), nu x nv control
 * points P[i + j*nu] (u fastest) as x y z triples, knots U (nu+p+1) and V
 * (nv+q+1), weights w (nu*nv) or NULL for a non-rational surface. */
typedef struct cellfit_surface {
    int p, q, nu, nv;
    const double *U, *V;
    const double *cp;
    const double *w;
} cellfit_surface_t;

enum cellfit_solver {
    CELLFIT_SOLVER_AUTO = 0, /* the fastest that fits in memory */
    CELLFIT_SOLVER_GS = 1,   /* Gauss-Seidel on the stripes (the paper, Section 3.2) */
    CELLFIT_SOLVER_CHOL = 2, /* banded Cholesky, exact */
    CELLFIT_SOLVER_PCG = 3   /* preconditioned conjugate gradients */
};

typedef struct cellfit_params {
    double alpha; /* Greville criterion weight (default 0.1) */
    double beta;  /* stay-near-nominal weight (default 0.001) */
    int solver;   /* enum cellfit_solver (default AUTO) */
} cellfit_params_t;

/* The paper's defaults: alpha 0.1, beta 0.001, solver AUTO. */
void cellfit_params_default(cellfit_params_t *prm);

typedef struct cellfit_fit cellfit_fit_t;

/* Bytes a fit of this nominal needs (prm NULL: the defaults); a negative
 * CELLFIT_E* code for an invalid surface. */
long cellfit_fit_bytes(const cellfit_surface_t *nominal, const cellfit_params_t *prm);

/* Open a fit on nominal's space (degrees, knots, weights kept) with its net
 * as the nominal P0 (the surface is copied). mem: NULL, or at least
 * cellfit_fit_bytes() bytes aligned to 16 that the caller keeps until
 * cellfit_fit_close(). CELLFIT_EBUDGET when mem is too small. */
int cellfit_fit_open(cellfit_fit_t **fit, const cellfit_surface_t *nominal,
                     const cellfit_params_t *prm, void *mem, size_t mem_bytes);

/* cellfit_fit_open with the nominal read from an IGES file (entity 128,
 * the first one). On failure *fit is NULL; msg (may be NULL) gets the
 * detail naming file and line. */
int cellfit_fit_open_file(cellfit_fit_t **fit, const char *path, const cellfit_params_t *prm,
                          char *msg, size_t msglen);

/* n points as u v x y z (5 doubles each), parameters known. */
int cellfit_fit_add_uvxyz(cellfit_fit_t *fit, const double *uvxyz, size_t n);

/* n points as x y z (3 doubles each); parameters by projection onto the
 * nominal (closest point, Newton to 1e-9 of the domain). */
int cellfit_fit_add_xyz(cellfit_fit_t *fit, const double *xyz, size_t n);

/* Solve Eq. 7 for the net. After it, points can no longer be added. */
int cellfit_fit_solve(cellfit_fit_t *fit);

typedef struct cellfit_stats {
    long points;         /* points accumulated */
    long control_points; /* nu * nv */
    long bytes;          /* memory of the fit (cellfit_fit_bytes) */
    int solver;          /* enum cellfit_solver that ran */
    int iterations;      /* sweeps or CG steps (0 for Cholesky) */
    double rel_residual; /* of the linear system, max over x, y, z */
    double max_move;     /* largest control-point move from the nominal */
} cellfit_stats_t;

int cellfit_fit_stats(const cellfit_fit_t *fit, cellfit_stats_t *st);

/* The fitted surface (after solve); its arrays stay valid until close. */
int cellfit_fit_surface(const cellfit_fit_t *fit, cellfit_surface_t *out);

/* Write the fitted surface as IGES (entity 128), atomically. */
int cellfit_fit_write(const cellfit_fit_t *fit, const char *path);

/* The detail of the handle's last failure ("" when none). */
const char *cellfit_fit_message(const cellfit_fit_t *fit);

void cellfit_fit_close(cellfit_fit_t *fit);

/* Surface point S(u, v) (parameters clamped to the domain). */
int cellfit_surface_eval(const cellfit_surface_t *s, double u, double v, double xyz[3]);

/* The measured points of a cell's journal (cellfit scan, serve), in
 * order, each record's checksum verified; a torn tail ends the points. */
typedef struct cellfit_journal cellfit_journal_t;

typedef struct cellfit_point {
    double x, y, z; /* mm, the part's frame */
    double t;       /* seconds since the scan started */
    double utc;     /* wall-clock UTC, seconds since 1970 (0: the board had no clock) */
    long index;     /* record number in the journal */
    int valid;      /* 0: the probe had no reading there (x y z meaningless) */
} cellfit_point_t;

int cellfit_journal_open(cellfit_journal_t **j, const char *path, char *msg, size_t msglen);
/* 1 and *pt filled, 0 at the end, or a negative code. */
int cellfit_journal_next(cellfit_journal_t *j, cellfit_point_t *pt);
/* Records in the journal (valid or not). */
long cellfit_journal_count(const cellfit_journal_t *j);
void cellfit_journal_close(cellfit_journal_t *j);

#ifdef __cplusplus
}
#endif

#endif
