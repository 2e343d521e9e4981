#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_cycle.py STEP PORT [ARGS]: a third-party Modbus TCP client
# (pymodbus) driving `cellfit serve` through its registers only, the way a
# PLC does (docs/plc-register-map.md). Prints "ok ..." / "FAIL ..." lines;
# tests/cli/plc.sh counts them. Steps: identity PORT; cycle PORT RESULTS_DIR
# NPOINTS MBPOLL [DIR_OUT]; abort PORT (invalid commands idle and busy, then
# an abort mid-job); watchdog PORT; net PORT; errors PORT folder|fit CODE;
# limit PORT MAX_CLIENTS MBPOLL. errors folder 1xx: the EXPORT refused. Run with /usr/bin/python3 (Debian's python3-pymodbus).
import glob
import json
import os
import struct
import subprocess
import sys
import time
import types

try:
    from pymodbus.client import ModbusTcpClient
except ModuleNotFoundError:
    # Debian's pymodbus 3.0 imports its serial client, which needs
    # serial_asyncio (python3-serial-asyncio), even for TCP: stand it in.
    _stub = types.ModuleType("serial_asyncio")
    _stub.create_serial_connection = None
    sys.modules["serial_asyncio"] = _stub
    from pymodbus.client import ModbusTcpClient

# Addresses and codes, as a PLC programmer copies them from the docs.
MAGIC, VERSION, TEST_F32, TEST_U32, WORD_ORDER = 0, 1, 2, 4, 7
COMMAND, HEARTBEAT, WATCHDOG_MS = 20, 22, 23
STATUS, ACK_SEQ, DONE_SEQ, STATE, PROGRESS, ERROR_CODE, CELL_HB, CMD_RESULT = range(40, 48)
PART, PROGRAM, FOLDER, TOL, NET_U = 60, 62, 63, 64, 70
RMS, MAX_DEV, MIN_DEV, WITHIN, VERDICT, RESULT_SEQ, POINTS, CPS, DURATION, RPART = (
    100, 102, 104, 106, 108, 109, 110, 112, 114, 116)
READY, BUSY, DONE, ERROR, RESULTS, ABORTED, REJECTED = 1, 2, 4, 8, 16, 32, 64
WD_ARMED = 512
HOME, SCAN, FIT, SCAN_FIT, ABORT, RESET, EXPORT, ACK_RESULTS = range(1, 9)
IDLE, FITTING, EXPORTING, S_ERROR = 0, 3, 4, 6

npass = nfail = 0


def check(cond, what):
    global npass, nfail
    if cond:
        npass += 1
        print("ok   " + what)
    else:
        nfail += 1
        print("FAIL " + what)
    sys.stdout.flush()
    return cond


class Cell:
    """The registers of one cell, 32-bit values in the word order chosen."""

    def __init__(self, port):
        self.c = ModbusTcpClient("127.0.0.1", port=port, timeout=5)
        if not self.c.connect():
            raise SystemExit("FAIL cannot connect to 127.0.0.1:%d" % port)
        self.order = self.read(WORD_ORDER, 1)[0]
        self.seq = self.read(ACK_SEQ, 1)[0]

    def read(self, addr, n):
        r = self.c.read_holding_registers(addr, n, slave=1)
        if r.isError():
            raise RuntimeError("read %d x %d: %s" % (addr, n, r))
        return r.registers

    def exc_read(self, addr, n):
        r = self.c.read_holding_registers(addr, n, slave=1)
        return r.exception_code if r.isError() else 0

    def write(self, addr, values):
        """0, or the Modbus exception code the cell answered with."""
        r = self.c.write_registers(addr, values, slave=1)
        return r.exception_code if r.isError() else 0

    def words(self, u32):
        lo, hi = u32 & 0xFFFF, u32 >> 16
        return [lo, hi] if self.order == 0 else [hi, lo]

    def u32(self, w):
        return w[0] | w[1] << 16 if self.order == 0 else w[0] << 16 | w[1]

    def f32(self, w):
        return struct.unpack("<f", struct.pack("<I", self.u32(w)))[0]

    def fwords(self, x):
        return self.words(struct.unpack("<I", struct.pack("<f", x))[0])

    def status(self):
        return dict(zip(("status", "ack", "done", "state", "progress", "error", "hb",
                         "result"), self.read(STATUS, 8)))

    def command(self, code):
        """Command and a new sequence in ONE request; wait for the echo."""
        self.seq = (self.seq % 65535) + 1
        ex = self.write(COMMAND, [code, self.seq])
        if ex:
            return {"exception": ex}
        t = time.time()
        while time.time() - t < 10:
            s = self.status()
            if s["ack"] == self.seq:
                return s
            time.sleep(0.01)
        raise RuntimeError("command %d seq %d never acknowledged" % (code, self.seq))

    def wait_done(self, seq, limit=120):
        t = time.time()
        while time.time() - t < limit:
            s = self.status()
            if s["done"] == seq and s["status"] & DONE and not s["status"] & BUSY:
                return s
            time.sleep(0.02)
        raise RuntimeError("job seq %d did not end in %d s" % (seq, limit))


