#!/bin/sh
# Installs the Debian packages the build, the simulator and the tests need.
# Idempotent: installs only what is missing. Run it as yourself or as root:
# it asks sudo for root only when it has something to install and is not
# root already (a container or CI often has no sudo at all).
set -e
as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
PKGS="build-essential make pkg-config libcmocka-dev libexpat1-dev valgrind clang \
clang-format clang-tidy cppcheck gcc-arm-none-eabi libnewlib-arm-none-eabi socat \
libgpiod-dev gpiod libmodbus-dev libevdev-dev python3-pymodbus python3-serial-asyncio \
libclang-rt-14-dev gcovr python3-serial python3-can python3-matplotlib qemu-system-arm \
omniidl libomniorb4-dev omniorb-nameserver python3-venv python3-pip python3-setuptools \
python3-wheel"
missing=""
for p in $PKGS; do
	dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
	echo "installing:$missing"
	as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
	as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
		$missing >/dev/null
fi
# The QEMU guest for the SocketCAN, GPIO and uinput tests: kernel, headers,
# qemu, can-utils, gpiod, python3-can; builds the test gpiochip module. It
# needs root only to install packages: as yourself first, then through sudo.
setup="$(dirname "$0")/qemu/setup.sh"
if [ "$(id -u)" -eq 0 ]; then
	"$setup"
else
	"$setup" || sudo "$setup"
fi
