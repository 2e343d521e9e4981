#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_rig.py STEP PORT SIMPORT [ARGS]: `cellfit serve` on the
# simulated rig (cellsim), driven through its registers only by pymodbus
# (and mbpoll as a second client), the way a PLC does; the simulator's own
# registers (stage unit 1, docs/rig-devices.md) are read to see the stage
# really stopped. Prints "ok ..." / "FAIL ..." lines; tests/cli/plc_rig.sh
# counts them. Steps: cycle RESDIR MBPOLL OUT; tolfit RESDIR NCP OUT;
# otffit RESDIR OUT [WHAT];
# abort RESDIR OUT; watchdog;
# fault CONTROL_FILE KIND CODE; gone; garbage; rate; allow WANT; soak TX.
import glob
import os
import socket
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the Cell class, register addresses, check)
from plc_cycle import check, Cell  # noqa: E402

HOMED, RIG = 128, 256
SCANNING = 2
HOME, SCAN, FIT, SCAN_FIT, ABORT, RESET, EXPORT, ACK_RESULTS = range(1, 9)
SX0, SSTEP = 72, 80
STG_STATUS, STG_MOVES = 5, 20
STG_BUSY = 2


def region(c, x0, y0, x1, y1, step):
    return c.write(SX0, sum((c.fwords(v) for v in (x0, y0, x1, y1, step)), []))


def sim_stage(simport):
    """Stage STATUS and MOVES, read from cellsim directly (unit 1)."""
    s = pc.ModbusTcpClient("127.0.0.1", port=simport, timeout=5)
    s.connect()
    st = s.read_holding_registers(STG_STATUS, 1, slave=1).registers[0]
    mv = s.read_holding_registers(STG_MOVES, 1, slave=1).registers[0]
    s.close()
    return st, mv


def stage_stopped(simport, what):
    st0, mv0 = sim_stage(simport)
    time.sleep(0.4)
    st1, mv1 = sim_stage(simport)
    check(not st1 & STG_BUSY and mv1 == mv0,
          "%s: cellsim's stage stopped (status 0x%x, moves %d then %d)" % (what, st1, mv0, mv1))


def home(c, what):
    s = c.command(HOME)
    check(s.get("result") == 0, "%s: HOME accepted" % what)
    s = c.wait_done(c.seq, 60)
    check(s["status"] & HOMED and not s["status"] & pc.ERROR, "%s: homed" % what)


def wait_progress(c, pct, limit=60):
    t = time.time()
    while time.time() - t < limit:
        s = c.status()
        if s["progress"] >= pct or not s["status"] & pc.BUSY:
            return s
        time.sleep(0.02)
    return c.status()


def newest_journal(resdir):
    js = sorted(glob.glob(os.path.join(resdir, "*.jnl")), key=os.path.getmtime)
    return js[-1] if js else ""


