#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/faults.py CELLFIT [POWER_CUTS]: the fault-injection matrix and the
# power cuts of issue 7 (docs/reliability-faults.md), run by faults.sh.
#
# Matrix: every fault (cellsim's wire and device faults over Modbus TCP, a
# disk full while journalling, an unwritable output) x every phase of
# `cellfit scan` (homing with --home, scanning, fitting with --fit,
# exporting the fit and the report). Per cell: the job ends in a defined
# state (exit 0 when the HAL's retries recovered, else 1 with one line
# naming the cause and its code), the journal is consistent (read here by
# an independent parser: CRC-32, sequence, whole records), holds every
# acknowledged point, each grid point once and in plan order, a fit equals
# the fit replayed from the journal, and the next job on the same cellsim
# succeeds. One cellsim per row (fault), its faults armed through its
# control file at the start of each cell.
#
# Power cuts: `cellfit scan` killed with SIGKILL at seeded random moments;
# then the loss of the unsynced page cache is played on the file (cut at a
# seeded offset at or after the last acknowledged record, half the time
# zero-filled up to the old size, as a file system leaves unwritten
# blocks); `cellfit journal recover` must keep every acknowledged record,
# drop only the torn tail, and `cellfit journal fit` must fit what is left.
import json
import os
import random
import re
import resource
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zlib

signal.signal(signal.SIGTERM, lambda *a: sys.exit(1))  # timeout: the finally below stops cellsim
CF = os.path.realpath(sys.argv[1])
SIM = os.path.join(os.path.dirname(CF), "cellsim")
CUTS = int(sys.argv[2]) if len(sys.argv) > 2 else 25
T = tempfile.mkdtemp(prefix="cellfit-faults.")
os.environ["HAL_DEBUG"] = "1"  # the HAL says each retry: the table counts them
NOM = os.path.join(T, "part", "nominal.igs")
REGION, STEP = (0.0, 50.0, 0.0, 30.0), 10.0  # 6 x 4 = 24 points
passed = failed = 0
procs = []


def ok(name):
    global passed
    passed += 1
    print("ok   " + name, flush=True)


def no(name):
    global failed
    failed += 1
    print("FAIL " + name, flush=True)


def check(cond, name, detail=""):
    if cond:
        ok(name)
    else:
        no(name + (": " + detail if detail else ""))
    return cond


def run(args, timeout=60, limit=None, **kw):
    """Run a command; limit: RLIMIT_FSIZE in bytes (SIGXFSZ ignored, so a
    write past it fails with EFBIG as on a full file system)."""

    def pre():
        if limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, preexec_fn=pre, **kw)


def stop(p):
    if p.poll() is None:
        p.terminate()
        try:
            p.wait(2)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def plan():
    """The serpentine raster of scan.h, in scan order."""
    nx = int((REGION[1] - REGION[0]) / STEP + 1e-9) + 1
    ny = int((REGION[3] - REGION[2]) / STEP + 1e-9) + 1
    pts = []
    for k in range(nx * ny):
        j, i = divmod(k, nx)
        if j % 2:
            i = nx - 1 - i
        pts.append((REGION[0] + i * STEP, REGION[2] + j * STEP))
    return pts


PLAN = plan()


def parse_journal(path):
    """docs/journal.md read independently of jnl.c: the header (128 bytes,
    magic, CRC), then 80-byte records: CRC-32 over bytes 0..75 at 76, seq
    0, 1, 2 ... , type 1 (point) or 2 (end). Stops at the first record that
    fails: what follows is the torn tail."""
    with open(path, "rb") as f:
        b = f.read()
    if len(b) < 128 or struct.unpack_from("<I", b, 0)[0] != 0x314E4A43:
        return None
    if struct.unpack_from("<I", b, 124)[0] != zlib.crc32(b[:124]):
        return None
    out = {"records": 0, "points": 0, "flagged": 0, "ended": 0, "end_code": None, "synced": 0, "stages": []}
    off = 128
    while off + 80 <= len(b) and not out["ended"]:
        r = b[off:off + 80]
        seq, synced, typ, flags, code = struct.unpack_from("<IIHHi", r, 0)
        if struct.unpack_from("<I", r, 76)[0] != zlib.crc32(r[:76]) or seq != out["records"] or typ not in (1, 2):
            break
        out["synced"] = max(out["synced"], synced)
        if typ == 2:
            out["ended"], out["end_code"] = 1, code
        else:
            out["stages"].append(struct.unpack_from("<dd", r, 16))
            out["flagged" if flags & 1 else "points"] += 1
        out["records"] += 1
        off += 80
    out["tail_bytes"] = len(b) - off
    return out


def on_plan(stages):
    """Record k is grid point k (within the stage's 2 um): none twice,
    none skipped."""
    return len(stages) <= len(PLAN) and all(
        abs(s[0] - p[0]) <= 0.002 and abs(s[1] - p[1]) <= 0.002 for s, p in zip(stages, PLAN))


