# SPDX-License-Identifier: MIT
# mk/dl.mk: the libraries loaded at their first use (issue 20, hal/hal_dl.h):
# Aravis (hal_gev), libusb (hal_usb), SQLite (cf_resdb), libpq and
# libmosquitto (cf_forward). Nothing links them (cellsim aside: mk/gev.mk);
# their sonames come from this build: mk/dl-libs.sh reads the SONAME of the
# library each pkg-config package names, as the target's compiler finds it,
# and the Debian package that holds it, into $(BUILD)/gen/hal_dl_libs.h.
# An install lists them as dependencies itself (dist/debian-depends: shlib
# tools see no dlopen).
DL_HDR := $(BUILD)/gen/hal_dl_libs.h
# Those this build compiles against (mk/gev.mk, mk/plant.mk decide; read
# when the recipe runs, after them): its header, install and tests follow.
DL_LIST = USB=libusb-1.0 $(if $(GEV_HAVE),ARAVIS=aravis-0.8) \
	$(if $(PLANT_HAVE),SQLITE3=sqlite3 PQ=libpq MOSQUITTO=libmosquitto)
DL_OBJ := $(BUILD)/hal/hal_gev.o $(BUILD)/hal/hal_usb.o $(BUILD)/host/cell/cf_forward.o \
	$(BUILD)/host/cell/cf_resdb.o

$(DL_HDR): mk/dl.mk mk/dl-libs.sh
	@mkdir -p $(@D)
	$(if $(TARGET),PKG_CONFIG_LIBDIR=$(ARCH_PKG_LIBDIR)) sh mk/dl-libs.sh "$(CC)" $(DL_LIST) >$@.tmp
	@mv $@.tmp $@
$(DL_OBJ): $(DL_HDR)
$(DL_OBJ): override CFLAGS += -I$(BUILD)/gen

# dlopen is in glibc's libc since 2.34; an older toolchain needs -ldl. Tried
# once per make run, at the first link.
DL_HASH := \#
DL_LDLIBS = $(eval DL_LDLIBS := $(shell printf '$(DL_HASH)include <dlfcn.h>\nint main(void) { return !dlopen("x", RTLD_NOW); }\n' | \
	$(CC) -x c -o /dev/null - 2>/dev/null || echo -ldl))$(DL_LDLIBS)
LIBS += $(DL_LDLIBS)
