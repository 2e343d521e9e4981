/* SPDX-License-Identifier: MIT */
/* cf_thread.c: threads that take no signals (cf_thread.h). */
#include "cf_thread.h"
#include <signal.h>

int cf_thread_start(pthread_t *th, void *(*fn)(void *), void *arg)
{
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    int rc = pthread_create(th, NULL, fn, arg);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    return rc;
}
