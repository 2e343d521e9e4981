/* SPDX-License-Identifier: MIT */
/* cellfit_api.c: libcellfit's public API (include/cellfit.h) over the fit
 * job's pass of Eq. 7 (cf_fitpass: the firmware fitter in stripe storage,
 * in a block it is given), the projection start grid (cf_seedgrid) and the
 * IGES and journal readers. One block holds the handle, both surfaces and
 * the fitter's arena, so a caller's memory is enough; cellfit_fit_bytes()
 * is that block's size. */
#include "cellfit.h"
#include "cf_err.h"
#include "cf_fitpass.h"
#include "cf_iges.h"
#include "cf_seedgrid.h"
#include "cf_store_file.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_version.h"
#include "jnl.h"
#include "nf_err.h"
#include "rig_err.h"
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define API_PROJ_TOL 1e-9 /* parameter accuracy, relative to the domain (as cellfit fit) */
#define API_ALIGN 16
#define API_ROWS 64 /* x y z points projected before they are added */

struct cellfit_fit {
    nf_surf_t nominal, fitted; /* arrays inside the block */
    double alpha, beta;
    nf_solver_t solver;
    cf_fitpass_t fp;  /* the fitter, its arena the end of the block */
    cf_seedgrid_t pj; /* x y z points: allocated on first use */
    int have_pj, solved, own;
    void *block; /* the block the handle lies in (the caller's or ours) */
    long bytes;
    char msg[512];
};

struct cellfit_journal {
    cf_store_file_t sf;
    rig_store_t st;
    jnl_reader_t rd;
    jnl_header_t h;
    jnl_info_t info;
    long index;
};

static const char *const api_msgs[] = {
    "success",
    "invalid argument (a bug in the caller)",
    "cannot open, read or write a file",
    "malformed or unsupported file or surface",
    "the net needs more memory than allowed or given",
    "out of memory",
    "parameter outside the surface's domain, or a non-finite value",
    "the points do not determine the net (add alpha, beta or points there)",
    "call out of order",
    "the solver did not converge",
};

const char *cellfit_strerror(int code)
{
    if (code > 0 || code < -(int)(sizeof api_msgs / sizeof api_msgs[0] - 1))
        return "unknown cellfit error code";
    return api_msgs[-code];
}

const char *cellfit_version(void)
{
    return cf_version_string() + sizeof "cellfit"; /* "0.13.0 (rev)" */
}

void cellfit_version_numbers(int *major, int *minor, int *patch)
{
    if (major)
        *major = CELLFIT_VERSION_MAJOR;
    if (minor)
        *minor = CELLFIT_VERSION_MINOR;
    if (patch)
        *patch = CELLFIT_VERSION_PATCH;
}

void cellfit_params_default(cellfit_params_t *prm)
{
    if (prm) {
        prm->alpha = 0.1;
        prm->beta = 0.001;
        prm->solver = CELLFIT_SOLVER_AUTO;
    }
}

/* Firmware and host codes as the API's. */
static int api_code(int rc)
{
    switch (rc) {
    case 0: return CELLFIT_OK;
    case NF_EARG:
    case CF_EARG:
    case RIG_EARG: return CELLFIT_EARG;
    case NF_EBUDGET:
    case NF_EARENA:
    case NF_ESIZE: return CELLFIT_EBUDGET;
    case NF_EDEGREE:
    case NF_EKNOTS:
    case NF_EWEIGHT:
    case CF_EPARSE:
    case CF_EUNSUPPORTED:
    case CF_ENOTFOUND:
    case RIG_ECORRUPT: return CELLFIT_EFORMAT;
    case NF_EDOMAIN:
    case NF_ENONFINITE: return CELLFIT_EDOMAIN;
    case NF_ENODATA:
    case NF_ESINGULAR: return CELLFIT_EDATA;
    case NF_ENOCONV: return CELLFIT_ESOLVE;
    case NF_ESTATE:
    case RIG_ESTATE: return CELLFIT_ESTATE;
    case CF_ENOMEM: return CELLFIT_ENOMEM;
    default: return CELLFIT_EIO;
    }
}

