#!/bin/bash
# Guest test: the link watchdog over CAN (docs/can.md, "Link watchdog").
# A host drives the unit with vehiclectl over vcan0: power, servo, a 5 m
# moveForward and a queued moveLinearAbs back to the start, then getPosition
# keep-alives until it cruises. Then the sender stops. Without sending anything more, the test watches the unit's status
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
expect "moveForward 5000" "true"
expect "moveLinearAbs 0 0 0" "true"
# getPosition as the keep-alive until the unit cruises (600 mm and on); the
# last one's answer is the pose at the last request the unit hears.
x0=""
for _ in $(seq 1 100); do
	# one attempt, long: a retransmission would be answered with the pose
	# of the first (docs/can.md) while it restarts the watchdog later
	last=$(vehiclectl --can vcan0 --timeout 3000 --retries 0 getPosition 2>&1) ||
		fail "getPosition: $last"
	x0=$(printf '%s\n' "$last" | sed -n 's/^true x=\([-0-9.]*\) .*/\1/p')
	[ -n "$x0" ] || fail "getPosition: $last"
	awk -v x="$x0" 'BEGIN { exit !(x >= 600) }' && break
	sleep 0.1
done
# cruising, and the route's end farther than the bound
awk -v x="$x0" 'BEGIN { exit !(x >= 600 && x <= 4000) }' ||
	fail "x $x0 at the last request: expected the unit cruising, 600..4000 mm"
pass "keep-alives hold the route: x $x0 mm at the last request"

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
near "$x2" "$x1" 0.05 || fail "moved after the stop: $x1 -> $x2 (the queued move must be gone)"
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
