#!/bin/bash
# Guest test: the link watchdog over CAN (docs/can.md, "Link watchdog").
# A host drives the unit with vehiclectl over vcan0: power, servo, a 3 m
# moveForward and a queued moveLinearAbs back to the start, then getState
# keep-alives every 200 ms for 2 s, and a last getPosition. Then the sender
# stops. Without sending anything more, the test watches the unit's status
# frames (node 1, 10 Hz) until the state leaves Busy and the speed is 0.
# Asserted: the stop lies within timeout x v + v^2 / (2 a_max) + 2 ticks of
# travel (1 s x 500 mm/s + 125 mm + 1 mm = 626 mm) of the pose of the last
# request; warning 153 "link lost: CAN silent 1000 ms"; the queued move is
# gone (the unit stays put); and a new command afterwards runs.
# The simulator keeps its own regular time, so the bound holds however busy
# the host is.
set -u
T=can_watchdog
. /test/can_lib.sh

start_sim --node 1 --status-hz 10 --config /test/config/vehicle.xml --io /test/config/io.xml
expect "setPower true" "true"
expect "setServo true" "true"
expect "moveForward 3000" "true"
expect "moveLinearAbs 0 0 0" "true"
for _ in $(seq 1 10); do
	sleep 0.2
	vc getState
	case $OUT in "true state=17 "*) ;; *) fail "keep-alive getState: $OUT" ;; esac
done
last=$(pos)
x0=$(printf '%s\n' "$last" | sed -n 's/^true x=\([-0-9.]*\) .*/\1/p')
[ -n "$x0" ] || fail "getPosition: $last"
near "$x0" 1000 600 || fail "x $x0 at the last request: expected the unit at speed"
pass "keep-alives hold the route: x $x0 mm after 2 s"

# Silent from here: only the unit's status frames are read.
stopped=""
for _ in $(seq 1 100); do
	timeout 2 candump -L -n 3 vcan0,181:7FF,281:7FF >/tmp/st 2>/dev/null
	a=$(grep ' vcan0 181#' /tmp/st | tail -1 | cut -d'#' -f2)
	case $a in 1100*) continue ;; ????????????0000) stopped=$a; break ;; esac
done
[ -n "$stopped" ] || fail "the unit did not stop without its host (last status A: $a)"
sleep 0.5
last=$(pos)
x1=$(printf '%s\n' "$last" | sed -n 's/^true x=\([-0-9.]*\) .*/\1/p')
awk -v a="$x0" -v b="$x1" 'BEGIN { d = b - a; exit !(d <= 626.0 && d > 600.0) }' ||
	fail "stopping distance $x0 -> $x1 mm, expected within 626 mm (and over 600)"
pass "stopped $(awk -v a="$x0" -v b="$x1" 'BEGIN { printf "%.1f", b - a }') mm after the last request (bound 626)"

expect "getActiveAlarm 4" 'true numOfActiveAlarm=1 activeAlarms=1[153 warning "link lost: CAN silent 1000 ms"]'
vc getState
case $OUT in "true state=18 Msg=\"Warning-153\"") ;; *) fail "getState after the stop: $OUT" ;; esac
sleep 1
x2=$(pos | sed -n 's/^true x=\([-0-9.]*\) .*/\1/p')
[ "$x2" = "$x1" ] || fail "moved after the stop: $x1 -> $x2 (the queued move must be gone)"
pass "warning 153 names CAN; the queue is discarded"

expect "moveForward 100" "true"
for _ in $(seq 1 50); do
	sleep 0.2
	vc getState
	case $OUT in "true state=17 "*) ;; *) break ;; esac
done
x3=$(pos | sed -n 's/^true x=\([-0-9.]*\) .*/\1/p')
near "$x3" "$(awk -v a="$x2" 'BEGIN { print a + 100 }')" 1.0 || fail "new move: $x2 -> $x3"
pass "a new command runs: $x2 -> $x3 mm"
stop_sim