static int api_fail(cellfit_fit_t *f, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int api_fail(cellfit_fit_t *f, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(f->msg, sizeof f->msg, fmt, ap);
    va_end(ap);
    return code;
}

static size_t up(size_t n)
{
    return (n + API_ALIGN - 1) / API_ALIGN * API_ALIGN;
}

#define HANDLE_ALIGN _Alignof(cellfit_fit_t)

/* The handle and the padding that aligns it in a block aligned to 16. */
static size_t handle_bytes(void)
{
    return up(sizeof(cellfit_fit_t) + (HANDLE_ALIGN > API_ALIGN ? HANDLE_ALIGN - API_ALIGN : 0));
}

static nf_solver_t api_solver(const cellfit_params_t *prm)
{
    static const nf_solver_t map[] = {NF_SOLVER_AUTO, NF_SOLVER_GS, NF_SOLVER_CHOL, NF_SOLVER_PCG};
    return prm && prm->solver >= 0 && prm->solver <= 3 ? map[prm->solver] : NF_SOLVER_AUTO;
}

/* The public surface as the firmware's (arrays shared, const dropped only
 * for the checks, which do not write). */
static nf_surf_t as_nf(const cellfit_surface_t *s)
{
    nf_surf_t t = {s->p,           s->q,           s->nu,           s->nv,
                   (double *)s->U, (double *)s->V, (double *)s->cp, (double *)s->w};
    return t;
}

static long surf_bytes(const cellfit_surface_t *s)
{
    return (long)up(sizeof(double) * (size_t)NF_SURF_DOUBLES(s->nu, s->nv, s->p, s->q));
}

long cellfit_fit_bytes(const cellfit_surface_t *nominal, const cellfit_params_t *prm)
{
    if (!nominal || !nominal->U || !nominal->V || !nominal->cp)
        return CELLFIT_EARG;
    nf_surf_t s = as_nf(nominal);
    int rc = nf_surf_check(&s);
    if (rc)
        return api_code(rc);
    long fb = cf_fitpass_bytes(&s, api_solver(prm), 1);
    if (fb < 0)
        return CELLFIT_EBUDGET;
    return (long)handle_bytes() + 2 * surf_bytes(nominal) + fb;
}

static void copy_surf(nf_surf_t *dst, const cellfit_surface_t *src, double *mem)
{
    nf_surf_wire(dst, src->p, src->q, src->nu, src->nv, mem);
    long n = (long)src->nu * src->nv;
    memcpy(dst->U, src->U, sizeof(double) * (size_t)(src->nu + src->p + 1));
    memcpy(dst->V, src->V, sizeof(double) * (size_t)(src->nv + src->q + 1));
    memcpy(dst->cp, src->cp, sizeof(double) * 3 * (size_t)n);
    if (src->w)
        memcpy(dst->w, src->w, sizeof(double) * (size_t)n);
    else
        dst->w = NULL;
}

int cellfit_fit_open(cellfit_fit_t **fit, const cellfit_surface_t *nominal,
                     const cellfit_params_t *prm, void *mem, size_t mem_bytes)
{
    if (!fit)
        return CELLFIT_EARG;
    *fit = NULL;
    long need = cellfit_fit_bytes(nominal, prm);
    if (need < 0)
        return (int)need;
    if (need > NF_ARENA_BYTES + (long)handle_bytes() + 2 * surf_bytes(nominal))
        return CELLFIT_EBUDGET; /* the board's budget, as for every job */
    int own = !mem;
    if (own) {
        mem = aligned_alloc(API_ALIGN, (size_t)need);
        if (!mem)
            return CELLFIT_ENOMEM;
    } else if (mem_bytes < (size_t)need || ((size_t)mem % API_ALIGN)) {
        return mem_bytes < (size_t)need ? CELLFIT_EBUDGET : CELLFIT_EARG;
    }
    /* The handle at its own alignment (the accumulator's vectors may want
     * 32) inside the first handle_bytes() of a block aligned to 16. */
    uintptr_t at = ((uintptr_t)mem + HANDLE_ALIGN - 1) & ~(uintptr_t)(HANDLE_ALIGN - 1);
    cellfit_fit_t *f = (cellfit_fit_t *)at;
    memset(f, 0, sizeof *f);
    f->block = mem;
    char *p = (char *)mem + handle_bytes();
    long sb = surf_bytes(nominal);
    copy_surf(&f->nominal, nominal, (double *)(void *)p);
    copy_surf(&f->fitted, nominal, (double *)(void *)(p + sb));
    f->own = own;
    f->bytes = need;
    cellfit_params_t d;
    cellfit_params_default(&d);
    if (!prm)
        prm = &d;
    f->alpha = prm->alpha;
    f->beta = prm->beta;
    f->solver = api_solver(prm);
    if (!(f->alpha >= 0) || !(f->beta >= 0) || !isfinite(f->alpha + f->beta)) {
        cellfit_fit_close(f);
        return CELLFIT_EARG;
    }
    size_t off = handle_bytes() + 2 * (size_t)sb;
    int rc = cf_fitpass_begin(&f->fp, (char *)mem + off, (size_t)need - off, &f->nominal, f->alpha,
                              f->beta, f->solver, 1, "points", f->msg, sizeof f->msg);
    if (rc) {
        cellfit_fit_close(f);
        return api_code(rc);
    }
    *fit = f;
    return CELLFIT_OK;
}

int cellfit_fit_open_file(cellfit_fit_t **fit, const char *path, const cellfit_params_t *prm,
                          char *msg, size_t msglen)
{
    if (!fit || !path)
        return CELLFIT_EARG;
    *fit = NULL;
    nf_surf_t s;
    char m[512];
    int rc = cf_surfio_read(path, 0, &s, m, sizeof m);
    if (rc) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s", m);
        return api_code(rc);
    }
    cellfit_surface_t cs = {s.p, s.q, s.nu, s.nv, s.U, s.V, s.cp, s.w};
    rc = cellfit_fit_open(fit, &cs, prm, NULL, 0);
    if (rc && msg && msglen)
        snprintf(msg, msglen, "%s: %s", path, cellfit_strerror(rc));
    cf_surf_free(&s);
    return rc;
}

