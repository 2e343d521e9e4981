/* SPDX-License-Identifier: MIT */
/* cf_simchild.h: cellsim as a child process of `cellfit serve --sim`: found
 * beside the running cellfit binary, started on a free TCP port of
 * 127.0.0.1 (plus the caller's extra arguments), its port read from its
 * start-up lines, watched for an early end (a crash is an error the PLC
 * sees), and stopped by its PID (TERM, then KILL) when serve ends. The
 * child also gets SIGTERM if serve itself dies (PR_SET_PDEATHSIG). */
#ifndef CF_SIMCHILD_H
#define CF_SIMCHILD_H

#include <stddef.h>
#include <sys/types.h>

typedef struct cf_simchild {
    pid_t pid;      /* 0: none */
    int port;       /* its Modbus TCP port on 127.0.0.1 */
    int out_fd;     /* read end of its stdout (kept open: it may still write) */
    int status;     /* wait status once it ended */
    int ended;      /* 1 once reaped */
    char stage[64]; /* "tcp:127.0.0.1:PORT:1" */
    char probe[64]; /* "tcp:127.0.0.1:PORT:2" */
    /* Started with --gev SERIAL (issue 19): its profiler's URI
     * "gev:127.0.0.1:SERIAL" and geometry line (cf_scanfast_geom_parse);
     * "" otherwise. */
    char gev_uri[64];
    char gev_geom[512];
} cf_simchild_t;

/* Start it and wait (up to timeout_ms) for "cellsim: ready". extra: a
 * whitespace-separated argument list (NULL: none). 0, or CF_EIO / CF_EARG
 * with msg saying why. */
int cf_simchild_start(cf_simchild_t *c, const char *extra, int timeout_ms, char *msg, size_t ml);

/* 1 when the child has ended since the last call (then msg says how),
 * else 0. Never blocks. */
int cf_simchild_ended(cf_simchild_t *c, char *msg, size_t ml);

/* Stop it by PID: SIGTERM, up to 2 s, then SIGKILL; reaped. */
void cf_simchild_stop(cf_simchild_t *c);

#endif
