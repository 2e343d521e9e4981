# SPDX-License-Identifier: MIT
# cellfit top-level Makefile.
#   make              build/cellfit and build/firmware/*.o (BOARD=linux-cell)
#   make test         every test: unit (sim board; clang on linux-cell),
#                     ASan+UBSan, CLI, lint; installs missing Debian packages
#                     first
#   make demo         the main job, end to end, with its report
#   make bench        benchmarks (printed figures, no assertions)
#   make BOARD=b      build for boards/b
# Build trees: build/ (linux-cell), build/t-<what>/ for test variants.

BOARD ?= linux-cell
BUILD ?= build
CC ?= cc
SAN ?=
ifeq ($(origin CC),default)
CC := gcc
endif
# Another CPU's Linux (mk/arch.mk): make TARGET=aarch64-linux-gnu builds
# build/<TARGET>/ with Debian's cross compiler <TARGET>-gcc (CC=... on the
# command line still wins); pkg-config then reads the :arm64 libraries
# (ARCH_PKG_LIBDIR, used by mk/arch.mk). One block, ahead of BUILD's uses.
TARGET ?=
ifneq ($(TARGET),)
ifeq ($(origin BUILD),file)
BUILD := build/$(TARGET)
endif
ifneq ($(origin CC),command line)
CC := $(TARGET)-gcc
endif
ARCH_PKG_LIBDIR := /usr/lib/$(TARGET)/pkgconfig:/usr/share/pkgconfig
endif

include boards/$(BOARD)/board.mk

WARN := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wmissing-prototypes
OPT ?= $(BOARD_CFLAGS)
CFLAGS_BASE := -std=c11 -D_POSIX_C_SOURCE=200809L $(WARN) $(OPT) -g
ifeq ($(SAN),1)
CFLAGS_BASE += -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
LDSAN := -fsanitize=address,undefined
endif
# Each layer compiles with its own include paths only, so an include that
# breaks the arrows (host/cmd -> host/cell -> host/jobs -> host/report -> lib
# -> firmware; hal -> firmware; sim -> lib, hal, firmware) cannot build.
FW_INC := -Iboards/$(BOARD) -Ifirmware
HAL_INC := $(FW_INC) -Ihal
LIB_INC := $(FW_INC) -Ilib -I$(BUILD)/gen
REPORT_INC := $(LIB_INC) -Ihost/report
JOBS_INC := $(REPORT_INC) -Ihost/jobs
CELL_INC := $(JOBS_INC) -Ihost/cell -Ihal
CMD_INC := $(CELL_INC) -Ihost/cmd
SIM_INC := $(LIB_INC) -Ihal -Isim
# Tests and tools see every layer.
INC := $(CMD_INC) -Isim -Itests/unit
CFLAGS_ALL = $(CFLAGS_BASE) $(INC) $(CFLAGS)
CF = $(CFLAGS_BASE) -MMD -MP $(CFLAGS)

