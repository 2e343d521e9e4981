# SPDX-License-Identifier: MIT
# mk/arch.mk: any cell controller (issue 16).
#   native x86-64 builds   firmware/ gets NF_ISA_DISPATCH=1 and the hot
#                          modules' v3 copies (firmware/nf_*_v3.c) are built
#                          with -mavx2 -mfma: baseline x86-64 everywhere else,
#                          AVX2/FMA chosen at run time (firmware/nf_isa.h)
#   make TARGET=aarch64-linux-gnu
#                          build/aarch64-linux-gnu/cellfit and cellsim with
#                          Debian's cross compiler and the :arm64 libraries
#   make test-westmere     (in make test) ARCH_X86_TESTS of build/t-sim and one
#                          fit of build/cellfit under qemu-x86_64 -cpu Westmere
#                          (no AVX): the baseline path, on a CPU that lacks v3
#   make test-aarch64      (in make test) the cross build, ARCH_A64_TESTS of its
#                          unit tests and one fit under qemu-aarch64
# Packages: scripts/deps.sh arch (part of test).
ARCH_MACHINE := $(shell $(CC) -dumpmachine 2>/dev/null)
ARCH_X86 := $(if $(filter 1,$(BOARD_CROSS)),,$(filter x86_64-%,$(ARCH_MACHINE)))

ifneq ($(ARCH_X86),)
# override: these flags make the two copies and must survive CFLAGS=... .
$(BUILD)/firmware/%.o: override CFLAGS += -DNF_ISA_DISPATCH=1
$(BUILD)/firmware/%_v3.o: override CFLAGS += -mavx2 -mfma
endif

# A cross build for another CPU's Linux (TARGET, top Makefile): its
# libraries' pkg-config (make 4.3 does not hand exported variables to
# $(shell)), and no umockdev testbed (GLib of the build machine).
ifneq ($(TARGET),)
HAL_CFLAGS = $(shell PKG_CONFIG_LIBDIR=$(ARCH_PKG_LIBDIR) pkg-config --cflags $(HAL_PKGS) 2>/dev/null)
HAL_LIBS = $(if $(HAL_SRC),$(shell PKG_CONFIG_LIBDIR=$(ARCH_PKG_LIBDIR) pkg-config --libs $(HAL_LINK_PKGS) 2>/dev/null))
override UMOCK_HAVE :=
endif

QEMU_X86 ?= qemu-x86_64 -cpu Westmere
# The arm64 loader and libc of the multiarch packages (libc6:arm64, which the
# :arm64 libraries bring), not the cross toolchain's copy in
# /usr/aarch64-linux-gnu: that ld.so (2.36-8) with multiarch's newer libc
# hangs the first pthread_create (the parse thread) under qemu-aarch64.
QEMU_A64 ?= qemu-aarch64 -L /
A64 := aarch64-linux-gnu
# The unit tests run under emulation: the fitter's numerics (basis, stripe
# accumulation and the solvers against dense references, PCG, refinement,
# curve fits, Coons bases), IGES files, the dispatch test and dlopen
# (test_hal_dl: libm.so.6 through the target's loader); about 40 s
# under qemu-aarch64 on a busy 2-core machine. Left out for time (each
# 40 s to several minutes emulated): test_accum, test_quad, test_project,
# test_points, test_jnl; and the rig, PLC, USB, scan and loop tests, which
# need sockets, ptys, umockdev and timing and run natively.
ARCH_EMU_TESTS ?= test_basis test_fit test_pcg test_refine test_curvefit test_coons test_iges test_hal_dl \
	test_dispatch
ARCH_A64_TESTS ?= $(ARCH_EMU_TESTS)
ARCH_X86_TESTS ?= $(ARCH_EMU_TESTS)

.PHONY: test-westmere test-aarch64 arch-a64-bins

test-westmere:
	$(MAKE) BOARD=sim BUILD=build/t-sim $(patsubst %,build/t-sim/tests/%,$(ARCH_X86_TESTS))
	$(MAKE) cellfit
	@ARCH_CC="$(CC)" sh mk/arch-test.sh westmere "$(QEMU_X86)" build/cellfit build/cellfit \
	  $(patsubst %,build/t-sim/tests/%,$(ARCH_X86_TESTS))

test-aarch64: arch-a64-bins
	$(MAKE) cellfit
	@sh mk/arch-test.sh aarch64 "$(QEMU_A64)" build/$(A64)/cellfit build/cellfit \
	  $(patsubst %,build/$(A64)/t-sim/tests/%,$(ARCH_A64_TESTS))

# The cross builds alone (also made ahead by make test's test-prebuild).
arch-a64-bins:
	$(MAKE) TARGET=$(A64) cellfit cellsim
	$(MAKE) TARGET=$(A64) BOARD=sim BUILD=build/$(A64)/t-sim \
	  $(patsubst %,build/$(A64)/t-sim/tests/%,$(ARCH_A64_TESTS))

TEST_EXTRA += test-westmere test-aarch64
