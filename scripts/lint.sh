#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/lint.sh: clang-format (the project's .clang-format) and cppcheck on
# every C file we own, and no include arrow running up (scripts/arrows.sh).
# Fails on any difference or finding.
set -eu
# cppcheck on every core (CI's run is timed; the checks enabled here do not
# need cppcheck's whole-program pass, which -j turns off).
jobs="-j $(nproc 2>/dev/null || echo 1)"
files=$(ls firmware/*.[ch] lib/*.[ch] include/*.h examples/*.c host/*/*.[ch] hal/*.[ch] sim/*.[ch] tests/unit/*.[ch] boards/*/*.[ch] bench/*.[ch] 2>/dev/null || true)
bad=0
# clang-format one file a process, on every core (xargs -P); a file it
# finds unformatted prints a line, and any line fails the lint.
# shellcheck disable=SC2086 # files: one name a word
unformatted=$(printf '%s\n' $files | xargs -P "$(nproc 2>/dev/null || echo 1)" -n 1 sh -c \
    'clang-format --dry-run -Werror "$1" >/dev/null 2>&1 || echo "lint: $1 is not clang-formatted (make format)"' sh)
if [ -n "$unformatted" ]; then
    printf '%s\n' "$unformatted" | sort
    bad=1
fi
# cppcheck: the firmware with each board's configuration, the rest as host code.
cppcheck $jobs --quiet --error-exitcode=1 --enable=warning,performance,portability \
    --inline-suppr --suppress=missingIncludeSystem -Iboards/linux-cell -Ifirmware -Ilib \
    -Ihost/report -Ihost/jobs -Ihost/cell -Ihost/cmd -Ihal -Isim -Itests/unit -Iinclude \
    --std=c11 -D__GNUC__ firmware lib include host tests hal sim examples || bad=1
# Benchmarks (CHOLMOD's headers when installed: make bench installs them).
cppcheck $jobs --quiet --error-exitcode=1 --enable=warning,performance,portability --inline-suppr \
    --suppress=missingIncludeSystem -I/usr/include/suitesparse --std=c11 bench || bad=1
# Board ports, with a cross board's configuration.
cppcheck $jobs --quiet --error-exitcode=1 --enable=warning,performance,portability --inline-suppr \
    --suppress=missingIncludeSystem -Iboards/mps2-an500 -Iboards/common -Ifirmware --std=c11 \
    -D__GNUC__ boards/common boards/mps2-an500 boards/nucleo-h743zi || bad=1
# Include arrows between folders run one way (README, Layout).
sh scripts/arrows.sh || bad=1
# Every source file carries its licence (LICENSE, MIT) in its first two lines.
for f in $(git ls-files '*.c' '*.h' '*.cpp' '*.sh' '*.py' '*.mk' Makefile .ci/run 2>/dev/null); do
    head -n 2 "$f" | grep -q 'SPDX-License-Identifier: MIT' || { echo "lint: $f has no SPDX line"; bad=1; }
done
[ $bad -eq 0 ] && echo "lint: clang-format and cppcheck clean ($(echo $files | wc -w) files)"
exit $bad
