#!/bin/bash
# vehicle-fw's QEMU guest tests (docs/linux.md, docs/qemu.md), one boot per
# tests/qemu/fw_*.sh. A script that passes counts as one passed test, one
# that fails as one failed test. Last line: "qemu-fw: N passed, M failed"
# (the suite format of tests/run_tests.sh).
#
#   tests/qemu/run_fw.sh [BUILD]     (after make; root on the first run:
#                                     tools/qemu/setup.sh installs packages)
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
for f in "$build/vehicle-fw" "$build/ujoy"; do
	[ -x "$f" ] || { echo "qemu-fw: $f missing: run make first"; summary 0 1; exit 1; }
done

# Under TCG on a loaded host the guest's 100 Hz tick is sometimes late
# enough for the firmware's overrun fault (209), which stops the unit and
# spoils the scenario. Such a run (and only such a run) is repeated, up to
# twice, and says so.
passed=0; failed=0
for t in "$here"/fw_*.sh; do
	for attempt in 1 2 3; do
		echo "=== $(basename "$t")${attempt#1}"
		out=$("$top/tools/qemu/run-guest.sh" "$t" "$build/vehicle-fw" "$build/ujoy" 2>&1)
		rc=$?
		printf '%s\n' "$out"
		[ $rc -eq 0 ] && break
		case $out in
		*'FAIL:'*' 209 fault "control tick overrun"'*)
			echo "qemu-fw: $(basename "$t"): tick overrun in the guest (TCG timing), run again" ;;
		*) break ;;
		esac
	done
	if [ $rc -eq 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
done
summary $passed $failed
[ $failed -eq 0 ]
