/* SPDX-License-Identifier: MIT */
/* boards/sim/board_config.h: the board the tests run on. Deliberately small
 * so that budget refusals are reachable with small jobs. */
#ifndef BOARD_CONFIG_H
#define BOARD_CONFIG_H

#define BOARD_NAME "sim"
/* The journal's CRC from a 256-entry table (firmware/jnl_crc.c). */
#define BOARD_JNL_CRC_TABLE256 1
/* ... eight bytes a step from 8 KiB of slicing-by-8 tables (firmware/jnl_crc8.h). */
#define BOARD_JNL_CRC_SLICE8 1
/* jnl_scan reads 512 records (40 KiB, on the stack) a call (firmware/jnl.c). */
#define BOARD_JNL_SCAN_RECS 512

#define NF_MAX_CP 40000L
#define NF_MAX_DEGREE 5
#define NF_ARENA_BYTES (64L * 1024L * 1024L)
#define NF_DESIGN_DEGREE 3

/* Solver jobs use unless they ask (nf_solver_t). */
#define BOARD_SOLVER NF_SOLVER_AUTO
/* Journal of measured points: a file on the host, no flash address. */
#define BOARD_JOURNAL_ORIGIN 0
#define BOARD_JOURNAL_BYTES (1L * 1024L * 1024L)
/* Transports: Modbus RTU on a serial port, and TCP. */
#define BOARD_HAS_MODBUS_RTU 1
#define BOARD_UART_BAUD 115200
#define BOARD_HAS_TCP 1

#endif
