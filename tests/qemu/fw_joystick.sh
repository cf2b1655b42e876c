#!/bin/bash
# Guest test: vehicle-fw's evdev joystick backend against a uinput virtual
# joystick (ujoy, range 0..1023). Centre stick: no motion; full forward: the
# unit drives forward; the device unplugged while in use: warning 152
# "joystick lost" and the unit stops (the tick never waits for the kernel
# to release the dead device: at the product's 1 kHz, fault 209 would show
# it); SIGTERM: exit 0.
# Run: tools/qemu/run-guest.sh -i tests/qemu/fw_joystick.sh build/vehicle-fw build/ujoy
set -u
# On failure also the unit's active alarms.
fail() {
	local al=""
	[ -p /tmp/in ] && kill -0 "${fw:-0}" 2>/dev/null && al="; alarms: $(reply 'getActiveAlarm 8')"
	echo "fw_joystick: FAIL: $*$al"
	[ -f /tmp/fw.err ] && sed 's/^/  fw: /' /tmp/fw.err
	exit 1
}
expect() { [ "$2" = "$3" ] || fail "$1: got '$2', expected '$3'"; }

coproc UJ { ujoy; }
read -r -t 5 -u "${UJ[0]}" line || fail "ujoy did not start"
case $line in "ujoy: /dev/input/event"*) dev=${line#ujoy: } ;; *) fail "ujoy: '$line'" ;; esac
uj() { echo "$1" >&"${UJ[1]}"; read -r -t 5 -u "${UJ[0]}" r || fail "ujoy: no answer to $1"; expect "ujoy $1" "$r" ok; }

cat >/tmp/vehicle.xml <<EOF2
<vehicle kinematics="differential" tick_hz="1000">
  <devices contact_sensor="false" obstacle_input="false" estop="false" joystick="true"
           joystick_deadband="0.05"/>
  <backends>
    <joystick device="$dev" x="ABS_X" rotation="ABS_RX"/>
  </backends>
</vehicle>
EOF2
echo '<io/>' >/tmp/io.xml
mkfifo /tmp/in
: >/tmp/out
vehicle-fw --config /tmp/vehicle.xml --io /tmp/io.xml --rt-priority 50 </tmp/in >/tmp/out \
	2>/tmp/fw.err &
fw=$!
exec 3>/tmp/in

reply() {
	local before now
	before=$(wc -l </tmp/out)
	echo "$1" >&3
	for _ in $(seq 1 200); do
		now=$(wc -l </tmp/out)
		[ "$now" -gt "$before" ] && break
		sleep 0.02
	done
	sed -n "$((before + 1))p" /tmp/out
}
cmd() { expect "$1" "$(reply "$1")" "$2"; }
# x in whole mm from "ok true X Y THETA"
pos_x() { reply getPosition | awk '{printf "%d", $3}'; }
# x in mm as reported (3 decimals)
pos_xf() { reply getPosition | awk '{print $3}'; }
# near A B: |A - B| below 0.1 mm
near() { awk -v a="$1" -v b="$2" 'BEGIN { d = a - b; exit !(d < 0.1 && d > -0.1) }'; }

cmd 'setPower true' 'ok true'
cmd 'setServo true' 'ok true'
cmd 'setJoystick true' 'ok true'
# Centre (512 of 0..1023 is inside the dead band): no motion.
uj 'x 512'
uj 'r 512'
sleep 0.5
cmd 'getPosition' 'ok true 0.000 0.000 0.000'

# Full forward: the unit moves forward, straight.
uj 'x 1023'
sleep 1.0
x1=$(pos_x)
[ "$x1" -gt 50 ] || fail "x after 1 s of full stick: $x1 mm; $(reply getState); $(reply 'getActiveAlarm 3'); $(reply '$rt')"
r=$(reply getPosition)
th=$(echo "$r" | awk '{print $5}')
expect "heading while driving straight" "$th" "0.000"

# Unplugged while in use: warning 152, the unit stops.
echo quit >&"${UJ[1]}"
read -r -t 5 -u "${UJ[0]}" r || fail "ujoy did not quit"
sleep 1.5 # stopping from speed at the acceleration limit takes 0.5 s
cmd 'getActiveAlarm 1' 'ok true 1 1 152 warning "joystick lost"'
# At rest the wheel loop may still dither by an encoder count (0.03 mm):
# standing still means less than 0.1 mm in 0.3 s.
a=$(pos_xf); sleep 0.3; b=$(pos_xf)
near "$b" "$a" || fail "position after the stop (stands still): $a mm, then $b mm"
awk -v a="$a" -v x="$x1" 'BEGIN { exit !(a > x) }' ||
	fail "position did not advance past $x1 mm before the stop: $a"

kill -TERM $fw
for _ in $(seq 1 250); do kill -0 $fw 2>/dev/null || break; sleep 0.02; done
kill -0 $fw 2>/dev/null && fail "vehicle-fw still running 5 s after SIGTERM"
wait $fw
expect "exit status" "$?" 0
grep -q 'final state: unpowered, relay open, servo off, stopped' /tmp/fw.err ||
	fail "final state not logged"
echo "fw_joystick: PASS"
