#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/record.sh CELLFIT: `cellfit fit --record` and `cellfit scan
# --fit --record` (with cellsim beside CELLFIT) write the job's row into
# results.db as serve does: `cellfit results show UUID --json` checked
# against the command's own JSON summary, sha256sum of the files written
# and sqlite3 reading the database directly; a database that cannot be
# opened fails the command (exit 1) with the surface still written; `results
# --db` takes a folder, and refuses (fit --record too) a file that is not a
# results database, leaving it as it was.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
SIM=$(dirname "$CF")/cellsim
PY=/usr/bin/python3
T=$(mktemp -d "${TMPDIR:-/tmp}/cellfit-record.XXXXXX")
trap 'stop_all; rm -rf "$T"' EXIT
trap 'exit 1' INT TERM
if "$CF" results list --db "$T/none.db" 2>&1 | grep -q "without SQLite"; then
    echo "skip record: cellfit built without SQLite"
    echo "record: 0 passed, 0 failed"
    exit 0
fi
# same ROW.json CMD.json KEY:KEY...: the row's fields equal the command's
# (numbers compared as the doubles they parse to).
same() {
    "$PY" - "$@" <<'PYEOF'
import json, sys
row = json.load(open(sys.argv[1]))
cmd = json.loads(open(sys.argv[2]).read().strip().splitlines()[-1])
bad = [f"{a}={row.get(a)!r} vs {b}={cmd.get(b)!r}" for a, b in (p.split(":") for p in sys.argv[3:])
       if row.get(a) != cmd.get(b)]
print("; ".join(bad))
sys.exit(1 if bad else 0)
PYEOF
}
field() { "$PY" -c 'import json,sys; v=json.load(open(sys.argv[1]))[sys.argv[2]]; print("null" if v is None else v)' "$1" "$2"; }
uuid_of() { sed -n 's/^[a-z]*: recorded job \([0-9a-f-]*\) in .*/\1/p' "$1"; }

"$CF" gen --dir "$T/part" --nu 8 --nv 8 --count 20000 --noise 0.002 >/dev/null
grep -v '^#' "$T/part/points.uvxyz" | cut -d' ' -f3- >"$T/points.xyz"
mkdir -p "$T/results"
DB="$T/results/results.db"

# A plain fit, recorded into the results folder (its results.db).
expect 0 "fit --record --db FOLDER" "$CF" fit --base "$T/part/nominal.igs" --points "$T/points.xyz" \
    --out "$T/f1.igs" --json --record --db "$T/results"
cp "$T/out" "$T/f1.json"
u1=$(uuid_of "$T/err")
[ -n "$u1" ] && ok "fit names the job it recorded ($u1)" || no "no recorded job on stderr: $(cat "$T/err")"
expect 0 "results show UUID --json" "$CF" results show "$u1" --db "$DB" --json
cp "$T/out" "$T/r1.json"
m=$(same "$T/r1.json" "$T/f1.json" rms:rms points:points control_points:control_points) &&
    ok "row rms, points, control points = the fit's JSON" || no "row vs fit: $m"
[ "$(field "$T/r1.json" job_uuid)" = "$u1" ] && [ "$(field "$T/r1.json" command)" = fit ] &&
    [ "$(field "$T/r1.json" state)" = done ] && [ "$(field "$T/r1.json" fit_status)" = 0 ] &&
    ok "row: its UUID, command fit, state done, fit_status 0 (no loop)" || no "row: $(cat "$T/r1.json")"
[ "$(field "$T/r1.json" surface_path)" = "$(realpath "$T/f1.igs")" ] &&
    [ "$(field "$T/r1.json" surface_sha256)" = "$(sha256sum "$T/f1.igs" | cut -d' ' -f1)" ] &&
    ok "row: the surface's absolute path and its sha256sum" || no "surface: $(cat "$T/r1.json")"
[ "$(field "$T/r1.json" max_dev)" = null ] && [ "$(field "$T/r1.json" within_pct)" = null ] &&
    [ "$(field "$T/r1.json" verdict)" = null ] &&
    ok "row: no signed deviations, share within or verdict without a tolerance (NULL)" ||
    no "unknown figures: $(cat "$T/r1.json")"
"$PY" - "$T/r1.json" "$T/f1.json" <<'PYEOF' && ok "started_at .. ended_at spans the fit's seconds" || no "times"
import json, sys
from datetime import datetime
r = json.load(open(sys.argv[1])); f = json.load(open(sys.argv[2]))
t = lambda s: datetime.strptime(s, "%Y-%m-%dT%H:%M:%S.%fZ").timestamp()
d = t(r["ended_at"]) - t(r["started_at"])
print(f"     {d:.3f} s recorded, the fit says {f['seconds']:.3f} s")
sys.exit(0 if f["seconds"] - 0.002 <= d < f["seconds"] + 5 else 1)
PYEOF

