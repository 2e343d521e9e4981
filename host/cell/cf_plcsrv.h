/* SPDX-License-Identifier: MIT */
/* cf_plcsrv.h: the cell's Modbus TCP server. Several clients at once (a
 * PLC and HMIs) are served by one thread with select() over non-blocking
 * sockets; each client's bytes are framed by the MBAP header here (no call
 * ever waits for a slow or broken client: a malformed header closes that
 * connection, a frame left half-sent for FRAME_MS too), so the heartbeat
 * and the watchdog never stall. Reads and writes go through the register
 * map and the state machine (plc_map.h, plc_fsm.h) under one mutex. A job
 * runs in a worker thread behind a job runner (the table below) and keeps
 * running while clients come and go. Function codes: 03 read, 06 write
 * single, 16 write multiple holding registers; anything else is exception
 * 01 (the PDUs themselves: firmware/plc_mbap.h). Hardening: at most
 * max_clients connections, a new one evicting the longest idle when all
 * are taken (dead connections never lock the PLC out); an idle timeout;
 * TCP keepalive on every connection; an optional allow-list of client
 * addresses; a request rate limit per client (a token bucket: requests
 * beyond it are answered exception 06, server busy); a log line repeated
 * by one client is logged once, then as a count every CF_PLCSRV_LOG_REPEAT_MS. */
#ifndef CF_PLCSRV_H
#define CF_PLCSRV_H

#include "cf_job.h"
#include "plc_fsm.h"
#include <signal.h>
#include <stdint.h>

#define CF_PLC_ABORTED (-1)           /* a phase's return: it stopped on request */
#define CF_PLC_MAX_ALLOW 16           /* allow-list entries */
#define CF_PLCSRV_IDLE_MS 60000u      /* default idle timeout */
#define CF_PLCSRV_LOG_REPEAT_MS 5000u /* a repeated log line: its count this often */
/* TCP keepalive on every accepted socket: a peer gone without a FIN (cable
 * pulled, PLC powered off) is found within IDLE + CNT x INTVL seconds even
 * when the idle timeout is long. */
#define CF_PLCSRV_KA_IDLE_S 10
#define CF_PLCSRV_KA_INTVL_S 5
#define CF_PLCSRV_KA_CNT 3

/* What runs the jobs. Phases run in the worker thread and return 0, a 3xx
 * PLC code (plc_err.h), or CF_PLC_ABORTED; ctl gives progress and the stop
 * request. check runs in the server thread before a command is accepted (0
 * or a 1xx code). abort runs in the server thread when a job must stop (an
 * abort command, the watchdog, shutdown): stop motion now. */
typedef struct cf_runner {
    int (*check)(void *ctx, int cmd, const plc_params_t *p);
    int (*home)(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl);
    int (*scan)(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl);
    int (*fit)(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl, plc_results_t *res);
    int (*export_result)(void *ctx, const plc_params_t *p, const cf_job_ctl_t *ctl);
    void (*abort)(void *ctx);
    /* server thread, every tick: 0, or a 2xx code once when the rig is
     * gone for good (the simulator's process ended); may be NULL */
    int (*health)(void *ctx);
    void *ctx;
    int rig; /* 1: a stage and probe are configured (home and scan possible) */
} cf_runner_t;

/* Map version 3's figures from the rest of the cell (cf_plcstats.h): the
 * plant outbox (OUTBOX_PG .. OUTBOX_DROPPED) and the last scan's
 * on-the-fly counts (SCAN_TRIGGERS .. SCAN_OVERRUNS, in address order). */
#define CF_PLC_SCAN_COUNTS 7
typedef struct cf_plc_stats {
    int have_outbox; /* 0: the OUTBOX_* registers are left as they are */
    uint32_t outbox_pg, outbox_mqtt, outbox_age_s, outbox_dropped;
    uint32_t scan[CF_PLC_SCAN_COUNTS];
} cf_plc_stats_t;
#define CF_PLCSRV_STATS_MS 1000u /* how often the server asks for them */

typedef struct cf_plcsrv_opts {
    const char *addr; /* IPv4 address to listen on */
    int port;         /* 0: the kernel picks one */
    int max_clients;  /* connections beyond are closed at once */
    int word_order;   /* PLC_ORDER_* at start */
    unsigned watchdog_ms;
    const char *port_file;  /* the port actually bound is written here */
    float tol, alpha, beta; /* parameter defaults in the registers */
    /* fit setting defaults in the registers (FIT_TOL .. FIT_REPARAM);
     * fit_within 0: the state machine's (100 %) */
    float fit_tol, fit_within;
    uint32_t fit_max_cp;
    uint16_t fit_refine, fit_robust, fit_reparam;
    /* clients allowed: address & mask == net for one of the nallow entries
     * (host byte order); nallow 0: any */
    int nallow;
    uint32_t allow_net[CF_PLC_MAX_ALLOW], allow_mask[CF_PLC_MAX_ALLOW];
    double max_rate; /* requests a second per client (burst the same), 0: no limit */
    /* A connection without a complete request for this long is closed (a
     * PLC's heartbeat writes keep its own open); 0: CF_PLCSRV_IDLE_MS. */
    unsigned idle_ms;
    /* Appended: port_file claimed by the caller (cf_portfile.h: locked,
     * "PORT\nPID\n"), written through it and released by the caller; NULL:
     * port_file written plainly and removed at a clean exit. */
    struct cf_portfile *portfile;
    /* Appended (map version 3): asked from the server thread every
     * CF_PLCSRV_STATS_MS, without the register lock; quick: no I/O at all
     * (cf_plcstats reads results.db on a thread of its own), since every
     * Modbus answer waits for it. NULL: those registers stay 0. */
    void (*stats)(void *ctx, cf_plc_stats_t *out);
    void *stats_ctx;
} cf_plcsrv_opts_t;

/* Serve until *stop becomes non-zero (SIGTERM). Returns 0 after a clean
 * shutdown (a running job aborted), -1 when the server could not start
 * (logged). */
int cf_plcsrv_run(const cf_plcsrv_opts_t *o, const cf_runner_t *r, volatile sig_atomic_t *stop);

#endif
