#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_v2.py STEP PORT [ARGS]: the registers of map version 2 as a
# job uses them, driven by pymodbus like a PLC (docs/plc-register-map.md):
# the fit settings, RECIPE, FIT_STATUS, PART_ID and JOB_TIME in report.json,
# exports that never overwrite, WD_ARMED, the idle timeout. Prints "ok ..."
# / "FAIL ..." lines; tests/cli/plc_v2.sh counts them. Steps:
# export2 PORT RESDIR; recipe PORT RESDIR NOMINAL2; fitset PORT NCP;
# defaults PORT TOL WITHIN MAXCP REFINE ROBUST REPARAM; partid PORT RESDIR;
# wdarm PORT; idle PORT MS; gonescan PORT SIMPID.
import glob
import json
import os
import re
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the Cell class, register addresses, check)
from plc_cycle import check, Cell  # noqa: E402

FIT, EXPORT, ACK_RESULTS = 3, 7, 8
FIT_TOL, FIT_WITHIN, FIT_MAX_CP, FIT_REFINE, FIT_ROBUST, FIT_REPARAM, RECIPE = (
    82, 84, 86, 88, 89, 90, 91)
JOB_TIME, FIT_STATUS, PART_ID = 118, 120, 124
UUID = r"[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}"


def fit(c, what):
    """FIT, waited for: the done status (RESULTS expected)."""
    s = c.command(FIT)
    if not check(s.get("result") == 0, "%s: FIT seq %d accepted (%s)" % (what, c.seq, s)):
        return s
    s = c.wait_done(c.seq)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR,
          "%s: FIT done with results (status 0x%x, error %d)" % (what, s["status"], s["error"]))
    return s


def export(c, what):
    s = c.command(EXPORT)
    check(s.get("result") == 0, "%s: EXPORT seq %d accepted" % (what, c.seq))
    s = c.wait_done(c.seq)
    check(not s["status"] & pc.ERROR, "%s: EXPORT done without error (%d)" % (what, s["error"]))
    return c.seq


def ack(c):
    c.command(ACK_RESULTS)


def folders(resdir, part):
    return sorted(d for d in glob.glob(os.path.join(resdir, "%d_*" % part)) if os.path.isdir(d))


def report(d):
    try:
        return json.load(open(os.path.join(d, "report.json")))
    except (OSError, ValueError):
        return {}


def export2(port, resdir):
    """Two exports of one part within one second: two folders, each whole."""
    c = Cell(port)
    c.write(pc.PART, c.words(4712) + [1, 0] + c.fwords(0.05))
    fit(c, "export2")
    job = c.seq
    t0 = time.time()
    e1 = export(c, "export2")
    e2 = export(c, "export2")
    dt = time.time() - t0
    check(dt < 1.0, "export2: both exports within one second (%.3f s)" % dt)
    ds = folders(resdir, 4712)
    check(len(ds) == 2, "export2: two folders (%d: %s)" % (len(ds), [os.path.basename(d) for d in ds]))
    seqs = set()
    for d in ds:
        name = os.path.basename(d)
        check(re.fullmatch(r"4712_\d{8}T\d{6}Z_%d_%s" % (job, UUID), name) is not None,
              "export2: %s names part, UTC, the job's sequence %d and a UUID" % (name, job))
        check(os.path.getsize(os.path.join(d, "fitted.igs")) > 0, "export2: %s/fitted.igs" % name)
        r = report(d)
        check(r.get("part") == 4712 and r.get("seq") == job,
              "export2: %s/report.json: part 4712, seq %s (the job's %d)" % (name, r.get("seq"), job))
        seqs.add(r.get("export_seq"))
    check(seqs == {e1, e2}, "export2: the reports name exports %d and %d (%s)" % (e1, e2, seqs))
    left = [n for n in os.listdir(resdir) if n.startswith(".")]
    check(not left, "export2: no temporary folder left (%s)" % left)
    ack(c)


def recipe(port, resdir, nominal2):
    """RECIPE N uses nominal.N; one not configured is refused with 114."""
    c = Cell(port)
    c.write(pc.PART, c.words(4713) + [1, 0] + c.fwords(0.05))
    check(c.write(RECIPE, [3]) == 0, "recipe: RECIPE 3 written")
    s = c.command(FIT)
    check(s.get("result") == 114 and s["state"] == pc.IDLE,
          "recipe: FIT with RECIPE 3 (not configured) refused with 114 (%s)" % s.get("result"))
    c.write(RECIPE, [0])
    check(c.write(FIT_MAX_CP, c.words(2000000)) == 0, "recipe: FIT_MAX_CP 2000000 written")
    s = c.command(FIT)
    check(s.get("result") == 110, "recipe: FIT_MAX_CP beyond the board's refused with 110 (%s)"
          % s.get("result"))
    c.write(FIT_MAX_CP, c.words(0))
    c.write(RECIPE, [2])
    fit(c, "recipe")
    export(c, "recipe")
    ds = folders(resdir, 4713)
    r = report(ds[-1]) if ds else {}
    check(r.get("nominal") == nominal2, "recipe: report.json names nominal.2 (%s)" % r.get("nominal"))
    ack(c)
    c.write(RECIPE, [0])


