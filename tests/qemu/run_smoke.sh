#!/bin/bash
# Runs the QEMU guest smoke tests (SocketCAN, GPIO, uinput), each in its own
# boot, after making sure the host is set up. Prints one summary line and
# exits non-zero when any test failed.
#
#   tests/qemu/run_smoke.sh        (as root on the first run: setup installs packages)
set -u
here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/../.." && pwd)
build=${BUILD:-$top/build}
case $build in /*) ;; *) build=$top/$build ;; esac
export BUILD=$build

t0=$(date +%s)
"$top/tools/qemu/setup.sh" || { echo "qemu smoke: setup failed"; exit 1; }
t1=$(date +%s)

probe=$build/qemu/uinput_probe
${CC:-cc} -std=c11 -O2 -Wall -Wextra -Werror -D_GNU_SOURCE -o "$probe" "$here/uinput_probe.c" ||
	{ echo "qemu smoke: building uinput_probe failed"; exit 1; }

passed=0; failed=""
run() {
	local t=$1; shift
	echo "=== $t"
	if "$top/tools/qemu/run-guest.sh" "$here/$t" "$@"; then
		passed=$((passed + 1))
	else
		failed="$failed $t"
	fi
}
run smoke_can.sh
run smoke_gpio.sh
run smoke_input.sh "$probe"
t2=$(date +%s)

echo "qemu smoke: setup $((t1 - t0)) s, guests $((t2 - t1)) s"
if [ -n "$failed" ]; then
	echo "qemu smoke: $passed passed, FAILED:$failed"
	exit 1
fi
echo "qemu smoke: $passed passed, 0 failed"