/* n rows u v x y z into the pass; i0 numbers the first in messages. */
static int add_rows(cellfit_fit_t *f, const double *rows, size_t n, size_t i0)
{
    long b = 0;
    int rc = cf_fitpass_rows(&f->fp, rows, (long)n, 5, &b);
    if (rc) {
        const double *r = rows + 5 * b;
        return api_fail(f, api_code(rc), "point %zu (u %.17g, v %.17g): %s", i0 + (size_t)b, r[0],
                        r[1], nf_strerror(rc));
    }
    return CELLFIT_OK;
}

int cellfit_fit_add_uvxyz(cellfit_fit_t *f, const double *uvxyz, size_t n)
{
    if (!f || (!uvxyz && n))
        return CELLFIT_EARG;
    if (f->solved)
        return api_fail(f, CELLFIT_ESTATE, "points added after cellfit_fit_solve");
    return n ? add_rows(f, uvxyz, n, 0) : CELLFIT_OK;
}

int cellfit_fit_add_xyz(cellfit_fit_t *f, const double *xyz, size_t n)
{
    if (!f || (!xyz && n))
        return CELLFIT_EARG;
    if (f->solved)
        return api_fail(f, CELLFIT_ESTATE, "points added after cellfit_fit_solve");
    if (!f->have_pj) {
        if (cf_seedgrid_init(&f->pj, &f->nominal, 8))
            return api_fail(f, CELLFIT_ENOMEM, "no memory for the projection start grid");
        f->have_pj = 1;
    }
    double rows[5 * API_ROWS]; /* projected rows go in API_ROWS at a time */
    size_t m = 0, i0 = 0;
    for (size_t i = 0; i < n; i++) {
        const double *q = xyz + 3 * i;
        if (!isfinite(q[0] + q[1] + q[2]))
            return api_fail(f, CELLFIT_EDOMAIN, "point %zu: not finite", i);
        nf_proj_t pr;
        int rc = cf_seedgrid_project(&f->pj, q, API_PROJ_TOL, &pr);
        if (rc && rc != NF_ENOCONV) /* the best point is kept on ENOCONV, as cellfit fit */
            return api_fail(f, api_code(rc), "point %zu: projection: %s", i, nf_strerror(rc));
        double *r = rows + 5 * m++;
        r[0] = pr.u, r[1] = pr.v, r[2] = q[0], r[3] = q[1], r[4] = q[2];
        if (m == API_ROWS || i + 1 == n) {
            if ((rc = add_rows(f, rows, m, i0)))
                return rc;
            i0 = i + 1;
            m = 0;
        }
    }
    return CELLFIT_OK;
}

int cellfit_fit_solve(cellfit_fit_t *f)
{
    if (!f)
        return CELLFIT_EARG;
    if (f->solved)
        return api_fail(f, CELLFIT_ESTATE, "already solved");
    nf_solve_opts_t so = NF_SOLVE_OPTS_DEFAULT;
    int rc = cf_fitpass_solve(&f->fp, &so, &f->fitted, "points", f->msg, sizeof f->msg);
    if (rc)
        return api_code(rc);
    f->solved = 1;
    f->msg[0] = '\0';
    return CELLFIT_OK;
}

