#!/bin/bash
# Guest test: the CAN link end to end on vcan0. vehicle-sim --can serves the
# unit; vehiclectl (the client library's CAN transport) drives conformance
# scenarios; the jog watchdog stops a unit whose host went silent; floods of
# malformed and random frames at full rate neither crash nor move the unit,
# lose no queued motion, and are counted. Run by tests/run_qemu_tests.sh.
set -u
T=can_link
. /test/can_lib.sh

start_sim --node 1 --status-hz 20

# ---- random frames at full rate on the request id, unit unpowered ---------
cangen vcan0 -I 601 -L r -D r -g 0 -i -n 20000 || fail "cangen random flood"
alive "random flood"
expect "getServoStatus 0" "true status=false"
expect "getServoStatus 1" "true status=false"
vc getPosition
[ "$OUT" = "true x=0 y=0 theta=0" ] || fail "random flood moved the pose: $OUT"
# Undo whatever a random frame may have happened to set.
expect "setJoystick false" "true"
expect "setDigitalSensorLock false" "true"
expect "setPower false" "true"
expect clearAlarm "true"
pass "20000 random frames: alive, servo off, pose 0 0 0, link answers"

# ---- conformance over CAN --------------------------------------------------
vc info
case $OUT in "protocol 1 table 0x"*" operations 34 "*) ;; *) fail "info: $OUT" ;; esac
expect getState 'true state=25 Msg="Unpowered"'
expect getIFVersion 'true version="RTC VehicleService interface: ver.2.0.0"'
expect getVersion 'true ver="Ver.1.0.0"'
expect getVelocityLimit "true velLimitT=1000 velLimitR=180"
expect getAccelerationLimit "true accLimitT=1000 accLimitR=360"
expect getDefaultVelocity "true translation=500 rotation=90"
expect "getActiveAlarm 4" "true numOfActiveAlarm=0 activeAlarms=0[]"
expect "moveForward 100" "false" 1
expect "getActiveAlarm 4" \
	'true numOfActiveAlarm=1 activeAlarms=1[121 warning "moveForward refused: servo off"]'
expect clearAlarm "true"
expect "setPower true" "true"
expect "setServo true" "true"
expect getState 'true state=16 Msg="Ready"'
expect "moveForward 500" "true"
expect getState 'true state=17 Msg="Busy"'
expect "moveTurn 90" "false" 1
wait_state 18 10 # Warning-120 after the refused moveTurn, idle again
sleep 1 # the wheels settle on the end of the trajectory
x=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/')
near "$x" 500 0.05 || fail "moveForward 500 ended at x=$x"
expect clearAlarm "true"
expect "setVelocity 0 90" "false" 1
expect "setJogTimeout 0" "false" 1
expect clearAlarm "true"
pass "conformance scenario over CAN (queries, refusals, moveForward 500 -> x=$x)"

# ---- jog watchdog: the host goes silent -----------------------------------
expect "setJogTimeout 300" "true"
x0=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/')
expect "moveJog 200 0 0" "true"
expect getState 'true state=17 Msg="Busy"'
sleep 1.5
expect getState 'true state=16 Msg="Ready"'
# at rest the encoder may still flip by one count (0.029 mm)
x1=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/'); sleep 0.5
x2=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/')
near "$x1" "$x2" 0.05 || fail "still moving after the jog watchdog: x $x1 then $x2"
near "$x2" "$x0" 20 && fail "the jog did not move the unit: x $x0 -> $x2"
candump -L -n 1 vcan0,181:7FF >/tmp/st &
wait $! || fail "no status frame"
# status A: state 0x0010 (Ready), speed bytes 6-7 zero
grep -qE ' vcan0 181#1000........0000$' /tmp/st || fail "status after the stop: $(cat /tmp/st)"
pass "jog watchdog stopped the unit 300 ms after the last moveJog (x $x2)"

# ---- malformed floods while motion is queued -------------------------------
expect "setPosition 0 0 0" "true"
expect pause "true"
expect "moveLinearAbs 200 0 0" "true"
expect "moveLinearAbs 400 0 0" "true"
expect "moveLinearAbs 600 0 0" "true"
# Each 3000 frames back to back: reserved frame type; stray consecutive
# frame; oversize first frame (NAKed), then its consecutive frames
# (discarded); single frame shorter than it says; unknown opcode (NAKed);
# moveForward with 2 payload bytes (NAKed); first frame shorter than 8.
for spec in "-L 8 -D 3F00112233445566" "-L 8 -D 2A00112233445566" \
	"-L 8 -D 1FFF010203040506" "-L 8 -D 2B00112233445566" "-L 2 -D 0709000000000000" \
	"-L 3 -D 0201EE0000000000" "-L 5 -D 0402110000000000" "-L 4 -D 1014010200000000"; do
	# shellcheck disable=SC2086
	cangen vcan0 -I 601 $spec -g 0 -i -n 3000 || fail "cangen $spec"
	alive "flood $spec"
done
# other nodes' identifiers
cangen vcan0 -I r -L r -D r -g 0 -i -n 5000 || fail "cangen random ids"
sleep 0.5
alive "floods"
expect getState 'true state=21 Msg="Paused"'
# setPosition 0 0 0 then paused: at most the one-count flicker of a
# wheel at rest
x=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/')
near "$x" 0 0.05 || fail "the unit moved during the floods: x=$x"
expect resume "true"
wait_state 16 20
sleep 1
x=$(pos | sed 's/^true x=\([^ ]*\) .*/\1/')
near "$x" 600 0.05 || fail "queued motion after the floods ended at x=$x, expected 600"
pass "malformed floods: nothing moved while paused, queue kept, ended at x=$x"

stop_sim
for c in bad_pci sequence bad_dlc oversize discarded naks; do
	v=$(counter $c)
	[ -n "$v" ] && [ "$v" -gt 0 ] || fail "counter $c is '$v' after the floods ($COUNTERS)"
done
echo "$T: counters: $COUNTERS"
# Every frame sent to the unit was taken (rx) or dropped by the kernel for a
# full receive buffer (sock_rx_overflow): 44000 flood frames plus requests.
total=$(($(counter rx) + $(counter sock_rx_overflow)))
[ "$total" -ge 44000 ] || fail "only $total of at least 44000 frames accounted for"
pass "every kind of bad frame counted"
echo "$T: all passed"
