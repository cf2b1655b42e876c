#!/bin/sh
# The Cortex-M images on QEMU's emulated boards (tests/mcu/mcu_test.py,
# tests/mcu/mcu_drives.py, docs/mcu.md). Last line: "mcu: N passed, M
# failed" (the suite format of tests/run_tests.sh).
#   tests/mcu/run_mcu.sh [BUILD]     (after make check's image build, or
#                                     make TARGET=cortex-m4 and cortex-m0)
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
for f in qemu-system-arm arm-none-eabi-nm; do
	command -v $f >/dev/null || { echo "mcu: $f missing (tools/deps.sh)"; echo "mcu: 0 passed, 1 failed"; exit 1; }
done
for f in "$build/cortex-m4/vehicle.elf" "$build/cortex-m4/bench.elf" "$build/cortex-m4/divcheck.elf" \
	"$build/cortex-m4/vehicle-cut.elf" \
	"$build/cortex-m4-omni/vehicle.elf" \
	"$build/cortex-m0/vehicle.elf" \
	"$build/cortex-m4-mb/vehicle-test.elf" \
	"$build/vehiclectl" "$build/mbdrive-sim"; do
	[ -f "$f" ] || { echo "mcu: $f missing (make check builds it)"; echo "mcu: 0 passed, 1 failed"; exit 1; }
done
# The loopback board's suite, then the Modbus board's drives, watchdog and
# fault handler (mcu_drives.py: the moves against mbdrive-sim and pymodbus,
# the alarm, the silent drive, the restarts); one summary line for both.
out=$(mktemp)
trap 'rm -f "$out"' EXIT
/usr/bin/python3 "$here/mcu_test.py" "$build" | tee "$out" | grep -v '^mcu: '
/usr/bin/python3 "$here/mcu_drives.py" "$build" | tee -a "$out" |
	grep -v '^mcu-drives: '
awk '/^mcu: [0-9]+ passed|^mcu-drives: [0-9]+ passed/ { p += $2; f += $4; n++ }
	END { if (n != 2) f++; printf "mcu: %d passed, %d failed\n", p, f; exit f > 0 }' "$out"
