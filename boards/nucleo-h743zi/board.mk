# SPDX-License-Identifier: MIT
# boards/nucleo-h743zi/board.mk: STM32H743ZI, Cortex-M7 with the double-
# precision FPv5 unit; cross-built with arm-none-eabi-gcc and newlib-nano.
# mk/cross.mk links build/nucleo-h743zi/firmware.elf from these.
BOARD_CROSS   := 1
BOARD_HOSTED  := 0
CROSS_COMPILE ?= arm-none-eabi-
# The cross compiler is the board's, not a user choice: override beats a
# CC=... handed down from the command line or a parent make.
override CC   := $(CROSS_COMPILE)gcc
BOARD_CC      := $(CC)
BOARD_ARCH    := -mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard
# -fno-math-errno: sqrt becomes one vsqrt.f64; nothing reads errno.
BOARD_CFLAGS  := -O2 -ffunction-sections -fdata-sections -fno-math-errno
# The ABI flags must survive OPT=... on the command line.
override CFLAGS += $(BOARD_ARCH)
BOARD_SRC     := boards/common/bd_cortexm.c boards/common/bd_selftest.c \
                 boards/common/bd_text.c boards/nucleo-h743zi/main.c
BOARD_LDFLAGS := --specs=nano.specs -nostartfiles -Wl,--gc-sections
BOARD_QEMU_MACHINE :=
# Build tree build/<board> unless the command line names one.
ifeq ($(origin BUILD),file)
BUILD := build/nucleo-h743zi
endif
