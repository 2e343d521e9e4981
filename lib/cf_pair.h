/* SPDX-License-Identifier: MIT */
/* cf_pair.h: a helper thread kept for the process's life, for work split
 * in two halves many times a second (the fit loop's passes: about 15 a fit
 * of 4,000 points, each a few hundred microseconds). A thread created and
 * joined per pass costs its clone, its stack's page faults and, at its
 * exit, the release of that stack on both cores. The helper takes every
 * signal blocked (cf_thread.h). A caller that finds the helper in use
 * (another job's half, or a half that splits again) gets a thread of its
 * own, as before. A child of fork starts a helper of its own. */
#ifndef CF_PAIR_H
#define CF_PAIR_H

#include <pthread.h>

typedef struct cf_pair {
    int pooled; /* 1: fn runs on the helper; 0: on th */
    pthread_t th;
} cf_pair_t;

/* Start fn(arg) on the helper, or on a thread of its own when the helper
 * is in use or cannot be started. 0 when fn runs; else pthread_create's
 * error number (fn not run: the caller runs it itself). */
int cf_pair_start(cf_pair_t *h, void *(*fn)(void *), void *arg);

/* Wait for fn to return: once after each successful cf_pair_start, on
 * the thread that started it (the helper stays taken until then). */
void cf_pair_join(cf_pair_t *h);

#endif
