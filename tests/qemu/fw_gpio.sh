#!/bin/bash
# Guest test: vehicle-fw's libgpiod backend against the gpio test chip
# (docs/qemu.md). Input levels are forced through the module parameter,
# outputs read back from it; the console runs on a fifo (stdin) and a file
# (stdout). Covers: relay that does not close (setPower false + alarm 205),
# relay with feedback, servo enable lines, io.xml ids (active-low, 4-bit
# field, output), e-stop line (active-low) -> fault 208, SIGTERM mid-move
# -> decelerate, servo lines low, relay low, exit 0. A tick overrun (fault
# 209) fails the test (run-guest.sh -i keeps the host's load out of the
# guest's clock). 100 Hz: setPower waits settle_ms (10 ms) on the loop's
# thread, longer than half a period at 1 kHz.
# Run: tools/qemu/run-guest.sh -i tests/qemu/fw_gpio.sh build/vehicle-fw
set -u
# On failure also the unit's active alarms.
fail() {
	local al=""
	[ -p /tmp/in ] && kill -0 "${fw:-0}" 2>/dev/null && al="; alarms: $(reply 'getActiveAlarm 8')"
	echo "fw_gpio: FAIL: $*$al"
	[ -f /tmp/fw.err ] && sed 's/^/  fw: /' /tmp/fw.err
	exit 1
}
P=/sys/module/gpio_testchip/parameters
expect() { [ "$2" = "$3" ] || fail "$1: got '$2', expected '$3'"; }

# Lines: tc0 relay, tc1 relay feedback, tc2 e-stop (active-low: high =
# released), tc3/tc4 servo enable axis 0/1, tc5 contact; io.xml: id 1 on tc8
# (active-low), id 4 on tc10..13, id 5 output on tc14.
cat >/tmp/vehicle.xml <<'EOF'
<vehicle kinematics="differential" tick_hz="100">
  <devices contact_sensor="true" obstacle_input="false" estop="true" joystick="false"/>
  <backends>
    <power settle_ms="10"/>
    <line function="relay" chip="vs-testchip" line="0"/>
    <line function="relay_feedback" chip="vs-testchip" line="1"/>
    <line function="estop" chip="vs-testchip" line="2" active_low="true"/>
    <line function="servo_enable" axis="0" chip="vs-testchip" line="3"/>
    <line function="servo_enable" axis="1" chip="vs-testchip" line="4"/>
    <line function="contact" chip="vs-testchip" line="5"/>
  </backends>
</vehicle>
EOF
cat >/tmp/io.xml <<'EOF'
<io>
  <input id="1" name="dock" chip="vs-testchip" line="8" active_low="true"/>
  <input id="4" name="selector" width="4" chip="vs-testchip" line="10"/>
  <output id="5" name="lamp" chip="vs-testchip" line="14"/>
</io>
EOF

echo 0x0004 >$P/inputs # e-stop released, feedback open, dock line high (= inactive)
mkfifo /tmp/in
: >/tmp/out
vehicle-fw --config /tmp/vehicle.xml --io /tmp/io.xml --rt-priority 50 </tmp/in >/tmp/out \
	2>/tmp/fw.err &
fw=$!
exec 3>/tmp/in

# reply LINE: sends one console line, prints its one reply (4 s bound).
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
outputs() { cat $P/outputs; }

cmd 'getState' 'ok true 25 "Unpowered"'
expect "outputs at start (all inactive)" "$(outputs)" 0
r=$(reply '$rt')
case $r in *" sched fifo prio 50 mlock yes gpio_errors 0 joystick none battery_errors 0") ;; *) fail "\$rt: '$r'" ;; esac

# Relay commanded but its feedback stays open: refused, fault 205, relay
# commanded open again.
cmd 'setPower true' 'ok false'
expect "relay after failed close" "$(outputs)" 0
cmd 'getActiveAlarm 1' 'ok true 1 1 205 fault "main relay did not close"'
cmd 'clearAlarm' 'ok true'

# Feedback closes: power on; the relay line drives high.
echo 0x0006 >$P/inputs
cmd 'setPower true' 'ok true'
expect "relay closed" "$(outputs)" 1
cmd 'setServo true' 'ok true'
expect "relay + servo enable lines" "$(outputs)" 25

# io.xml ids: active-low input, 4-bit field, output.
echo $((0x0006 | 0x2c00)) >$P/inputs # tc8 low (dock active), selector 0b1011
cmd 'getInput 1' 'ok true 1'
cmd 'getInput 4' 'ok true 11'
cmd 'setOutput 5 1 1' 'ok true'
expect "lamp output" "$(outputs)" $((25 | 0x4000))
cmd 'setOutput 5 0 1' 'ok true'

# E-stop pressed (line low): fault 208, servo lines drop.
echo $((0x0002)) >$P/inputs
sleep 0.2
cmd 'getState' 'ok true 19 "Alarm-208"'
o=$(outputs)
expect "servo lines after e-stop" "$((o & 24))" 0

# Release, clear, servo on again, move, then SIGTERM mid-move.
echo 0x0006 >$P/inputs
cmd 'clearAlarm' 'ok true'
cmd 'setServo true' 'ok true'
cmd 'moveForward 2000' 'ok true'
sleep 0.5
cmd 'getState' 'ok true 17 "Busy"'
kill -TERM $fw
for _ in $(seq 1 250); do kill -0 $fw 2>/dev/null || break; sleep 0.02; done
kill -0 $fw 2>/dev/null && fail "vehicle-fw still running 5 s after SIGTERM"
wait $fw
expect "exit status" "$?" 0
expect "outputs after SIGTERM (relay, servo, lamp low)" "$(outputs)" 0
grep -q 'shutdown: stopped after' /tmp/fw.err || fail "no deceleration logged"
grep -q 'final state: unpowered, relay open, servo off, stopped' /tmp/fw.err ||
	fail "final state not logged"
echo "fw_gpio: PASS"