class Sim:
    """cellsim on Modbus TCP (127.0.0.1, a free port), or on Modbus RTU at
    115200 baud over a socat pty pair (stage and probe on one line)."""

    def __init__(self, name, *extra, homed=False, rtu=False):
        self.name = name
        self.ctl = os.path.join(T, name + ".ctl")
        self.err = os.path.join(T, name + ".sim.err")
        out = os.path.join(T, name + ".sim.out")
        wire = ["--tcp", "0"]
        if rtu:
            a, b, log = (os.path.join(T, name + x) for x in (".a", ".b", ".socat"))
            sp = subprocess.Popen(["socat", "-d", "-d", "pty,raw,echo=0,link=" + a, "pty,raw,echo=0,link=" + b],
                                  stderr=open(log, "w"))
            procs.append(sp)
            self.socat = sp
            for _ in range(200):
                with open(log) as f:
                    if "starting data transfer loop" in f.read():
                        break
                time.sleep(0.05)
            time.sleep(0.1)  # socat is ready about 100 ms after its line
            wire = ["--rtu", b]
        args = [SIM] + wire + ["--part", NOM, "--speed", "5000", "--verbose", "--control", self.ctl]
        args += ["--homed"] if homed else []
        self.p = subprocess.Popen(args + list(extra), stdout=open(out, "w"), stderr=open(self.err, "w"))
        procs.append(self.p)
        for _ in range(200):
            with open(out) as f:
                s = f.read()
            if "cellsim: ready" in s:
                break
            time.sleep(0.05)
        if rtu:
            self.stage, self.probe = ("rtu:%s:115200:8N1:%d" % (a, u) for u in (1, 2))
        else:
            port = int(s.split("cellsim: tcp 127.0.0.1 ")[1].split()[0])
            self.stage, self.probe = ("tcp:127.0.0.1:%d:%d" % (port, u) for u in (1, 2))

    def control(self, line, wait=True):
        """Write the control file (renamed into place: cellsim never reads
        half of it) and wait until cellsim has obeyed it (removed it)."""
        tmp = self.ctl + ".tmp"
        with open(tmp, "w") as f:
            f.write(line + "\n")
        os.rename(tmp, self.ctl)
        for _ in range(100):
            if not wait or not os.path.exists(self.ctl):
                return
            time.sleep(0.02)

    def fired(self):
        with open(self.err) as f:
            return f.read().count("cellsim: fault ")

    def rig(self, op):
        return run([CF, "rig", op, "--stage", self.stage, "--json"], timeout=30)

    def wait_line(self, secs=8):
        """The line is back (after a long disconnect)."""
        t = time.time() + secs
        while time.time() < t:
            if self.rig("status").returncode == 0:
                return True
            time.sleep(0.2)
        return False

    def stop(self):
        stop(self.p)
        if hasattr(self, "socat"):
            stop(self.socat)


jobs = 0


def scan(sim, extra=(), limit=None, at100=None, region=None, at_pct=100):
    """One job; at100: called when the scan has printed a progress line of
    at_pct % or more (100: the last reading is in, the job is fitting and
    exporting)."""
    global jobs
    jobs += 1
    jnl = os.path.join(T, "%s-%d.jnl" % (sim.name, jobs))
    args = [CF, "scan", "--stage", sim.stage, "--probe", sim.probe, "--nominal", NOM, "--journal", jnl,
            "--region", "%g:%g:%g:%g" % (region or REGION), "--step", str(STEP), "--home", "--json"] + list(extra)
    if at100 is None:
        r = run(args, limit=limit)
        return jnl, r.returncode, r.stdout, r.stderr
    errf = os.path.join(T, "job%d.err" % jobs)
    with open(errf, "w") as e:
        p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=e, text=True)
        procs.append(p)
        done = False
        while p.poll() is None and not done:
            with open(errf) as f:
                done = any(int(ln.split("(")[1].split("%")[0]) >= at_pct for ln in f if ln.startswith("scan: "))
            time.sleep(0.002)
        if done:
            at100()
        out = p.communicate(timeout=60)[0]
    with open(errf) as f:
        return jnl, p.returncode, out, f.read()


def mb_write(sim, addr, value):
    """Modbus TCP function 06 to the stage (unit 1), as a PLC or a panel
    would: cellsim's register 100 is its E-stop button."""
    import socket
    port = int(sim.stage.split(":")[2])
    with socket.create_connection(("127.0.0.1", port), timeout=5) as c:
        c.sendall(struct.pack(">HHHBBHH", 7, 0, 6, 1, 6, addr, value))
        c.recv(64)