def cycle(port, simport, resdir, mbpoll, out):
    c = Cell(port)
    s = c.status()
    check(s["status"] & RIG and s["state"] == pc.IDLE, "cycle: RIG set, IDLE (0x%x)" % s["status"])
    s = c.command(SCAN_FIT)
    check(s["result"] == 107, "cycle: SCAN_FIT before HOME refused with 107 (%d)" % s["result"])
    home(c, "cycle")
    check(c.write(pc.PART, c.words(4711) + [3, 0] + c.fwords(0.05)) == 0,
          "cycle: part 4711, program 3, folder 0, tolerance 0.05 mm")
    check(region(c, 100, 50, 0, 0, 2.5) == 0, "cycle: region (100, 50)-(0, 0), step 2.5 mm written")
    # The part's ID (PART_ID, 124..139, two characters a register, the first
    # in the high byte) goes into the scan's journal (issue 19).
    raw = b"CYCLE-4711".ljust(32, b"\0")
    check(c.write(124, [raw[i] << 8 | raw[i + 1] for i in range(0, 32, 2)]) == 0,
          "cycle: PART_ID 'CYCLE-4711' written")
    s = c.command(SCAN_FIT)
    seq = c.seq
    check(s["result"] == 0 and s["state"] == SCANNING, "cycle: SCAN_FIT seq %d: SCANNING" % seq)
    s = wait_progress(c, 20)
    check(s["state"] == SCANNING and 20 <= s["progress"] < 100,
          "cycle: progress %d %% while scanning" % s["progress"])
    # While it runs: parameters refused (exception 06), heartbeat taken.
    check(c.write(pc.TOL, c.fwords(0.5)) == 6, "cycle: parameter write while busy: exception 06")
    check(c.write(pc.HEARTBEAT, [77]) == 0, "cycle: heartbeat write while busy accepted")
    r = subprocess.run(["timeout", "10", mbpoll, "-m", "tcp", "-p", str(port), "-0", "-r", "43",
                        "-c", "2", "-1", "127.0.0.1"], capture_output=True, text=True).stdout
    check("[43]: \t2" in r or "[43]: \t3" in r, "cycle: mbpoll sees STATE 2/3 while busy")
    s = c.wait_done(seq, 60)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR and s["progress"] == 100,
          "cycle: done with RESULTS, no error (0x%x)" % s["status"])
    res = pc.results(c)
    check(res["seq"] == seq and res["part"] == 4711, "cycle: results of seq %d, part 4711" % seq)
    check(res["points"] == 41 * 21, "cycle: 861 points measured and fitted (%d)" % res["points"])
    check(res["cps"] == 1200, "cycle: 1200 control points, the nominal's 40 x 30 (%d)" % res["cps"])
    # cellsim's part is the nominal plus a dent and warp of a few tenths;
    # the fit follows it: residuals at the noise (0.002 mm) level.
    check(0 < res["rms"] < 0.01 and res["min"] < 0 < res["max"],
          "cycle: rms %.4g, min %.4g, max %.4g mm" % (res["rms"], res["min"], res["max"]))
    check(res["verdict"] == 1 and res["within"] == 100.0,
          "cycle: verdict pass, %.1f %% within 0.05 mm" % res["within"])
    check(res["ms"] > 0, "cycle: duration %d ms" % res["ms"])
    # EXPORT from mbpoll (a third-party client), registers only.
    c.seq += 1
    r = subprocess.run(["timeout", "10", mbpoll, "-m", "tcp", "-p", str(port), "-0", "-r", "20",
                        "-1", "127.0.0.1", str(EXPORT), str(c.seq)], capture_output=True,
                       text=True).stdout
    check("Written 2 references" in r, "cycle: mbpoll writes EXPORT seq %d" % c.seq)
    s = c.wait_done(c.seq, 30)
    check(not s["status"] & pc.ERROR and s["result"] == 0, "cycle: EXPORT done")
    dirs = glob.glob(os.path.join(resdir, "4711_*"))
    dirs = [d for d in dirs if os.path.isdir(d)]
    check(len(dirs) == 1 and os.path.isfile(os.path.join(dirs[0], "fitted.igs")),
          "cycle: results folder with fitted.igs")
    rep = pc.json.load(open(os.path.join(dirs[0], "report.json"))) if dirs else {}
    jnl = rep.get("journal", "")
    check(os.path.isfile(jnl) and os.path.basename(jnl).startswith("4711_") and
          jnl.endswith(".jnl"), "cycle: report.json names the journal %s" % jnl)
    check(rep.get("points") == 861 and rep.get("part") == 4711 and rep.get("program") == 3,
          "cycle: report.json: part 4711, program 3, 861 points")
    ok = all(abs(res[k] - rep.get(j, 1e9)) <= 1e-6 * max(1.0, abs(rep.get(j, 1e9))) for k, j in
             (("rms", "rms"), ("max", "max"), ("min", "min")))
    check(ok, "cycle: registers match report.json (rms, max, min)")
    s = c.command(ACK_RESULTS)
    check(s["result"] == 0 and not s["status"] & pc.RESULTS, "cycle: ACK_RESULTS")
    open(out, "w").write("%s\n%s\n" % (dirs[0] if dirs else "", jnl))


