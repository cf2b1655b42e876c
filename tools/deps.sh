#!/bin/sh
# Installs the Debian packages the build, the simulator and the tests need.
# Idempotent: installs only what is missing. Run as root (or with sudo).
set -e
PKGS="build-essential make pkg-config libcmocka-dev libexpat1-dev valgrind clang \
clang-format clang-tidy cppcheck gcc-arm-none-eabi libnewlib-arm-none-eabi socat \
libgpiod-dev gpiod libmodbus-dev libevdev-dev python3-pymodbus python3-serial-asyncio \
libclang-rt-14-dev gcovr omniidl libomniorb4-dev omniorb-nameserver"
missing=""
for p in $PKGS; do
	dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
	echo "installing:$missing"
	export DEBIAN_FRONTEND=noninteractive
	apt-get update -qq
	apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
# The QEMU guest for the SocketCAN, GPIO and uinput tests: kernel, headers,
# qemu, can-utils, gpiod, python3-can; builds the test gpiochip module.
"$(dirname "$0")/qemu/setup.sh"