# A fit to a tolerance: status, share within and verdict as serve's rule.
expect 0 "fit --tol 0.05 --within 99 --record --db FILE" "$CF" fit --base "$T/part/nominal.igs" \
    --points "$T/points.xyz" --out "$T/f2.igs" --json --tol 0.05 --within 99 --db "$DB"
cp "$T/out" "$T/f2.json"
u2=$(uuid_of "$T/err")
"$CF" results show "$u2" --db "$DB" --json >"$T/r2.json"
m=$(same "$T/r2.json" "$T/f2.json" rms:rms within_pct:within_tol_pct points:points) &&
    ok "row rms and within_pct = the fit's rms and within_tol_pct" || no "row vs fit: $m"
want=$("$PY" -c 'import json,sys; f=json.load(open(sys.argv[1])); print(1 if f["max_abs"] <= f["tol"] else 2, 1 if f["fit_status"] == "met" else 0)' "$T/f2.json")
[ "$(field "$T/r2.json" verdict) $(field "$T/r2.json" fit_status)" = "$want" ] &&
    ok "row: verdict and fit_status from the fit's max_abs, tol and status ($want)" ||
    no "verdict/status $(field "$T/r2.json" verdict) $(field "$T/r2.json" fit_status), want $want"

# sqlite3 directly: two rows, nothing for the plant (no outbox entries).
[ "$(sqlite3 "$DB" 'SELECT count(*) FROM jobs')" = 2 ] && [ "$(sqlite3 "$DB" 'SELECT count(*) FROM outbox')" = 0 ] &&
    ok "sqlite3: 2 jobs, an empty outbox" || no "sqlite3: $(sqlite3 "$DB" 'SELECT count(*) FROM jobs, outbox')"
[ "$(sqlite3 "$DB" "SELECT surface_sha256 FROM jobs WHERE job_uuid = '$u2'")" = "$(sha256sum "$T/f2.igs" | cut -d' ' -f1)" ] &&
    ok "sqlite3: the second row's checksum is sha256sum's" || no "sqlite3 checksum"
n=$("$CF" results list --db "$DB" | wc -l)
[ "$n" = 2 ] && ok "results list: 2 jobs" || no "results list: $n"

# Without --record nothing is created; a database that cannot be opened
# fails the command, the surface written all the same.
mkdir "$T/cwd"
(cd "$T/cwd" && "$CF" fit --base "$T/part/nominal.igs" --points "$T/points.xyz" --out f.igs >/dev/null 2>&1)
[ -f "$T/cwd/f.igs" ] && [ ! -e "$T/cwd/results" ] && ok "no --record: no database" || no "no --record"
expect 1 "--db in a folder that does not exist: exit 1" "$CF" fit --base "$T/part/nominal.igs" \
    --points "$T/points.xyz" --out "$T/f3.igs" --db "$T/nowhere/results.db"
grep -q "not recorded" "$T/err" && [ -f "$T/f3.igs" ] && ok "  said so; the surface is written" ||
    no "  message: $(cat "$T/err")"

# `results --db` takes a folder like `fit --db`; a file that is not a
# results database (text, empty, another application's SQLite database)
# is refused, exit 2 saying what --db takes, and left as it was (cmp);
# `fit --record --db` on one likewise (exit 1, the surface written).
n=$("$CF" results list --db "$T/results" | wc -l)
[ "$n" = 2 ] && ok "results list --db FOLDER: its results.db, 2 jobs" || no "results list --db FOLDER: $n"
printf 'x y z\n1 2 3\n' >"$T/notes.txt"
: >"$T/empty.db"
sqlite3 "$T/other.db" "CREATE TABLE parts (id INTEGER); INSERT INTO parts VALUES (7)"
for f in notes.txt empty.db other.db; do
    cp "$T/$f" "$T/$f.orig"
    for sub in list outbox; do
        expect 2 "results $sub --db $f: refused, exit 2" "$CF" results $sub --db "$T/$f"
        grep -q "$f: not a cellfit results database (.*); --db takes the results.db that .cellfit serve. or .cellfit fit --record. wrote, or their results folder" "$T/err" &&
            ok "  says it is not one and what --db takes" || no "  message: $(cat "$T/err")"
    done
    expect 1 "fit --record --db $f: not recorded, exit 1" "$CF" fit --base "$T/part/nominal.igs" \
        --points "$T/points.xyz" --out "$T/f5.igs" --db "$T/$f"
    grep -q "not a cellfit results database" "$T/err" && [ -f "$T/f5.igs" ] &&
        ok "  said so; the surface is written" || no "  message: $(cat "$T/err")"
    cmp -s "$T/$f" "$T/$f.orig" && [ ! -e "$T/$f-wal" ] && ok "  $f left as it was" ||
        no "$f changed: $(ls -la "$T/$f"*)"
    rm -f "$T/f5.igs"