def identity(port):
    c = Cell(port)
    r = c.read(0, 16)
    check(r[MAGIC] == 17222, "identity: magic 17222 (%d)" % r[MAGIC])
    check(r[VERSION] == 3, "identity: map version 3")
    name = b"".join(struct.pack(">H", w) for w in r[8:16]).rstrip(b"\0").decode()
    check(len(name) > 0, "identity: board name '%s'" % name)
    for order in (1 - c.order, c.order):
        check(c.write(WORD_ORDER, [order]) == 0, "identity: word order %d selected" % order)
        c.order = order
        r = c.read(0, 8)
        f, u = c.f32(r[TEST_F32:TEST_F32 + 2]), c.u32(r[TEST_U32:TEST_U32 + 2])
        check(abs(f - 123.456) < 1e-4, "identity: test float 123.456 in order %d (%r)" % (order, f))
        check(u == 305419896, "identity: test uint32 305419896 in order %d (%d)" % (order, u))
    # Out of range word order: exception 03, nothing changed.
    check(c.write(WORD_ORDER, [2]) == 3, "identity: word order 2 refused with exception 03")
    check(c.read(WORD_ORDER, 1)[0] == c.order, "identity: word order unchanged")


def results(c):
    r = c.read(100, 18)
    return {"rms": c.f32(r[0:2]), "max": c.f32(r[2:4]), "min": c.f32(r[4:6]),
            "within": c.f32(r[6:8]), "verdict": r[8], "seq": r[9], "points": c.u32(r[10:12]),
            "cps": c.u32(r[12:14]), "ms": c.u32(r[14:16]), "part": c.u32(r[16:18])}


