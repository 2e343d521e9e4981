# SPDX-License-Identifier: MIT
# boards/linux-cell/board.mk: native build for the cell controller.
BOARD_CC      ?= $(CC)
# Baseline x86-64 (any cell controller's CPU); the hot kernels get an
# AVX2/FMA copy chosen at run time (mk/arch.mk, firmware/nf_isa.h).
BOARD_CFLAGS  := -O2 -ffp-contract=fast
BOARD_HOSTED  := 1