def estop_row():
    """The E-stop pressed (cellsim's register 100) before homing, during the
    scan (at the 30% line), during the streamed fit, and when the last
    reading is in; released before the next job."""
    sim = Sim("estop")
    res = []
    cause = "emergency stop active"
    for ph in PHASES:
        tag = "e-stop x " + ph
        fit = os.path.join(T, "estop-%d.igs" % (jobs + 1)) if ph in ("fitting", "exporting") else None
        extra = ["--fit", fit] if fit else []
        press = lambda: mb_write(sim, 100, 1)  # noqa: E731
        if ph == "homing":
            press()
            jnl, rc, out, err = scan(sim)
            outc = judge(tag, jnl, rc, out, err, 1, -210, cause) + " (before motion)"
            st = summary(sim.rig("status").stdout)
            check(st.get("homed") == 0 and st.get("estop") == 1, tag + ": not homed, e-stop shown", str(st))
        elif ph in ("scanning", "fitting"):
            jnl, rc, out, err = scan(sim, extra, at100=press, at_pct=30)
            outc = judge(tag, jnl, rc, out, err, 1, -210, cause, fit=fit)
        else:
            jnl, rc, out, err = scan(sim, extra, at100=press)
            outc = judge(tag, jnl, rc, out, err, 0, 0, "", fit=fit)
            jnl, rc, out, err = scan(sim)
            outc += "; next job " + judge(tag + " (next job)", jnl, rc, out, err, 1, -210, cause)
        mb_write(sim, 100, 0)
        res.append(outc + "; released, " + next_job(sim, tag, 0))
    sim.stop()
    table.append(("e-stop", res))