def fitset(port, ncp):
    """FIT_TOL > 0 runs the loop; FIT_STATUS says how it ended."""
    c = Cell(port)
    c.write(pc.PART, c.words(4714) + [1, 0] + c.fwords(0.05))
    # No loop: FIT_STATUS 0; the plain fit's figures at TOLERANCE.
    c.write(FIT_TOL, c.fwords(0.0))
    fit(c, "fitset")
    r0 = pc.results(c)
    check(c.read(FIT_STATUS, 1)[0] == 0 and r0["cps"] == ncp,
          "fitset: FIT_TOL 0: FIT_STATUS 0, the nominal's %d control points" % ncp)
    ack(c)
    # FIT_TOL = TOLERANCE, 100 %: met means every point within TOLERANCE.
    c.write(FIT_TOL, c.fwords(0.05))
    c.write(FIT_WITHIN, c.fwords(100.0))
    fit(c, "fitset")
    r = pc.results(c)
    st = c.read(FIT_STATUS, 1)[0]
    check(st == 1 and r["within"] == 100.0 and r["verdict"] == 1 and r["cps"] >= ncp,
          "fitset: FIT_TOL 0.05: FIT_STATUS 1 met (%d), WITHIN_PCT 100 (%.2f), pass, %d control "
          "points" % (st, r["within"], r["cps"]))
    ack(c)
    # 0.0001 mm is below the noise: not met; with FIT_MAX_CP the nominal's
    # net no refinement is allowed: 3 (max control points), and the fit is
    # the plain one, whose figures at TOLERANCE the registers show.
    c.write(FIT_TOL, c.fwords(0.0001))
    c.write(FIT_MAX_CP, c.words(ncp))
    fit(c, "fitset")
    r = pc.results(c)
    st = c.read(FIT_STATUS, 1)[0]
    check(st == 3 and r["cps"] == ncp,
          "fitset: FIT_TOL 0.0001, FIT_MAX_CP %d: FIT_STATUS 3 (%d), %d control points"
          % (ncp, st, r["cps"]))
    check(r["within"] == r0["within"] and r["verdict"] == r0["verdict"] and r["rms"] == r0["rms"],
          "fitset: within, verdict at TOLERANCE as the plain fit's (%.2f %% / %.2f %%, %d / %d)"
          % (r["within"], r0["within"], r["verdict"], r0["verdict"]))
    ack(c)
    # Uniform refinement (every span halved) up to 1000 control points:
    # 16 x 12 -> 29 x 21 (609); 55 x 39 would exceed it: 3.
    c.write(FIT_MAX_CP, c.words(1000))
    c.write(FIT_REFINE, [0])
    fit(c, "fitset")
    r = pc.results(c)
    st = c.read(FIT_STATUS, 1)[0]
    check(st == 3 and r["cps"] == 609,
          "fitset: uniform loop to 0.0001 within 1000 control points: FIT_STATUS 3 (%d), 29 x 21 "
          "= 609 control points (%d)" % (st, r["cps"]))
    ack(c)
    c.write(FIT_MAX_CP, c.words(0))
    c.write(FIT_REFINE, [2])  # the default again (auto)
    c.write(FIT_TOL, c.fwords(0.0))


def defaults(port, tol, within, maxcp, refine, robust, reparam):
    """The config's fit settings are the registers' values at start."""
    c = Cell(port)
    r = c.read(FIT_TOL, 10)
    got = (c.f32(r[0:2]), c.f32(r[2:4]), c.u32(r[4:6]), r[6], r[7], r[8])
    want = (float(tol), float(within), int(maxcp), int(refine), int(robust), int(reparam))
    check(all(abs(a - b) <= 1e-6 * max(1.0, abs(b)) for a, b in zip(got, want)),
          "defaults: FIT_TOL..FIT_REPARAM %s from the config (%s)" % (want, got))


