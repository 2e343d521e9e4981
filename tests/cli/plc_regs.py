#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_regs.py: the OUTBOX_* registers of `cellfit serve` (map v3,
# docs/plc-register-map.md) read as a PLC does, for the scripts that check
# them (outbox_lock.py, plc_cell15.py). A module, not a step: no main.
import time

OUTBOX_PG = 160  # OUTBOX_PG, OUTBOX_MQTT, OUTBOX_AGE, OUTBOX_DROPPED: u32 each


def outbox_regs(c):
    """The four outbox registers by name, through a plc_cycle.Cell."""
    r = c.read(OUTBOX_PG, 8)
    return {"pg": c.u32(r[0:2]), "mqtt": c.u32(r[2:4]), "age": c.u32(r[4:6]),
            "dropped": c.u32(r[6:8])}


def wait_outbox(c, cond, limit):
    """Read them every 0.1 s until cond(registers) or limit s: the last
    registers read and the seconds it took."""
    t = time.time()
    r = outbox_regs(c)
    while time.time() - t < limit and not cond(r):
        time.sleep(0.1)
        r = outbox_regs(c)
    return r, time.time() - t