def tolfit(port, simport, resdir, ncp, out):
    """SCAN_FIT on a cell configured to fit to TOLERANCE (99 % within),
    robustly: the results say more control points than the nominal's ncp
    and 99 % within; the export names fit_status "met". OUT gets the export
    folder and the journal."""
    c = Cell(port)
    home(c, "tolfit")
    check(c.write(pc.PART, c.words(4712) + [4, 0] + c.fwords(0.01)) == 0,
          "tolfit: part 4712, program 4, folder 0, tolerance 0.01 mm")
    check(region(c, 100, 50, 0, 0, 2.5) == 0, "tolfit: region (100, 50)-(0, 0), step 2.5 mm")
    s = c.command(SCAN_FIT)
    seq = c.seq
    check(s["result"] == 0, "tolfit: SCAN_FIT seq %d accepted" % seq)
    s = c.wait_done(seq, 120)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR,
          "tolfit: done with RESULTS, no error (0x%x)" % s["status"])
    res = pc.results(c)
    check(res["points"] == 41 * 21, "tolfit: 861 points fitted (%d)" % res["points"])
    check(res["cps"] > ncp, "tolfit: the loop refined the net: %d control points > the nominal's %d"
          % (res["cps"], ncp))
    check(res["within"] >= 99.0, "tolfit: %.2f %% within 0.01 mm (the cell asks 99 %%)" % res["within"])
    c.seq += 1
    s = c.command(EXPORT)
    s = c.wait_done(c.seq, 30)
    check(not s["status"] & pc.ERROR, "tolfit: EXPORT done")
    dirs = [d for d in glob.glob(os.path.join(resdir, "4712_*")) if os.path.isdir(d)]
    rep = pc.json.load(open(os.path.join(dirs[0], "report.json"))) if dirs else {}
    check(rep.get("fit_status") == "met" and rep.get("control_points") == res["cps"],
          "tolfit: report.json: fit_status %s, %s control points" %
          (rep.get("fit_status"), rep.get("control_points")))
    s = c.command(ACK_RESULTS)
    open(out, "w").write("%s\n%s\n" % (dirs[0] if dirs else "", rep.get("journal", "")))


def otffit(port, simport, resdir, out, what="otffit"):
    """SCAN_FIT on a cell scanning on the fly (scan_method otf; WHAT names
    the step, "profiler" on a profiler cell): its points streamed into the
    fit (issue 19). OUT gets the export folder, the journal and the POINTS
    register."""
    c = Cell(port)
    home(c, what)
    check(c.write(pc.PART, c.words(4713) + [5, 0] + c.fwords(0.05)) == 0,
          what + ": part 4713, program 5, folder 0, tolerance 0.05 mm")
    check(region(c, 100, 50, 0, 0, 1) == 0, what + ": region (100, 50)-(0, 0), step 1 mm")
    s = c.command(SCAN_FIT)
    seq = c.seq
    check(s["result"] == 0, what + ": SCAN_FIT seq %d accepted" % seq)
    s = c.wait_done(seq, 120)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR,
          what + ": done with RESULTS, no error (0x%x)" % s["status"])
    res = pc.results(c)
    check(res["points"] > 0, what + ": %d points fitted" % res["points"])
    s = c.command(EXPORT)
    s = c.wait_done(c.seq, 30)
    check(not s["status"] & pc.ERROR, what + ": EXPORT done")
    dirs = [d for d in glob.glob(os.path.join(resdir, "4713_*")) if os.path.isdir(d)]
    rep = pc.json.load(open(os.path.join(dirs[0], "report.json"))) if dirs else {}
    c.command(ACK_RESULTS)
    open(out, "w").write("%s\n%s\n%d\n" % (dirs[0] if dirs else "", rep.get("journal", ""),
                                            res["points"]))


def abort(port, simport, resdir, out):
    c = Cell(port)
    check(region(c, 0, 0, 200, 150, 2) == 0, "abort: the whole part at 2 mm (7676 points)")
    s = c.command(SCAN_FIT)
    seq = c.seq
    check(s["result"] == 0, "abort: SCAN_FIT accepted")
    wait_progress(c, 2)
    # Invalid commands while scanning: all but ABORT refused with 102.
    for code, name in ((HOME, "HOME"), (SCAN, "SCAN"), (FIT, "FIT"), (SCAN_FIT, "SCAN_FIT"),
                       (RESET, "RESET"), (EXPORT, "EXPORT"), (ACK_RESULTS, "ACK_RESULTS")):
        s = c.command(code)
        check(s["result"] == 102 and s["state"] == SCANNING,
              "abort: %s while SCANNING refused with 102 (%d)" % (name, s["result"]))
    check(c.write(pc.WORD_ORDER, [1]) == 6, "abort: WORD_ORDER while SCANNING: exception 06")
    check(c.write(pc.COMMAND, [9, c.seq + 1]) == 3, "abort: command 9 while SCANNING: exception 03")
    s = c.command(ABORT)
    check(s["result"] == 0, "abort: ABORT accepted mid-scan (progress %d %%)" % s["progress"])
    s = c.wait_done(seq, 20)
    check(s["status"] & pc.READY and s["status"] & pc.ABORTED and not s["status"] & pc.ERROR and
          not s["status"] & pc.RESULTS, "abort: READY, ABORTED, no results (0x%x)" % s["status"])
    check(s["status"] & HOMED, "abort: a scan aborted keeps the reference")
    stage_stopped(simport, "abort")
    open(out, "w").write(newest_journal(resdir) + "\n")
    # Ready again: a small scan completes.
    region(c, 0, 0, 20, 20, 10)
    s = c.command(SCAN_FIT)
    s = c.wait_done(c.seq, 30)
    check(s["status"] & pc.RESULTS and pc.results(c)["points"] == 9, "abort: the next SCAN_FIT "
          "measures its 9 points")
    check(c.command(ACK_RESULTS)["result"] == 0, "abort: acknowledged")


