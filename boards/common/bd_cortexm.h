/* SPDX-License-Identifier: MIT */
/* bd_cortexm.h: what the Cortex-M startup code (bd_cortexm.c) offers the
 * board's main: stack measurement, halting, and the fault hook. */
#ifndef BD_CORTEXM_H
#define BD_CORTEXM_H

/* Called by the reset handler once .data and .bss are set up. */
int main(void);

/* Bytes of the main stack reserved by the linker script, and the most used
 * so far (the reset handler paints the stack; this finds the high tide). */
unsigned long bd_stack_size(void);
unsigned long bd_stack_used(void);

/* Sleep forever: what a board does when it has nothing left to do. */
_Noreturn void bd_halt(void);

/* Any exception without a handler of its own lands here with its number
 * (IPSR: 2 NMI, 3 HardFault, ..., 16 + n IRQ n). Weak: a board overrides it
 * to report the fault; the default halts. */
void bd_fault(unsigned exception);

#endif