def summary(out):
    try:
        return json.loads(out.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return {}


def fits_equal(a, b):
    ea = run([CF, "eval", a, os.path.join(T, "part", "check.uv")])
    eb = run([CF, "eval", b, os.path.join(T, "part", "check.uv")])
    return ea.returncode == 0 and ea.stdout == eb.stdout


def judge(tag, jnl, rc, out, err, want_rc, want_code, cause, fit=None):
    """The checks of one cell; returns the outcome for the table."""
    s = summary(out)
    lines = [ln for ln in err.splitlines() if ln.startswith("cellfit scan:")]
    good = check(rc == want_rc, tag + ": exit %d" % want_rc, "exit %d, %s" % (rc, err.strip()[-300:]))
    if want_rc == 1:
        good &= check(len(lines) == 1 and cause in lines[0] and ("[%d]" % want_code) in lines[0],
                      tag + ": one line, '%s' [%d]" % (cause, want_code), " | ".join(lines))
    if want_rc == 2:
        good &= check(len(lines) == 1 and cause in lines[0] and not os.path.exists(jnl),
                      tag + ": refused before the scan, one line, no journal", " | ".join(lines))
        return "2 refused" if good else "FAIL"
    if not os.path.exists(jnl):
        # Refused before the first record (the rig or the journal could not
        # be opened): nothing measured, no journal left behind.
        good &= check(rc == 1 and "nothing measured" in " ".join(lines), tag + ": nothing measured, no journal left",
                      " | ".join(lines))
        return ("1 %s before the job" % rig_name(want_code)) if good else "FAIL"
    j = parse_journal(jnl)
    info = summary(run([CF, "journal", "info", jnl, "--json"]).stdout)
    acked = s.get("acknowledged_records", 0)
    if not check(j is not None and info.get("records") == j["records"], tag + ": journal readable by both readers",
                 str(info)):
        return "FAIL"
    good &= check(j["tail_bytes"] == 0 and info.get("torn_tail") == 0, tag + ": no torn tail")
    good &= check(j["records"] >= acked and acked >= j["synced"],
                  tag + ": %d acknowledged records kept (%d in the journal)" % (acked, j["records"]),
                  "journal %d, acked %d, synced field %d" % (j["records"], acked, j["synced"]))
    good &= check(on_plan(j["stages"]) and len(j["stages"]) == s.get("done", -1),
                  tag + ": %d grid points, each once, in plan order" % len(j["stages"]),
                  "done %s" % s.get("done"))
    if want_code != -215:  # a full disk leaves no room for the end record
        good &= check(j["ended"] == 1 and j["end_code"] == want_code, tag + ": end record with code %d" % want_code,
                      "ended %d code %s" % (j["ended"], j["end_code"]))
    if fit is not None:
        replay = jnl + ".replay.igs"
        rf = run([CF, "journal", "fit", jnl, "--nominal", NOM, "--out", replay])
        good &= check(rf.returncode == 0, tag + ": journal fit of the acknowledged points", rf.stderr.strip())
        if rc == 0 and os.path.exists(fit):
            good &= check(fits_equal(fit, replay), tag + ": streamed fit = fit replayed from the journal")
        elif rc != 0:
            good &= check(not os.path.exists(fit), tag + ": no fit file left by the failed job")
    if not good:
        return "FAIL"
    if os.environ.get("FAULTS_SHOW"):
        print("     " + tag + ": " + " | ".join(ln for ln in err.splitlines() if ln.startswith("hal: ")))
    if rc == 0:
        n = err.count("hal: ")  # HAL_DEBUG: one line per retried request
        return "0" + (", %d retr%s" % (n, "y" if n == 1 else "ies") if n else "") + \
            (", %d flagged" % s.get("flagged", 0) if s.get("flagged") else "")
    return "1 %s" % rig_name(want_code)


NAMES = {-202: "ETIMEOUT", -205: "EEXCEPTION", -206: "EDISCONNECT", -209: "EFAULT", -210: "EESTOP", -215: "EFULL"}


def rig_name(code):
    return "RIG_" + NAMES.get(code, str(code))


def next_job(sim, tag, code):
    """The cell takes the next job: a latched drive fault is reset first
    (the drive refuses motion until then), a lost line is waited for."""
    note = ""
    if code == -209:
        r = sim.rig("reset")
        check(r.returncode == 0, tag + ": fault reset", r.stderr.strip())
        note = "reset, "
    if code == -206:
        check(sim.wait_line(), tag + ": line back")
        note = "line back, "
    jnl, rc, out, err = scan(sim, region=(0.0, 20.0, 0.0, 10.0))
    s = summary(out)
    good = check(rc == 0 and s.get("done") == 6, tag + ": next job takes the cell",
                 "exit %d %s" % (rc, err.strip()[-200:]))
    return note + ("next ok" if good else "next FAIL")


# Rows: fault name, cellsim spec (K filled per phase), per phase the K, the
# expected exit and code, and the cause the error line names. Requests:
# opening reads limits and range (2), preflight status (3), homing's
# status, counter, command, counter, polls (4..): K 6 is the home command.
# A grid point is about 9 requests: K 100 is near point 11 of 24.
# On TCP cellsim's crc and garble both flip the transaction id (TCP frames
# carry no checksum): one row; on RTU a flipped CRC bit and a changed data
# byte are two faults.
WIRE_OK = [("crc (RTU)", "crc:n%d"), ("garble (RTU)", "garble:n%d"), ("drop (RTU)", "drop:n%d"),
           ("disconnect 0.5 s (RTU)", "disconnect:n%d:500"), ("crc/garble (TCP)", "crc:n%d"),
           ("drop (TCP)", "drop:n%d"), ("slow 600 ms", "slow:n%d:600"), ("silent", "silent:n%d"),
           ("busy", "busy:n%d"), ("disconnect 0.5 s", "disconnect:n%d:500")]


def row_cells(name):
    """(phase -> (spec K, want rc, want code, cause)) for a row."""
    if name == "disconnect 4 s":
        c = (1, -206, "line or connection lost")
        return {"homing": (6,) + c, "scanning": (100,) + c, "fitting": (100,) + c, "exporting": (1, 0, 0, "")}
    if name == "probe out of range":
        return {"homing": None, "scanning": (10, 0, 0, ""), "fitting": (10, 0, 0, ""), "exporting": (1, 0, 0, "")}
    if name == "probe error":
        c = (1, -205, "device refused the request")
        return {"homing": None, "scanning": (10,) + c, "fitting": (10,) + c, "exporting": (1, 0, 0, "")}
    if name == "stage fault":
        c = (1, -209, "stage drive fault")
        return {"homing": (1,) + c, "scanning": (10,) + c, "fitting": (10,) + c, "exporting": (1, 0, 0, "")}
    return {"homing": (6, 0, 0, ""), "scanning": (100, 0, 0, ""), "fitting": (100, 0, 0, ""),
            "exporting": (1, 0, 0, "")}


ROWS = WIRE_OK + [("disconnect 4 s", "disconnect:n%d:4000"), ("probe out of range", "nosurf:n%d"),
                  ("probe error", "proberr:n%d"), ("stage fault", "stagefault:n%d")]
PHASES = ["homing", "scanning", "fitting", "exporting"]
table = []


def device_row(name, spec):
    sim = Sim(name.split()[0].replace("/", "") + str(len(table)), rtu="RTU" in name)
    cells = row_cells(name)
    res = []
    for ph in PHASES:
        c = cells[ph]
        tag = "%s x %s" % (name, ph)
        if c is None:
            res.append("n/a")
            continue
        k, want_rc, code, cause = c
        before = sim.fired()
        fit = os.path.join(T, "%s-%d.igs" % (sim.name, jobs + 1)) if ph in ("fitting", "exporting") else None
        extra = ["--fit", fit] if fit else []
        if ph == "exporting":
            # Armed when the last reading is in: the fit and the report are
            # written without the rig; the next job meets the fault.
            rep = fit + ".json"
            arm = (lambda: sim.control("stagefault")) if name == "stage fault" else \
                (lambda: sim.control("fault " + spec % k))
            jnl, rc, out, err = scan(sim, extra + ["--report", rep], at100=arm)
            outc = judge(tag, jnl, rc, out, err, 0, 0, "", fit=fit)
            check(os.path.exists(rep) and summary(open(rep).read()).get("done") == len(PLAN), tag + ": report written")
            # The next job meets the pending fault: it ends as the scanning
            # cell says (the first request, reading or move).
            jnl2, rc2, out2, err2 = scan(sim)
            want = {"disconnect 4 s": (1, -206, "line or connection lost"), "probe error":
                    (1, -205, "device refused the request"), "stage fault": (1, -209, "stage drive fault")}
            w = want.get(name, (0, 0, ""))
            if name == "disconnect 4 s":
                w = (1, -206, "lost")  # refused at opening the line: "line lost, reopening failed"
            o2 = judge(tag + " (next job)", jnl2, rc2, out2, err2, w[0], w[1], w[2])
            if name != "stage fault":  # latched at once, not counted: the next job's EFAULT shows it
                check(sim.fired() > before, tag + ": the fault fired (cellsim's log)")
            outc += "; next job " + o2
            if w[0]:
                outc += "; " + next_job(sim, tag, w[1])
            res.append(outc)
            continue
        sim.control("fault " + spec % k)
        jnl, rc, out, err = scan(sim, extra)
        outc = judge(tag, jnl, rc, out, err, want_rc, code, cause, fit=fit)
        check(sim.fired() > before, tag + ": the fault fired (cellsim's log)")
        if ph == "homing" and rc == 0:
            check("unit 1: writing 1 register at 4:" in err or "slave 1: writing 1 register at 4:" in err,
                  tag + ": the home command was the request retried", err.strip()[-300:])
        if name == "stage fault" and ph == "homing":
            st = summary(sim.rig("status").stdout)
            check(st.get("fault") == 1 and st.get("homed") == 0, tag + ": drive fault latched, not homed", str(st))
        outc += "; " + next_job(sim, tag, code)
        res.append(outc)
    sim.stop()
    table.append((name, res))


def disk_row():
    """A full disk (RLIMIT_FSIZE: EFBIG, as ENOSPC -> RIG_EFULL) and
    /dev/full for the report."""
    sim = Sim("disk")
    res = []
    # homing: the header cannot be written: refused before any motion.
    jnl, rc, out, err = scan(sim, limit=64)
    outc = judge("disk full x homing", jnl, rc, out, err, 1, -215, "storage full")
    st = summary(sim.rig("status").stdout)
    check(st.get("homed") == 0 and st.get("x") == 37.5, "disk full x homing: the stage did not move", str(st))
    res.append(outc + " (before motion); " + next_job(sim, "disk full x homing", 0))
    # scanning: room for the header and 15 records; the 16th is cut.
    lim = 128 + 15 * 80 + 40
    jnl, rc, out, err = scan(sim, limit=lim)
    outc = judge("disk full x scanning", jnl, rc, out, err, 1, -215, "storage full")
    j = parse_journal(jnl)
    check(j and j["records"] == 15 and os.path.getsize(jnl) == 128 + 15 * 80,
          "disk full x scanning: the torn 16th record cut, 15 whole records left")
    res.append(outc + "; " + next_job(sim, "disk full x scanning", 0))
    # fitting: the journal fits, the surface (about 100 KB) does not.
    fit = os.path.join(T, "disk-fit.igs")
    jnl, rc, out, err = scan(sim, ["--fit", fit], limit=16384)
    lines = [ln for ln in err.splitlines() if ln.startswith("cellfit scan:")]
    good = check(rc == 1 and len(lines) == 1 and fit in lines[0] and "File too large" in lines[0],
                 "disk full x fitting: exit 1, one line naming the fit file", err.strip()[-300:])
    j = parse_journal(jnl)
    good &= check(j and j["ended"] and j["end_code"] == 0 and j["points"] == len(PLAN) and not os.path.exists(fit),
                  "disk full x fitting: journal complete and ended 0, no partial fit file")
    rf = run([CF, "journal", "fit", jnl, "--nominal", NOM, "--out", fit + ".replay"])
    good &= check(rf.returncode == 0, "disk full x fitting: the fit is re-run from the journal")
    res.append(("1 EFBIG, journal ended 0" if good else "FAIL") + "; " + next_job(sim, "disk full x fitting", 0))
    # exporting: the report goes to a full device.
    fit = os.path.join(T, "disk-exp.igs")
    jnl, rc, out, err = scan(sim, ["--fit", fit, "--report", "/dev/full"])
    lines = [ln for ln in err.splitlines() if ln.startswith("cellfit scan:")]
    good = check(rc == 1 and len(lines) == 1 and "/dev/full" in lines[0] and "No space" in lines[0],
                 "disk full x exporting: exit 1, one line naming the report", err.strip()[-300:])
    j = parse_journal(jnl)
    good &= check(j and j["ended"] and j["end_code"] == 0 and os.path.exists(fit),
                  "disk full x exporting: journal ended 0, the fit written")
    res.append(("1 ENOSPC, fit kept" if good else "FAIL") + "; " + next_job(sim, "disk full x exporting", 0))
    table.append(("disk full", res))
    # An output nobody can write: refused before the job moves anything.
    res = ["n/a", "n/a"]
    for ph, opt in (("fitting", "--fit"), ("exporting", "--report")):
        jnl, rc, out, err = scan(sim, [opt, os.path.join(T, "no-such-dir", "out")])
        res.append(judge("unwritable output x " + ph, jnl, rc, out, err, 2, 0, "no-such-dir") + "; " +
                   next_job(sim, "unwritable output x " + ph, 0))
    table.append(("unwritable output", res))
    sim.stop()


def power_cuts(n):
    """n kills of `cellfit scan` at seeded random moments."""
    sim = Sim("cut", homed=True)
    rng = random.Random(7)
    global REGION, PLAN
    REGION, PLAN = (0.0, 100.0, 0.0, 50.0), None
    PLAN = plan()  # 11 x 6 = 66 points, synced at each row end
    kept_all = acked_all = dropped = torn = early = 0
    bad = []
    for i in range(n):
        jnl = os.path.join(T, "cut%d.jnl" % i)
        args = [CF, "scan", "--stage", sim.stage, "--probe", sim.probe, "--nominal", NOM, "--journal", jnl,
                "--region", "%g:%g:%g:%g" % REGION, "--step", str(STEP)]
        errf = os.path.join(T, "cut%d.err" % i)
        with open(errf, "w") as e:
            p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=e)
            procs.append(p)
            time.sleep(rng.uniform(0.0, 0.45))
            p.kill()
            p.wait()
        with open(errf) as f:
            said = [int(m.group(1)) for m in re.finditer(r"^scan: .*, (\d+) acknowledged$", f.read(), re.M)]
        if not os.path.exists(jnl) or os.path.getsize(jnl) < 128:
            early += 1  # killed before the header was durable: nothing promised
            continue
        j = parse_journal(jnl)
        if j is None:
            bad.append("run %d: header unreadable" % i)
            continue
        acked = max([j["synced"]] + said)
        # The power cut: what was not synced may be lost, from any byte on.
        size = os.path.getsize(jnl)
        cut = rng.randint(128 + acked * 80, size)
        with open(jnl, "r+b") as f:
            f.truncate(cut)
            if i % 2 and size > cut:
                f.seek(cut)
                f.write(bytes(size - cut))  # blocks allocated, never written
        whole = (cut - 128) // 80
        info = summary(run([CF, "journal", "info", jnl, "--json"]).stdout)
        tb = info.get("torn_tail_bytes", -1)
        want_tb = (size if i % 2 else cut) - (128 + whole * 80)
        r = run([CF, "journal", "recover", jnl])
        j2 = parse_journal(jnl)
        kept = j2["records"] if j2 else -1
        if r.returncode or kept != whole or kept < acked or os.path.getsize(jnl) != 128 + kept * 80 or \
                tb != want_tb or \
                not on_plan(j2["stages"]):
            bad.append("run %d: acked %d, cut at %d of %d, kept %d, tail %d: %s" %
                       (i, acked, cut, size, kept, tb, r.stderr.strip()))
            continue
        torn += tb > 0
        kept_all += kept
        acked_all += acked
        dropped += (size - 128) // 80 - kept
        if j2["points"] > 0:
            rf = run([CF, "journal", "fit", jnl, "--nominal", NOM, "--out", jnl + ".igs", "--json"])
            if rf.returncode or summary(rf.stdout).get("points") != j2["points"]:
                bad.append("run %d: journal fit after recovery: %s" % (i, rf.stderr.strip()))
    sim.stop()
    for b in bad:
        print("     " + b)
    check(not bad, "power cut x %d: every acknowledged record kept, only the torn tail dropped, fit works" % n)
    print("power cuts: %d kills (%d before the header was durable), %d acknowledged records, %d kept, "
          "%d unsynced records lost, %d torn tails cut" % (n, early, acked_all, kept_all, dropped, torn))


