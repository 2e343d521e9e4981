/* SPDX-License-Identifier: MIT */
/* test_prune.c: the pruning stage of the fitting loop (issue 14).
 * nf_prune_remove by exact reproduction: a knot Boehm inserted into a
 * random surface (polynomial and rational) comes out again with error 0
 * and the coarse net back; a knot the surface needs gives the error
 * nf_refine measures (the removed surface refined again differs from the
 * fine net by exactly that much). nf_prune_rank: the start's knots are
 * never offered, the removable knot comes first. The fit job: data from a
 * known coarse bicubic spline, the loop (--refine auto) from a plane
 * overshoots it; pruning gets back to the coarse count, still within the
 * tolerance, and the fit is the coarse spline (exact reproduction). */
#include "cf_err.h"
#include "cf_fitjob.h"
#include "cf_points.h"
#include "cf_surf.h"
#include "cf_test.h"
#include "nf_err.h"
#include "nf_prune.h"
#include "nf_refine.h"
#include "ref_dense.h"
#include "ref_job.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char msg[1024];

static double net_gap(const nf_surf_t *a, const nf_surf_t *b)
{
    double worst = 0.0;
    for (long i = 0; i < 3L * a->nu * a->nv; i++)
        worst = fmax(worst, fabs(a->cp[i] - b->cp[i]));
    for (long i = 0; a->w && b->w && i < (long)a->nu * a->nv; i++)
        worst = fmax(worst, fabs(a->w[i] - b->w[i]));
    return worst;
}

/* Insert x into s (dir), remove it again: the same net, error 0. */
static void check_roundtrip(const nf_surf_t *s, int dir, double x)
{
    nf_surf_t fine, back;
    assert_int_equal(cf_surf_alloc(&fine, s->p, s->q, s->nu + !dir, s->nv + dir), 0);
    assert_int_equal(cf_surf_alloc(&back, s->p, s->q, s->nu, s->nv), 0);
    assert_int_equal(dir ? nf_refine_insert_v(s, x, 1, &fine) : nf_refine_insert_u(s, x, 1, &fine),
                     NF_OK);
    const double *K = dir ? fine.V : fine.U;
    int idx = -1;
    for (int i = 0; i < (dir ? fine.nv + fine.q + 1 : fine.nu + fine.p + 1); i++)
        if (K[i] == x)
            idx = i;
    assert_true(idx > 0);
    double err = -1.0;
    assert_int_equal(nf_prune_remove(&fine, dir, idx, &back, &err), NF_OK);
    assert_true(err < 1e-12);
    assert_true(net_gap(&back, s) < 1e-12);
    for (int i = 0; i < s->nu + s->p + 1; i++)
        assert_near(back.U[i], s->U[i], 0.0);
    for (int i = 0; i < s->nv + s->q + 1; i++)
        assert_near(back.V[i], s->V[i], 0.0);
    cf_surf_free(&fine);
    cf_surf_free(&back);
}

static void test_remove_exact(void **state)
{
    (void)state;
    ref_seed(14);
    for (int rational = 0; rational < 2; rational++)
        for (int p = 1; p <= 4; p++) {
            nf_surf_t s;
            ref_surf_random(&s, p, 3, p + 5, 7, 0.0, 1.0, 0.0, 2.0, 1.0, rational ? 2.0 : 1.0);
            double *w = s.w;
            if (!rational) /* a polynomial net without weights */
                s.w = NULL;
            /* inside a span, in u and in v */
            check_roundtrip(&s, 0, 0.5 * (s.U[p + 1] + s.U[p + 2]));
            check_roundtrip(&s, 1, 0.5 * (s.V[3 + 1] + s.V[3 + 2]) + 0.01);
            s.w = w;
            ref_surf_free(&s);
        }
}

/* A knot the surface needs: the error is the gap between the fine net and
 * the removed surface refined again (A5.8's one mismatched equation). */
