#!/usr/bin/python3
# SPDX-License-Identifier: MIT
# tests/cli/plc_slots.py STEP PORT [ARGS]: `cellfit serve` under what a shop
# floor and an attacker do to its connections and its handshake (issue 15),
# seen from raw sockets and pymodbus. Prints "ok ..." / "FAIL ..." lines;
# tests/cli/plc_slots.sh counts them. Steps:
#   slots PORT NSLOTS     NSLOTS silent connections (half of them after a
#                         request: pulled cables) and a slowloris
#                         trickling a header: a fresh pymodbus
#                         client is served within 3 s, 10 times of 10
#   abortblock PORT       COMMAND + sequence + heartbeat in one request
#                         (20-22): ABORT taken while a FIT runs
#   seq PORT              sequence 0 refused 112, the last sequence with
#                         another command 113, a retransmission ignored
#   spam PORT N           N refused commands as fast as possible (the log
#                         is counted by the script)
#   keepalive PORT        the server's end of a connection runs the kernel's
#                         keepalive timer (/proc/net/tcp, timer 2), 10 s
#   v2 PORT               map version 2: PART_ID, fit settings, JOB_TIME,
#                         counters, input registers
# Run with /usr/bin/python3 (Debian's python3-pymodbus).
import socket
import struct
import sys
import threading
import time
import types

try:
    from pymodbus.client import ModbusTcpClient
except ModuleNotFoundError:  # Debian's pymodbus 3.0 wants serial_asyncio even for TCP
    _stub = types.ModuleType("serial_asyncio")
    _stub.create_serial_connection = None
    sys.modules["serial_asyncio"] = _stub
    from pymodbus.client import ModbusTcpClient

# Addresses and codes from docs/plc-register-map.md.
MAGIC, VERSION, COMMAND, HEARTBEAT = 0, 1, 20, 22
STATUS, ACK_SEQ, DONE_SEQ, STATE, CMD_RESULT = 40, 41, 42, 43, 47
FIT_TOL, FIT_WITHIN, FIT_MAX_CP, FIT_REFINE, RECIPE = 82, 84, 86, 88, 91
JOB_TIME, FIT_STATUS, PART_ID = 118, 120, 124
JOBS_OK, JOBS_ABORTED, CONN_ACCEPTED, CONN_EVICTED, CONN_TIMED_OUT = 140, 144, 146, 148, 150
REQ_REFUSED, CMD_REFUSED, LAST_ERROR = 152, 154, 156
BUSY, DONE, ABORTED, REJECTED = 2, 4, 32, 64
FIT, ABORT, RESET, ACK_RESULTS = 3, 5, 6, 8
IDLE, ABORTING = 0, 5

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


def client(port, timeout=3):
    c = ModbusTcpClient("127.0.0.1", port=port, timeout=timeout, retries=0)
    return c if c.connect() else None


def rd(c, addr, n):
    r = c.read_holding_registers(addr, n, slave=1)
    if r.isError():
        raise RuntimeError("read %d x %d: %s" % (addr, n, r))
    return r.registers


def wr(c, addr, values):
    r = c.write_registers(addr, values, slave=1)
    return r.exception_code if r.isError() else 0


def u32(w):  # the default word order (0): low word first
    return w[0] | w[1] << 16


def silent(port, served=False):
    """A connection that goes quiet: at once (a port scan, a half-open
    socket), or after one request (a PLC whose cable was pulled)."""
    s = socket.create_connection(("127.0.0.1", port), timeout=2)
    if served:
        try:
            s.sendall(struct.pack(">HHHBBHH", 1, 0, 6, 1, 3, MAGIC, 1))
            s.recv(64)
        except OSError:  # a server without a free slot (the old code) closed it
            pass
    return s


def slowloris(port, stop):
    """Half a header now and then, reconnecting whenever it is closed."""
    s = None
    while not stop.is_set():
        try:
            if s is None:
                s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.send(b"\x00")
        except OSError:
            if s is not None:
                s.close()
            s = None
        stop.wait(0.3)
    if s is not None:
        s.close()