class Plc:
    """A PLC on Modbus TCP (functions 03 and 16), word order 0 (low word
    first), as docs/plc-register-map.md describes the handshake."""

    def __init__(self, port):
        import socket
        self.s = socket.create_connection(("127.0.0.1", port), timeout=10)
        self.tid = 0
        self.seq = 0

    def _recv(self, n):
        b = b""
        while len(b) < n:
            c = self.s.recv(n - len(b))
            if not c:
                raise IOError("cell closed the connection")
            b += c
        return b

    def _req(self, pdu):
        self.tid = (self.tid + 1) & 0xFFFF
        self.s.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, 1) + pdu)
        tid, _, ln, _ = struct.unpack(">HHHB", self._recv(7))
        body = self._recv(ln - 1)
        if body[0] & 0x80:
            raise IOError("exception %d" % body[1])
        return body

    def read(self, addr, n=1):
        body = self._req(struct.pack(">BHH", 3, addr, n))
        return list(struct.unpack(">%dH" % n, body[2:2 + 2 * n]))

    def write(self, addr, regs):
        self._req(struct.pack(">BHHB", 16, addr, len(regs), 2 * len(regs)) + struct.pack(">%dH" % len(regs), *regs))

    def region(self, x0, y0, x1, y1, step):
        regs = []
        for v in (x0, y0, x1, y1, step):
            u = struct.unpack(">I", struct.pack(">f", v))[0]
            regs += [u & 0xFFFF, u >> 16]
        self.write(72, regs)

    def job(self, code, secs=60):
        """Command, acknowledged, ended: (CMD_RESULT, STATE, ERROR_CODE)."""
        self.seq = self.seq % 65535 + 1
        self.write(20, [code, self.seq])
        t = time.time() + secs
        while time.time() < t:
            st, ack, done, state, _, err, _, res = self.read(40, 8)
            if ack == self.seq and res:
                return res, state, err
            if ack == self.seq and (code not in (1, 2, 3, 4, 7) or done == self.seq and not st & 2):
                return 0, state, err  # RESET, ABORT, ACK_RESULTS: taken is done
            time.sleep(0.01)
        return -1, -1, -1


