#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plant.py STEP ...: the PLC side and the independent checks of
# tests/cli/plant.sh. Steps:
#   job PORT PART OUT [HOOK]: FIT (HOOK, a shell command, run while it is
#       busy), EXPORT, ACK_RESULTS through the registers (pymodbus), as a
#       PLC; appends the figures the PLC read, one JSON line, to OUT.
#   verify OUT SQLITE_DB PSQL_ARGS MQTT_FILE: every job of OUT, with those
#       figures, once in results.db (sqlite3 CLI), once in PostgreSQL (psql)
#       and at least once on the broker (mosquitto_sub's output).
# Prints "ok ..." / "FAIL ..." lines (py_step counts them).
import json
import os
import shlex
import struct
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the register map and the client)
from plc_cycle import check  # noqa: E402

KEYS = ("rms", "max", "min", "within")
COLS = ("rms", "max_dev", "min_dev", "within_pct")


def job(port, part, out, hook):
    c = pc.Cell(port)
    check(c.write(pc.PART, c.words(part) + [7, 0] + c.fwords(0.02)) == 0,
          "job %d: part, program 7, folder 0, tolerance written" % part)
    s = c.command(pc.FIT)
    fit_seq = c.seq
    check(s.get("result") == 0, "job %d: FIT seq %d accepted" % (part, fit_seq))
    if hook:
        busy = c.status()["status"] & pc.BUSY
        subprocess.run(hook, shell=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        print("     (hook run while the job was %s: %s)" % ("busy" if busy else "done", hook))
    s = c.wait_done(fit_seq)
    check(s["status"] & pc.RESULTS and not s["status"] & pc.ERROR,
          "job %d: FIT done with results (0x%x)" % (part, s["status"]))
    r = pc.results(c)
    s = c.command(pc.EXPORT)
    exp_seq = c.seq
    s = c.wait_done(exp_seq)
    check(not s["status"] & pc.ERROR, "job %d: EXPORT seq %d done" % (part, exp_seq))
    s = c.command(pc.ACK_RESULTS)
    check(s["result"] == 0, "job %d: ACK_RESULTS" % part)
    r.update(fit_seq=fit_seq, export_seq=exp_seq, part_set=part)
    with open(out, "a") as f:
        f.write(json.dumps(r) + "\n")


def f32(x):
    return struct.pack("<f", float(x))


def same(row, reg):
    """The row's figures are the very float32 values the PLC read."""
    return (all(row[c] is not None and f32(row[c]) == f32(reg[k]) for k, c in zip(KEYS, COLS))
            and int(row["verdict"]) == reg["verdict"] and int(row["points"]) == reg["points"]
            and int(row["control_points"]) == reg["cps"])


def rows_csv(text, cols):
    rows = []
    for line in text.strip().splitlines():
        v = line.split("|")
        rows.append({c: (x if x != "" else None) for c, x in zip(cols, v)})
    return rows


def verify(out, dbfile, psql, mqtt_file):
    regs = [json.loads(x) for x in open(out)]
    cols = ("job_uuid", "part_number", "result_seq", "command", "state") + COLS + (
        "verdict", "points", "control_points", "report_sha256", "report_path")
    sel = "SELECT %s FROM jobs ORDER BY ended_at" % ", ".join(cols)
    lite = rows_csv(subprocess.run(["sqlite3", "-separator", "|", dbfile, sel],
                                   capture_output=True, text=True).stdout, cols)
    pg = rows_csv(subprocess.run(shlex.split(psql) + ["-At", "-F", "|", "-c", sel],
                                 capture_output=True, text=True).stdout, cols)
    n = 2 * len(regs)
    check(len(lite) == n, "verify: results.db holds %d rows for %d jobs (FIT and EXPORT each)"
          % (len(lite), len(regs)))
    check(len(pg) == n and len({r["job_uuid"] for r in pg}) == n,
          "verify: PostgreSQL holds %d rows, %d distinct job_uuids (want %d: exactly once)"
          % (len(pg), len({r["job_uuid"] for r in pg}), n))
    check({r["job_uuid"] for r in pg} == {r["job_uuid"] for r in lite},
          "verify: PostgreSQL's job_uuids are results.db's")
    msgs = []
    for line in open(mqtt_file):
        topic, _, payload = line.partition(" ")
        if topic.endswith("/result"):
            msgs.append(json.loads(payload))
    uu = [m["job_uuid"] for m in msgs]
    check(set(uu) == {r["job_uuid"] for r in lite},
          "verify: the broker carried every job (%d messages, %d distinct, %d duplicates)"
          % (len(uu), len(set(uu)), len(uu) - len(set(uu))))
    for name, rows in (("results.db", lite), ("PostgreSQL", pg), ("MQTT", None)):
        good = 0
        for reg in regs:
            for seq, cmd in ((reg["fit_seq"], "fit"), (reg["export_seq"], "export")):
                if rows is None:
                    cand = [m for m in msgs if m["result_seq"] == seq and
                            m["part_number"] == reg["part"] and m["command"] == cmd]
                    cand = [{**m, "verdict": m["verdict"], "points": m["points"]} for m in cand]
                else:
                    cand = [r for r in rows if int(r["result_seq"]) == seq and
                            int(r["part_number"]) == reg["part"] and r["command"] == cmd]
                good += bool(cand) and all(r["state"] == "done" and same(r, reg) for r in cand)
        check(good == n, "verify: %s: %d of %d rows carry the figures the PLC read "
              "(rms, max, min, within, verdict, points, control points)" % (name, good, n))
    ok = 0
    for r in lite:
        if r["command"] == "export" and r["report_path"] and os.path.isfile(r["report_path"]):
            h = subprocess.run(["sha256sum", r["report_path"]], capture_output=True,
                               text=True).stdout.split()[0]
            ok += h == r["report_sha256"]
    check(ok == len(regs), "verify: report.json's SHA-256 (sha256sum) recorded for %d of %d "
          "exports" % (ok, len(regs)))


if __name__ == "__main__":
    step = sys.argv[1]
    try:
        if step == "job":
            job(int(sys.argv[2]), int(sys.argv[3]), sys.argv[4],
                sys.argv[5] if len(sys.argv) > 5 else "")
        elif step == "verify":
            verify(*sys.argv[2:6])
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
