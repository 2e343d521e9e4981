# boards/linux-cell/board.mk: native build for the cell controller.
BOARD_CC      ?= $(CC)
BOARD_CFLAGS  := -O2 -march=x86-64-v3 -ffp-contract=fast
BOARD_HOSTED  := 1
