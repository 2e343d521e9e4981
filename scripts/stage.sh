#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/stage.sh: run one stage of make test and record its wall time
# (build/stages.txt), so a slow CI run says which stage it was.
# Usage: stage.sh NAME COMMAND [ARG...]
set -eu
name=$1
shift
mkdir -p build
t0=$(date +%s)
"$@"
t=$(($(date +%s) - t0))
printf 'stage %-12s %5d s\n' "$name" "$t" | tee -a build/stages.txt