def watchdog(port, simport):
    c = Cell(port)
    check(c.write(pc.WATCHDOG_MS, [300]) == 0, "watchdog: WATCHDOG_MS 300")
    for hb in range(1, 5):
        c.write(pc.HEARTBEAT, [hb])
        time.sleep(0.05)
    region(c, 0, 0, 200, 150, 2)
    s = c.command(SCAN)
    seq = c.seq
    check(s["result"] == 0, "watchdog: SCAN accepted, then the heartbeat stops")
    s = c.wait_done(seq, 20)
    check(s["state"] == pc.S_ERROR and s["error"] == 201 and s["status"] & pc.ABORTED,
          "watchdog: ERROR 201, ABORTED (state %d, error %d)" % (s["state"], s["error"]))
    check(s["progress"] < 100, "watchdog: tripped mid-scan (%d %%)" % s["progress"])
    stage_stopped(simport, "watchdog")
    s = c.command(RESET)
    check(s["result"] == 0 and s["state"] == pc.IDLE, "watchdog: RESET: IDLE")
    check(c.write(pc.WATCHDOG_MS, [0]) == 0, "watchdog: off again")


def fault(port, simport, ctl, kind, code):
    c = Cell(port)
    region(c, 0, 0, 200, 150, 2)
    s = c.command(SCAN_FIT)
    seq = c.seq
    wait_progress(c, 1)
    with open(ctl + ".tmp", "w") as f:
        f.write(kind + "\n")
    os.rename(ctl + ".tmp", ctl)
    s = c.wait_done(seq, 20)
    check(s["state"] == pc.S_ERROR and s["error"] == code and not s["status"] & HOMED,
          "%s: ERROR %d, reference lost (state %d, error %d, status 0x%x)" %
          (kind, code, s["state"], s["error"], s["status"]))
    if kind.startswith("estop"):
        with open(ctl + ".tmp", "w") as f:
            f.write("estop off\n")
        os.rename(ctl + ".tmp", ctl)
        time.sleep(0.3)
    s = c.command(RESET)
    check(s["result"] == 0 and s["state"] == pc.IDLE, "%s: RESET: IDLE" % kind)
    s = c.command(SCAN)
    check(s["result"] == 107, "%s: SCAN refused with 107 until homed" % kind)
    home(c, kind)
    region(c, 0, 0, 20, 20, 10)
    c.command(SCAN_FIT)
    s = c.wait_done(c.seq, 30)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR,
          "%s: the next SCAN_FIT succeeds" % kind)
    check(c.command(ACK_RESULTS)["result"] == 0, "%s: acknowledged" % kind)


def gone(port):
    c = Cell(port)
    t = time.time()
    while time.time() - t < 10 and c.status()["state"] != pc.S_ERROR:
        time.sleep(0.05)
    s = c.status()
    check(s["state"] == pc.S_ERROR and s["error"] == 203 and not s["status"] & RIG,
          "gone: cellsim killed: ERROR 203, RIG cleared (state %d, error %d, status 0x%x)" %
          (s["state"], s["error"], s["status"]))
    check(c.command(RESET)["result"] == 0, "gone: RESET accepted")
    check(c.command(HOME)["result"] == 106, "gone: HOME refused with 106 (no rig any more)")


def raw(port):
    s = socket.create_connection(("127.0.0.1", port), timeout=3)
    return s


def frame(tid, pdu, unit=1, proto=0, length=None):
    n = len(pdu) + 1 if length is None else length
    return struct.pack(">HHHB", tid, proto, n, unit) + pdu


def closed(s, wait=3.0):
    """1 when the server closed the connection (EOF) within wait s."""
    s.settimeout(wait)
    try:
        while True:
            d = s.recv(512)
            if not d:
                return True
    except (socket.timeout, TimeoutError):
        return False
    except OSError:
        return True


