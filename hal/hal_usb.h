/* SPDX-License-Identifier: MIT */
/* hal_usb.h: the usb: backend (libusb) beyond hal.h: the error mapping,
 * exposed for tests. */
#ifndef HAL_USB_H
#define HAL_USB_H

#include "hal.h"

/* A libusb_error as a rig_err_t: TIMEOUT -> RIG_ETIMEOUT, NO_DEVICE ->
 * RIG_EDISCONNECT, PIPE (stall) -> RIG_EEXCEPTION, and the rest. */
int hal_usb_err(int libusb_err);

#endif
