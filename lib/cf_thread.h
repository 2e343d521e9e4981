/* SPDX-License-Identifier: MIT */
/* cf_thread.h: a thread started with every signal blocked, so that
 * SIGINT/SIGTERM reach the main thread (its select or poll loop sees EINTR
 * and stops the process cleanly) and never a worker; the caller's own mask
 * is as it was on return. */
#ifndef CF_THREAD_H
#define CF_THREAD_H

#include <pthread.h>

/* pthread_create(th, NULL, fn, arg) with all signals blocked in the new
 * thread (it inherits the mask in force at its creation). 0, or
 * pthread_create's error number (strerror names it). */
int cf_thread_start(pthread_t *th, void *(*fn)(void *), void *arg);

#endif
