/* SPDX-License-Identifier: MIT */
/* boards/mps2-an500/board_config.h: ARM MPS2 with the AN500 FPGA image
 * (Cortex-M7, double-precision FPU) as QEMU emulates it: the board the
 * Cortex-M7 port is tested on. Only #define lines (link.ld.in includes it). */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#define BOARD_NAME "mps2-an500"

/* The fitter budget is nucleo-h743zi's on purpose, so that the QEMU run of
 * the largest net proves the H743's numbers on the same core and ABI. */
#define NF_ARENA_BYTES (448L * 1024L)
#define NF_MAX_CP 1192L
#define NF_MAX_DEGREE 5
#define NF_DESIGN_DEGREE 3
#define BOARD_SOLVER NF_SOLVER_AUTO

/* Memory map of QEMU's mps2-an500 (`info mtree`): 4 MiB ZBT SSRAM1 at 0
 * holds the image, 4 MiB SSRAM2/3 at 0x20000000 the data. */
#define BOARD_FLASH_ORIGIN 0x00000000
#define BOARD_FLASH_BYTES (4096 * 1024)
#define BOARD_RAM_ORIGIN 0x20000000
#define BOARD_RAM_BYTES (4096 * 1024)
#define BOARD_STACK_BYTES (16 * 1024)
/* CMSDK peripherals: 32 external interrupts. */
#define BOARD_IRQ_COUNT 32

/* Journal and transports: none on the emulated board; results go out
 * through semihosting. */
#define BOARD_JOURNAL_ORIGIN 0
#define BOARD_JOURNAL_BYTES 0
#define BOARD_HAS_MODBUS_RTU 0
#define BOARD_UART_BAUD 0
#define BOARD_HAS_TCP 0

/* Output goes to the debugger console through semihosting (QEMU
 * -semihosting-config enable=on,target=native). */
#define BOARD_SEMIHOSTING 1

#endif
