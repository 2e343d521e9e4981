# SPDX-License-Identifier: MIT
# boards/mps2-an500/board.mk: ARM MPS2 AN500 (Cortex-M7, FPv5 double
# precision) as QEMU emulates it; cross-built like nucleo-h743zi, plus
# semihosting output, and run by `make boards-test`.
BOARD_CROSS   := 1
BOARD_HOSTED  := 0
CROSS_COMPILE ?= arm-none-eabi-
override CC   := $(CROSS_COMPILE)gcc
BOARD_CC      := $(CC)
BOARD_ARCH    := -mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard
BOARD_CFLAGS  := -O2 -ffunction-sections -fdata-sections -fno-math-errno
override CFLAGS += $(BOARD_ARCH)
BOARD_SRC     := boards/common/bd_cortexm.c boards/common/bd_selftest.c \
                 boards/common/bd_text.c boards/common/bd_semihost.c \
                 boards/mps2-an500/main.c
BOARD_LDFLAGS := --specs=nano.specs -nostartfiles -Wl,--gc-sections
# QEMU machine that runs build/mps2-an500/firmware.elf (mk/cross.mk).
BOARD_QEMU_MACHINE := mps2-an500
ifeq ($(origin BUILD),file)
BUILD := build/mps2-an500
endif