def slots(port, nslots):
    hold = [silent(port, k % 2 == 0) for k in range(nslots)]
    stop = threading.Event()
    th = threading.Thread(target=slowloris, args=(port, stop))
    th.start()
    time.sleep(0.5)
    served, worst = 0, 0.0
    for k in range(10):
        hold.append(silent(port, k % 2 == 0))  # the slots full again before each try
        time.sleep(0.1)
        t = time.time()
        ok = False
        while time.time() - t < 3 and not ok:
            try:
                c = client(port, 1)
                if c is not None:
                    ok = rd(c, MAGIC, 1)[0] == 17222
                    c.close()
            except Exception:
                ok = False
        dt = time.time() - t
        worst = max(worst, dt)
        served += ok
    stop.set()
    th.join()
    check(served == 10, "slots: %d silent + a slowloris: a fresh client served %d of 10 times "
          "within 3 s (slowest %.2f s)" % (nslots, served, worst))
    c = client(port)
    ev = u32(rd(c, CONN_EVICTED, 2)) if c else 0
    check(ev >= 10, "slots: CONN_EVICTED counts the evictions (%d)" % ev)
    for s in hold:
        s.close()


def keepalive(port):
    s = silent(port)
    time.sleep(0.3)
    timers = []
    for line in open("/proc/net/tcp").read().splitlines()[1:]:
        f = line.split()
        local, state, timer = f[1], f[3], f[5]
        if state == "01" and int(local.split(":")[1], 16) == port:
            tr, when = timer.split(":")
            timers.append((int(tr, 16), int(when, 16)))
    # tr 2: the keepalive timer; "when" in jiffies (USER_HZ 100), under 10 s
    check(len(timers) >= 1 and all(tr == 2 and 0 < w <= 1000 for tr, w in timers),
          "keepalive: the server's socket runs the keepalive timer, due within 10 s (%s)" % timers)
    s.close()


def wait_ack(c, seq):
    t = time.time()
    while time.time() - t < 10:
        r = rd(c, STATUS, 8)
        if r[1] == seq:
            return r
        time.sleep(0.01)
    raise RuntimeError("seq %d never acknowledged" % seq)


def abortblock(port):
    c = client(port)
    seq = rd(c, ACK_SEQ, 1)[0] + 1
    check(wr(c, COMMAND, [FIT, seq, 1]) == 0, "abortblock: FIT + sequence + heartbeat in one "
          "request accepted in IDLE")
    r = wait_ack(c, seq)
    check(r[0] & BUSY and r[7] == 0, "abortblock: the FIT runs (status 0x%x, state %d)" %
          (r[0], r[3]))
    ex = wr(c, COMMAND, [ABORT, seq + 1, 2])
    check(ex == 0, "abortblock: ABORT + sequence + heartbeat accepted while BUSY (exception %d)"
          % ex)
    r = rd(c, STATUS, 8)
    check(r[1] == seq + 1 and r[7] == 0, "abortblock: ACK_SEQ %d, CMD_RESULT %d" % (r[1], r[7]))
    t = time.time()
    while time.time() - t < 30 and rd(c, STATUS, 1)[0] & BUSY:
        time.sleep(0.02)
    r = rd(c, STATUS, 8)
    check(r[2] == seq and r[0] & ABORTED and r[3] == IDLE,
          "abortblock: the job ended ABORTED (status 0x%x, DONE_SEQ %d)" % (r[0], r[2]))
    check(wr(c, COMMAND, [ABORT, seq + 1, 3]) == 0 and rd(c, HEARTBEAT, 1)[0] == 3,
          "abortblock: the same block again: the heartbeat stored, the command a retransmission")
    c.close()


def seq(port):
    c = client(port)
    r0 = rd(c, STATUS, 8)
    n0 = u32(rd(c, CMD_REFUSED, 2))
    check(wr(c, COMMAND, [FIT, 0]) == 0, "seq: sequence 0 written")
    r = rd(c, STATUS, 8)
    check(r[7] == 112 and r[0] & REJECTED and r[1] == 0 and r[3] == r0[3],
          "seq: sequence 0 refused with 112 (CMD_RESULT %d, ACK_SEQ %d), no job" % (r[7], r[1]))
    s = r0[1] + 1
    check(wr(c, COMMAND, [RESET, s]) == 0 and rd(c, CMD_RESULT, 1)[0] == 109,
          "seq: RESET seq %d refused 109 (idle)" % s)
    check(wr(c, COMMAND, [RESET, s]) == 0 and rd(c, CMD_RESULT, 1)[0] == 109,
          "seq: the same command and sequence again: a retransmission, CMD_RESULT kept")
    check(wr(c, COMMAND, [FIT, s]) == 0, "seq: another command with the same sequence written")
    r = rd(c, STATUS, 8)
    check(r[7] == 113 and r[0] & REJECTED and r[1] == s and r[3] == r0[3],
          "seq: refused with 113 (CMD_RESULT %d), no job (state %d)" % (r[7], r[3]))
    n = u32(rd(c, CMD_REFUSED, 2))
    check(n == n0 + 3, "seq: CMD_REFUSED counts the three refusals (%d -> %d)" % (n0, n))
    c.close()