def plc_codes():
    """PLC_E_* from firmware/plc_err.h (the names the mapping is stated in)."""
    src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "firmware", "plc_err.h")
    with open(src) as f:
        return {m.group(1): int(m.group(2)) for m in re.finditer(r"(PLC_E_\w+) = (\d+)", f.read())}


def serve_has_rig():
    r = run([CF, "serve", "--plc", "tcp:127.0.0.1:0", "--stage", "x"], timeout=10)
    return "needs both --stage URI and --probe URI" in r.stderr


def plc_column():
    """The scanning column as the PLC sees it: `cellfit serve` on the rig,
    a PLC client homing and scanning, each fault armed before its SCAN; the
    code in ERROR_CODE, then RESET, HOME, and the next SCAN must end clean."""
    pc = plc_codes()
    want = {0: 0, -206: pc.get("PLC_E_RIG_LINK"), -205: pc.get("PLC_E_PROBE"), -209: pc.get("PLC_E_STAGE"),
            -210: pc.get("PLC_E_ESTOP", pc.get("PLC_E_STAGE")), -215: pc.get("PLC_E_RIG")}
    names = {v: k for k, v in pc.items()}
    col = {}

    def serve(sim, tag, limit=None):
        jd = os.path.join(T, "plc-" + tag)
        os.mkdir(jd)
        pf = os.path.join(jd, "port")

        def pre():
            if limit is not None:
                signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
                resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

        p = subprocess.Popen([CF, "serve", "--plc", "tcp:127.0.0.1:0", "--port-file", pf, "--stage", sim.stage,
                              "--probe", sim.probe, "--nominal", NOM, "--journal-dir", jd, "--watchdog-ms", "0"],
                             stdout=subprocess.DEVNULL, stderr=open(jd + ".log", "w"), preexec_fn=pre)
        procs.append(p)
        for _ in range(200):
            if os.path.exists(pf) and open(pf).read().strip():
                break
            time.sleep(0.05)
        plc = Plc(int(open(pf).read().split()[0]))
        plc.region(REGION[0], REGION[2], REGION[1], REGION[3], STEP)
        return p, plc, jd

    def cell(plc, jd, tag, code, after_error=None):
        before = set(os.listdir(jd))
        res, state, err = plc.job(2)
        w = want[code]
        new = sorted(set(os.listdir(jd)) - before)
        jn = [os.path.join(jd, n) for n in new if n.endswith(".jnl")]
        j = parse_journal(jn[0]) if jn else None
        good = check(res == 0 and err == w and state == (6 if w else 0),
                     "plc %s: SCAN ends with ERROR_CODE %s (%s)" % (tag, w, names.get(w, "none")),
                     "CMD_RESULT %d, STATE %d, ERROR_CODE %d" % (res, state, err))
        good &= check(j is not None and j["tail_bytes"] == 0 and on_plan(j["stages"]) and
                      (code == -215 or (j["ended"] and j["end_code"] == code)),
                      "plc %s: its journal consistent, ended %d" % (tag, code), str(j and {k: j[k] for k in j if k != "stages"}))
        if w:
            if after_error:
                after_error()
            r1 = plc.job(6)
            r2 = plc.job(1)
            good &= check(r1[:2] == (0, 0) and r2 == (0, 0, 0), "plc %s: RESET, HOME" % tag, "%s %s" % (r1, r2))
        return ("%d %s" % (err, names.get(err, "")) if err else "0") if good else "FAIL"

    sim = Sim("plc", homed=False)
    p, plc, jd = serve(sim, "tcp")
    check(plc.job(1) == (0, 0, 0), "plc: HOME")
    for name, spec in ROWS:
        if "RTU" in name:
            continue
        c = row_cells(name)["scanning"]
        k, _, code, _ = c
        before = sim.fired()
        sim.control("fault " + spec % k)
        after = (lambda: sim.wait_line()) if code == -206 else None
        col[name] = cell(plc, jd, name, code, after)
        check(sim.fired() > before, "plc %s: the fault fired (cellsim's log)" % name)
        r = plc.job(2)  # the cell takes the next job
        check(r == (0, 0, 0), "plc %s: next SCAN clean" % name, str(r))
    # E-stop pressed mid-scan (at 30 % PROGRESS), released, RESET, HOME.
    plc.seq = plc.seq % 65535 + 1
    plc.write(20, [2, plc.seq])
    t = time.time() + 30
    while time.time() < t and plc.read(44)[0] < 30:
        time.sleep(0.002)
    mb_write(sim, 100, 1)
    while time.time() < t and plc.read(42)[0] != plc.seq:
        time.sleep(0.01)
    st, _, _, state, _, err, _, _ = plc.read(40, 8)
    mb_write(sim, 100, 0)
    w = want[-210]
    good = check(state == 6 and err == w, "plc e-stop: SCAN ends with ERROR_CODE %s" % w, "STATE %d ERROR_CODE %d" % (state, err))
    r1, r2, r3 = plc.job(6), plc.job(1), plc.job(2)
    good &= check(r1[:2] == (0, 0) and r2 == (0, 0, 0) and r3 == (0, 0, 0), "plc e-stop: RESET, HOME, next SCAN",
                  "%s %s %s" % (r1, r2, r3))
    col["e-stop"] = ("%d %s" % (err, names.get(err, ""))) if good else "FAIL"
    stop(p)
    sim.stop()
    # A full disk under the cell's journal: 15 records fit, the 16th not.
    sim = Sim("plcdisk")
    p, plc, jd = serve(sim, "disk", limit=128 + 15 * 80 + 40)
    check(plc.job(1) == (0, 0, 0), "plc disk full: HOME")
    col["disk full"] = cell(plc, jd, "disk full", -215)
    plc.region(0, 0, 20, 10, STEP)  # a job of 6 points fits
    r = plc.job(2)
    check(r == (0, 0, 0), "plc disk full: next (smaller) SCAN clean", str(r))
    stop(p)
    sim.stop()
    return col


