/* SPDX-License-Identifier: MIT */
/* bd_semihost.c: semihosting calls (ARM IHI 0070 / "Semihosting for AArch32
 * and AArch64"): operation in r0, argument in r1, BKPT 0xAB on M profile. */
#include "bd_semihost.h"

#define SYS_WRITE0 0x04
#define SYS_EXIT 0x18
#define ADP_STOPPED_APPLICATION_EXIT 0x20026
#define ADP_STOPPED_RUN_TIME_ERROR 0x20023

static int semihost_call(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    /* "memory": the host reads the buffer r1 points to. */
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void bd_semihost_write0(const char *s)
{
    semihost_call(SYS_WRITE0, s);
}

_Noreturn void bd_semihost_exit(int ok)
{
    /* On AArch32 the reason code itself is the argument, not a block. */
    unsigned long reason = ok ? ADP_STOPPED_APPLICATION_EXIT : ADP_STOPPED_RUN_TIME_ERROR;
    semihost_call(SYS_EXIT, (const void *)reason);
    for (;;) /* a debugger that ignores SYS_EXIT: stay here */
        __asm__ volatile("wfi");
}
