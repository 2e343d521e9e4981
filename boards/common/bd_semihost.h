/* SPDX-License-Identifier: MIT */
/* bd_semihost.h: ARM semihosting, the debugger's (or QEMU's) console and
 * exit. Only for boards run under a debugger or emulator: without one, the
 * BKPT instruction faults. */
#ifndef BD_SEMIHOST_H
#define BD_SEMIHOST_H

/* Write a NUL-terminated string to the host console (SYS_WRITE0). */
void bd_semihost_write0(const char *s);

/* End the session (SYS_EXIT): ok != 0 reports ADP_Stopped_ApplicationExit,
 * which QEMU turns into exit status 0; anything else exits with status 1. */
_Noreturn void bd_semihost_exit(int ok);

#endif
