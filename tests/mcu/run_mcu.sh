#!/bin/sh
# The Cortex-M images on QEMU's emulated boards (tests/mcu/mcu_test.py,
# docs/mcu.md). Last line: "mcu: N passed, M failed" (the suite format of
# tests/run_tests.sh).
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
	"$build/vehiclectl"; do
	[ -f "$f" ] || { echo "mcu: $f missing (make check builds it)"; echo "mcu: 0 passed, 1 failed"; exit 1; }
done
exec /usr/bin/python3 "$here/mcu_test.py" "$build"
