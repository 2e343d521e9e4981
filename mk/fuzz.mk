# SPDX-License-Identifier: MIT
# mk/fuzz.mk: libFuzzer targets for every parser of outside input (issue 7,
# docs/reliability.md), one tests/fuzz/fuzz_<name>.c each:
#   make fuzz             clang -fsanitize=fuzzer,address,undefined into
#                         build/fuzz/, each target run FUZZ_SECONDS (30) from
#                         tests/fuzz/corpus/<name>/; a crash, leak or hang
#                         stops it and leaves the input in build/fuzz/findings/
#   make test-fuzz        (in make test) every target once over its corpus
#                         and tests/fuzz/regress/<name>/ (inputs that found
#                         bugs), built with gcc, ASan+UBSan, by a plain main
#                         (tests/fuzz/driver.c): no fuzzing, a few seconds
#   make fuzz-short       (in make test) make fuzz for FUZZ_SHORT_SECONDS (10)
#                         each: a harness that drifted from the code it
#                         fuzzes (issue 15: fuzz_plc predated exception 06
#                         and stopped after ~13,000 runs) fails CI, not only
#                         a manual make fuzz
#   make valgrind         the firmware-core unit tests, no sanitizers, once
#                         under valgrind memcheck (in make test)
FUZZ_NAMES := iges step points jnl plc mbap probe modbus trig conf uri
FUZZ_SECONDS ?= 30
FUZZ_BIN := $(patsubst %,$(BUILD)/fuzz/fuzz_%,$(FUZZ_NAMES))
# The device-driver targets run on a virtual clock (tests/fuzz/fuzz_hal.h).
FUZZ_WRAP := -Wl,--wrap=hal_now_ms -Wl,--wrap=hal_sleep_ms
FUZZ_LIBFUZZER ?=
# The parsers under test are compiled again for the targets, with
# float-to-int overflow checks (gcc's -fsanitize=undefined leaves them out).
FUZZ_UNITS := lib/cf_iges_read.c lib/cf_points.c lib/cf_conf.c host/cmd/cmd_serve.c hal/hal_uri.c \
	hal/hal_stage.c hal/hal_probe.c hal/hal_probe_mb.c hal/hal_trig.c firmware/jnl.c \
	firmware/plc_map.c firmware/plc_fsm.c firmware/plc_mbap.c lib/cf_step_read.c
FUZZ_UNIT_OBJ := $(patsubst %.c,$(BUILD)/fuzz/unit/%.o,$(FUZZ_UNITS))
FUZZ_COMMON := $(BUILD)/fuzz/fuzz_util.o $(BUILD)/fuzz/fuzz_hal.o $(BUILD)/tests/ref_memstore.o \
	$(FUZZ_UNIT_OBJ) \
	$(filter-out $(patsubst %.c,$(BUILD)/%.o,$(FUZZ_UNITS)),$(HOST_OBJ) $(filter-out $(BUILD)/host/cmd/main.o,$(CMD_OBJ)) $(HAL_OBJ) $(FW_OBJ))

.PHONY: fuzz fuzz-build fuzz-bins fuzz-run test-fuzz fuzz-regress-run valgrind valgrind-run lint-fuzz