FW_SRC := $(sort $(wildcard firmware/*.c))
FW_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(FW_SRC))
LIB_SRC := $(sort $(wildcard lib/*.c))
LIB_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(LIB_SRC))
# host/: the layers above lib/ (report, jobs, cell) as one archive; host/cmd
# holds the subcommands and main.
HOSTLIB_SRC := $(sort $(wildcard host/report/*.c host/jobs/*.c host/cell/*.c))
HOSTLIB_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(HOSTLIB_SRC))
CMD_SRC := $(sort $(wildcard host/cmd/*.c))
CMD_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(CMD_SRC))
TEST_SRC := $(sort $(wildcard tests/unit/test_*.c))
TEST_BIN := $(patsubst tests/unit/%.c,$(BUILD)/tests/%,$(TEST_SRC))
TESTLIB_SRC := $(sort $(wildcard tests/unit/ref_*.c))
TESTLIB_OBJ := $(patsubst tests/unit/%.c,$(BUILD)/tests/%.o,$(TESTLIB_SRC))
# hal/: transports to real devices (libmodbus, libserialport, libusb), host
# builds only; firmware/ never sees them. libusb is loaded at first use
# (hal/hal_dl.h, mk/dl.mk): its headers only, not its library, at build time.
HAL_SRC := $(sort $(wildcard hal/*.c))
HAL_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(HAL_SRC))
HAL_PKGS := libmodbus libserialport libusb-1.0
HAL_LINK_PKGS := libmodbus libserialport
HAL_CFLAGS = $(shell pkg-config --cflags $(HAL_PKGS) 2>/dev/null)
HAL_LIBS = $(if $(HAL_SRC),$(shell pkg-config --libs $(HAL_LINK_PKGS) 2>/dev/null))
# sim/: cellsim, the simulated rig (its own main), on the same wire protocols.
SIM_SRC := $(sort $(wildcard sim/*.c))
SIM_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(SIM_SRC))
LIBS = -lm $(HAL_LIBS) -lpthread
# The archives, linked in the arrows' order; a program pulls only what it uses.
A_FW := $(BUILD)/libcf_firmware.a
A_HAL := $(BUILD)/libcf_hal.a
A_LIB := $(BUILD)/libcf_lib.a
A_HOST := $(BUILD)/libcf_host.a
# Every object a host program may need, for fragments that link their own
# tools (fuzz targets, benchmarks).
HOST_OBJ := $(HOSTLIB_OBJ) $(LIB_OBJ)
# Extra test targets that mk/*.mk files add (TEST_EXTRA += ...); make test runs them.
TEST_EXTRA :=
# Version: the release, and the git revision the build came from (cellfit
# --version, IGES headers, report.json, the journal header).
CF_VERSION := 0.13.0
CF_REV := $(shell git describe --always --dirty --abbrev=12 2>/dev/null || echo unknown)

.PHONY: all firmware cellfit cellsim test check unit unit-run unit-bins test-prebuild demo bench clean lint format deps \
	test-cli fwcheck test-extra
all: $(if $(filter 1,$(BOARD_CROSS)),,cellfit $(if $(SIM_SRC),cellsim)) firmware

cellfit: $(BUILD)/cellfit
firmware: $(FW_OBJ)

$(BUILD)/firmware/%.o: firmware/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(FW_INC) -c $< -o $@

$(BUILD)/hal/%.o: hal/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(HAL_INC) $(HAL_CFLAGS) -c $< -o $@

$(BUILD)/lib/%.o: lib/%.c | $(BUILD)/gen/cf_rev.h
	@mkdir -p $(@D)
	$(CC) $(CF) $(LIB_INC) -c $< -o $@

$(BUILD)/host/report/%.o: host/report/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(REPORT_INC) -c $< -o $@

$(BUILD)/host/jobs/%.o: host/jobs/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(JOBS_INC) -c $< -o $@

$(BUILD)/host/cell/%.o: host/cell/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(CELL_INC) $(HAL_CFLAGS) -c $< -o $@

$(BUILD)/host/cmd/%.o: host/cmd/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(CMD_INC) $(HAL_CFLAGS) -c $< -o $@

$(BUILD)/sim/%.o: sim/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(SIM_INC) $(HAL_CFLAGS) -c $< -o $@

# The revision header changes only when the revision does (no needless rebuilds).
.PHONY: FORCE
$(BUILD)/gen/cf_rev.h: FORCE
	@mkdir -p $(@D)
	@printf '#define CF_VERSION "%s"\n#define CF_REV "%s"\n' '$(CF_VERSION)' '$(CF_REV)' >$@.tmp
	@if cmp -s $@.tmp $@; then rm -f $@.tmp; else mv $@.tmp $@; fi
$(BUILD)/lib/cf_version.o: $(BUILD)/gen/cf_rev.h

$(A_FW): $(FW_OBJ)
$(A_HAL): $(HAL_OBJ)
$(A_LIB): $(LIB_OBJ)
$(A_HOST): $(HOSTLIB_OBJ)
$(A_FW) $(A_HAL) $(A_LIB) $(A_HOST):
	@rm -f $@
	$(AR) rcs $@ $^

$(BUILD)/cellfit: $(CMD_OBJ) $(A_HOST) $(A_LIB) $(A_HAL) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

cellsim: $(BUILD)/cellsim
$(BUILD)/cellsim: $(SIM_OBJ) $(A_LIB) $(A_HAL) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

$(BUILD)/tests/%.o: tests/unit/%.c | $(BUILD)/gen/cf_rev.h
	@mkdir -p $(@D)
	$(CC) $(CF) $(INC) $(HAL_CFLAGS) -c $< -o $@

# A unit test links the archives; it pulls only the objects it calls.
$(BUILD)/tests/test_%: $(BUILD)/tests/test_%.o $(TESTLIB_OBJ) $(A_HOST) $(A_LIB) $(A_HAL) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ -lcmocka $(LIBS)

# Unit tests of one build tree, UNIT_JOBS at a time (scripts/unit-run.sh),
# each in its own CF_TEST_TMP; their outputs (cmocka's summaries) follow in
# order, with seconds. UNIT_SOLO run alone afterwards: test_plcsrv times its
# server's idle rule. UNIT_FIRST (the slowest) start first.
UNIT_JOBS ?= $(shell nproc 2>/dev/null || echo 1)
UNIT_SOLO := test_plcsrv
UNIT_FIRST := test_foot test_project test_points test_quad test_fmt
UNIT_ORDER = $(filter $(patsubst %,$(BUILD)/tests/%,$(UNIT_FIRST)),$(TEST_BIN)) \
	$(filter-out $(patsubst %,$(BUILD)/tests/%,$(UNIT_FIRST)),$(TEST_BIN))
unit-bins: $(TEST_BIN)
unit-run: $(TEST_BIN)
	@sh scripts/unit-run.sh $(UNIT_JOBS) $(BUILD)/tmp "$(UNIT_SOLO)" $(UNIT_ORDER)

deps:
	@sh scripts/deps.sh test

# firmware/ must not reference the heap (nm on its objects proves it) and
# includes nothing from hal/, host/ or sim/.
fwcheck: $(FW_OBJ) $(BUILD)/cellsim
	@bad=$$(nm -u $(FW_OBJ) | grep -E ' (malloc|calloc|realloc|free|aligned_alloc|posix_memalign)$$' || true); \
	if [ -n "$$bad" ]; then echo "firmware uses the heap:"; echo "$$bad"; exit 1; fi; \
	echo "fwcheck: firmware/ objects reference no allocator"
	@if grep -nE '#include +"(hal|host|sim|cf_)' firmware/*.c firmware/*.h; then \
	  echo "firmware includes outside code"; exit 1; fi
	@bad=$$(nm $(BUILD)/cellsim | grep -E ' T (cmd_|cf_plc|cf_job|cf_scanjob|cf_sfit)' || true); \
	if [ -n "$$bad" ]; then echo "cellsim links host code:"; echo "$$bad"; exit 1; fi; \
	echo "fwcheck: cellsim holds no cellfit command, job or PLC server"

# Each stage prints its wall time, so a slow CI run says where it went.
# The builds use every core (TEST_JOBS); unit tests and the valgrind and
# emulated runs go two at a time (scripts/unit-run.sh, mk/arch-test.sh),
# test_plcsrv alone; the CLI scripts, whose rigs and servers keep time, one
# at a time, with only the later stages' builds beside them at nice 19.
# The unit tests run on the sim board (gcc, ASan) and, with clang, on
# linux-cell, the board the host tools are built for: tests that size their
# cases from the board's limits are checked against both. (A build tree
# holds one board: the objects do not depend on BOARD, so the linux-cell
# tree has a name of its own, t-clang-lc, not the sim tree's t-clang.)
STAGE = sh scripts/stage.sh
TEST_JOBS ?= $(shell nproc 2>/dev/null || echo 1)
test: deps
	@rm -f build/stages.txt
	@$(STAGE) all $(MAKE) -j$(TEST_JOBS) all
	@$(STAGE) fwcheck $(MAKE) fwcheck
	@$(STAGE) unit-sim $(MAKE) -j$(TEST_JOBS) BOARD=sim BUILD=build/t-sim unit-run
	@$(STAGE) test-cli sh scripts/beside.sh build/prebuild.log "$(MAKE) test-prebuild" $(MAKE) test-cli
	@$(STAGE) unit-asan $(MAKE) -j$(TEST_JOBS) BOARD=sim BUILD=build/t-asan SAN=1 OPT=-O1 unit-run
	@$(STAGE) unit-clang $(MAKE) -j$(TEST_JOBS) BOARD=linux-cell BUILD=build/t-clang-lc CC=clang unit-run
	@$(STAGE) test-extra $(MAKE) test-extra
	@$(STAGE) boards $(MAKE) -j$(TEST_JOBS) boards
	@$(STAGE) boards-test $(MAKE) boards-test
	@$(STAGE) lint $(MAKE) lint
	@cat build/stages.txt
	@echo "make test: all passed"

# The builds of the stages after test-cli (no test runs), made beside it at
# the lowest priority (scripts/beside.sh): test-cli mostly waits on its
# simulated rigs and leaves the cores idle. Each stage still runs its own
# make, which then finds little or nothing to do, and fails on an error.
test-prebuild:
	-$(MAKE) -j$(TEST_JOBS) BOARD=sim BUILD=build/t-asan SAN=1 OPT=-O1 unit-bins
	-$(MAKE) -j$(TEST_JOBS) BOARD=linux-cell BUILD=build/t-clang-lc CC=clang unit-bins
	-$(MAKE) -j$(TEST_JOBS) arch-a64-bins
	-$(MAKE) -j$(TEST_JOBS) BOARD=sim BUILD=build/t-asan SAN=1 OPT=-O1 fuzz-bins
	-$(MAKE) -j$(TEST_JOBS) fuzz-build
	-$(MAKE) -j$(TEST_JOBS) boards
	@echo "test-prebuild: done"

# Every tests/cli/*.sh script (lib.sh and engines.sh aside: they are
# sourced), each given the cellfit binary (and cellsim beside it); each
# prints "<name>: N passed, N failed" and fails on a failure.
test-cli: all
	@set -e; for s in $(filter-out tests/cli/lib.sh tests/cli/engines.sh,$(sort $(wildcard tests/cli/*.sh))); do \
	  echo "== $$s"; t0=$$(date +%s); sh $$s $(BUILD)/cellfit; \
	  echo "== $$s: $$(( $$(date +%s) - t0 )) s"; done


lint:
	@sh scripts/lint.sh

format:
	clang-format -i $(wildcard firmware/*.[ch] lib/*.[ch] host/*/*.[ch] hal/*.[ch] sim/*.[ch] tests/unit/*.[ch] boards/*/*.[ch])

demo:
	@sh scripts/deps.sh demo
	$(MAKE) all
	@sh scripts/demo.sh $(BUILD)/cellfit

bench:
	@sh scripts/deps.sh bench
	$(MAKE) all
	@sh bench/run.sh $(BUILD)/cellfit

clean:
	rm -rf build

# Header dependencies (-MMD).
-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)

# Cross builds for microcontroller boards (make BOARD=<b> firmware, make boards)
# and the parts' own fragments (mk/<part>.mk, each adding to TEST_EXTRA).
include $(sort $(wildcard mk/*.mk))

# After the fragments, which fill TEST_EXTRA.
# Each extra builds on every core; its own runs stay one at a time unless the
# target says otherwise (fuzz-run).
test-extra:
	@set -e; for t in $(TEST_EXTRA); do $(STAGE) $$t $(MAKE) -j$(TEST_JOBS) $$t; done
