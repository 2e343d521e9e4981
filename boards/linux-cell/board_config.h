/* SPDX-License-Identifier: MIT */
/* boards/linux-cell/board_config.h: the cell controller (x86-64 Linux PC).
 * Budgets for firmware/nf_config.h; see docs/memory.md for the byte formula. */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#define BOARD_NAME "linux-cell"
/* The journal's CRC from a 256-entry table (firmware/jnl_crc.c). */
#define BOARD_JNL_CRC_TABLE256 1
/* ... eight bytes a step from 8 KiB of slicing-by-8 tables (firmware/jnl_crc8.h). */
#define BOARD_JNL_CRC_SLICE8 1
/* jnl_scan reads 512 records (40 KiB, on the stack) a call (firmware/jnl.c). */
#define BOARD_JNL_SCAN_RECS 512

/* Largest control net a job may ask for, in control points (Nu*Nv). */
#define NF_MAX_CP 1100000L
/* Largest degree in either direction. */
#define NF_MAX_DEGREE 7
/* Fitter arena: the host allocates exactly what a job needs, up to this. */
#define NF_ARENA_BYTES (1536L * 1024L * 1024L)
/* Degree the board is dimensioned for at NF_MAX_CP (bicubic parts). */
#define NF_DESIGN_DEGREE 3

/* Solver jobs use unless they ask (nf_solver_t). */
#define BOARD_SOLVER NF_SOLVER_AUTO
/* Journal of measured points: a file on the host, no flash address. */
#define BOARD_JOURNAL_ORIGIN 0
#define BOARD_JOURNAL_BYTES (64L * 1024L * 1024L)
/* Transports: Modbus RTU on a serial port, and TCP. */
#define BOARD_HAS_MODBUS_RTU 1
#define BOARD_UART_BAUD 115200
#define BOARD_HAS_TCP 1

#endif