done
"$CF" results list --db "$T/empty.db" 2>&1 | grep -q "(an empty file)" &&
    ok "an empty file is called one" || no "empty file: $("$CF" results list --db "$T/empty.db" 2>&1)"
expect 2 "results list --db a folder without results.db: exit 2" "$CF" results list --db "$T/cwd"
grep -q "cwd/results.db: no results database there" "$T/err" && ok "  names the results.db it looked for" ||
    no "  message: $(cat "$T/err")"

# cellfit scan --fit --record on the simulated rig: the journal, the
# surface and the report, each with sha256sum's checksum.
if [ -x "$SIM" ]; then
    "$SIM" --tcp 0 --homed --part "$T/part/nominal.igs" --noise 0.002 >"$T/sim.out" 2>"$T/sim.err" &
    PIDS="$PIDS $!"
    i=0
    while ! grep -q "cellsim: ready" "$T/sim.out" 2>/dev/null && [ $i -lt 200 ]; do sleep 0.05; i=$((i + 1)); done
    PORT=$(sed -n 's/^cellsim: tcp 127.0.0.1 \([0-9]*\)$/\1/p' "$T/sim.out")
    expect 0 "scan --fit --record" timeout 120 "$CF" scan --stage "tcp:127.0.0.1:$PORT:1" \
        --probe "tcp:127.0.0.1:$PORT:2" --nominal "$T/part/nominal.igs" --journal "$T/s.jnl" \
        --region 0:100:0:50 --step 10 --fit "$T/s.igs" --report "$T/s.json" --json --record --db "$DB"
    u3=$(uuid_of "$T/err")
    "$CF" results show "$u3" --db "$DB" --json >"$T/r3.json"
    m=$(same "$T/r3.json" "$T/s.json" rms:rms points:points) && [ "$(field "$T/r3.json" command)" = scan_fit ] &&
        ok "scan row: command scan_fit, rms and points = the scan's report" || no "scan row: $m $(cat "$T/r3.json")"
    bad=""
    for k in surface:s.igs report:s.json journal:s.jnl; do
        [ "$(field "$T/r3.json" "${k%%:*}_sha256")" = "$(sha256sum "$T/${k#*:}" | cut -d' ' -f1)" ] &&
            [ "$(field "$T/r3.json" "${k%%:*}_path")" = "$(realpath "$T/${k#*:}")" ] || bad="$bad $k"
    done
    [ -z "$bad" ] && ok "scan row: surface, report and journal paths with sha256sum's checksums" ||
        no "scan row files:$bad"
    stop_all
    # A drive fault at the 20th move: the scan fails (exit 1) and is
    # recorded as an error with the rig's code, its journal kept.
    "$SIM" --tcp 0 --homed --part "$T/part/nominal.igs" --fault stagefault:n20 >"$T/sim2.out" 2>"$T/sim2.err" &
    PIDS="$PIDS $!"
    i=0
    while ! grep -q "cellsim: ready" "$T/sim2.out" 2>/dev/null && [ $i -lt 200 ]; do sleep 0.05; i=$((i + 1)); done
    PORT=$(sed -n 's/^cellsim: tcp 127.0.0.1 \([0-9]*\)$/\1/p' "$T/sim2.out")
    expect 1 "scan --fit --record with a drive fault: exit 1" timeout 120 "$CF" scan \
        --stage "tcp:127.0.0.1:$PORT:1" --probe "tcp:127.0.0.1:$PORT:2" --nominal "$T/part/nominal.igs" \
        --journal "$T/e.jnl" --region 0:100:0:50 --step 10 --fit "$T/e.igs" --report "$T/e.json" --record --db "$DB"
    u4=$(uuid_of "$T/err")
    "$CF" results show "$u4" --db "$DB" --json >"$T/r4.json"
    code=$(field "$T/e.json" code)
    [ "$(field "$T/r4.json" state)" = error ] && [ "$(field "$T/r4.json" error_code)" = "${code#-}" ] &&
        [ "$code" -lt 0 ] && [ "$(field "$T/r4.json" rms)" = null ] && [ "$(field "$T/r4.json" surface_path)" = null ] &&
        [ "$(field "$T/r4.json" journal_sha256)" = "$(sha256sum "$T/e.jnl" | cut -d' ' -f1)" ] &&
        ok "failed scan's row: state error, error_code ${code#-} (the report's code $code), no fit, the journal's checksum" ||
        no "failed scan row: $(cat "$T/r4.json")"
    stop_all
else
    echo "skip scan --record: no cellsim beside $CF"
fi
echo "record: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
