/* SPDX-License-Identifier: MIT */
/* sim_umock.h: the umockdev-based simulated USB devices (build/sim-umock):
 * an FTDI serial adapter with the laser probe behind it, and the USB
 * trigger/encoder box, each with its faults on demand. Shared by
 * sim_umock.c (testbed, child process), sim_umock_serial.c and
 * sim_umock_usb.c. Host test tool: GLib and libumockdev, no firmware. */
#ifndef SIM_UMOCK_H
#define SIM_UMOCK_H

#include <umockdev.h>

#define SIM_MAX_TABLE 64
#define SIM_MAX_FAULTS 16

typedef struct sim_serial_cfg {
    int enabled;
    double table[SIM_MAX_TABLE]; /* probe distances, mm, cycled; NAN: out of range */
    int ntable;
    int garble[SIM_MAX_FAULTS]; /* reply numbers (1-based) sent garbled */
    int ngarble;
    int errat[SIM_MAX_FAULTS], errcode[SIM_MAX_FAULTS]; /* reply n is ER,M0,code */
    int nerr;
    int unplug_after; /* unplug the adapter after this many replies (0: never) */
    /* No replug: umockdev 0.17 keeps a removed tty's pty in its table and
     * asserts when the same node is added again. */
} sim_serial_cfg_t;

typedef struct sim_usb_cfg {
    int enabled;
    int silent_after; /* bulk IN packets sent before bulk IN goes silent (0: never) */
    int unplug_after; /* packets sent before the box is unplugged (0: never) */
    int replug_ms;
    int badcrc[SIM_MAX_FAULTS]; /* packet numbers (1-based) sent with a bad CRC */
    int nbadcrc;
    int skip[SIM_MAX_FAULTS]; /* packet numbers never sent (a sequence gap) */
    int nskip;
} sim_usb_cfg_t;

extern int sim_verbose;
void sim_log(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Each device: add it to the testbed (0, or -1 with msg), then tick() from
 * the main loop every few ms (serial traffic, unplug and replug). */
int sim_serial_start(UMockdevTestbed *tb, const sim_serial_cfg_t *cfg, char *msg, size_t len);
void sim_serial_tick(void);
int sim_usb_start(UMockdevTestbed *tb, const sim_usb_cfg_t *cfg, char *msg, size_t len);
void sim_usb_tick(void);

/* Monotonic milliseconds. */
double sim_now_ms(void);

#endif
