#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# scripts/plant_demo.py: the PLC side and the figures of `make plant-demo`.
#   drive PORT SECONDS PART0: FIT, EXPORT, ACK_RESULTS in a loop through the
#       registers (pymodbus) for SECONDS, parts PART0, PART0 + 1, ...
#   report CELLS_DIR PSQL MQTT_FILE OUTAGES: per cell jobs from its
#       results.db (sqlite3), latency from a job's end (ended_at) to its row
#       in PostgreSQL (received_at) and to its message at a subscriber
#       (mosquitto_sub %U), median and p99, lost and duplicated counts.
import glob
import json
import os
import shlex
import subprocess
import sys
import time
from datetime import datetime

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "cli"))
import plc_cycle as pc  # noqa: E402


def drive(port, seconds, part0):
    c = pc.Cell(port)
    t_end = time.time() + seconds
    part = part0
    while time.time() < t_end:
        c.write(pc.PART, c.words(part) + [1, 0] + c.fwords(0.02))
        c.command(pc.FIT)
        c.wait_done(c.seq)
        c.command(pc.EXPORT)
        c.wait_done(c.seq)
        c.command(pc.ACK_RESULTS)
        part += 1
        time.sleep(0.5)


def ts(s):
    return datetime.fromisoformat(s.replace("Z", "+00:00")).timestamp()


def pct(xs, p):
    if not xs:
        return float("nan")
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(p / 100.0 * len(xs)))]


def report(cells_dir, psql, mqtt_file, outages):
    spans = [tuple(map(float, o.split(":"))) for o in outages.split(",") if o]
    cells = {}
    for db in sorted(glob.glob(os.path.join(cells_dir, "*", "results", "results.db"))):
        out = subprocess.run(["sqlite3", "-separator", "|", db,
                              "SELECT job_uuid, cell_id, ended_at FROM jobs"],
                             capture_output=True, text=True).stdout
        for line in out.split():
            u, cell, end = line.split("|")
            cells.setdefault(cell, {})[u] = ts(end)
    allj = {u: (cell, e) for cell, d in cells.items() for u, e in d.items()}
    pg = subprocess.run(shlex.split(psql) + ["-At", "-F", "|", "-c",
                        "SELECT job_uuid, extract(epoch FROM received_at) FROM jobs"],
                        capture_output=True, text=True).stdout.split()
    pgd = {}
    for line in pg:
        u, t = line.split("|")
        pgd.setdefault(u, []).append(float(t))
    mq = {}
    for line in open(mqtt_file):
        parts = line.split(" ", 2)
        if len(parts) == 3 and parts[1].endswith("/result"):
            mq.setdefault(json.loads(parts[2])["job_uuid"], []).append(float(parts[0]))

    def in_outage(t):
        return any(a <= t <= b for a, b in spans)

    print("%-8s %6s %12s %12s %12s %12s" % ("cell", "jobs", "pg median", "pg p99",
                                            "mqtt median", "mqtt p99"))
    lat_all = {"pg": [], "mqtt": []}
    lat_calm = {"pg": [], "mqtt": []}
    for cell in sorted(cells):
        lp, lm = [], []
        for u, e in cells[cell].items():
            if u in pgd:
                lp.append(min(pgd[u]) - e)
            if u in mq:
                lm.append(min(mq[u]) - e)
            for k, v in (("pg", pgd.get(u)), ("mqtt", mq.get(u))):
                if v:
                    lat_all[k].append(min(v) - e)
                    if not in_outage(e):
                        lat_calm[k].append(min(v) - e)
        print("%-8s %6d %10.3f s %10.3f s %10.3f s %10.3f s" % (
            cell, len(cells[cell]), pct(lp, 50), pct(lp, 99), pct(lm, 50), pct(lm, 99)))
    for name, lat in (("all jobs", lat_all), ("jobs ended outside the outages", lat_calm)):
        print("%s: job end -> PostgreSQL row median %.3f s, p99 %.3f s; -> MQTT message "
              "median %.3f s, p99 %.3f s (%d, %d jobs)" % (
                  name, pct(lat["pg"], 50), pct(lat["pg"], 99), pct(lat["mqtt"], 50),
                  pct(lat["mqtt"], 99), len(lat["pg"]), len(lat["mqtt"])))
    lost_pg = len(set(allj) - set(pgd))
    lost_mq = len(set(allj) - set(mq))
    dup_pg = sum(len(v) - 1 for v in pgd.values())
    dup_mq = sum(len(v) - 1 for v in mq.values())
    print("jobs %d; PostgreSQL: lost %d, duplicated %d; MQTT: lost %d, duplicated %d "
          "(consumers dedupe by job_uuid)" % (len(allj), lost_pg, dup_pg, lost_mq, dup_mq))
    return 0 if lost_pg == 0 and lost_mq == 0 and dup_pg == 0 and allj else 1


if __name__ == "__main__":
    if sys.argv[1] == "drive":
        drive(int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))
    elif sys.argv[1] == "report":
        sys.exit(report(*sys.argv[2:6]))
    else:
        raise SystemExit("unknown step " + sys.argv[1])
