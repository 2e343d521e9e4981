# SPDX-License-Identifier: MIT
# mk/plant.mk: results at the cell (SQLite) and for the plant (PostgreSQL
# through libpq, MQTT through libmosquitto): host/cell/cf_resdb.c,
# cf_forward.c, cf_record.c and `cellfit results`. cf_resdb and cf_forward
# load the libraries at first use (hal/hal_dl.h, mk/dl.mk): nothing links
# them but test_resdb, which reads its databases with SQLite itself.
PLANT_PKGS := sqlite3 libpq libmosquitto
# The target's own libraries decide (a cross build looks in its pkg-config):
# without them cellfit is built with CF_NO_PLANT (no results.db, no forwarding).
PLANT_PC := $(if $(TARGET),PKG_CONFIG_LIBDIR=$(ARCH_PKG_LIBDIR)) pkg-config
PLANT_HAVE := $(shell $(PLANT_PC) --exists $(PLANT_PKGS) 2>/dev/null && echo 1)
PLANT_CFLAGS := $(if $(PLANT_HAVE),$(shell pkg-config --cflags $(PLANT_PKGS) 2>/dev/null),-DCF_NO_PLANT=1)
$(BUILD)/host/cell/%.o $(BUILD)/host/cmd/%.o $(BUILD)/tests/%.o: CFLAGS += $(PLANT_CFLAGS)
$(BUILD)/tests/test_resdb: LIBS += $(if $(PLANT_HAVE),$(shell $(PLANT_PC) --libs sqlite3 2>/dev/null))

.PHONY: test-plant plant-demo
# tests/cli/plant.sh, plant_tls.sh (TLS to both engines) and record.sh
# (fit/scan --record) also run with test-cli (every tests/cli script).
test-plant: all
	sh tests/cli/plant.sh $(BUILD)/cellfit
	sh tests/cli/plant_tls.sh $(BUILD)/cellfit
	sh tests/cli/record.sh $(BUILD)/cellfit

# A plant on one machine: 4 cells, one broker, one database, an outage in
# the middle (scripts/plant_demo.sh; PLANT_SECONDS, default 120).
PLANT_SECONDS ?= 120
plant-demo:
	@sh scripts/deps.sh demo
	$(MAKE) all
	@sh scripts/plant_demo.sh $(BUILD)/cellfit $(PLANT_SECONDS)
