/* SPDX-License-Identifier: MIT */
/* cf_pair.c: the helper thread (cf_pair.h). */
#include "cf_pair.h"
#include "cf_thread.h"
#include <stdatomic.h>
#include <time.h>

/* owner: held from cf_pair_start to cf_pair_join by the helper's one user.
 * state 0: no helper (yet, or it could not start), 1 idle, 2 a job
 * posted, 3 the job done; mu and the conditions for the sleeps. */
static pthread_mutex_t owner = PTHREAD_MUTEX_INITIALIZER;
static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t go = PTHREAD_COND_INITIALIZER, fin = PTHREAD_COND_INITIALIZER;
static atomic_int state;
static int tried;
static void *(*job_fn)(void *);
static void *job_arg;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Wait for state s: polling for up to CF_PAIR_SPIN_S first, then asleep.
 * A core that sleeps on a virtual machine takes from tens of microseconds
 * to milliseconds to wake (measured on the CI machine: 0.4 to 13.6 ms over
 * the 15 passes of one fit of 3,833 points, against 11 ms for the whole
 * fit), while the loop's next pass usually comes within a millisecond. */
#define CF_PAIR_SPIN_S 0.003
static void wait_for(int s, pthread_cond_t *cv)
{
    const double t0 = now_s();
    for (unsigned k = 1; atomic_load_explicit(&state, memory_order_acquire) != s; k++) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
        if (k % 64 == 0 && now_s() - t0 > CF_PAIR_SPIN_S) {
            pthread_mutex_lock(&mu);
            while (atomic_load_explicit(&state, memory_order_acquire) != s)
                pthread_cond_wait(cv, &mu);
            pthread_mutex_unlock(&mu);
            return;
        }
    }
}

/* state s, and a wake-up for whoever sleeps on cv (the check of state
 * under mu before each sleep makes it never lost). */
static void set_state(int s, pthread_cond_t *cv)
{
    atomic_store_explicit(&state, s, memory_order_release);
    pthread_mutex_lock(&mu);
    pthread_cond_signal(cv);
    pthread_mutex_unlock(&mu);
}

/* A child of fork has no helper (only the forking thread goes on there):
 * it starts its own at its first use. */
static void child_reset(void)
{
    pthread_mutex_init(&owner, NULL);
    pthread_mutex_init(&mu, NULL);
    pthread_cond_init(&go, NULL);
    pthread_cond_init(&fin, NULL);
    atomic_store(&state, 0);
    tried = 0;
}

static void *helper_main(void *unused)
{
    (void)unused;
    for (;;) {
        wait_for(2, &go);
        (void)job_fn(job_arg);
        set_state(3, &fin);
    }
    return NULL;
}

int cf_pair_start(cf_pair_t *h, void *(*fn)(void *), void *arg)
{
    h->pooled = 0;
    if (pthread_mutex_trylock(&owner) == 0) {
        if (!tried) { /* the first user starts it; owner keeps that to one */
            tried = 1;
            pthread_t th;
            if (pthread_atfork(NULL, NULL, child_reset) == 0 &&
                cf_thread_start(&th, helper_main, NULL) == 0) {
                pthread_detach(th);
                atomic_store(&state, 1);
            }
        }
        if (atomic_load(&state) == 1) {
            job_fn = fn;
            job_arg = arg;
            set_state(2, &go);
            h->pooled = 1;
            return 0;
        }
        pthread_mutex_unlock(&owner);
    }
    return cf_thread_start(&h->th, fn, arg);
}

void cf_pair_join(cf_pair_t *h)
{
    if (!h->pooled) {
        pthread_join(h->th, NULL);
        return;
    }
    wait_for(3, &fin);
    atomic_store(&state, 1);
    pthread_mutex_unlock(&owner);
}
