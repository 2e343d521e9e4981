#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_cell15.py STEP PORT [ARGS]: issue 15's leftovers driven by
# pymodbus like a PLC (docs/plc-register-map.md): ABORT against a hung
# device within its stated bound, a scan cut by the rig's loss, a scan
# refused before any motion for want of free space, the outbox and
# on-the-fly loss registers, FIT_REFINE 2 (auto). Prints "ok ..." / "FAIL
# ..." lines; tests/cli/plc_cell15.sh counts them. Steps: hung PORT CONTROL
# BOUND_S; lost PORT SIMPID; nospace PORT; regs PORT ...
import os
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the Cell class, register addresses, check)
from plc_cycle import check, Cell  # noqa: E402

HOME, SCAN, ABORT = 1, 2, 5
REGION = 72


def home_and_region(c, what, region):
    c.command(HOME)
    s = c.wait_done(c.seq, 60)
    check(s["status"] & 128, "%s: homed (status 0x%x)" % (what, s["status"]))
    c.write(REGION, sum((c.fwords(v) for v in region), []))


def scan_started(c, what, cmd=SCAN):
    s = c.command(cmd)
    check(s.get("result") == 0, "%s: scan accepted (%s)" % (what, s.get("result")))
    t = time.time()
    while time.time() - t < 20 and c.status()["progress"] < 2:
        time.sleep(0.02)


def hung(port, control, bound):
    """The device stops answering mid-scan (cellsim's 'silent' fault on
    every request); ABORT must reach IDLE + ABORTED within the bound."""
    bound = float(bound)
    c = Cell(port)
    home_and_region(c, "hung", (0, 0, 200, 150, 2))
    scan_started(c, "hung")
    with open(control + ".tmp", "w") as f:
        f.write("fault silent:e1\n")
    os.rename(control + ".tmp", control)
    # cellsim reads its control file every 100 ms; then the job's request
    # in flight is unanswered: the abort lands on a hung device.
    t = time.time()
    while os.path.exists(control) and time.time() - t < 5:
        time.sleep(0.01)
    time.sleep(0.3)
    t0 = time.time()
    c.command(ABORT)
    s = c.status()
    while time.time() - t0 < 30 and (s["state"] != pc.IDLE or not s["status"] & pc.ABORTED):
        time.sleep(0.01)
        s = c.status()
    dt = time.time() - t0
    print("     hung: ABORT to IDLE + ABORTED in %.3f s (bound %.1f s)" % (dt, bound))
    check(s["state"] == pc.IDLE and s["status"] & pc.ABORTED and dt <= bound,
          "hung: ABORT against a hung device: IDLE + ABORTED after %.3f s <= %.1f s (state %d, "
          "status 0x%x)" % (dt, bound, s["state"], s["status"]))


def lost(port, simpid):
    """cellsim killed mid-scan: ERROR 203; the journal (checked by the
    script with cellfit journal info) says the rig was lost."""
    c = Cell(port)
    home_and_region(c, "lost", (0, 0, 200, 150, 2))
    scan_started(c, "lost")
    os.kill(int(simpid), signal.SIGKILL)
    t0 = time.time()
    s = c.status()
    while time.time() - t0 < 30 and s["state"] != pc.S_ERROR:
        time.sleep(0.02)
        s = c.status()
    check(s["state"] == pc.S_ERROR and s["error"] == 203,
          "lost: ERROR 203 after cellsim was killed, %.2f s (state %d, error %d)"
          % (time.time() - t0, s["state"], s["error"]))


def nospace(port, code):
    """A scan whose journal folder lacks room is refused when accepted,
    before any motion: CMD_RESULT code, STATE IDLE, no move made."""
    c = Cell(port)
    home_and_region(c, "nospace", (0, 0, 200, 150, 2))
    s = c.command(SCAN)
    check(s.get("result") == int(code) and s["state"] == pc.IDLE and s["status"] & pc.REJECTED,
          "nospace: SCAN refused with %s at acceptance (CMD_RESULT %s, state %d, status 0x%x)"
          % (code, s.get("result"), s["state"], s["status"]))
    time.sleep(0.3)
    s = c.status()
    check(s["state"] == pc.IDLE and not s["status"] & pc.BUSY and s["progress"] in (0, 100),
          "nospace: still IDLE, nothing started (state %d, progress %d)"
          % (s["state"], s["progress"]))


if __name__ == "__main__":
    step, port = sys.argv[1], int(sys.argv[2])
    a = sys.argv[3:]
    try:
        if step == "hung":
            hung(port, a[0], a[1])
        elif step == "lost":
            lost(port, a[0])
        elif step == "nospace":
            nospace(port, a[0])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
