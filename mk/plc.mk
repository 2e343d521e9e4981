# mk/plc.mk: the PLC interface (firmware/plc_*, host/cf_plcsrv.c, cellfit
# serve). The server needs libmodbus's headers and library even before hal/
# brings them in for everything.
PLC_CFLAGS := $(shell pkg-config --cflags libmodbus 2>/dev/null)
PLC_LIBS := $(shell pkg-config --libs libmodbus 2>/dev/null)
$(BUILD)/host/cf_plcsrv.o: CFLAGS += $(PLC_CFLAGS)
LIBS += $(PLC_LIBS)
