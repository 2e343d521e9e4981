/* SPDX-License-Identifier: MIT */
/* test_pair.c: cf_pair, the helper thread kept for the process's life:
 * each job runs once, on a thread other than the caller's, with its
 * results visible after the join; the same helper serves job after job,
 * also after gaps long enough for it (and the joiner) to sleep; a second
 * caller while the helper is in use gets a thread of its own, also a job
 * on the helper that splits again; a child of fork gets a helper of its
 * own; the helper takes no SIGINT or SIGTERM. */
#include "cf_pair.h"
#include "cf_test.h"
#include <signal.h>
#include <stdio.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

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

/* A job on the helper that splits again: its half gets a thread of its
 * own; and a child of fork runs jobs on a helper of its own. */
typedef struct nested {
    job_t inner;
    int pooled;
    int rc;
} nested_t;

static void *nested_main(void *p)
{
    nested_t *n = p;
    cf_pair_t h;
    n->rc = cf_pair_start(&h, job_main, &n->inner);
    if (n->rc == 0) {
        n->pooled = h.pooled;
        cf_pair_join(&h);
    }
    return NULL;
}

static void t_nested_and_fork(void **state)
{
    (void)state;
    nested_t n = {.inner = {.in = 4}, .pooled = -1};
    cf_pair_t h;
    assert_int_equal(cf_pair_start(&h, nested_main, &n), 0);
    cf_pair_join(&h);
    assert_int_equal(h.pooled, 1);
    assert_int_equal(n.rc, 0);
    assert_int_equal(n.pooled, 0);
    assert_int_equal(n.inner.runs, 1);
    assert_true(n.inner.out == 13);
    fflush(NULL);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) { /* the child: exit 0 when a job runs and joins */
        job_t j = {.in = 2};
        cf_pair_t c;
        int ok = cf_pair_start(&c, job_main, &j) == 0;
        if (ok)
            cf_pair_join(&c);
        _exit(ok && c.pooled == 1 && j.runs == 1 && j.out == 7 ? 0 : 1);
    }
    /* a child whose helper never came would wait for it for good: 10 s */
    int st = 0;
    pid_t w = 0;
    for (int k = 0; k < 1000 && (w = waitpid(pid, &st, WNOHANG)) == 0; k++)
        nap(10);
    if (w == 0) {
        kill(pid, SIGKILL);
        waitpid(pid, &st, 0);
        fail_msg("the child's job did not end in 10 s");
    }
    assert_int_equal(w, pid);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(t_many),
        cmocka_unit_test(t_sleepers),
        cmocka_unit_test(t_busy),
        cmocka_unit_test(t_nested_and_fork),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
