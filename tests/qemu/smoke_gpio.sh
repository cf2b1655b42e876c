#!/bin/bash
# Guest smoke test: libgpiod tools against the gpio test chip. Input levels
# are forced through the module parameter and read with gpioget; outputs are
# driven with gpioset and read back through the parameter; edges written to
# the parameter arrive as gpiomon events.
# Run through tools/qemu/run-guest.sh.
set -u
fail() { echo "smoke_gpio: FAIL: $*"; exit 1; }
P=/sys/module/gpio_testchip/parameters

expect() { # expect WHAT GOT WANT
	[ "$2" = "$3" ] || fail "$1: got '$2', expected '$3'"
}
# gpioinfo's line for OFFSET with runs of blanks squeezed and ends trimmed.
info_line() {
	gpioinfo gpiochip0 | sed -n "$(($1 + 2))p" | tr -s ' \t' ' ' | sed 's/^ //; s/ $//'
}

# Waits until a consumer named $2 holds line $1.
wait_held() {
	for _ in $(seq 1 100); do
		[ "$(info_line "$1" | cut -d' ' -f4)" = "\"$2\"" ] && return 0
		sleep 0.05
	done
	fail "line $1 not requested by $2 within 5 s: $(info_line "$1")"
}

# Exactly one chip in the guest, and it is ours.
expect gpiodetect "$(gpiodetect)" "gpiochip0 [vs-testchip] (16 lines)"
chip=gpiochip0
expect "gpiofind tc5" "$(gpiofind tc5)" "gpiochip0 5"
expect "line 0 after load" "$(info_line 0)" \
	'line 0: "tc0" unused input active-high'

# Input levels: two different patterns, so a cached or constant value fails.
echo 0x8005 >$P/inputs || fail "cannot write $P/inputs"
expect "inputs readback" "$(cat $P/inputs)" 32773
expect "gpioget 0 1 2 3 15" "$(gpioget $chip 0 1 2 3 15)" "1 0 1 0 1"
echo 0x7ffa >$P/inputs
expect "gpioget 0 1 2 3 15" "$(gpioget $chip 0 1 2 3 15)" "0 1 0 1 0"
expect "gpioget -l 1 (active-low)" "$(gpioget -l $chip 1)" "0"
expect "dirs after gpioget" "$(cat $P/dirs)" 0

# Outputs: gpioset drives, the chip records level and direction.
gpioset $chip 4=1 6=1 7=0 || fail "gpioset 4=1 6=1 7=0"
expect "outputs after gpioset" "$(cat $P/outputs)" 80
expect "dirs after gpioset" "$(cat $P/dirs)" 208
gpioset $chip 4=0 || fail "gpioset 4=0"
expect "outputs after clearing line 4" "$(cat $P/outputs)" 64
expect "line 6 after gpioset" "$(info_line 6)" \
	'line 6: "tc6" unused output active-high'
# Requesting the line as input again hands it back to the forced level.
echo 0x0040 >$P/inputs
expect "gpioget 6 back as input" "$(gpioget $chip 6)" 1
expect "dirs after gpioget 6" "$(cat $P/dirs)" 144

# A line held by a consumer is reported busy to a second one.
gpioset --mode=signal $chip 9=1 &
set_pid=$!
wait_held 9 gpioset
expect "outputs while line 9 held" "$(cat $P/outputs)" 576
gpioget $chip 9 >/dev/null 2>&1 && fail "gpioget of a held line succeeded"
kill $set_pid
wait $set_pid 2>/dev/null
echo "smoke_gpio: levels ok"

# Edge events. The guest has one CPU and the kernel's event thread has
# real-time priority, so each edge is queued before the next write returns;
# no sleeps needed. Unchanged levels and unwatched lines must not add events.
echo 0 >$P/inputs
timeout 10 gpiomon -n 4 -F '%e %o' $chip 3 5 >/tmp/mon &
mon_pid=$!
wait_held 3 gpiomon
echo 0x0008 >$P/inputs # line 3 rises
echo 0x0008 >$P/inputs # no change
echo 0x0808 >$P/inputs # line 11, not watched
echo 0x0828 >$P/inputs # line 5 rises
echo 0x0820 >$P/inputs # line 3 falls
echo 0x0800 >$P/inputs # line 5 falls
wait $mon_pid || fail "gpiomon exited with $? (timeout: events missing); got: $(cat /tmp/mon)"
# Each line is its own event stream (v1 uAPI); only the order within a line
# is defined, so the streams are compared one by one.
expect "gpiomon event count" "$(wc -l </tmp/mon)" 4
expect "gpiomon both edges, line 3" "$(grep ' 3$' /tmp/mon)" "1 3
0 3"
expect "gpiomon both edges, line 5" "$(grep ' 5$' /tmp/mon)" "1 5
0 5"
# An edge nobody listened to is not replayed to the next requester: a stale
# event would read the current level (1) and report "1 3" first.
echo 0x0008 >$P/inputs
timeout 10 gpiomon -n 1 -F '%e %o' $chip 3 >/tmp/mon &
mon_pid=$!
wait_held 3 gpiomon
echo 0x0000 >$P/inputs
wait $mon_pid || fail "gpiomon exited with $?; got: $(cat /tmp/mon)"
expect "gpiomon after an unwatched edge" "$(cat /tmp/mon)" "0 3"
# A rising-edge request skips falling edges.
timeout 10 gpiomon -r -n 2 -F '%e %o' $chip 3 >/tmp/mon &
mon_pid=$!
wait_held 3 gpiomon
echo 0x0008 >$P/inputs
echo 0x0000 >$P/inputs
echo 0x0008 >$P/inputs
wait $mon_pid || fail "gpiomon -r exited with $?; got: $(cat /tmp/mon)"
expect "gpiomon rising edges" "$(cat /tmp/mon)" "1 3
1 3"
echo "smoke_gpio: edge events ok"
echo "smoke_gpio: PASS"
