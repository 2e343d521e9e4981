/* SPDX-License-Identifier: MIT */
/* cmd_info.c: `cellfit info SURF.igs`: what a surface is and what a fit of
 * its space costs on this board. */
#include "cf_cli.h"
#include "cf_iges.h"
#include "cf_json.h"
#include "cf_opt.h"
#include "cf_surf.h"
#include "cf_surfio.h"
#include "cf_surfrow.h"
#include "cmd.h"
#include "nf_budget.h"
#include <math.h>

static void bbox(const nf_surf_t *s, double lo[3], double hi[3], double *wlo, double *whi)
{
    long n = (long)s->nu * s->nv;
    for (int c = 0; c < 3; c++)
        lo[c] = hi[c] = s->cp[c];
    *wlo = *whi = s->w ? s->w[0] : 1.0;
    for (long i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) {
            lo[c] = fmin(lo[c], s->cp[3 * i + c]);
            hi[c] = fmax(hi[c], s->cp[3 * i + c]);
        }
        double w = s->w ? s->w[i] : 1.0;
        *wlo = fmin(*wlo, w);
        *whi = fmax(*whi, w);
    }
}

/* Box of the surface itself: the control-net box plus a dense sample of the
 * surface (at least 8 samples per knot span and direction, the end points
 * and every knot line included), inside the edges row by row of one v
 * (cf_surfrow: a net of 10^5 control points took 0.65 s with nf_surf_eval
 * per sample). */
static void surf_box(const nf_surf_t *s, double lo[3], double hi[3])
{
    cf_surfrow_t ev;
    const int rows = cf_surfrow_init(&ev, s) == 0;
    int nsu = 8 * (s->nu - s->p), nsv = 8 * (s->nv - s->q);
    nsu = nsu > 2000 ? 2000 : nsu;
    nsv = nsv > 2000 ? 2000 : nsv;
    double u0, u1, v0, v1;
    nf_surf_domain(s, &u0, &u1, &v0, &v1);
    for (int c = 0; c < 3; c++) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (int j = 0; j <= nsv; j++)
        for (int i = 0; i <= nsu; i++) {
            double P[3];
            const double u = u0 + (u1 - u0) * i / nsu, v = v0 + (v1 - v0) * j / nsv;
            /* The edges by the basis itself: at the domain's ends it is
             * exact (a corner is its control point; the power form gave x
             * 3.7e-15 for 0 on a test surface). */
            if (rows && i > 0 && i < nsu && j > 0 && j < nsv)
                cf_surfrow_eval(&ev, u, v, P);
            else
                nf_surf_eval(s, u, v, P);
            for (int c = 0; c < 3; c++) {
                lo[c] = P[c] < lo[c] ? P[c] : lo[c];
                hi[c] = P[c] > hi[c] ? P[c] : hi[c];
            }
        }
    if (rows)
        cf_surfrow_free(&ev);
}

static void print_knots(const char *name, const double *U, int len)
{
    printf("%s (%d):", name, len);
    for (int i = 0; i < len; i++)
        printf(" %.17g", U[i]);
    printf("\n");
}