int cellfit_fit_stats(const cellfit_fit_t *f, cellfit_stats_t *st)
{
    if (!f || !st)
        return CELLFIT_EARG;
    memset(st, 0, sizeof *st);
    st->points = cf_fitpass_points(&f->fp);
    st->control_points = (long)f->nominal.nu * f->nominal.nv;
    st->bytes = f->bytes;
    if (!f->solved)
        return CELLFIT_ESTATE;
    const nf_solve_stats_t *ss = &f->fp.st;
    st->solver = ss->solver == NF_SOLVER_GS     ? CELLFIT_SOLVER_GS
                 : ss->solver == NF_SOLVER_CHOL ? CELLFIT_SOLVER_CHOL
                                                : CELLFIT_SOLVER_PCG;
    st->iterations = ss->iterations;
    st->rel_residual = ss->rel_residual;
    for (long i = 0; i < st->control_points; i++) {
        const double *a = f->fitted.cp + 3 * i, *b = f->nominal.cp + 3 * i;
        double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                        (a[2] - b[2]) * (a[2] - b[2]));
        if (d > st->max_move)
            st->max_move = d;
    }
    return CELLFIT_OK;
}

int cellfit_fit_surface(const cellfit_fit_t *f, cellfit_surface_t *out)
{
    if (!f || !out)
        return CELLFIT_EARG;
    if (!f->solved)
        return CELLFIT_ESTATE;
    const nf_surf_t *s = &f->fitted;
    cellfit_surface_t r = {s->p, s->q, s->nu, s->nv, s->U, s->V, s->cp, s->w};
    *out = r;
    return CELLFIT_OK;
}

int cellfit_fit_write(const cellfit_fit_t *f, const char *path)
{
    if (!f || !path)
        return CELLFIT_EARG;
    cellfit_fit_t *m = (cellfit_fit_t *)f; /* the message buffer only */
    if (!f->solved)
        return api_fail(m, CELLFIT_ESTATE, "nothing to write before cellfit_fit_solve");
    int rc = cf_surfio_write(path, &f->fitted, "cellfit fit", cf_version_string(), m->msg,
                             sizeof m->msg);
    return api_code(rc);
}

const char *cellfit_fit_message(const cellfit_fit_t *f)
{
    return f ? f->msg : "no fit";
}

void cellfit_fit_close(cellfit_fit_t *f)
{
    if (!f)
        return;
    if (f->have_pj)
        cf_seedgrid_free(&f->pj);
    if (f->own)
        free(f->block);
}

int cellfit_surface_eval(const cellfit_surface_t *s, double u, double v, double xyz[3])
{
    if (!s || !xyz)
        return CELLFIT_EARG;
    nf_surf_t t = as_nf(s);
    int rc = nf_surf_check(&t);
    if (rc)
        return api_code(rc);
    nf_surf_eval(&t, u, v, xyz);
    return CELLFIT_OK;
}

int cellfit_journal_open(cellfit_journal_t **out, const char *path, char *msg, size_t msglen)
{
    char m[512];
    if (!out || !path)
        return CELLFIT_EARG;
    *out = NULL;
    cellfit_journal_t *j = calloc(1, sizeof *j);
    if (!j)
        return CELLFIT_ENOMEM;
    int rc = cf_store_file_open(&j->sf, path, CF_STORE_READ, &j->st, m, sizeof m);
    if (rc) {
        free(j);
        if (msg && msglen)
            snprintf(msg, msglen, "%s", m);
        return CELLFIT_EIO;
    }
    rc = jnl_reader_open(&j->rd, j->st, &j->h, &j->info);
    if (rc) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s: not a readable journal: %s", path, rig_strerror(rc));
        cf_store_file_close(&j->sf);
        free(j);
        return rc == RIG_EIO ? CELLFIT_EIO : CELLFIT_EFORMAT;
    }
    *out = j;
    return CELLFIT_OK;
}

int cellfit_journal_next(cellfit_journal_t *j, cellfit_point_t *pt)
{
    if (!j || !pt)
        return CELLFIT_EARG;
    jnl_rec_t r;
    for (;;) {
        int rc = jnl_reader_next(&j->rd, &r);
        if (rc <= 0)
            return rc == 0 ? 0 : api_code(rc);
        long idx = j->index++;
        if (r.type != JNL_T_POINT)
            continue;
        pt->x = r.xyz[0];
        pt->y = r.xyz[1];
        pt->z = r.xyz[2];
        pt->t = r.t - j->h.t_start;
        pt->utc = j->h.utc_start > 0 ? j->h.utc_start + pt->t : 0.0;
        pt->index = idx;
        pt->valid = r.code == 0 && isfinite(r.xyz[0] + r.xyz[1] + r.xyz[2]);
        return 1;
    }
}

long cellfit_journal_count(const cellfit_journal_t *j)
{
    return j ? (long)j->info.records : CELLFIT_EARG;
}

void cellfit_journal_close(cellfit_journal_t *j)
{
    if (!j)
        return;
    cf_store_file_close(&j->sf);
    free(j);
}
