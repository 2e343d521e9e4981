#!/bin/sh
# SPDX-License-Identifier: MIT
# tests/cli/faults.sh CELLFIT: the fault-injection matrix (every cellsim
# fault, a full disk and an unwritable output x homing, scanning, fitting,
# exporting: defined ending, the code, a consistent journal holding every
# acknowledged point, the next job on the same cellsim) and 25 power cuts
# of `cellfit scan` (kill -9, then recovery); tests/cli/faults.py does the
# work (docs/reliability-faults.md). FAULTS_CUTS=N for more power cuts.
# Without cellsim (a build without sim/) there is nothing to run.
set -u
. "$(dirname "$0")/lib.sh"
CF=$(realpath "$1")
if [ ! -x "$(dirname "$CF")/cellsim" ]; then
    echo "skip faults: no cellsim beside $CF"
    echo "faults: 0 passed, 0 failed"
    exit 0
fi
exec timeout 300 /usr/bin/python3 "$(dirname "$0")/faults.py" "$CF" "${FAULTS_CUTS:-25}"
