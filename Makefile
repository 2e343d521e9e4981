# cellfit top-level Makefile.
#   make              build/cellfit and build/firmware/*.o (BOARD=linux-cell)
#   make test         every test: unit (sim board), ASan+UBSan, clang, CLI,
#                     lint; installs missing Debian packages first
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
INC := -Iboards/$(BOARD) -Ifirmware -Ihost -Ihal
CFLAGS_ALL = $(CFLAGS_BASE) $(INC) $(CFLAGS)

FW_SRC := $(sort $(wildcard firmware/*.c))
FW_OBJ := $(patsubst firmware/%.c,$(BUILD)/firmware/%.o,$(FW_SRC))
HOST_SRC := $(sort $(filter-out host/main.c,$(wildcard host/*.c)))
HOST_OBJ := $(patsubst host/%.c,$(BUILD)/host/%.o,$(HOST_SRC))
TEST_SRC := $(sort $(wildcard tests/test_*.c))
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
TESTLIB_SRC := $(sort $(wildcard tests/ref_*.c))
TESTLIB_OBJ := $(patsubst tests/%.c,$(BUILD)/tests/%.o,$(TESTLIB_SRC))
# hal/: transports to real devices (libmodbus, libserialport, libusb), host
# builds only; firmware/ never sees them.
HAL_SRC := $(sort $(wildcard hal/*.c))
HAL_OBJ := $(patsubst hal/%.c,$(BUILD)/hal/%.o,$(HAL_SRC))
HAL_PKGS := libmodbus libserialport libusb-1.0
HAL_CFLAGS = $(shell pkg-config --cflags $(HAL_PKGS) 2>/dev/null)
HAL_LIBS = $(if $(HAL_SRC),$(shell pkg-config --libs $(HAL_PKGS) 2>/dev/null))
# sim/: cellsim, the simulated rig (its own main), on the same wire protocols.
SIM_SRC := $(sort $(wildcard sim/*.c))
SIM_OBJ := $(patsubst sim/%.c,$(BUILD)/sim/%.o,$(SIM_SRC))
LIBS = -lm $(HAL_LIBS) -lpthread
# Extra test targets that mk/*.mk files add (TEST_EXTRA += ...); make test runs them.
TEST_EXTRA :=

.PHONY: all firmware cellfit cellsim test check unit unit-run demo bench clean lint format deps \
	test-cli fwcheck test-extra
all: $(if $(filter 1,$(BOARD_CROSS)),,cellfit $(if $(SIM_SRC),cellsim)) firmware

cellfit: $(BUILD)/cellfit
firmware: $(FW_OBJ)

$(BUILD)/firmware/%.o: firmware/%.c $(wildcard firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/host/%.o: host/%.c $(wildcard host/*.h hal/*.h firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/hal/%.o: hal/%.c $(wildcard hal/*.h firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) -c $< -o $@

$(BUILD)/sim/%.o: sim/%.c $(wildcard sim/*.h hal/*.h host/*.h firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) -Isim -c $< -o $@

$(BUILD)/cellfit: $(BUILD)/host/main.o $(HOST_OBJ) $(HAL_OBJ) $(FW_OBJ)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

cellsim: $(BUILD)/cellsim
$(BUILD)/cellsim: $(SIM_OBJ) $(HOST_OBJ) $(HAL_OBJ) $(FW_OBJ)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

$(BUILD)/tests/%.o: tests/%.c $(wildcard tests/*.h host/*.h hal/*.h firmware/*.h)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) -Itests -c $< -o $@

$(BUILD)/tests/test_%: $(BUILD)/tests/test_%.o $(TESTLIB_OBJ) $(HOST_OBJ) $(HAL_OBJ) $(FW_OBJ)
	$(CC) $(LDSAN) -o $@ $^ -lcmocka $(LIBS)

# Unit tests of one build tree, each binary in turn; cmocka prints its summary.
unit-run: $(TEST_BIN)
	@set -e; for t in $(TEST_BIN); do echo "== $$t"; CF_TEST_TMP=$(BUILD)/tmp $$t; done

deps:
	@sh scripts/deps.sh test

# firmware/ must not reference the heap (nm on its objects proves it) and
# includes nothing from hal/, host/ or sim/.
fwcheck: $(FW_OBJ)
	@bad=$$(nm -u $(FW_OBJ) | grep -E ' (malloc|calloc|realloc|free|aligned_alloc|posix_memalign)$$' || true); \
	if [ -n "$$bad" ]; then echo "firmware uses the heap:"; echo "$$bad"; exit 1; fi; \
	echo "fwcheck: firmware/ objects reference no allocator"
	@if grep -nE '#include +"(hal|host|sim|cf_)' firmware/*.c firmware/*.h; then \
	  echo "firmware includes outside code"; exit 1; fi

test: deps
	$(MAKE) all
	$(MAKE) fwcheck
	$(MAKE) BOARD=sim BUILD=build/t-sim unit-run
	$(MAKE) BOARD=sim BUILD=build/t-asan SAN=1 OPT=-O1 unit-run
	$(MAKE) BOARD=sim BUILD=build/t-clang CC=clang unit-run
	$(MAKE) test-cli
	$(MAKE) test-extra
	$(MAKE) boards
	$(MAKE) boards-test
	$(MAKE) lint
	@echo "make test: all passed"

# Every tests/cli/*.sh script, each given the cellfit binary (and cellsim
# beside it); each prints "<name>: N passed, N failed" and fails on a failure.
test-cli: all
	@set -e; for s in $(filter-out tests/cli/lib.sh,$(sort $(wildcard tests/cli/*.sh))); do \
	  echo "== $$s"; sh $$s $(BUILD)/cellfit; done


lint:
	@sh scripts/lint.sh

format:
	clang-format -i $(wildcard firmware/*.[ch] host/*.[ch] hal/*.[ch] sim/*.[ch] tests/*.[ch] boards/*/*.[ch])

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

# Cross builds for microcontroller boards (make BOARD=<b> firmware, make boards)
# and the parts' own fragments (mk/<part>.mk, each adding to TEST_EXTRA).
include $(sort $(wildcard mk/*.mk))

# After the fragments, which fill TEST_EXTRA.
test-extra: $(TEST_EXTRA)
