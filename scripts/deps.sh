#!/bin/sh
# scripts/deps.sh: install the Debian packages cellfit needs that this machine
# lacks. Usage: scripts/deps.sh [build|test|demo|bench|all]. Says what it
# installs; does nothing when everything is present.
set -eu

# The rig's libraries are build dependencies: cellfit talks to devices.
build_pkgs="gcc make libc6-dev pkg-config libmodbus-dev libserialport-dev libusb-1.0-0-dev"
# Results at the cell and for the plant (mk/plant.mk): SQLite, libpq, libmosquitto.
build_pkgs="$build_pkgs libsqlite3-dev libpq-dev libmosquitto-dev"
# The simulated rig's wiring and the third-party peers the tests use.
rig_pkgs="socat mbpoll python3-pymodbus python3-serial python3-serial-asyncio umockdev libumockdev-dev"
# The real engines tests/cli/plant.sh and make plant-demo start, and their clients.
plant_pkgs="postgresql mosquitto mosquitto-clients sqlite3"
test_pkgs="$rig_pkgs $plant_pkgs libcmocka-dev clang libclang-rt-14-dev cppcheck clang-format valgrind python3 libocct-data-exchange-dev libocct-foundation-dev libocct-modeling-data-dev g++ gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
demo_pkgs="$rig_pkgs $plant_pkgs"
bench_pkgs="libsuitesparse-dev python3-scipy python3-numpy"

what="${1:-build}"
case "$what" in
build) want="$build_pkgs" ;;
test) want="$build_pkgs $test_pkgs" ;;
demo) want="$build_pkgs $demo_pkgs" ;;
bench) want="$build_pkgs $bench_pkgs" ;;
all) want="$build_pkgs $test_pkgs $demo_pkgs $bench_pkgs" ;;
*) echo "usage: $0 [build|test|demo|bench|all]" >&2; exit 2 ;;
esac

missing=""
for p in $want; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done
[ -z "$missing" ] && exit 0

echo "deps: installing Debian packages:$missing"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q >/dev/null
# shellcheck disable=SC2086
$SUDO apt-get install -y -q --no-install-recommends $missing >/dev/null
echo "deps: done"
