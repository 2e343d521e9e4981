# SPDX-License-Identifier: MIT
# boards/sim/board.mk: native build with the small test budget.
BOARD_CC      ?= $(CC)
BOARD_CFLAGS  := -O2
BOARD_HOSTED  := 1
