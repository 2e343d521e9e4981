/* SPDX-License-Identifier: MIT */
/* boards/nucleo-h743zi/board_config.h: NUCLEO-H743ZI (STM32H743ZI, Cortex-M7
 * with double-precision FPU, 2 MiB flash, 1 MiB SRAM in several regions).
 * Only #define lines: the linker script is preprocessed against this file. */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#define BOARD_NAME "nucleo-h743zi"

/* Fitter budget (docs/memory.md). The arena takes 448 KiB of the 512 KiB AXI
 * SRAM, the largest RAM block and clocked from reset; the other 64 KiB stay
 * for later DMA buffers (Ethernet DMA cannot reach DTCM). */
#define NF_ARENA_BYTES (448L * 1024L)
/* Largest net the arena holds with PCG at bicubic, (448 KiB - 1 KiB slack) /
 * 384 bytes; main.c proves it is also the largest such number. */
#define NF_MAX_CP 1192L
#define NF_MAX_DEGREE 5
#define NF_DESIGN_DEGREE 3
/* Solver jobs use unless they ask (nf_solver_t): AUTO takes Cholesky when its
 * band fits the arena, PCG otherwise. */
#define BOARD_SOLVER NF_SOLVER_AUTO

/* Memory map (RM0433, 2.3.2). Shared by link.ld.in and the static asserts. */
#define BOARD_FLASH_ORIGIN 0x08000000
#define BOARD_FLASH_BYTES (2048 * 1024)
#define BOARD_ITCM_ORIGIN 0x00000000
#define BOARD_ITCM_BYTES (64 * 1024)
#define BOARD_DTCM_ORIGIN 0x20000000
#define BOARD_DTCM_BYTES (128 * 1024)
#define BOARD_AXISRAM_ORIGIN 0x24000000
#define BOARD_AXISRAM_BYTES (512 * 1024)
/* SRAM1-3 (128 + 128 + 32 KiB, contiguous) and SRAM4: clocks off at reset,
 * so nothing is placed there until a port enables them in RCC. */
#define BOARD_SRAM123_ORIGIN 0x30000000
#define BOARD_SRAM123_BYTES (288 * 1024)
#define BOARD_SRAM4_ORIGIN 0x38000000
#define BOARD_SRAM4_BYTES (64 * 1024)
/* Main stack at the top of DTCM; the self-test measures what it used. */
#define BOARD_STACK_BYTES (16 * 1024)
/* External interrupts after the 16 system exceptions (WWDG .. WAKEUP_PIN). */
#define BOARD_IRQ_COUNT 150

/* Journal of fitted results (later issue): the last 128 KiB flash sector of
 * bank 2, erased as a whole; the linker script keeps code out of it. */
#define BOARD_JOURNAL_ORIGIN 0x081E0000
#define BOARD_JOURNAL_BYTES (128 * 1024)

/* Transports (later issues): Modbus RTU on USART3, the ST-LINK virtual COM
 * port; no TCP until an IP stack is chosen, although the board has Ethernet. */
#define BOARD_HAS_MODBUS_RTU 1
#define BOARD_UART_BAUD 115200
#define BOARD_HAS_TCP 0

#endif
