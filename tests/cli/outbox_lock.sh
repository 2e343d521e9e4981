#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/outbox_lock.sh CELLFIT: the OUTBOX_* registers (map v3) come
# from results.db, which another process may lock (a `sqlite3` session,
# `cellfit results`, a slow disk): `cellfit serve` (no rig, results
# recorded) must keep answering Modbus requests within 0.5 s meanwhile
# (tests/cli/outbox_lock.py, pymodbus), and show the outbox again after.
# serve is stopped by PID.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
plc_setup outbox_lock
"$PY" -c "import sqlite3, fcntl" 2>/dev/null || { echo "outbox_lock: $PY without sqlite3"; exit 1; }
mkdir "$T/results"
serve_start a --results "$T/results"
[ -s "$T/results/results.db" ] && ok "results.db created" || no "no results.db: $(tail -2 "$T/a.log")"
py_step outbox_lock.py 60 regs "$port" "$T/results/results.db"
stop_servers
grep -q "outbox registers" "$T/a.log" && no "outbox registers: $(grep 'outbox registers' "$T/a.log")" ||
    ok "no outbox register warning in serve's log"
grep -q "Sanitizer\|runtime error" "$T/a.log" && no "a sanitizer report: $(grep -m1 "Sanitizer\|runtime error" "$T/a.log")" ||
    ok "no sanitizer report in serve's log"
echo "outbox_lock: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
