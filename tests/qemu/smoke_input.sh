#!/bin/bash
# Guest smoke test: uinput and evdev are loaded, /dev/uinput is usable and a
# virtual gamepad's events arrive on its evdev node (uinput_probe, copied in
# by run_smoke.sh). Run through tools/qemu/run-guest.sh.
set -u
fail() { echo "smoke_input: FAIL: $*"; exit 1; }

[ -d /sys/module/uinput ] || fail "uinput module not loaded"
[ -d /sys/module/evdev ] || fail "evdev module not loaded"
[ -c /dev/uinput ] || fail "/dev/uinput missing or not a character device"
[ -x /test/uinput_probe ] || fail "/test/uinput_probe not in the guest"
/test/uinput_probe || fail "uinput_probe exited with $?"
echo "smoke_input: PASS"