static void test_remove_needed(void **state)
{
    (void)state;
    ref_seed(7);
    nf_surf_t s, back, again;
    ref_surf_random(&s, 3, 2, 9, 6, 0.0, 1.0, 0.0, 1.0, 0.9, 1.1);
    for (int dir = 0; dir < 2; dir++) {
        const int n = dir ? s.nv : s.nu, p = dir ? s.q : s.p;
        const double *K = dir ? s.V : s.U;
        for (int r = p + 1; r < n; r++) {
            assert_int_equal(cf_surf_alloc(&back, s.p, s.q, s.nu - !dir, s.nv - dir), 0);
            assert_int_equal(cf_surf_alloc(&again, s.p, s.q, s.nu, s.nv), 0);
            double err;
            assert_int_equal(nf_prune_remove(&s, dir, r, &back, &err), NF_OK);
            assert_true(err > 1e-6); /* random nets need every knot */
            assert_int_equal(dir ? nf_refine_insert_v(&back, K[r], 1, &again)
                                 : nf_refine_insert_u(&back, K[r], 1, &again),
                             NF_OK);
            /* Homogeneous distance of the one equation left over, per row. */
            double worst = 0.0;
            for (long i = 0; i < (long)s.nu * s.nv; i++) {
                double d2 = 0.0, wa = s.w[i], wb = again.w[i];
                for (int c = 0; c < 3; c++)
                    d2 += pow(wa * s.cp[3 * i + c] - wb * again.cp[3 * i + c], 2);
                d2 += (wa - wb) * (wa - wb);
                worst = fmax(worst, sqrt(d2));
            }
            assert_near(err, worst, 1e-9 * (1.0 + worst));
            cf_surf_free(&back);
            cf_surf_free(&again);
        }
    }
    /* Refusals: a clamped end knot, a knot of multiplicity 2, wrong shape. */
    assert_int_equal(cf_surf_alloc(&back, s.p, s.q, s.nu - 1, s.nv), 0);
    double err;
    assert_int_equal(nf_prune_remove(&s, 0, s.p, &back, &err), NF_EARG);
    assert_int_equal(nf_prune_remove(&s, 1, s.q + 1, &back, &err), NF_EARG);
    cf_surf_free(&back);
    ref_surf_free(&s);
}

static void test_rank(void **state)
{
    (void)state;
    ref_seed(3);
    nf_surf_t s, fine, keep;
    ref_surf_random(&s, 3, 3, 7, 6, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0);
    assert_int_equal(cf_surf_alloc(&fine, 3, 3, 7, 7), 0);
    assert_int_equal(nf_refine_insert_v(&s, 0.61, 1, &fine), NF_OK);
    nf_prune_cand_t c[32];
    int n = -1;
    assert_int_equal(nf_prune_rank(&fine, NULL, c, 32, &n), NF_OK);
    assert_int_equal(n, (7 - 3 - 1) + (7 - 3 - 1)); /* every simple interior knot */
    assert_int_equal(c[0].dir, 1);
    assert_near(c[0].x, 0.61, 0.0);
    assert_true(c[0].err < 1e-12);
    for (int i = 1; i < n; i++)
        assert_true(c[i - 1].score <= c[i].score);
    /* With s as the start, only the knot inserted since is offered. */
    assert_int_equal(cf_surf_copy(&keep, &s), 0);
    assert_int_equal(nf_prune_rank(&fine, &keep, c, 32, &n), NF_OK);
    assert_int_equal(n, 1);
    assert_near(c[0].x, 0.61, 0.0);
    cf_surf_free(&keep);
    cf_surf_free(&fine);
    ref_surf_free(&s);
}

/* The coarse spline S* (bicubic, u knot 0.5, none in v: 5 x 4 = 20
 * control points) sampled at 48 x 48 parameters (u v x y z), and the job
 * from a 4 x 4 plane, auto, within 100 % of 1e-6, alpha = beta = 0: the
 * loop meets it at 7 x 7 (0.5 with its side knots 0.25 and 0.75 in u,
 * three knots in v). */
#define SU REF_JOB_SU
#define SV REF_JOB_SV
static nf_surf_t star, bez;
static char starfile[600], starxyz[600];

static int prune_setup(void)
{
    const char *d = getenv("CF_TEST_TMP");
    snprintf(starfile, sizeof starfile, "%s/cf_prune_%ld.uvxyz", d && *d ? d : "/tmp",
             (long)getpid());
    snprintf(starxyz, sizeof starxyz, "%s/cf_prune_%ld.xyz", d && *d ? d : "/tmp", (long)getpid());
    return ref_job_star(&star, &bez, starfile, starxyz);
}

