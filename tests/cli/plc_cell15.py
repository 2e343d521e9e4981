#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_cell15.py STEP PORT [ARGS]: issue 15's leftovers driven by
# pymodbus like a PLC (docs/plc-register-map.md): ABORT against a hung
# device within its stated bound, a scan cut by the rig's loss, a scan
# refused before any motion for want of free space, the outbox and
# on-the-fly loss registers, FIT_REFINE 2 (auto). Prints "ok ..." / "FAIL
# ..." lines; tests/cli/plc_cell15.sh counts them. Steps: hung PORT CONTROL
# BOUND_S; lost PORT SIMPID; nospace PORT CODE; outbox PORT CELLFIT DB
# down|up; otfregs PORT OUT; refine PORT OUT.
import json
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the Cell class, register addresses, check)
from plc_cycle import check, Cell  # noqa: E402
from plc_regs import outbox_regs, wait_outbox  # noqa: E402

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


SCAN_TRIGGERS, FIT_TOL, FIT_REFINE = 168, 82, 88
SCAN_NAMES = ("triggers", "dropped", "no_reading", "no_trigger", "both_lost", "duplicates",
              "overruns")


def outbox_cli(cf, db):
    out = subprocess.run([cf, "results", "outbox", "--json", "--db", db], capture_output=True,
                         text=True, timeout=20).stdout
    return json.loads(out)


def same_outbox(c, cf, db, what):
    """The registers against `cellfit results outbox` (read around them)."""
    a = outbox_cli(cf, db)
    r = outbox_regs(c)
    b = outbox_cli(cf, db)
    ok = (r["pg"] in (a["pg"], b["pg"]) and r["mqtt"] in (a["mqtt"], b["mqtt"])
          and r["dropped"] in (a["dropped"], b["dropped"])
          and a["oldest_age_s"] - 2 <= r["age"] <= b["oldest_age_s"] + 2)
    check(ok, "outbox: %s: registers %s = cellfit results outbox %s" % (what, r, b))
    return r


def outbox(port, cf, db, phase):
    """OUTBOX_* while the broker is down (a job waits, its age grows), then
    (phase up, once the script has started mosquitto) drained."""
    c = Cell(port)
    if phase == "up":
        r, dt = wait_outbox(c, lambda r: r["mqtt"] == 0 and r["age"] == 0, 30)
        check(r["mqtt"] == 0 and r["age"] == 0,
              "outbox: broker up: drained to 0 within %.1f s (%s)" % (dt, r))
        same_outbox(c, cf, db, "drained")
        return
    r = outbox_regs(c)
    check(r == {"pg": 0, "mqtt": 0, "age": 0, "dropped": 0}, "outbox: empty at start (%s)" % r)
    c.write(pc.PART, c.words(4801) + [1, 0] + c.fwords(0.05))
    s = c.command(3)  # FIT
    check(s.get("result") == 0, "outbox: FIT accepted")
    c.wait_done(c.seq)
    c.command(8)  # ACK_RESULTS
    r, _ = wait_outbox(c, lambda r: r["mqtt"] >= 1 and r["age"] >= 2, 10)
    check(r["mqtt"] == 1 and r["pg"] == 0 and r["age"] >= 2,
          "outbox: broker down: OUTBOX_MQTT 1, OUTBOX_PG 0, OUTBOX_AGE %d s growing (%s)"
          % (r["age"], r))
    same_outbox(c, cf, db, "broker down")


def scan_regs(c):
    r = c.read(SCAN_TRIGGERS, 14)
    return dict(zip(SCAN_NAMES, (c.u32(r[i:i + 2]) for i in range(0, 14, 2))))


def otfregs(port, out):
    """SCAN on the fly with the probe's FIFO overflowing: the SCAN_*
    registers; the script checks them against the journal and the log."""
    c = Cell(port)
    home_and_region(c, "otfregs", (60, 30, 140, 31, 0.1))
    s = c.command(SCAN)
    check(s.get("result") == 0, "otfregs: SCAN on the fly accepted")
    s = c.wait_done(c.seq, 120)
    check(not s["status"] & pc.ERROR, "otfregs: SCAN done (error %d)" % s["error"])
    time.sleep(1.5)  # the registers follow within a second
    r = scan_regs(c)
    with open(out, "w") as f:
        f.write(" ".join(str(r[n]) for n in SCAN_NAMES) + "\n")
    check(r["triggers"] > 0, "otfregs: SCAN_* %s" % r)


def refine(port, out):
    """FIT_REFINE 2 (auto) is the default and is accepted, 3 is not; the
    loop's control points with FIT_REFINE 2 and 1 (the script compares them
    with `cellfit fit --refine auto` and `--refine residual`)."""
    c = Cell(port)
    check(c.read(FIT_REFINE, 1)[0] == 2, "refine: FIT_REFINE 2 (auto) at start")
    check(c.write(FIT_REFINE, [0]) == 0 and c.write(FIT_REFINE, [2]) == 0,
          "refine: FIT_REFINE 0 and 2 accepted")
    check(c.write(FIT_REFINE, [3]) == 3, "refine: FIT_REFINE 3: exception 03")
    c.write(pc.PART, c.words(4802) + [1, 0] + c.fwords(0.05))
    c.write(FIT_TOL, c.fwords(0.01) + c.fwords(99.0))
    cps = {}
    for rf in (2, 1):
        c.write(FIT_REFINE, [rf])
        s = c.command(3)
        check(s.get("result") == 0, "refine: FIT with the loop, FIT_REFINE %d, accepted" % rf)
        s = c.wait_done(c.seq)
        cps[rf] = pc.results(c)["cps"]
        check(s["status"] & pc.RESULTS, "refine: FIT_REFINE %d: %d control points" % (rf, cps[rf]))
        c.command(8)
    with open(out, "w") as f:
        f.write("%d %d\n" % (cps[2], cps[1]))
    c.write(FIT_TOL, c.fwords(0.0) + c.fwords(100.0))
    c.write(FIT_REFINE, [2])


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
        elif step == "outbox":
            outbox(port, a[0], a[1], a[2])
        elif step == "otfregs":
            otfregs(port, a[0])
        elif step == "refine":
            refine(port, a[0])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
