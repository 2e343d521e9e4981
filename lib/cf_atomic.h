/* SPDX-License-Identifier: MIT */
/* cf_atomic.h: a file written whole or not at all: the data goes to a
 * temporary sibling ("PATH.tmp.PID"), which is flushed, synced and renamed
 * over PATH only when everything was written; on any failure the temporary
 * is removed and PATH is what it was. A reader never sees half a file. */
#ifndef CF_ATOMIC_H
#define CF_ATOMIC_H

#include <stddef.h>
#include <stdio.h>

typedef struct cf_atomic {
    FILE *f; /* write here (read back too: opened "w+") */
    const char *path;
    char tmp[4096];
} cf_atomic_t;

/* Create the temporary. CF_OK, or CF_EIO with msg naming the file. */
int cf_atomic_open(cf_atomic_t *a, const char *path, char *msg, size_t ml);

/* Flush, fsync (when sync), close and rename over the path. CF_OK, or
 * CF_EIO with msg (the temporary removed). */
int cf_atomic_commit(cf_atomic_t *a, int sync, char *msg, size_t ml);

/* Give up: close and remove the temporary. */
void cf_atomic_abort(cf_atomic_t *a);

/* The time (Unix seconds) a written file states in its header: the
 * environment's SOURCE_DATE_EPOCH when set (the reproducible-builds
 * convention), else now. One rule for the IGES and STEP writers. */
long long cf_atomic_stamp(void);

#endif
