# SPDX-License-Identifier: MIT
# mk/usb.mk: the USB parts (issue 4): build/sim-umock, the umockdev testbed
# that plays the FTDI-attached laser probe and the USB trigger box (GLib and
# libumockdev, so not part of cellsim, whose build links sim/*.c only).
# `make all` builds it beside cellfit (when libumockdev is there), so
# tests/cli/usb.sh (run by test-cli) finds it; `make test-usb` runs it alone.
UMOCK_PKGS := umockdev-1.0 glib-2.0 gio-2.0
UMOCK_CFLAGS = $(shell pkg-config --cflags $(UMOCK_PKGS) 2>/dev/null)
UMOCK_LIBS = $(shell pkg-config --libs $(UMOCK_PKGS) 2>/dev/null)
UMOCK_SRC := $(sort $(wildcard sim/umock/*.c))
UMOCK_OBJ := $(patsubst sim/umock/%.c,$(BUILD)/sim/umock/%.o,$(UMOCK_SRC))

.PHONY: sim-umock test-usb lint-usb
# Only where libumockdev-dev is installed (scripts/deps.sh test and demo
# install it; a plain build does not need it).
UMOCK_HAVE := $(shell pkg-config --exists $(UMOCK_PKGS) 2>/dev/null && echo yes)
ifneq ($(BOARD_CROSS),1)
ifeq ($(UMOCK_HAVE),yes)
all: sim-umock
endif
endif
sim-umock: $(BUILD)/sim-umock

# GLib's headers come in as system headers (they are not -Wstrict-prototypes clean).
$(BUILD)/sim/umock/%.o: sim/umock/%.c sim/umock/sim_umock.h hal/hal_trig.h hal/hal.h firmware/rig.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -D_DEFAULT_SOURCE $(patsubst -I%,-isystem %,$(UMOCK_CFLAGS)) \
	  -Isim/umock -c $< -o $@

$(BUILD)/sim-umock: $(UMOCK_OBJ) $(BUILD)/hal/hal_trig.o $(BUILD)/firmware/rig_err.o
	$(CC) $(LDSAN) -o $@ $^ $(UMOCK_LIBS) -lm

test-usb: $(BUILD)/sim-umock $(BUILD)/cellfit
	@sh tests/cli/usb.sh $(BUILD)/cellfit

# scripts/lint.sh formats sim/*.[ch] only; sim/umock is checked here.
lint-usb:
	@for f in sim/umock/*.[ch]; do clang-format --dry-run -Werror $$f >/dev/null 2>&1 || \
	  { echo "lint: $$f is not clang-formatted"; exit 1; }; done; echo "lint-usb: sim/umock clean"

TEST_EXTRA += lint-usb
