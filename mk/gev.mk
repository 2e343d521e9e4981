# SPDX-License-Identifier: MIT
# mk/gev.mk: the GigE Vision laser line profiler (issue 19): hal/hal_gev.c
# (the driver) and sim/sim_gev.c (cellsim's fake camera) compile against
# Aravis (Debian libaravis-dev, scripts/deps.sh build). hal_gev loads
# libaravis at its first open (hal/hal_dl.h, mk/dl.mk); only cellsim, whose
# fake camera calls Aravis directly, links it. Also build/gev-check (tests/unit/gev_check.c: receives
# frames through hal_gev and checks them against the part, for
# tests/cli/profiler.sh) and build/scan-bench (bench/scan_bench.c: the scan
# benchmark, make bench-scan).
GEV_PKGS := aravis-0.8
# The target's pkg-config (a cross build looks in its own libraries); without
# Aravis there, hal_gev and cellsim --gev are built as "unsupported".
GEV_PC := $(if $(TARGET),PKG_CONFIG_LIBDIR=$(ARCH_PKG_LIBDIR)) pkg-config
GEV_HAVE := $(shell $(GEV_PC) --exists $(GEV_PKGS) 2>/dev/null && echo 1)
# GLib's headers come in as system headers (they are not -Wstrict-prototypes clean).
GEV_CFLAGS = $(if $(GEV_HAVE),-DCF_HAVE_ARAVIS=1 $(patsubst -I%,-isystem %,$(shell $(GEV_PC) --cflags $(GEV_PKGS) 2>/dev/null)))
GEV_LIBS = $(if $(GEV_HAVE),$(shell $(GEV_PC) --libs $(GEV_PKGS) 2>/dev/null))
$(BUILD)/cellsim: LIBS += $(GEV_LIBS)

$(BUILD)/hal/hal_gev.o: HAL_CFLAGS += $(GEV_CFLAGS)
$(BUILD)/sim/sim_gev.o: HAL_CFLAGS += $(GEV_CFLAGS)

.PHONY: gev-tools bench-scan test-profiler
ifneq ($(BOARD_CROSS),1)
all: gev-tools
endif
gev-tools: $(BUILD)/gev-check $(BUILD)/scan-bench

# The tools link the simulated part (sim/sim_part.c, sim_util.c) for the truth.
GEV_SIMPART := $(BUILD)/sim/sim_part.o $(BUILD)/sim/sim_util.o

$(BUILD)/tools/%.o: tests/unit/%.c
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) $(GEV_CFLAGS) -c $< -o $@

$(BUILD)/tools/%.o: bench/%.c
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) $(HAL_CFLAGS) $(GEV_CFLAGS) -c $< -o $@

$(BUILD)/gev-check: $(BUILD)/tools/gev_check.o $(GEV_SIMPART) $(A_HOST) $(A_LIB) $(A_HAL) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

$(BUILD)/scan-bench: $(BUILD)/tools/scan_bench.o $(GEV_SIMPART) $(A_HOST) $(A_LIB) $(A_HAL) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

test-profiler: $(BUILD)/gev-check $(BUILD)/cellsim
	@sh tests/cli/profiler.sh $(BUILD)/cellfit

bench-scan: $(BUILD)/scan-bench $(BUILD)/cellsim
	@sh bench/scan.sh $(BUILD)