static int run_prune(const char *file, int cols, double tol, long prune, cf_fitjob_result_t *r)
{
    cf_fitjob_opts_t o;
    cf_fitjob_defaults(&o);
    o.alpha = o.beta = 0.0;
    o.solver = NF_SOLVER_CHOL;
    o.tol = tol;
    o.loop = 1;
    o.refine = CF_REFINE_AUTO;
    o.prune = prune;
    cf_fitjob_t *j;
    int rc = cf_fitjob_open(&j, &bez, &o, msg, sizeof msg);
    if (rc)
        return rc;
    rc = ref_job_file(j, file, cols, r, msg, sizeof msg);
    cf_fitjob_close(j);
    return rc;
}

static void test_job_prunes_back(void **state)
{
    (void)state;
    assert_int_equal(prune_setup(), 0);
    /* Given parameters, then x y z (projected: the trials' first pass at
     * the kept feet, their check a projection). */
    for (int cols = 5; cols >= 3; cols -= 2) {
        const char *file = cols == 5 ? starfile : starxyz;
        const double tol = cols == 5 ? 1e-6 : 1e-4;
        /* Without pruning the loop meets the tolerance with more lines than S*. */
        cf_fitjob_result_t r0, r;
        if (run_prune(file, cols, tol, 0, &r0))
            fail_msg("%s", msg);
        assert_int_equal(r0.status, CF_FITJOB_MET);
        assert_int_equal(r0.pruned, 0);
        const long cp0 = (long)r0.surf.nu * r0.surf.nv;
        assert_true(cp0 > SU * SV);
        for (int i = 0; i < r0.nrounds; i++)
            assert_int_equal(r0.rounds[i].prune, 0);
        /* With it (budget enough for every line: the stage ends when none is
         * left to try, or a trial is undone): given parameters, back
         * to S*'s 5 x 4, and the fit is S*; projected (the loop takes other
         * knots there), fewer lines, still all within tol. */
        if (run_prune(file, cols, tol, 40, &r))
            fail_msg("%s", msg);
        assert_int_equal(r.status, CF_FITJOB_MET);
        assert_true(r.within_pct >= 100.0);
        assert_true(r.max_abs <= tol);
        assert_true(r.pruned > 0);
        if (cols == 5) {
            assert_int_equal(r.surf.nu, SU);
            assert_int_equal(r.surf.nv, SV);
            assert_true(r.max_abs < 1e-8);
            assert_true(ref_job_gap(&r.surf, &star) < 1e-8);
            for (int i = 0; i < SU + 3 + 1; i++)
                assert_near(r.surf.U[i], star.U[i], 0.0);
            for (int i = 0; i < SV + 3 + 1; i++)
                assert_near(r.surf.V[i], star.V[i], 0.0);
        }
        /* The rounds say it: the loop's as without, then one kept trial per
         * line pruned (each one line fewer than the last kept), the undone
         * ones with the net of the best fit less one line. */
        int kept = 0;
        long last = cp0;
        for (int i = 0; i < r.nrounds; i++) {
            if (i < r0.nrounds) {
                assert_int_equal(r.rounds[i].prune, 0);
                assert_int_equal(r.rounds[i].nu, r0.rounds[i].nu);
                continue;
            }
            assert_true(r.rounds[i].prune == 1 || r.rounds[i].prune == -1);
            long cp = (long)r.rounds[i].nu * r.rounds[i].nv;
            assert_true(cp < last);
            if (r.rounds[i].prune > 0) {
                kept++;
                last = cp;
                assert_true(r.rounds[i].within_pct >= 100.0);
            } else
                assert_true(r.rounds[i].within_pct < 100.0);
        }
        assert_int_equal(kept, r.pruned);
        assert_int_equal(last, (long)r.surf.nu * r.surf.nv);
        if (cols == 5)
            assert_int_equal(last, SU * SV);
        assert_non_null(strstr(r.why, "pruned"));
        cf_fitjob_result_free(&r0);
        cf_fitjob_result_free(&r);
    }
    remove(starfile);
    remove(starxyz);
    cf_surf_free(&star);
    cf_surf_free(&bez);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_remove_exact),
        cmocka_unit_test(test_remove_needed),
        cmocka_unit_test(test_rank),
        cmocka_unit_test(test_job_prunes_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
