/* SPDX-License-Identifier: MIT */
/* hal.h: one small transport interface for the cell's devices, with one
 * backend per wire (libmodbus's backend table is the model):
 *   rtu:PATH:BAUD:8N1:SLAVE      Modbus RTU on a serial device (libmodbus)
 *   tcp:HOST:PORT[:UNIT]         Modbus TCP (libmodbus)
 *   serial:PATH:BAUD[:8N1]       byte stream on a serial port (libserialport)
 *   tty:PATH:BAUD[:8N1]          byte stream on a tty or pty (termios), for
 *                                pseudo-terminals libserialport cannot open
 *   usb:VID:PID[:SERIAL]         bulk and control transfers (libusb)
 *   gev:ADDRESS[:SERIAL]         a GigE Vision profiler (Aravis): parsed here,
 *                                opened by hal_gev_open (hal_gev.h)
 * A backend fills the operations its wire has and leaves the rest NULL
 * (hal_* then returns RIG_EUNSUPPORTED). Every call has a timeout; failures
 * come back as rig_err_t codes (rig_err.h), with the detail (errno text,
 * Modbus exception, what was expected) in hal_last_error(). Timeouts,
 * bounded retries with backoff and reconnection after a cable pull are the
 * backends' job, tuned by hal_opts_t. Host code only; firmware/ sees the
 * devices through rig.h. */
#ifndef HAL_H
#define HAL_H

#include "rig.h"
#include <stddef.h>
#include <stdint.h>

typedef enum hal_kind {
    HAL_RTU = 1,
    HAL_TCP = 2,
    HAL_SERIAL = 3,
    HAL_TTY = 4,
    HAL_USB = 5,
    HAL_GEV = 6 /* a GigE Vision profiler: hal_gev.h, not a hal_t transport */
} hal_kind_t;

/* A parsed device URI (hal_uri_parse). */
typedef struct hal_uri {
    hal_kind_t kind;
    char path[256]; /* device path (rtu, serial, tty) or host name (tcp) */
    int baud;       /* rtu, serial, tty */
    int data_bits;  /* 7 or 8 */
    char parity;    /* 'N', 'E' or 'O' */
    int stop_bits;  /* 1 or 2 */
    int port;       /* tcp */
    int unit;       /* Modbus slave / unit id (rtu, tcp) */
    uint16_t vid, pid;
    char serial[64]; /* usb, gev: optional serial number, "" for any */
} hal_uri_t;

/* Parse a URI of the forms above. RIG_EARG with the reason in msg. */
int hal_uri_parse(const char *s, hal_uri_t *u, char *msg, size_t msglen);

typedef struct hal_opts {
    int timeout_ms;   /* one request or read (default 500) */
    int retries;      /* extra attempts after a timeout or bad frame (default 3) */
    int backoff_ms;   /* first wait before a retry, doubled each time (default 20) */
    int reconnect_ms; /* how long to keep reopening a lost line (default 3000) */
    /* Appended fields: 0 (or absent from an older initializer) takes the default. */
    int byte_timeout_ms; /* silence allowed between bytes of one frame (default 50) */
    int late_ms; /* a device's worst-case reply delay: after a timeout the backend waits this
                  * long and drops what came late, so a late reply is never taken as the answer
                  * to the next request (default timeout_ms) */
} hal_opts_t;

#define HAL_OPTS_DEFAULT                                                                           \
    {                                                                                              \
        500, 3, 20, 3000, 50, 0                                                                    \
    }

typedef struct hal hal_t; /* an open transport; backends define it */

/* What a backend does. Byte streams: write all, read up to n (returns the
 * count in *got; a timeout with nothing read is RIG_ETIMEOUT). Register
 * devices: Modbus holding (kind 'h') and input ('i') registers, 0-based.
 * USB: control and bulk transfers. */
typedef struct hal_ops {
    int version; /* RIG_OPS_VERSION */
    const char *name;
    void (*close)(hal_t *h);
    int (*write)(hal_t *h, const void *buf, size_t n);
    int (*read)(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got);
    int (*flush)(hal_t *h); /* drop anything stale in the input */
    int (*read_regs)(hal_t *h, char kind, int addr, int n, uint16_t *dst);
    int (*write_regs)(hal_t *h, int addr, int n, const uint16_t *src);
    int (*control)(hal_t *h, uint8_t req_type, uint8_t req, uint16_t val, uint16_t idx, void *data,
                   uint16_t len, size_t *got);
    int (*bulk)(hal_t *h, uint8_t ep, void *data, size_t len, size_t *got);
    int (*reconnect)(hal_t *h);
} hal_ops_t;

/* The part every backend's struct starts with. */
struct hal {
    const hal_ops_t *ops;
    hal_uri_t uri;
    hal_opts_t opts;
    char err[256];         /* detail of the last failure */
    unsigned long retries; /* retries made since open (statistics) */
    unsigned long reconnects;
    /* Appended (issue 15, ABORT bounded): asked between attempts and in
     * every wait of a retry, late-reply or reconnect loop (hal_set_stop);
     * non-zero makes the call give up with RIG_EABORTED instead of waiting
     * out the retries. While it is set a request is tried once, so a STOP
     * still reaches a live device; once a request failed with it set, the
     * device is taken as hung and later requests fail at once (stop_dead)
     * until the stop is withdrawn. NULL: never. */
    int (*should_stop)(void *ctx);
    void *stop_ctx;
    int stop_dead;
};

/* Open the device a URI names (opts NULL: defaults). RIG_EOPEN,
 * RIG_EUNSUPPORTED (backend not built), RIG_EARG; msg says why. */
int hal_open(const char *uri, const hal_opts_t *opts, hal_t **h, char *msg, size_t msglen);
void hal_close(hal_t *h);
const char *hal_last_error(const hal_t *h);

int hal_write(hal_t *h, const void *buf, size_t n);
int hal_read(hal_t *h, void *buf, size_t n, int timeout_ms, size_t *got);
int hal_flush(hal_t *h);
int hal_read_regs(hal_t *h, char kind, int addr, int n, uint16_t *dst);
int hal_write_regs(hal_t *h, int addr, int n, const uint16_t *src);
int hal_control(hal_t *h, uint8_t req_type, uint8_t req, uint16_t val, uint16_t idx, void *data,
                uint16_t len, size_t *got);
int hal_bulk(hal_t *h, uint8_t ep, void *data, size_t len, size_t *got);
/* Close and reopen the line now (a backend also does it by itself when a
 * request finds the line gone); RIG_EDISCONNECT if it stays away for
 * reconnect_ms. */
int hal_reconnect(hal_t *h);

/* The stop check above (fn NULL: none). hal_stopped: 1 while it asks to
 * stop (and clears stop_dead when it no longer does). */
void hal_set_stop(hal_t *h, int (*fn)(void *ctx), void *ctx);
int hal_stopped(hal_t *h);

/* Backend constructors (one file each). hal_open dispatches on the URI. */
int hal_modbus_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len);
int hal_tty_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len);
int hal_serial_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len);
int hal_usb_open(const hal_uri_t *u, const hal_opts_t *o, hal_t **h, char *msg, size_t len);

/* The rig_err_t a libmodbus errno stands for (hal_modbus.c): ETIMEDOUT
 * RIG_ETIMEOUT, EMBBADCRC RIG_ECRC, EMBX* RIG_EEXCEPTION, malformed replies
 * RIG_EPROTO, a lost line (EIO, ECONNRESET, EBADF, ...) RIG_EDISCONNECT. */
int hal_modbus_errcode(int err);

#endif
