#!/bin/bash
# VehicleService over CORBA, end to end (make check; docs/corba.md):
#   1. the committed IDL equals the specification's appendix, both blocks joined
#   2. omniNames on a loopback port with its own data folder, started by
#      tools/corba/names.sh (the README's line) in a folder not yet there
#   3. vehicle-sim --pty --fast (lockstep), vehicle-corba on its pty, registered
#      under a configurable name, printing its IOR
#   4. vs-corba-client (stubs by omniidl from the same IDL) through the naming
#      service: all 34 operations and moves, exact results; through the IOR
#   5. a unit that does not answer (simulator stopped): TRANSIENT, bounded;
#      the gateway serves again when it answers
#   6. the gateway ends on SIGTERM and leaves the naming service clean; the
#      naming service ended and started again by the same line, on the data
#      file its first run left
#   7. the 34 operations again with the gateway on the unit's text console,
#      registered with that second naming service
# Every wait is bounded and polls for its condition; none is a fixed sleep.
# Usage: tests/corba/run.sh BUILD
set -u
build=${1:-build}
here=$(cd "$(dirname "$0")/../.." && pwd)
spec_dir=${VEHICLE_SPEC_DIR:-$here/../shared/spec}
spec_src=$spec_dir/000_1d9c60064e30aa86.txt
client=$build/tests/vs-corba-client
tmp=$(mktemp -d "${TMPDIR:-/tmp}/corba-test.XXXXXX")
passed=0
failed=0
pids=()

ok() { passed=$((passed + 1)); echo "ok   $*"; }
fail() { failed=$((failed + 1)); echo "FAIL $*"; }
cleanup() {
	local p
	for p in "${pids[@]}"; do kill -CONT "$p" 2>/dev/null; kill "$p" 2>/dev/null; done
	for p in "${pids[@]}"; do wait "$p" 2>/dev/null; done
	exec 7>&- 8<&- 2>/dev/null
	rm -rf "$tmp"
}
trap cleanup EXIT
finish() {
	echo "corba: $passed passed, $failed failed"
	exit $((failed > 0))
}
# wait_for SECONDS COMMAND...: polls COMMAND every 50 ms until it succeeds.
wait_for() {
	local end=$((SECONDS + $1))
	shift
	until "$@"; do
		[ $SECONDS -ge $end ] && return 1
		sleep 0.05
	done
}
# Folds the client's "corba-client: N passed, M failed" into the totals.
run_client() {
	local out p f rc
	out=$("$client" "$@" -ORBInitRef "NameService=corbaname::127.0.0.1:$ns_port" \
		-ORBclientCallTimeOutPeriod 60000 2>&1)
	rc=$?
	printf '%s\n' "$out" | sed 's/^/  /'
	p=$(printf '%s\n' "$out" | sed -n 's/^corba-client: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p')
	f=$(printf '%s\n' "$out" | sed -n 's/^corba-client: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p')
	if [ -z "$p" ]; then
		fail "vs-corba-client $1: no summary (crashed?)"
		return
	fi
	passed=$((passed + p))
	failed=$((failed + f))
	# A sanitizer report after the summary still fails the run.
	[ $rc -ne 0 ] && [ "$f" -eq 0 ] && fail "vs-corba-client $1: exit status $rc"
	return 0
}

# 1. The IDL. The specification lives next to the repository, not in it.
if [ -r "$spec_src" ]; then
	if "$here/tools/corba/extract-idl.sh" "$spec_src" | cmp -s - "$here/tools/corba/VehicleService.idl"; then
		ok "tools/corba/VehicleService.idl is the appendix IDL of $spec_src"
	else
		fail "tools/corba/VehicleService.idl differs from the appendix IDL of $spec_src"
	fi
else
	echo "note: $spec_src not found (VEHICLE_SPEC_DIR); IDL not compared"
fi

# 2. omniNames on 127.0.0.1 only, its own data folder (made by the script:
# not there yet); a free port found by trying (other builds may run beside
# this one).
names_dir=$tmp/names/data
# start_names PORT: tools/corba/names.sh in the background (its pid in ns;
# not holding the simulator's fifos, whose end the simulator waits for);
# true once it serves, false when it ended.
start_names() {
	rm -f "$tmp/names.log"
	"$here/tools/corba/names.sh" "$1" "$names_dir" -errlog "$tmp/names.log" \
		-ORBendPoint "giop:tcp:127.0.0.1:$1" >/dev/null 2>&1 7>&- 8<&- &
	ns=$!
	wait_for 30 sh -c "grep -q 'Root context is' '$tmp/names.log' 2>/dev/null || ! kill -0 $ns 2>/dev/null" &&
		kill -0 "$ns" 2>/dev/null && grep -q 'Root context is' "$tmp/names.log"
}
ns_port=
for try in 1 2 3 4 5 6 7 8 9 10; do
	port=$((20000 + (RANDOM * 7 + $$ + try * 997) % 30000))
	if start_names "$port"; then
		ns_port=$port
		pids+=("$ns")
		break
	fi
	kill "$ns" 2>/dev/null
	wait "$ns" 2>/dev/null
	rm -rf "$tmp/names"