def partid(port, resdir):
    """PART_ID and the job's UTC time into report.json; seq is RESULT_SEQ."""
    c = Cell(port)
    pid = "SN-0042/A b"
    raw = pid.encode().ljust(32, b"\0")
    words = [raw[i] << 8 | raw[i + 1] for i in range(0, 32, 2)]
    check(c.write(PART_ID, words) == 0, "partid: PART_ID '%s' written" % pid)
    c.write(pc.PART, c.words(4715) + [7, 0] + c.fwords(0.05))
    t0 = int(time.time())
    fit(c, "partid")
    job = c.seq
    jt = c.u32(c.read(JOB_TIME, 2))
    check(t0 - 1 <= jt <= int(time.time()) + 1, "partid: JOB_TIME %d is the job's UTC second" % jt)
    res = pc.results(c)
    export(c, "partid")
    ds = folders(resdir, 4715)
    r = report(ds[-1]) if ds else {}
    check(r.get("part_id") == pid, "partid: report.json part_id '%s'" % r.get("part_id"))
    check(r.get("seq") == res["seq"] == job, "partid: report.json seq %s = RESULT_SEQ %d"
          % (r.get("seq"), res["seq"]))
    iso = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(jt))
    check(r.get("utc") == jt and r.get("time") == iso,
          "partid: report.json utc %s, time %s = JOB_TIME (%s)" % (r.get("utc"), r.get("time"), iso))
    check(r.get("program") == 7, "partid: report.json program 7 (%s)" % r.get("program"))
    ack(c)
    c.write(PART_ID, [0] * 16)


def wdarm(port):
    """WD_ARMED only while the watchdog can trip (WATCHDOG_MS > 0)."""
    c = Cell(port)
    c.write(pc.WATCHDOG_MS, [0])
    c.write(pc.HEARTBEAT, [11])
    c.write(pc.HEARTBEAT, [12])
    s = c.status()
    check(not s["status"] & pc.WD_ARMED, "wdarm: WATCHDOG_MS 0: WD_ARMED clear (0x%x)" % s["status"])
    c.write(pc.WATCHDOG_MS, [30000])
    c.write(pc.HEARTBEAT, [13])
    s = c.status()
    check(s["status"] & pc.WD_ARMED, "wdarm: WATCHDOG_MS 30000: WD_ARMED set (0x%x)" % s["status"])
    c.write(pc.WATCHDOG_MS, [0])
    check(not c.status()["status"] & pc.WD_ARMED, "wdarm: WATCHDOG_MS 0 again: clear")


def idle(port, ms):
    """A silent connection is closed after the idle timeout (--idle-ms)."""
    ms = int(ms)
    sk = socket.create_connection(("127.0.0.1", port), timeout=5)
    t0 = time.time()
    sk.settimeout(ms / 1000.0 + 5)
    try:
        gone = sk.recv(1) == b""
    except OSError:
        gone = False
    dt = time.time() - t0
    check(gone and ms / 1000.0 - 0.1 <= dt <= ms / 1000.0 + 2,
          "idle: silent connection closed after %.2f s (idle_ms %d)" % (dt, ms))
    sk.close()


def gonescan(port, simpid):
    """cellsim killed mid-scan: ERROR_CODE says 203 when the cell sees it
    (one server tick), not when the scan's driver gives up."""
    import signal
    c = Cell(port)
    s = c.command(1)  # HOME
    c.wait_done(c.seq, 60)
    c.write(72, sum((c.fwords(v) for v in (0, 0, 200, 150, 2)), []))
    s = c.command(4)  # SCAN_FIT
    check(s.get("result") == 0, "gonescan: SCAN_FIT accepted")
    t = time.time()
    while time.time() - t < 20 and c.status()["progress"] < 2:
        time.sleep(0.02)
    os.kill(int(simpid), signal.SIGKILL)
    t0 = time.time()
    s = c.status()
    while time.time() - t0 < 20 and s["error"] == 0:
        time.sleep(0.01)
        s = c.status()
    dt = time.time() - t0
    check(s["error"] == 203 and dt < 1.0,
          "gonescan: ERROR_CODE 203 %.3f s after cellsim was killed (state %d)" % (dt, s["state"]))
    while time.time() - t0 < 30 and s["state"] != pc.S_ERROR:
        time.sleep(0.02)
        s = c.status()
    check(s["state"] == pc.S_ERROR and s["error"] == 203,
          "gonescan: ERROR 203 once the job stopped, %.2f s after (state %d)"
          % (time.time() - t0, s["state"]))


if __name__ == "__main__":
    step, port = sys.argv[1], int(sys.argv[2])
    a = sys.argv[3:]
    try:
        if step == "export2":
            export2(port, a[0])
        elif step == "recipe":
            recipe(port, a[0], a[1])
        elif step == "fitset":
            fitset(port, int(a[0]))
        elif step == "defaults":
            defaults(port, *a)
        elif step == "partid":
            partid(port, a[0])
        elif step == "wdarm":
            wdarm(port)
        elif step == "gonescan":
            gonescan(port, a[0])
        elif step == "idle":
            idle(port, a[0])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
