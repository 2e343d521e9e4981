/* SPDX-License-Identifier: MIT */
/* hal_serial.h: the serial: backend (libserialport) beyond hal.h: listing
 * the ports the system has, with their USB ids, and the error mapping
 * (exposed for tests). */
#ifndef HAL_SERIAL_H
#define HAL_SERIAL_H

#include "hal.h"
#include <stddef.h>
#include <stdint.h>

typedef struct hal_serial_port {
    char name[128];        /* /dev/ttyUSB0 */
    char description[128]; /* product string or the name */
    char serial[64];       /* USB serial number, "" if none */
    int usb;               /* 1: a USB adapter, vid and pid valid */
    uint16_t vid, pid;
} hal_serial_port_t;

/* Fill up to max ports, *count the number found (which may exceed max).
 * RIG_EUNSUPPORTED when libserialport cannot enumerate here. */
int hal_serial_list(hal_serial_port_t *out, size_t max, size_t *count, char *msg, size_t msglen);

/* An sp_return (and the errno it left) as a rig_err_t; opening says the
 * failure happened while opening (RIG_EOPEN rather than a lost line). */
int hal_serial_err(int sp_ret, int err_no, int opening);

#endif
