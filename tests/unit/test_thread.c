/* SPDX-License-Identifier: MIT */
/* test_thread.c: cf_thread_start: the new thread runs fn(arg) with
 * SIGINT and SIGTERM blocked (its own pthread_sigmask says so), and the
 * caller's mask is the one it had, whatever that was. */
#include "cf_test.h"
#include "cf_thread.h"
#include <signal.h>

typedef struct seen {
    int arg_ok;
    int sigint, sigterm; /* blocked in the thread */
} seen_t;

static void *probe_main(void *p)
{
    seen_t *s = p;
    sigset_t cur;
    sigemptyset(&cur);
    pthread_sigmask(SIG_BLOCK, NULL, &cur); /* a query: the mask is unchanged */
    s->arg_ok = 1;
    s->sigint = sigismember(&cur, SIGINT);
    s->sigterm = sigismember(&cur, SIGTERM);
    return s;
}

/* The caller's mask, signal by signal, against want. */
static void assert_mask(const sigset_t *want)
{
    sigset_t cur;
    sigemptyset(&cur);
    assert_int_equal(pthread_sigmask(SIG_BLOCK, NULL, &cur), 0);
    for (int sig = 1; sig < 65; sig++)
        if (sig != SIGKILL && sig != SIGSTOP)
            assert_int_equal(sigismember(&cur, sig), sigismember(want, sig));
}

static void t_blocked_and_restored(void **state)
{
    (void)state;
    /* Two caller masks: none blocked, and SIGUSR1 alone (not all or none). */
    for (int pass = 0; pass < 2; pass++) {
        sigset_t mine, saved;
        sigemptyset(&mine);
        if (pass)
            sigaddset(&mine, SIGUSR1);
        assert_int_equal(pthread_sigmask(SIG_SETMASK, &mine, &saved), 0);
        seen_t s = {0, 0, 0};
        pthread_t th;
        assert_int_equal(cf_thread_start(&th, probe_main, &s), 0);
        assert_mask(&mine);
        void *ret = NULL;
        assert_int_equal(pthread_join(th, &ret), 0);
        assert_ptr_equal(ret, &s);
        assert_int_equal(s.arg_ok, 1);
        assert_int_equal(s.sigint, 1);
        assert_int_equal(s.sigterm, 1);
        assert_mask(&mine);
        pthread_sigmask(SIG_SETMASK, &saved, NULL);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(t_blocked_and_restored),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