done
if [ -z "$ns_port" ]; then
	fail "omniNames did not start on a loopback port"
	finish
fi
ok "omniNames on 127.0.0.1:$ns_port by tools/corba/names.sh, data in a folder it made"

# 3. The simulator in lockstep on a pty; its stdin/stdout on fds 7/8 for the
# client ('$wait', '$sim', direct console).
start_sim() {
	mkfifo "$tmp/sim.in" "$tmp/sim.out"
	"$build/vehicle-sim" --pty --fast --config "$here/config/vehicle.xml" \
		--io "$here/config/io.xml" <"$tmp/sim.in" >"$tmp/sim.out" 2>"$tmp/sim.log" &
	sim=$!
	pids+=("$sim")
	exec 7>"$tmp/sim.in" 8<"$tmp/sim.out"
	if ! read -r -t 60 -u 8 pty || [ ! -c "$pty" ]; then
		fail "vehicle-sim --pty --fast did not give its pty"
		finish
	fi
	# Time passes in the client's lockstep waits with no request to the
	# unit: the link watchdog is off for this run (tested elsewhere).
	echo '$watchdog 0' >&7
	if ! read -r -t 60 -u 8 wd || [ "$wd" != "ok watchdog 0" ]; then
		fail "\$watchdog 0: ${wd:-no reply}"
		finish
	fi
}
start_sim

name="test.vehicles/VehicleService.unit"
# Generous per attempt, so that a busy machine delaying the simulator is a
# retry (answered from the unit's cache), never a failure.
gw_timeout=1500
gw_retries=3
start_gateway() {
	"$build/vehicle-corba" --port "$pty" "$@" --timeout $gw_timeout --retries $gw_retries \
		--name "$name" --ior \
		-ORBInitRef "NameService=corbaname::127.0.0.1:$ns_port" \
		-ORBendPoint giop:tcp:127.0.0.1: >"$tmp/ior" 2>"$tmp/gw.log" &
	gw=$!
	pids+=("$gw")
}
start_gateway
if wait_for 60 grep -q '^IOR:' "$tmp/ior"; then
	ok "vehicle-corba printed its IOR"
else
	fail "vehicle-corba printed no IOR"
	cat "$tmp/gw.log"
	finish
fi
grep -q "registered as $name" "$tmp/gw.log" && ok "vehicle-corba registered as $name" ||
	fail "vehicle-corba did not report its registration"

# 4. The 34 operations through the naming service, and one call by the IOR.
run_client --all 7 8 --name "$name"
run_client --ping 25 --ior "$(head -1 "$tmp/ior")"

# 5. A unit that does not answer: every attempt waits its timeout, then
# TRANSIENT (the lower bound allows for the clock's millisecond rounding).
kill -STOP "$sim"
run_client --silent $((gw_timeout * (gw_retries + 1) - 10)) --name "$name"
kill -CONT "$sim"
run_client --ping 25 --name "$name"

# 6. SIGTERM: the gateway unbinds its name and exits 0.
kill -TERM "$gw"
if wait_for 60 sh -c "! kill -0 $gw 2>/dev/null"; then
	wait "$gw"
	rc=$?
	[ $rc -eq 0 ] && ok "vehicle-corba exits 0 on SIGTERM" || fail "vehicle-corba exit status $rc"
else
	fail "vehicle-corba still running 60 s after SIGTERM"
fi
run_client --unbound --name "$name"

# The naming service's second run: the same line, the data file of the
# first run there (where "omniNames -start" alone refuses).
kill -TERM "$ns"
wait "$ns" 2>/dev/null
if ls "$names_dir"/omninames-*.dat >/dev/null 2>&1; then
	ok "the first run left its data file in $names_dir"
else
	fail "no data file in $names_dir after the first run"
fi
if start_names "$ns_port"; then
	pids+=("$ns")
	ok "tools/corba/names.sh started omniNames again on its data file"
else
	fail "tools/corba/names.sh did not start omniNames a second time"
	cat "$tmp/names.log"
	finish
fi

# 7. The same 34 operations with the gateway on the unit's text console
# (a fresh simulator; doubles come back with the console's three decimals).
exec 7>&- 8<&-
wait "$sim"
rm -f "$tmp/sim.in" "$tmp/sim.out" "$tmp/ior"
start_sim
name="test.vehicles/VehicleService.console"
start_gateway --console
if wait_for 60 grep -q '^IOR:' "$tmp/ior"; then
	run_client --all 7 8 --console-link --name "$name"
else
	fail "vehicle-corba --console printed no IOR"
	cat "$tmp/gw.log"
fi

finish