def cycle(port, resdir, npoints, mbpoll):
    c = Cell(port)
    tol = 0.02
    ex = c.write(PART, c.words(4711) + [12, 0] + c.fwords(tol))
    check(ex == 0, "cycle: part 4711, program 12, folder 0, tolerance %g written" % tol)
    s = c.command(FIT)
    seq = c.seq
    check(s.get("result") == 0 and s["status"] & BUSY, "cycle: FIT seq %d accepted, BUSY" % seq)
    # A second client while the job runs: mbpoll reads identity and status.
    out = subprocess.run(["timeout", "10", mbpoll, "-m", "tcp", "-p", str(port), "-0", "-r", "0",
                          "-c", "4", "-1", "127.0.0.1"], capture_output=True, text=True).stdout
    check("[0]: \t17222" in out, "cycle: mbpoll reads the magic while pymodbus runs the job")
    out = subprocess.run(["timeout", "10", mbpoll, "-m", "tcp", "-p", str(port), "-0", "-r", "40",
                          "-c", "4", "-1", "127.0.0.1"], capture_output=True, text=True).stdout
    check("[41]: \t%d" % seq in out, "cycle: mbpoll sees ACK_SEQ %d" % seq)
    busy = c.status()
    s = c.wait_done(seq)
    check(busy["state"] in (FITTING, IDLE), "cycle: state FITTING while busy (%d)" % busy["state"])
    check(s["status"] & READY and s["status"] & RESULTS and not s["status"] & ERROR,
          "cycle: done, READY, RESULTS valid, no ERROR (status 0x%x)" % s["status"])
    check(s["progress"] == 100, "cycle: progress 100 %")
    res = results(c)
    check(res["seq"] == seq and res["part"] == 4711, "cycle: results of seq %d, part 4711" % seq)
    check(res["points"] == npoints, "cycle: %d points fitted (%d)" % (npoints, res["points"]))
    check(res["cps"] == 192, "cycle: 192 control points (%d)" % res["cps"])
    # The results agree with `cellfit report` run on the same fit (float32).
    check(res["rms"] > 0 and res["min"] <= 0 <= res["max"], "cycle: rms %.6g, min %.6g, max %.6g"
          % (res["rms"], res["min"], res["max"]))
    check(0 <= res["within"] <= 100 and res["verdict"] in (1, 2),
          "cycle: within %.2f %%, verdict %d" % (res["within"], res["verdict"]))
    # Latched: a new fit is refused until the results are acknowledged.
    s = c.command(FIT)
    check(s["result"] == 104 and s["status"] & REJECTED and s["state"] == IDLE,
          "cycle: FIT with results latched refused with 104, still IDLE")
    s = c.command(EXPORT)
    check(s["result"] == 0, "cycle: EXPORT accepted")
    s = c.wait_done(c.seq)
    check(not s["status"] & ERROR, "cycle: export done without error")
    dirs = glob.glob(os.path.join(resdir, "4711_*"))
    check(len(dirs) == 1 and os.path.isfile(os.path.join(dirs[0] if dirs else "", "fitted.igs")),
          "cycle: results folder %s with fitted.igs" % (dirs[0] if dirs else "?"))
    rep = {}
    if dirs and os.path.isfile(os.path.join(dirs[0], "report.json")):
        rep = json.load(open(os.path.join(dirs[0], "report.json")))
    check(rep.get("part") == 4711 and rep.get("points") == npoints,
          "cycle: report.json names part 4711 and %d points" % npoints)
    # The register results are the report's figures, to float32 rounding.
    ok = rep and all(abs(res[k] - rep[j]) <= 1e-6 * max(1.0, abs(rep[j])) for k, j in
                     (("rms", "rms"), ("max", "max"), ("min", "min"), ("within", "within_tol_pct")))
    check(ok, "cycle: registers match report.json (rms, max, min, within)")
    s = c.command(ACK_RESULTS)
    check(s["result"] == 0 and not s["status"] & RESULTS, "cycle: ACK_RESULTS clears RESULTS")
    check(results(c)["points"] == 0, "cycle: results block cleared")
    s = c.command(EXPORT)
    check(s["result"] == 105, "cycle: EXPORT without results refused with 105")
    return dirs[0] if dirs else ""


def invalid(port):
    c = Cell(port)
    s0 = c.status()
    check(s0["state"] == IDLE, "invalid: cell IDLE")
    for code, want, name in ((RESET, 109, "RESET"), (HOME, 106, "HOME"), (SCAN, 106, "SCAN"),
                             (SCAN_FIT, 106, "SCAN_FIT"), (EXPORT, 105, "EXPORT"),
                             (ACK_RESULTS, 105, "ACK_RESULTS")):
        s = c.command(code)
        check(s["result"] == want and s["status"] & REJECTED and s["state"] == IDLE,
              "invalid: %s in IDLE refused with %d (got %d), state unchanged" %
              (name, want, s["result"], ))
    seq = c.seq
    check(c.write(COMMAND, [FIT, seq]) == 0 and c.status()["ack"] == seq and
          c.status()["state"] == IDLE, "invalid: the same sequence again is ignored (no job)")
    check(c.write(COMMAND, [9, seq + 1]) == 3, "invalid: unknown command 9: exception 03")
    check(c.write(COMMAND, [0, seq + 1]) == 3, "invalid: command 0: exception 03")
    check(c.status()["ack"] == seq, "invalid: refused requests leave ACK_SEQ")
    check(c.write(COMMAND, [FIT]) == 2, "invalid: command without its sequence: exception 02")
    check(c.write(COMMAND + 1, [seq + 1]) == 2, "invalid: sequence alone: exception 02")
    check(c.write(MAGIC, [1]) == 2, "invalid: write to read-only MAGIC: exception 02")
    check(c.write(STATUS, [0]) == 2, "invalid: write to read-only STATUS: exception 02")
    check(c.write(RMS, [0, 0]) == 2, "invalid: write to read-only RMS: exception 02")
    check(c.write(30, [0]) == 2, "invalid: write to unmapped 30: exception 02")
    check(c.write(TOL, [0]) == 2, "invalid: half a float: exception 02")
    tol = c.read(TOL, 2)
    check(c.write(TOL, c.fwords(500.0)) == 3, "invalid: tolerance 500 mm: exception 03")
    check(c.write(TOL, c.words(0x7FC00000)) == 3, "invalid: tolerance NaN: exception 03")
    check(c.write(PART, c.words(100000000)) == 3, "invalid: part number 1e8: exception 03")
    check(c.write(NET_U, [2001]) == 3, "invalid: net 2001: exception 03")
    # A request with one bad value changes none of the others.
    check(c.write(TOL, c.fwords(0.5) + [0, 0, 0, 0, 0xFFFF]) == 3 and c.read(TOL, 2) == tol,
          "invalid: a request with one bad value stores nothing")
    check(c.exc_read(181, 2) == 2, "invalid: read past the map (182 registers): exception 02")
    r = c.c.read_input_registers(0, 16, slave=1)
    check(not r.isError() and r.registers == c.read(0, 16),
          "invalid: input registers (function 04) read as the holding registers")
    r = c.c.write_coil(0, True, slave=1)
    check(r.isError() and r.exception_code == 1, "invalid: write coil (function 05): exception 01")
    check(c.status()["state"] == IDLE, "invalid: still IDLE after all that")
    # Busy: every command but ABORT refused with 102.
    s = c.command(FIT)
    fit_seq = c.seq
    check(s["result"] == 0 and s["status"] & BUSY, "invalid: FIT accepted")
    for code, name in ((FIT, "FIT"), (HOME, "HOME"), (RESET, "RESET"), (EXPORT, "EXPORT"),
                       (ACK_RESULTS, "ACK_RESULTS"), (SCAN_FIT, "SCAN_FIT")):
        s = c.command(code)
        check(s["result"] == 102 and s["status"] & BUSY,
              "invalid: %s while busy refused with 102 (got %d), job still running" %
              (name, s["result"]))
    return c, fit_seq