$(BUILD)/fuzz/%.o: tests/fuzz/%.c $(wildcard tests/fuzz/*.h tests/unit/*.h lib/*.h host/*/*.h hal/*.h firmware/*.h)
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) -Itests/fuzz -c $< -o $@

$(BUILD)/fuzz/unit/%.o: %.c $(wildcard lib/*.h host/*/*.h hal/*.h firmware/*.h) boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) $(if $(SAN),-fsanitize=float-cast-overflow) -c $< -o $@

$(FUZZ_BIN): $(BUILD)/fuzz/%: $(BUILD)/fuzz/%.o $(FUZZ_COMMON) \
	$(if $(FUZZ_LIBFUZZER),,$(BUILD)/fuzz/driver.o)
	$(CC) $(LDSAN) $(if $(FUZZ_LIBFUZZER),-fsanitize=fuzzer) $(FUZZ_WRAP) -o $@ $^ $(LIBS)

# The points reader with a 16 KiB buffer instead of 1 MiB: lines cross its
# refills often, and an open no longer fills 1 MiB (fuzz_points ran about
# 70 inputs a second under ASan, 762 in make test's 10 s).
$(BUILD)/fuzz/unit/lib/cf_points.o: CFLAGS_ALL += -DCF_POINTS_BUF=16384

fuzz-bins: $(FUZZ_BIN)

# libFuzzer: new inputs go to build/fuzz/work/<name> (the committed corpus
# is only read); final figures in build/fuzz/summary.txt.
fuzz: fuzz-build
	$(MAKE) BOARD=sim BUILD=build/fuzz FUZZ_LIBFUZZER=1 fuzz-run

# The libFuzzer builds alone (also made ahead by make test's test-prebuild).
fuzz-build:
	$(MAKE) -j$(FUZZ_JOBS) BOARD=sim BUILD=build/fuzz CC=clang SAN=1 OPT="-O1 -fsanitize=fuzzer-no-link" \
	  FUZZ_LIBFUZZER=1 fuzz-bins

# FUZZ_JOBS targets at a time (mk/fuzz-run.sh), one core each.
FUZZ_JOBS ?= $(shell nproc 2>/dev/null || echo 1)
fuzz-run:
	@sh mk/fuzz-run.sh $(BUILD) $(FUZZ_SECONDS) $(FUZZ_JOBS) $(FUZZ_NAMES)

# make test: the corpus and the regression inputs, once, under gcc's ASan+UBSan.
test-fuzz:
	$(MAKE) BOARD=sim BUILD=build/t-asan SAN=1 OPT=-O1 fuzz-regress-run

fuzz-regress-run: $(FUZZ_BIN)
	@set -e; for t in $(FUZZ_NAMES); do \
	  files=$$(ls tests/fuzz/corpus/$$t/* tests/fuzz/regress/$$t/* 2>/dev/null || true); \
	  if [ -z "$$files" ]; then echo "fuzz_$$t: no inputs"; exit 1; fi; \
	  if ! timeout 120 $(BUILD)/fuzz/fuzz_$$t $$files >$(BUILD)/fuzz/$$t.log 2>&1; then \
	    tail -30 $(BUILD)/fuzz/$$t.log; echo "FAIL fuzz_$$t regression inputs"; exit 1; fi; \
	  echo "ok   fuzz_$$t: $$(echo $$files | wc -w) corpus and regression inputs"; \
	done

TEST_EXTRA += test-fuzz

# make test: real fuzzing, briefly (libFuzzer, clang), every target.
FUZZ_SHORT_SECONDS ?= 10
fuzz-short:
	$(MAKE) fuzz FUZZ_SECONDS=$(FUZZ_SHORT_SECONDS)

TEST_EXTRA += fuzz-short

# valgrind memcheck over the unit tests that exercise firmware/ most (the
# fitter, basis, refinement, quads, journal, PLC map and state machine, scan
# job): the build/t-sim binaries make test has already built, without
# sanitizers (valgrind cannot run ASan binaries).
VALGRIND_TESTS := test_quad test_fit test_basis test_refine test_jnl test_plc test_scan
valgrind:
	$(MAKE) BOARD=sim BUILD=build/t-sim valgrind-run

# Two at a time (scripts/unit-run.sh; test_quad alone takes over half the
# serial time), each with its own CF_TEST_TMP; a memcheck error fails it.
VALGRIND_WRAP := valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite,indirect
valgrind-run: $(patsubst %,$(BUILD)/tests/%,$(VALGRIND_TESTS))
	@UNIT_WRAP="$(VALGRIND_WRAP)" sh scripts/unit-run.sh $(UNIT_JOBS) $(BUILD)/tmp/vg "" $^

TEST_EXTRA += valgrind

# scripts/lint.sh formats tests/*.[ch] only; tests/fuzz is checked here.
lint-fuzz:
	@for f in tests/fuzz/*.[ch]; do clang-format --dry-run -Werror $$f >/dev/null 2>&1 || \
	  { echo "lint: $$f is not clang-formatted"; exit 1; }; done; echo "lint-fuzz: tests/fuzz clean"

TEST_EXTRA += lint-fuzz
