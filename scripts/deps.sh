#!/bin/sh
# SPDX-License-Identifier: MIT
# scripts/deps.sh: install the Debian packages cellfit needs that this machine
# lacks. Usage: scripts/deps.sh [build|test|demo|bench|arch|all]. Says what
# it installs; does nothing when everything is present.
set -eu

# The rig's libraries are build dependencies: cellfit talks to devices.
# libaravis-dev: the GigE Vision profiler (hal/hal_gev.c) and its simulator (sim/sim_gev.c).
build_pkgs="gcc make libc6-dev pkg-config zlib1g-dev libmodbus-dev libserialport-dev libusb-1.0-0-dev libaravis-dev"
# Results at the cell and for the plant (mk/plant.mk): SQLite, libpq, libmosquitto.
build_pkgs="$build_pkgs libsqlite3-dev libpq-dev libmosquitto-dev"
# The simulated rig's wiring and the third-party peers the tests use.
rig_pkgs="socat mbpoll python3-pymodbus python3-serial python3-serial-asyncio umockdev libumockdev-dev"
# The real engines tests/cli/plant.sh and make plant-demo start, and their clients;
# openssl makes tests/cli/plant_tls.sh's certificates.
plant_pkgs="postgresql mosquitto mosquitto-clients sqlite3 openssl"
test_pkgs="$rig_pkgs $plant_pkgs libcmocka-dev clang libclang-rt-14-dev cppcheck clang-format valgrind python3 libocct-data-exchange-dev libocct-foundation-dev libocct-modeling-data-dev g++ gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm"
demo_pkgs="$rig_pkgs $plant_pkgs"
# Other CPUs (mk/arch.mk): qemu-user runs the build on a CPU without AVX
# (qemu-x86_64 -cpu Westmere) and the aarch64 cross build (qemu-aarch64);
# the cross compiler and the arm64 libraries (multiarch, below) build it;
# without Aravis for arm64 there, its GigE Vision profiler is "unsupported".
arch_pkgs="qemu-user gcc-aarch64-linux-gnu libc6-dev-arm64-cross"
arch_arm64_pkgs="libmodbus-dev:arm64 libserialport-dev:arm64 libusb-1.0-0-dev:arm64 libcmocka-dev:arm64 zlib1g-dev:arm64"
bench_pkgs="libsuitesparse-dev python3-scipy python3-numpy"

what="${1:-build}"
case "$what" in
build) want="$build_pkgs" ;;
test) want="$build_pkgs $test_pkgs $arch_pkgs $arch_arm64_pkgs" ;;
demo) want="$build_pkgs $demo_pkgs" ;;
bench) want="$build_pkgs $bench_pkgs" ;;
arch) want="$build_pkgs $arch_pkgs $arch_arm64_pkgs" ;;
all) want="$build_pkgs $test_pkgs $demo_pkgs $bench_pkgs $arch_pkgs $arch_arm64_pkgs" ;;
*) echo "usage: $0 [build|test|demo|bench|arch|all]" >&2; exit 2 ;;
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
# The :arm64 libraries need the architecture known to dpkg (then an update).
case "$missing" in
*:arm64*) dpkg --print-foreign-architectures | grep -qx arm64 || $SUDO dpkg --add-architecture arm64 ;;
esac
$SUDO apt-get update -q >/dev/null
# shellcheck disable=SC2086
$SUDO apt-get install -y -q --no-install-recommends $missing >/dev/null
echo "deps: done"
