#!/bin/bash
# The CAN link tests inside a QEMU-booted Debian kernel (docs/qemu.md): one
# guest boot per script in tests/qemu/can_*.sh, with vehicle-sim, vehiclectl,
# the configuration and (for can_peers.sh) python3 with python3-can.
# Every "<test>: PASS: ..." line in a guest counts as one passed test, a
# script that fails counts as one failed test. Last line:
#   qemu: N passed, M failed
#
#   tests/run_qemu_tests.sh [BUILD]     (after make; root on the first run:
#                                        tools/qemu/setup.sh installs packages)
set -u
here=$(cd "$(dirname "$0")" && pwd)
top=$(cd "$here/.." && pwd)
build=${1:-${BUILD:-$top/build}}
case $build in /*) ;; *) build=$top/$build ;; esac
export BUILD=$build
cd "$top" || exit 1

summary() { echo "qemu: $1 passed, $2 failed"; }

if ! out=$("$top/tools/qemu/setup.sh" 2>&1); then
	printf '%s\n' "$out"
	echo "qemu: setup failed (tools/qemu/setup.sh)"
	summary 0 1
	exit 1
fi
for f in "$build/vehicle-sim" "$build/vehicle-fw" "$build/vehiclectl" "$build/vehicle-corba" \
	"$build/tests/vs-corba-client"; do
	[ -x "$f" ] || { echo "qemu: $f missing: run make first"; summary 0 1; exit 1; }
done

common=("$build/vehicle-sim" "$build/vehiclectl" "$here/qemu/can_lib.sh"
	"$top/config/vehicle.xml=/test/config/vehicle.xml" "$top/config/io.xml=/test/config/io.xml")

# python3 and exactly the modules can_python.py imports, as compiled .pyc
# files in place of the sources (no compiling under TCG), from the host's
# Debian python3 (python3-can imports only there).
py=/usr/bin/python3
pyfiles=()
if ! mods=$("$py" "$here/qemu/can_python.py" --list-modules 2>&1) ||
	! mods2=$(PYTHONPATH=$top/python "$py" "$here/qemu/can_vs.py" --list-modules 2>&1); then
	printf '%s\n%s\n' "$mods" "${mods2:-}"
	echo "qemu: $py cannot import python3-can (apt-get install python3-can)"
	summary 0 1
	exit 1
fi
pyfiles+=("$(readlink -f "$py")=/usr/bin/python3")
declare -A seen=()
while IFS= read -r f; do
	case $f in "$here"/* | "$top"/python/*) continue ;; esac
	[ -n "${seen[$f]:-}" ] && continue
	seen[$f]=1
	case $f in
	*.py)
		d=$(dirname "$f"); b=$(basename "$f" .py)
		pyc=$d/__pycache__/$b.cpython-$("$py" -c 'import sys; print("%d%d" % sys.version_info[:2])').pyc
		if [ -f "$pyc" ]; then pyfiles+=("$pyc=$d/$b.pyc"); else pyfiles+=("$f=$f"); fi
		;;
	*) pyfiles+=("$f=$f") ;;
	esac
done <<<"$mods
$mods2"
# the Python client itself, as sources
for f in "$top"/python/vehicleservice/*.py; do
	pyfiles+=("$f=/test/vehicleservice/$(basename "$f")")
done

passed=0; failed=0; failed_names=""
run() {
	local script=$1; shift
	local log rc n
	echo "=== $script"
	log=$(mktemp)
	# -i: the guest's clock counts instructions, so a busy host cannot
	# stretch the time between two frames a script sends (the unit drops a
	# message whose next frame is 250 ms late) or make a peer time out.
	"$top/tools/qemu/run-guest.sh" -i -t 300 "$here/qemu/$script" "$@" 2>&1 | tee "$log"
	rc=${PIPESTATUS[0]}
	n=$(grep -cE '^[a-z_]+: PASS: ' "$log")
	rm -f "$log"
	passed=$((passed + n))
	if [ "$rc" -ne 0 ]; then
		failed=$((failed + 1))
		failed_names="$failed_names $script"
	fi
}
t0=$(date +%s)
run can_link.sh "${common[@]}"
run can_peers.sh "${common[@]}" "$here/qemu/can_python.py" "$here/qemu/can_vs.py" "${pyfiles[@]}"
run can_isotp.sh "${common[@]}"
run can_watchdog.sh "${common[@]}"
run can_fw.sh "${common[@]}" "$build/vehicle-fw"
run can_corba.sh "${common[@]}" "$build/vehicle-corba" "$build/tests/vs-corba-client"
echo "qemu: guests took $(($(date +%s) - t0)) s"
[ -n "$failed_names" ] && echo "qemu: FAILED:$failed_names"
summary "$passed" "$failed"
[ "$failed" -eq 0 ]
