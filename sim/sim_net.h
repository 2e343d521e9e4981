/* SPDX-License-Identifier: MIT */
/* sim_net.h: cellsim's servers: Modbus TCP on 127.0.0.1 (several clients,
 * one select() loop), Modbus RTU and ASCII on tty paths (socat pty ends),
 * replies held back for slow-reply faults, lines closed and reopened for
 * disconnect faults and when the pty goes away. */
#ifndef SIM_NET_H
#define SIM_NET_H

#include "sim.h"

#define SIM_MAX_PORTS 8
#define SIM_MAX_CONNS 16

typedef struct sim_conn {
    int fd; /* -1: free */
    int port;
    uint8_t in[1024];
    size_t nin;
    double t_last; /* last byte received (RTU frame gap) */
    uint8_t out[600];
    size_t nout;
    double t_send;      /* when the held reply goes out */
    uint8_t sout[8192]; /* the probe's streamed lines not yet taken by the line */
    size_t nsout;
} sim_conn_t;

typedef struct sim_port {
    int wire;       /* SIM_W_TCP, SIM_W_RTU or SIM_W_ASCII */
    char path[256]; /* tty path */
    int tcp_port;   /* asked (0: any), then bound */
    int fd;         /* listener (tcp) or the tty; -1 while down */
    double down_until;
} sim_port_t;

typedef struct sim_net {
    sim_port_t port[SIM_MAX_PORTS];
    int nports;
    sim_conn_t conn[SIM_MAX_CONNS];
    sim_rig_t *rig;
    sim_faults_t *faults;
    double gap_ms; /* RTU inter-frame silence */
    int verbose;
} sim_net_t;

/* Open every port (tcp listeners bound, ttys opened); -1 and msg on failure. */
int sim_net_start(sim_net_t *n, char *msg, size_t len);
/* One round of the loop: wait at most max_ms, serve what is ready. */
void sim_net_poll(sim_net_t *n, double max_ms);
void sim_net_stop(sim_net_t *n);

#endif