int cmd_info(int argc, char **argv)
{
    const char *pos[1];
    long entity = 0;
    int json = 0;
    const cf_opt_t opts[] = {
        {.name = "entity",
         .kind = CF_OPT_LONG,
         .dst = &entity,
         .arg = "DE",
         .help = "the surface's directory entry in SURF (0: the first surface)",
         .lo = 0,
         .hi = 9999999},
        {.name = "json", .kind = CF_OPT_FLAG, .dst = &json, .help = "one JSON object on stdout"},
        {0}};
    const cf_cmd_t cmd = {.prog = "cellfit",
                          .name = "info",
                          .args = "SURF.igs",
                          .summary = "degrees, net, knots, weights, bounding boxes and the bytes a "
                                     "fit of SURF needs on this board",
                          .opts = opts,
                          .min_pos = 1,
                          .max_pos = 1};
    int rc = cf_opt_parse(&cmd, argc, argv, pos, NULL);
    if (rc)
        return cf_opt_exit(rc);
    const char *path = pos[0];
    char msg[512];
    nf_surf_t s;
    if (cf_surfio_read(path, (int)entity, &s, msg, sizeof msg))
        return cli_error("info", CLI_USAGE, "%s", msg);
    double lo[3], hi[3], wlo, whi, slo[3], shi[3];
    bbox(&s, lo, hi, &wlo, &whi);
    surf_box(&s, slo, shi);
    /* The net's box bounds the surface (convex hull, positive weights). */
    long b_gs = nf_fit_bytes(s.nu, s.nv, s.p, s.q, NF_SOLVER_GS);
    long b_pcg = nf_fit_bytes(s.nu, s.nv, s.p, s.q, NF_SOLVER_PCG);
    long b_chol = nf_fit_bytes(s.nu, s.nv, s.p, s.q, NF_SOLVER_CHOL);
    nf_solver_t pick = nf_solver_pick(s.nu, s.nv, s.p, s.q);
    if (json) {
        cf_json_t j;
        cf_json_begin(&j, stdout);
        cf_json_int(&j, "p", s.p);
        cf_json_int(&j, "q", s.q);
        cf_json_int(&j, "nu", s.nu);
        cf_json_int(&j, "nv", s.nv);
        cf_json_int(&j, "control_points", (long)s.nu * s.nv);
        cf_json_num(&j, "u0", s.U[s.p]);
        cf_json_num(&j, "u1", s.U[s.nu]);
        cf_json_num(&j, "v0", s.V[s.q]);
        cf_json_num(&j, "v1", s.V[s.nv]);
        cf_json_num(&j, "weight_min", wlo);
        cf_json_num(&j, "weight_max", whi);
        cf_json_int(&j, "rational", wlo != whi);
        cf_json_num(&j, "xmin", slo[0]);
        cf_json_num(&j, "ymin", slo[1]);
        cf_json_num(&j, "zmin", slo[2]);
        cf_json_num(&j, "xmax", shi[0]);
        cf_json_num(&j, "ymax", shi[1]);
        cf_json_num(&j, "zmax", shi[2]);
        cf_json_num(&j, "net_xmin", lo[0]);
        cf_json_num(&j, "net_ymin", lo[1]);
        cf_json_num(&j, "net_zmin", lo[2]);
        cf_json_num(&j, "net_xmax", hi[0]);
        cf_json_num(&j, "net_ymax", hi[1]);
        cf_json_num(&j, "net_zmax", hi[2]);
        cf_json_int(&j, "bytes_gs", b_gs);
        cf_json_int(&j, "bytes_pcg", b_pcg);
        cf_json_int(&j, "bytes_chol", b_chol);
        cf_json_str(&j, "auto_solver", nf_solver_name(pick));
        cf_json_int(&j, "bytes", nf_fit_bytes(s.nu, s.nv, s.p, s.q, NF_SOLVER_AUTO));
        cf_json_str(&j, "board", BOARD_NAME);
        cf_json_int(&j, "board_bytes", (long)NF_ARENA_BYTES);
        cf_json_end(&j);
    } else {
        printf("%s: NURBS surface, degree %d x %d, net %d x %d (%ld control points)\n", path, s.p,
               s.q, s.nu, s.nv, (long)s.nu * s.nv);
        printf("domain: u [%.17g, %.17g]  v [%.17g, %.17g]\n", s.U[s.p], s.U[s.nu], s.V[s.q],
               s.V[s.nv]);
        print_knots("u knots", s.U, s.nu + s.p + 1);
        print_knots("v knots", s.V, s.nv + s.q + 1);
        printf("weights: %.17g .. %.17g (%s)\n", wlo, whi, wlo == whi ? "polynomial" : "rational");
        printf("bounding box (surface, sampled): x [%.6g, %.6g]  y [%.6g, %.6g]  z [%.6g, %.6g]\n",
               slo[0], shi[0], slo[1], shi[1], slo[2], shi[2]);
        printf("bounding box (control net):      x [%.6g, %.6g]  y [%.6g, %.6g]  z [%.6g, %.6g]\n",
               lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
        printf("fit bytes: gs %ld  pcg %ld  chol %ld  (auto: %s); board %s allows %ld\n", b_gs,
               b_pcg, b_chol, nf_solver_name(pick), BOARD_NAME, (long)NF_ARENA_BYTES);
    }
    cf_surf_free(&s);
    return CLI_OK;
}