def abort(port):
    c, seq = invalid(port)  # leaves a FIT running
    s = c.command(ABORT)
    check(s["result"] == 0, "abort: ABORT accepted mid-job")
    s = c.wait_done(seq, 30)
    check(s["status"] & READY and s["status"] & ABORTED and not s["status"] & RESULTS and
          not s["status"] & ERROR and s["state"] == IDLE,
          "abort: READY again, ABORTED, no results, no error (status 0x%x)" % s["status"])
    # Ready really: a full fit runs after the abort.
    s = c.command(FIT)
    s = c.wait_done(c.seq)
    check(s["status"] & RESULTS and not s["status"] & ERROR, "abort: the next FIT completes")
    check(c.command(ACK_RESULTS)["result"] == 0, "abort: results acknowledged")


def watchdog(port):
    c = Cell(port)
    check(c.write(WATCHDOG_MS, [300]) == 0, "watchdog: WATCHDOG_MS 300")
    for hb in range(1, 6):
        c.write(HEARTBEAT, [hb])
        time.sleep(0.05)
    check(c.status()["status"] & WD_ARMED, "watchdog: armed by the PLC heartbeat")
    s = c.command(FIT)
    check(s["result"] == 0, "watchdog: FIT accepted, heartbeat now stopped")
    seq = c.seq
    s = c.wait_done(seq, 60)
    check(s["state"] == S_ERROR and s["error"] == 201 and s["status"] & ERROR,
          "watchdog: trip: ERROR with code 201 (state %d, error %d)" % (s["state"], s["error"]))
    check(s["status"] & ABORTED and not s["status"] & RESULTS and not s["status"] & WD_ARMED,
          "watchdog: the job was aborted, no results, disarmed")
    hb = c.read(CELL_HB, 1)[0]
    time.sleep(0.3)
    check(c.read(CELL_HB, 1)[0] != hb, "watchdog: the cell's heartbeat keeps counting")
    check(c.command(FIT)["result"] == 103, "watchdog: FIT in ERROR refused with 103")
    s = c.command(RESET)
    check(s["result"] == 0 and s["state"] == IDLE and s["error"] == 0 and s["status"] & READY,
          "watchdog: RESET: IDLE, READY, error cleared")
    check(c.write(WATCHDOG_MS, [0]) == 0, "watchdog: off again")


def net(port):
    """NET_U x NET_V: refined nominal (more control points), or refused."""
    c = Cell(port)
    check(c.write(NET_U, [20, 16]) == 0, "net: 20 x 16 control points asked")
    s = c.command(FIT)
    check(s["result"] == 0, "net: FIT accepted")
    s = c.wait_done(c.seq)
    res = results(c)
    check(s["status"] & RESULTS and res["cps"] == 320,
          "net: fitted with 320 control points (%d)" % res["cps"])
    check(c.command(ACK_RESULTS)["result"] == 0, "net: acknowledged")
    c.write(NET_U, [10, 12])
    check(c.command(FIT)["result"] == 108, "net: 10 x 12, below the nominal's 16 x 12: 108")
    c.write(NET_U, [2000, 2000])
    check(c.command(FIT)["result"] == 110, "net: 2000 x 2000, beyond the budget: 110")
    check(c.write(NET_U, [0, 0]) == 0 and c.status()["state"] == IDLE, "net: back to the nominal's")


