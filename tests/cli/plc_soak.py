#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_soak.py soak PORT SIMPORT SERVE_PID TX MAX_GAP_MS: a soak of
# `cellfit serve --sim`: TX register transactions (reads of the status and
# results blocks, heartbeat writes) from four pymodbus clients in their own
# processes, while a fifth (the PLC) runs SCAN_FIT jobs on the simulated rig
# one after another and a sixth watches CELL_HEARTBEAT. The server's RSS
# (/proc/PID/status VmRSS) is read after a warm-up job and at the end. Prints
# ok/FAIL lines and the figures (transactions, seconds, RSS start and end,
# largest heartbeat gap). tests/cli/plc_rig.sh runs it scaled down.
import multiprocessing as mp
import os
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402
from plc_cycle import check, Cell  # noqa: E402

NLOAD = 4
HOME, SCAN_FIT, ACK_RESULTS = 1, 4, 8


def rss_kb(pid):
    for line in open("/proc/%d/status" % pid):
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return -1


def load(port, n, out):
    """n transactions; out gets (done, errors)."""
    c = Cell(port)
    err = 0
    for k in range(n):
        try:
            if k % 4 == 3:
                err += c.write(pc.HEARTBEAT, [k & 0xFFFF]) != 0
            elif k % 4 == 2:
                c.read(100, 18)
            else:
                c.read(40, 10)
        except Exception:
            err += 1
    out.put((n, err))


class Watch(threading.Thread):
    """Polls CELL_HEARTBEAT: the largest time between two changes, and the
    largest step (a step > 1 is a tick the cell missed publishing)."""

    def __init__(self, port):
        super().__init__(daemon=True)
        self.c = Cell(port)
        self.gap = 0.0
        self.step = 0
        self.reads = 0
        self.run_ = True

    def run(self):
        last = self.c.read(pc.CELL_HB, 1)[0]
        t_last = time.monotonic()
        while self.run_:
            v = self.c.read(pc.CELL_HB, 1)[0]
            self.reads += 1
            t = time.monotonic()
            if v != last:
                self.gap = max(self.gap, t - t_last)
                self.step = max(self.step, (v - last) & 0xFFFF)
                last, t_last = v, t
            time.sleep(0.01)


def job(c, what):
    c.command(SCAN_FIT)
    s = c.wait_done(c.seq, 60)
    good = bool(s["status"] & pc.RESULTS) and not s["status"] & pc.ERROR
    c.command(ACK_RESULTS)
    return good


def soak(port, pid, tx, max_gap_ms):
    c = Cell(port)
    c.command(HOME)
    c.wait_done(c.seq, 60)
    c.write(72, sum((c.fwords(v) for v in (0, 0, 40, 20, 5)), []))
    check(job(c, "warm-up"), "soak: warm-up SCAN_FIT (45 points)")
    rss0 = rss_kb(pid)
    w = Watch(port)
    w.start()
    q = mp.Queue()
    t0 = time.monotonic()
    procs = [mp.Process(target=load, args=(port, tx // NLOAD, q)) for _ in range(NLOAD)]
    for p in procs:
        p.start()
    jobs = good = 0
    while any(p.is_alive() for p in procs):
        jobs += 1
        good += job(c, "soak")
    for p in procs:
        p.join()
    secs = time.monotonic() - t0
    w.run_ = False
    w.join()
    res = [q.get() for _ in procs]
    done, errs = sum(r[0] for r in res), sum(r[1] for r in res)
    total = done + w.reads
    rss1 = rss_kb(pid)
    print("soak: %d transactions (%d load + %d heartbeat reads) in %.1f s (%.0f/s), %d SCAN_FIT "
          "jobs; RSS %d kB at start, %d kB at end; largest heartbeat gap %.0f ms, largest step %d"
          % (total, done, w.reads, secs, total / secs, jobs, rss0, rss1, 1e3 * w.gap, w.step))
    check(errs == 0, "soak: %d load transactions, %d failed" % (done, errs))
    check(jobs >= 1 and good == jobs, "soak: %d of %d scan jobs ended with results" % (good, jobs))
    # Flat: a job or a client costs nothing that stays (a little slack for
    # the allocator's arenas of the job threads).
    if "libasan" in open("/proc/%d/maps" % pid).read():
        print("soak: RSS not judged under ASan (its quarantine keeps freed memory)")
    else:
        check(0 < rss0 and rss1 - rss0 <= 2048,
              "soak: RSS flat (%d kB -> %d kB, +%d kB)" % (rss0, rss1, rss1 - rss0))
    check(1e3 * w.gap <= max_gap_ms and w.step <= max(2, max_gap_ms // 100),
          "soak: CELL_HEARTBEAT advanced steadily (gap %.0f ms <= %d ms)" % (1e3 * w.gap,
                                                                          max_gap_ms))


if __name__ == "__main__":
    try:
        soak(int(sys.argv[2]), int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]))
    except Exception as e:
        check(False, "soak: %s: %s" % (type(e).__name__, e))
    sys.exit(1 if pc.nfail else 0)