def main():
    t0 = time.time()
    r = run([CF, "gen", "--dir", os.path.join(T, "part"), "--nu", "40", "--nv", "30", "--count", "1000"])
    if r.returncode:
        no("gen: " + r.stderr)
        return
    only = os.environ.get("FAULTS_ONLY")
    for name, spec in ROWS:
        if not only or only in name:
            t = time.time()
            device_row(name, spec)
            print("row %s: %.1f s" % (name, time.time() - t))
    if not only or only == "e-stop":
        estop_row()
    if not only or only == "disk":
        disk_row()
    col = None
    if not only or only == "plc":
        if serve_has_rig():
            t = time.time()
            col = plc_column()
            print("plc column: %.1f s" % (time.time() - t))
        else:
            print("skip plc column: this cellfit serve has no --stage/--probe")
    w = max([len(n) for n, _ in table] + [5])
    print("\nfault matrix (exit and code; then the next job on the same cellsim)")
    print("| %-*s | %s |%s" % (w, "fault", " | ".join(PHASES), " PLC: ERROR_CODE after SCAN |" if col else ""))
    print("|%s|%s%s" % ("-" * (w + 2), "---|" * len(PHASES), "---|" if col else ""))
    for name, res in table:
        extra = (" %s |" % col.get(name, "(TCP rows)" if "RTU" in name else "n/a")) if col else ""
        print("| %-*s | %s |%s" % (w, name, " | ".join(res), extra))
    print("matrix: %d jobs in %.1f s" % (jobs, time.time() - t0))
    if CUTS > 0 and (not only or only == "cut"):
        t1 = time.time()
        power_cuts(CUTS)
        print("power cuts: %.1f s" % (time.time() - t1))


try:
    main()
finally:
    for p in procs:
        stop(p)
    subprocess.run(["rm", "-rf", T])
print("faults: %d passed, %d failed" % (passed, failed))
sys.exit(1 if failed else 0)
