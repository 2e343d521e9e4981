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

include boards/$(BOARD)/board.mk

WARN := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wmissing-prototypes
OPT ?= $(BOARD_CFLAGS)
CFLAGS_BASE := -std=c11 -D_POSIX_C_SOURCE=200809L $(WARN) $(OPT) -g
ifeq ($(SAN),1)
CFLAGS_BASE += -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
LDSAN := -fsanitize=address,undefined
endif
INC := -Iboards/$(BOARD) -Ifirmware -Ihost
CFLAGS_ALL = $(CFLAGS_BASE) $(INC) $(CFLAGS)

FW_SRC := $(sort $(wildcard firmware/*.c))
FW_OBJ := $(patsubst firmware/%.c,$(BUILD)/firmware/%.o,$(FW_SRC))
HOST_SRC := $(sort $(filter-out host/main.c,$(wildcard host/*.c)))
HOST_OBJ := $(patsubst host/%.c,$(BUILD)/host/%.o,$(HOST_SRC))
TEST_SRC := $(sort $(wildcard tests/test_*.c))
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
TESTLIB_SRC := $(sort $(wildcard tests/ref_*.c))
TESTLIB_OBJ := $(patsubst tests/%.c,$(BUILD)/tests/%.o,$(TESTLIB_SRC))
LIBS := -lm

.PHONY: all firmware cellfit test check unit unit-run demo bench clean lint format deps \
	test-cli fwcheck
all: $(if $(filter 1,$(BOARD_CROSS)),,cellfit) firmware

cellfit: $(BUILD)/cellfit
firmware: $(FW_OBJ)

$(BUILD)/firmware/%.o: firmware/%.c $(wildcard firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/host/%.o: host/%.c $(wildcard host/*.h firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/cellfit: $(BUILD)/host/main.o $(HOST_OBJ) $(FW_OBJ)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

$(BUILD)/tests/%.o: tests/%.c $(wildcard tests/*.h host/*.h firmware/*.h)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -Itests -c $< -o $@

$(BUILD)/tests/test_%: $(BUILD)/tests/test_%.o $(TESTLIB_OBJ) $(HOST_OBJ) $(FW_OBJ)
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
	$(MAKE) boards
	$(MAKE) boards-test
	$(MAKE) lint
	@echo "make test: all passed"

test-cli: $(BUILD)/cellfit
	@sh tests/cli/run.sh $(BUILD)/cellfit

lint:
	@sh scripts/lint.sh

format:
	clang-format -i firmware/*.[ch] host/*.[ch] tests/*.[ch] boards/*/*.[ch]

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

# Cross builds for microcontroller boards (make BOARD=<b> firmware, make boards).
-include mk/cross.mk
