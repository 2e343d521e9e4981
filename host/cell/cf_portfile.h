/* SPDX-License-Identifier: MIT */
/* cf_portfile.h: serve's port file (--port-file), which must never
 * mislead: two lines, the port bound and serve's PID; the live serve holds
 * a write lock (fcntl) on it for its whole life, so a file nobody locks is
 * stale (its serve was killed, SIGKILL or a power cut) and is replaced at
 * the next start with a log line, while a second serve naming a locked one
 * is refused before it starts anything. The lock, not the PID, decides: a
 * PID may be reused. The file is emptied when claimed, so a script waiting
 * for it to be non-empty reads the new port, never the old one. */
#ifndef CF_PORTFILE_H
#define CF_PORTFILE_H

#include <stddef.h>

typedef struct cf_portfile {
    int fd; /* -1: none claimed */
    char path[4096];
} cf_portfile_t;

/* Claim path (created when missing): 0; CF_EIO when it cannot be opened or
 * locked, or is held by a running serve (msg names its PID and port). A
 * stale one is logged and emptied. */
int cf_portfile_claim(cf_portfile_t *pf, const char *path, char *msg, size_t ml);

/* Write "PORT\nPID\n" (this process's PID): 0 or CF_EIO (errno set). */
int cf_portfile_write(cf_portfile_t *pf, int port);

/* Remove the file (when remove_it) and drop the lock. */
void cf_portfile_release(cf_portfile_t *pf, int remove_it);

#endif