def errors(port, missing_folder, code):
    """A job error (3xx): ERROR with its code until RESET; results kept."""
    c = Cell(port)
    if missing_folder:
        c.write(FOLDER, [1])
        s = c.command(FIT)
        s = c.wait_done(c.seq)
        check(s["status"] & RESULTS, "errors: a fit to export")
        s = c.command(EXPORT)
        if code < 200:  # checked when accepted: refused, nothing started
            check(s["result"] == code and s["state"] == IDLE and s["status"] & RESULTS,
                  "errors: EXPORT to folder 1 refused with %d, IDLE, results kept (%s)"
                  % (code, s))
            c.write(FOLDER, [0])
            s = c.command(EXPORT)
            s = c.wait_done(c.seq)
            check(not s["status"] & ERROR, "errors: EXPORT to folder 0 then works")
            check(c.command(ACK_RESULTS)["result"] == 0, "errors: acknowledged")
            return
        check(s["result"] == 0, "errors: EXPORT to folder 1 accepted")
    else:
        s = c.command(FIT)
        check(s["result"] == 0, "errors: FIT accepted")
    s = c.wait_done(c.seq)
    check(s["state"] == S_ERROR and s["error"] == code and s["status"] & ERROR,
          "errors: ERROR %d (state %d, error %d)" % (code, s["state"], s["error"]))
    check(c.command(HOME)["result"] == 103, "errors: commands refused with 103 in ERROR")
    check(c.command(RESET)["result"] == 0 and c.status()["state"] == IDLE, "errors: RESET: IDLE")
    if missing_folder:
        check(c.status()["status"] & RESULTS, "errors: the results stay latched")
        c.write(FOLDER, [0])
        s = c.command(EXPORT)
        s = c.wait_done(c.seq)
        check(not s["status"] & ERROR, "errors: EXPORT to folder 0 then works")
        check(c.command(ACK_RESULTS)["result"] == 0, "errors: acknowledged")


def limit(port, nmax, mbpoll):
    """nmax clients connected: one more is served, the longest idle evicted."""
    cells = [Cell(port) for _ in range(nmax)]
    check(cells[0].read(49, 1)[0] == nmax, "limit: CLIENTS reads %d" % nmax)
    ev0 = cells[0].u32(cells[0].read(148, 2))
    for c in cells:  # cells[0] is now the longest idle
        c.read(MAGIC, 1)
        time.sleep(0.05)
    mb = ["timeout", "10", mbpoll, "-m", "tcp", "-p", str(port), "-0", "-r", "0", "-1", "127.0.0.1"]
    out = subprocess.run(mb, capture_output=True, text=True).stdout
    check("[0]: \t17222" in out, "limit: client %d served" % (nmax + 1))
    sk = cells[0].c.socket  # the socket itself: pymodbus would reconnect
    sk.settimeout(2)
    try:
        gone = sk.recv(1) == b""
    except OSError:
        gone = False
    check(gone, "limit: the longest idle client was evicted")
    check(all(c.read(MAGIC, 1)[0] == 17222 for c in cells[1:]),
          "limit: the %d others still served" % (nmax - 1))
    check(cells[1].u32(cells[1].read(148, 2)) == ev0 + 1, "limit: CONN_EVICTED counts it")


if __name__ == "__main__":
    step, port = sys.argv[1], int(sys.argv[2])
    try:
        if step == "identity":
            identity(port)
        elif step == "cycle":
            d = cycle(port, sys.argv[3], int(sys.argv[4]), sys.argv[5])
            if len(sys.argv) > 6:
                open(sys.argv[6], "w").write(d + "\n")
        elif step == "abort":
            abort(port)
        elif step == "watchdog":
            watchdog(port)
        elif step == "net":
            net(port)
        elif step == "errors":
            errors(port, sys.argv[3] == "folder", int(sys.argv[4]))
        elif step == "limit":
            limit(port, int(sys.argv[3]), sys.argv[4])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if nfail else 0)
