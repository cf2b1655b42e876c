#!/bin/bash
# vehicle-fw's QEMU guest tests (docs/linux.md, docs/qemu.md), one boot per
# tests/qemu/fw_*.sh. A script that passes counts as one passed test, one
# that fails as one failed test. Last line: "qemu-fw: N passed, M failed"
# (the suite format of tests/run_tests.sh).
#
#   tests/qemu/run_fw.sh [BUILD]     (after make; root on the first run:
#                                     tools/qemu/setup.sh installs packages)
#   FW_ONLY=fw_process.sh tests/qemu/run_fw.sh [BUILD]    one script alone
set -u
here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/../.." && pwd)
build=${1:-${BUILD:-$top/build}}
case $build in /*) ;; *) build=$top/$build ;; esac
export BUILD=$build

summary() { echo "qemu-fw: $1 passed, $2 failed"; }
if ! out=$("$top/tools/qemu/setup.sh" 2>&1); then
	printf '%s\n' "$out"
	echo "qemu-fw: setup failed (tools/qemu/setup.sh)"
	summary 0 1
	exit 1
fi
for f in "$build/vehicle-fw" "$build/ujoy" "$build/cia402-sim"; do
	[ -x "$f" ] || { echo "qemu-fw: $f missing: run make first"; summary 0 1; exit 1; }
done

# The guest's clock counts instructions (run-guest.sh -i): under TCG on a
# busy host the QEMU process waits for a CPU now and then, and with the
# host's clock the guest would see its tick late by that much and
# raise the firmware's overrun fault (209). With -i the host's load cannot
# delay the tick; what delays it inside the guest (a call that blocks the
# tick) still raises 209 and fails the test. A busy host only makes a run
# take longer: hence the 240 s limit.
# fw_process.sh runs the host-side test programs of vehicle-fw in the guest:
# they, their peers (socat, mbdrive-sim, /usr/bin/python3 with pymodbus) and
# the files they read go under /g as in the tree. Its cmocka results count
# test by test; every other script counts as one test.
process_files() {
	local f py=/usr/bin/python3
	for f in tests/test_linux_fw tests/test_linux_modbus vehicle-fw mbdrive-sim; do
		[ -x "$build/$f" ] || { echo "qemu-fw: $build/$f missing: run make first" >&2; return 1; }
		echo "$build/$f=/g/build/$f"
	done
	echo "$(command -v socat)=/usr/bin/socat"
	echo "$top/host_sim/devices/mb_crosscheck.py=/g/host_sim/devices/mb_crosscheck.py"
	echo "$top/config/io.xml=/g/config/io.xml"
	echo "$top/config/io-modbus.xml=/g/config/io-modbus.xml"
	echo "$(readlink -f $py)=/usr/bin/python3"
	"$py" "$top/host_sim/devices/mb_crosscheck.py" --list-modules | while IFS= read -r f; do
		case $f in "$top"/*) continue ;; esac
		echo "$f=$f"
	done
}
passed=0; failed=0
for t in "$here"/fw_*.sh; do
	[ -n "${FW_ONLY:-}" ] && [ "$(basename "$t")" != "$FW_ONLY" ] && continue
	echo "=== $(basename "$t")"
	if [ "$(basename "$t")" = fw_process.sh ]; then
		if ! mapfile -t extra < <(process_files) || [ ${#extra[@]} -lt 8 ]; then
			echo "qemu-fw: cannot collect the files for fw_process.sh"
			failed=$((failed + 1))
			continue
		fi
		out=$("$top/tools/qemu/run-guest.sh" -i -t 600 "$t" "${extra[@]}" 2>&1)
		rc=$?
		printf '%s\n' "$out"
		p=$(printf '%s\n' "$out" | sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
		f=$(printf '%s\n' "$out" | sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' | awk '{s+=$1} END {print s+0}')
		passed=$((passed + p)); failed=$((failed + f))
		[ $rc -ne 0 ] && [ "$f" -eq 0 ] && failed=$((failed + 1))
		continue
	fi
	"$top/tools/qemu/run-guest.sh" -i -t 240 "$t" "$build/vehicle-fw" "$build/ujoy" \
		"$build/cia402-sim" 2>&1
	if [ $? -eq 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
done
summary $passed $failed
[ $failed -eq 0 ]
