/* SPDX-License-Identifier: MIT */
/* test_pair.c: cf_pair, the helper thread kept for the process's life:
 * each job runs once, on a thread other than the caller's, with its
 * results visible after the join; the same helper serves job after job,
 * also after gaps long enough for it (and the joiner) to sleep; a second
 * caller while the helper is in use gets a thread of its own; the helper
 * takes no SIGINT or SIGTERM. */
#include "cf_pair.h"
#include "cf_test.h"
#include <signal.h>
#include <time.h>

typedef struct job {
    pthread_t self;
    long in, out;
    int runs;
    int sigint, sigterm;
    long sleep_ms;
} job_t;

static void nap(long ms)
{
    struct timespec t = {ms / 1000, (ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

static void *job_main(void *p)
{
    job_t *j = p;
    j->self = pthread_self();
    sigset_t cur;
    sigemptyset(&cur);
    pthread_sigmask(SIG_BLOCK, NULL, &cur);
    j->sigint = sigismember(&cur, SIGINT);
    j->sigterm = sigismember(&cur, SIGTERM);
    if (j->sleep_ms)
        nap(j->sleep_ms);
    j->out = 3 * j->in + 1;
    j->runs++;
    return NULL;
}

static void t_many(void **state)
{
    (void)state;
    pthread_t helper;
    for (long k = 0; k < 3000; k++) {
        job_t j = {.in = k};
        cf_pair_t h;
        assert_int_equal(cf_pair_start(&h, job_main, &j), 0);
        cf_pair_join(&h);
        assert_int_equal(h.pooled, 1);
        assert_int_equal(j.runs, 1);
        assert_true(j.out == 3 * k + 1);
        assert_false(pthread_equal(j.self, pthread_self()));
        if (k == 0)
            helper = j.self;
        assert_true(pthread_equal(j.self, helper)); /* one helper, kept */
        assert_int_equal(j.sigint, 1);
        assert_int_equal(j.sigterm, 1);
    }
}

/* Gaps and jobs longer than the helper's polling: both sides sleep and wake. */
static void t_sleepers(void **state)
{
    (void)state;
    for (int k = 0; k < 4; k++) {
        nap(20); /* the helper has gone to sleep */
        job_t j = {.in = k, .sleep_ms = k % 2 ? 20 : 0};
        cf_pair_t h;
        assert_int_equal(cf_pair_start(&h, job_main, &j), 0);
        cf_pair_join(&h); /* for k odd, the joiner sleeps too */
        assert_int_equal(h.pooled, 1);
        assert_int_equal(j.runs, 1);
        assert_true(j.out == 3 * k + 1);
    }
}

/* While the helper runs a job, a second start (here from the same caller,
 * as a half that splits again would) gets a thread of its own. */
static void t_busy(void **state)
{
    (void)state;
    job_t a = {.in = 5, .sleep_ms = 30}, b = {.in = 7};
    cf_pair_t ha, hb;
    assert_int_equal(cf_pair_start(&ha, job_main, &a), 0);
    assert_int_equal(cf_pair_start(&hb, job_main, &b), 0);
    assert_int_equal(ha.pooled, 1);
    assert_int_equal(hb.pooled, 0);
    cf_pair_join(&hb);
    cf_pair_join(&ha);
    assert_int_equal(a.runs, 1);
    assert_int_equal(b.runs, 1);
    assert_true(a.out == 16 && b.out == 22);
    assert_false(pthread_equal(a.self, b.self));
    assert_int_equal(b.sigint, 1); /* its own thread: no signals either */
    /* and the helper is free again */
    job_t c = {.in = 1};
    cf_pair_t hc;
    assert_int_equal(cf_pair_start(&hc, job_main, &c), 0);
    cf_pair_join(&hc);
    assert_int_equal(hc.pooled, 1);
    assert_true(pthread_equal(c.self, a.self));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(t_many),
        cmocka_unit_test(t_sleepers),
        cmocka_unit_test(t_busy),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