def garbage(port):
    c = Cell(port)
    hb0 = c.read(pc.CELL_HB, 1)[0]
    cases = [
        ("random bytes", os.urandom(64)),
        ("protocol id 7", frame(1, b"\x03\x00\x00\x00\x01", proto=7)),
        ("length 0", frame(1, b"", length=0)),
        ("length 1000", frame(1, b"\x03\x00\x00\x00\x01", length=1000)),
        ("length 0xFFFF", struct.pack(">HHH", 1, 0, 0xFFFF) + b"\x01" * 40),
    ]
    for name, b in cases:
        s = raw(port)
        s.sendall(b)
        check(closed(s), "garbage: %s: connection closed" % name)
        s.close()
    # Well-framed but wrong PDUs: exceptions, the connection stays.
    s = raw(port)
    for name, pdu, ex in (("function 0x2B", b"\x2b\x0e\x01\x00", 1),
                          ("read with 2 bytes", b"\x03\x00", 3),
                          ("write 16 count 200", b"\x10\x00\x3c\x00\xc8\x02\x00\x01", 3),
                          ("write 16 byte count lies", b"\x10\x00\x3c\x00\x02\x09\x00\x01\x00\x02", 3),
                          ("read 0 registers", b"\x03\x00\x00\x00\x00", 3),
                          ("read past the map", b"\x03\x00\xb0\x00\x10", 2)):
        s.sendall(frame(9, pdu))
        r = s.recv(64)
        check(len(r) == 9 and r[7] == pdu[0] | 0x80 and r[8] == ex and r[:2] == b"\x00\x09",
              "garbage: %s: exception %d, same transaction id" % (name, ex))
    # Two requests in one segment: two replies, in order.
    s.sendall(frame(21, b"\x03\x00\x00\x00\x01") + frame(22, b"\x03\x00\x01\x00\x01"))
    r = b""
    while len(r) < 22:
        r += s.recv(64)
    check(r[:2] == b"\x00\x15" and r[9:11] == b"\x43\x46" and r[11:13] == b"\x00\x16" and
          r[20:22] == b"\x00\x03", "garbage: two pipelined requests answered in order")
    s.close()
    # A truncated header and a half frame, then silence: closed after ~1 s,
    # while another client is served meanwhile.
    halves = [raw(port), raw(port)]
    halves[0].sendall(b"\x00\x01\x00")
    halves[1].sendall(frame(5, b"\x03\x00\x00\x00\x01")[:9])
    served = all(c.read(pc.MAGIC, 1)[0] == 17222 for _ in range(20))
    check(served, "garbage: others served while two clients stall")
    check(all(closed(h, 4) for h in halves), "garbage: stalled half frames closed")
    hb1 = c.read(pc.CELL_HB, 1)[0]
    check(hb1 != hb0, "garbage: the cell's heartbeat kept counting (%d -> %d)" % (hb0, hb1))
    check(c.read(pc.MAGIC, 1)[0] == 17222, "garbage: the server is alive")


def rate(port):
    c = Cell(port)
    other = Cell(port)
    exc = ok = 0
    for _ in range(300):
        r = c.c.read_holding_registers(0, 1, slave=1)
        if r.isError():
            exc += r.exception_code == 6
        else:
            ok += 1
    check(exc > 0 and ok > 0, "rate: 300 requests at once: %d served, %d exception 06" % (ok, exc))
    check(other.read(pc.MAGIC, 1)[0] == 17222, "rate: another client is not limited")
    time.sleep(1.1)
    check(c.read(pc.MAGIC, 1)[0] == 17222, "rate: served again after a pause")


def allow(port, want):
    s = raw(port)
    s.sendall(frame(1, b"\x03\x00\x00\x00\x01"))
    s.settimeout(3)
    try:
        r = s.recv(64)
    except OSError:
        r = b""
    got = len(r) == 11 and r[9:11] == b"\x43\x46"
    check(got == (want == "served"), "allow: 127.0.0.1 %s" % want)


if __name__ == "__main__":
    step, port, simport = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    a = sys.argv[4:]
    try:
        if step == "cycle":
            cycle(port, simport, a[0], a[1], a[2])
        elif step == "tolfit":
            tolfit(port, simport, a[0], int(a[1]), a[2])
        elif step == "otffit":
            otffit(port, simport, a[0], a[1], *a[2:3])
        elif step == "abort":
            abort(port, simport, a[0], a[1])
        elif step == "watchdog":
            watchdog(port, simport)
        elif step == "fault":
            fault(port, simport, a[0], a[1], int(a[2]))
        elif step == "gone":
            gone(port)
        elif step == "garbage":
            garbage(port)
        elif step == "rate":
            rate(port)
        elif step == "allow":
            allow(port, a[0])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