def spam(port, n):
    c = client(port)
    s = rd(c, ACK_SEQ, 1)[0]
    for k in range(n):
        s = s % 65535 + 1
        wr(c, COMMAND, [RESET, s])  # idle: refused 109 every time
    check(rd(c, CMD_RESULT, 1)[0] == 109, "spam: %d refused commands sent" % n)
    c.close()


def v2(port):
    c = client(port)
    check(rd(c, VERSION, 1)[0] == 3, "v2: MAP_VERSION 3 (2 and its outbox and scan registers)")
    pid = b"SN-0042/A7 lot 2026-12-02"
    words = [struct.unpack(">H", (pid + b"\0" * 32)[i:i + 2])[0] for i in range(0, 32, 2)]
    check(wr(c, PART_ID, words) == 0 and rd(c, PART_ID, 16) == words,
          "v2: PART_ID written and read back (32 chars, high byte first)")
    bad = list(words)
    bad[0] = 0x0141  # a control character
    check(wr(c, PART_ID, bad) == 3 and rd(c, PART_ID, 16) == words,
          "v2: PART_ID with a control character: exception 03, unchanged")
    check(wr(c, PART_ID, words[:8]) == 2, "v2: half of PART_ID: exception 02")
    w = rd(c, FIT_TOL, 10)
    fw = struct.unpack("<f", struct.pack("<I", u32(w[2:4])))[0]
    check(u32(w[0:2]) == 0 and fw == 100.0 and w[6] == 2 and w[9] == 0,
          "v2: fit defaults: FIT_TOL 0, FIT_WITHIN 100, FIT_REFINE 2 (auto, map version 3), "
          "RECIPE 0")
    check(wr(c, FIT_REFINE, [3]) == 3 and wr(c, RECIPE, [16]) == 3,
          "v2: FIT_REFINE 3, RECIPE 16: exception 03")
    r3, r4 = rd(c, 140, 17), c.read_input_registers(140, 17, slave=1)
    check(not r4.isError() and r4.registers[:12] == r3[:12],
          "v2: the counters read as input registers (function 04) too")
    check(u32(r3[CONN_ACCEPTED - 140:][:2]) >= 1, "v2: CONN_ACCEPTED %d" %
          u32(r3[CONN_ACCEPTED - 140:][:2]))
    q0 = u32(rd(c, REQ_REFUSED, 2))
    wr(c, MAGIC, [1])
    check(u32(rd(c, REQ_REFUSED, 2)) == q0 + 1, "v2: REQ_REFUSED counts an exception")
    ok0 = u32(rd(c, JOBS_OK, 2))
    s = rd(c, ACK_SEQ, 1)[0] % 65535 + 1
    t0 = int(time.time())
    wr(c, COMMAND, [FIT, s])
    wait_ack(c, s)
    t = time.time()
    while time.time() - t < 60 and not (rd(c, STATUS, 1)[0] & DONE and rd(c, DONE_SEQ, 1)[0] == s):
        time.sleep(0.02)
    t1 = int(time.time())
    jt = u32(rd(c, JOB_TIME, 2))
    # time() in C is the coarse clock: up to a tick behind Python's.
    check(t0 - 1 <= jt <= t1, "v2: JOB_TIME %d in [%d, %d] (UTC s)" % (jt, t0 - 1, t1))
    check(u32(rd(c, JOBS_OK, 2)) == ok0 + 1, "v2: JOBS_OK counts the job")
    s = s % 65535 + 1
    wr(c, COMMAND, [ACK_RESULTS, s])
    wait_ack(c, s)
    check(u32(rd(c, JOB_TIME, 2)) == 0, "v2: ACK_RESULTS clears JOB_TIME with the results")
    check(u32(rd(c, JOBS_OK, 2)) == ok0 + 1 and rd(c, PART_ID, 16) == words,
          "v2: ... but not the counters nor PART_ID")
    c.close()


if __name__ == "__main__":
    step, port = sys.argv[1], int(sys.argv[2])
    try:
        if step == "slots":
            slots(port, int(sys.argv[3]))
        elif step == "abortblock":
            abortblock(port)
        elif step == "seq":
            seq(port)
        elif step == "keepalive":
            keepalive(port)
        elif step == "spam":
            spam(port, int(sys.argv[3]))
        elif step == "v2":
            v2(port)
        else:
            raise SystemExit("unknown step " + step)
    except Exception as e:  # a dead server or a protocol error is a failure, not a crash
        check(False, "%s: %s: %s" % (step, type(e).__name__, e))
    sys.exit(1 if nfail else 0)
