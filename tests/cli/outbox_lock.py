#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/outbox_lock.py regs PORT DB: the OUTBOX_* registers (map v3)
# of `cellfit serve` while another process locks its results.db: entries
# written with Python's sqlite3 show in the registers; with a write
# transaction held (BEGIN EXCLUSIVE), and then with the WAL-index locks a
# reader waits for held (SQLite's WAL recovery holds the same ones, the
# -shm file's bytes 121..127), every Modbus answer still comes within
# 0.5 s; once the lock goes, new entries show again. Prints ok/FAIL lines
# (tests/cli/outbox_lock.sh counts them). Run with /usr/bin/python3.
import os
import sqlite3
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plc_cycle as pc  # noqa: E402  (the register map and the client)
from plc_cycle import check  # noqa: E402
from plc_regs import outbox_regs, wait_outbox  # noqa: E402

BOUND = 0.5  # s: the slowest Modbus answer allowed while the database is locked

# The lockers, each in a process of its own (POSIX locks are per process):
# "locked" on stdout once they hold the lock, which they keep for SECS s.
SQL_LOCK = """
import sqlite3, sys, time
c = sqlite3.connect(sys.argv[1], isolation_level=None, timeout=10)
c.execute("BEGIN EXCLUSIVE")
c.execute("UPDATE counters SET value = value WHERE name = 'outbox_dropped'")
print("locked", flush=True)
time.sleep(float(sys.argv[2]))
c.execute("ROLLBACK")
"""
SHM_LOCK = """
import fcntl, os, sys, time
fd = os.open(sys.argv[1] + "-shm", os.O_RDWR)
fcntl.lockf(fd, fcntl.LOCK_EX, 7, 121, os.SEEK_SET)  # CKPT, RECOVER, READ(0..4)
print("locked", flush=True)
time.sleep(float(sys.argv[2]))
"""


def enqueue(db, uuid, targets, age):
    c = sqlite3.connect(db, timeout=10)
    with c:
        for t in targets:
            c.execute("INSERT INTO outbox (job_uuid, target, created) VALUES (?, ?, ?)",
                      (uuid, t, time.time() - age))
    c.close()


def polled_while(c, code, db, secs, what):
    """Read STATUS .. as a PLC does (every 20 ms) while a locker holds its lock."""
    p = subprocess.Popen([sys.executable, "-c", code, db, str(secs)], stdout=subprocess.PIPE,
                         text=True)
    try:
        locked = p.stdout.readline().strip() == "locked"
        check(locked, "%s: lock taken (pid %d)" % (what, p.pid))
        n, worst, err = 0, 0.0, ""
        t_end = time.time() + secs - 0.5
        while time.time() < t_end and not err:
            t = time.time()
            try:
                c.read(pc.STATUS, 8)
                outbox_regs(c)
            except RuntimeError as e:  # no answer within the client's 5 s
                err = ", then no answer: %s" % e
            worst = max(worst, time.time() - t)
            n += 1
            time.sleep(0.02)
        check(locked and not err and n >= 20 and worst < BOUND,
              "%s: %d Modbus reads, the slowest %.3f s (< %.1f s)%s"
              % (what, n, worst, BOUND, err))
    finally:
        p.kill()  # by its PID, whatever state it is in
        p.wait()


def main(port, db):
    c = pc.Cell(port)
    enqueue(db, "lock-1", ("pg", "mqtt"), 100)
    enqueue(db, "lock-2", ("pg",), 50)
    r, dt = wait_outbox(c, lambda r: r["pg"] == 2 and r["mqtt"] == 1, 5)
    check(r["pg"] == 2 and r["mqtt"] == 1 and 99 <= r["age"] <= 110 and r["dropped"] == 0,
          "3 entries written by sqlite3: OUTBOX_PG 2, OUTBOX_MQTT 1, OUTBOX_AGE 100 s "
          "(%s, after %.1f s)" % (r, dt))
    polled_while(c, SQL_LOCK, db, 4, "BEGIN EXCLUSIVE held 4 s")
    polled_while(c, SHM_LOCK, db, 8, "WAL-index read locks held 8 s")
    c = pc.Cell(port)  # a new connection, should the last one have timed out
    r = outbox_regs(c)
    check(r["pg"] == 2 and r["mqtt"] == 1, "the figures kept meanwhile (%s)" % r)
    enqueue(db, "lock-3", ("mqtt",), 0)
    r, dt = wait_outbox(c, lambda r: r["mqtt"] == 2, 5)
    check(r["pg"] == 2 and r["mqtt"] == 2,
          "after the locks: a new entry shows within %.1f s (%s)" % (dt, r))


if __name__ == "__main__":
    if sys.argv[1] != "regs":
        raise SystemExit("usage: outbox_lock.py regs PORT DB")
    main(int(sys.argv[2]), sys.argv[3])
    sys.exit(1 if pc.nfail else 0)
