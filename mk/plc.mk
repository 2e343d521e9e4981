# SPDX-License-Identifier: MIT
# mk/plc.mk: the PLC interface (firmware/plc_*, host/cell/cf_plcsrv.c, cellfit
# serve). The server frames Modbus TCP itself (no libmodbus server); the rig
# it drives links libmodbus through hal/ (HAL_LIBS), so nothing more here.
