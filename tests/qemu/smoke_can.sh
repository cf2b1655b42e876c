#!/bin/bash
# Guest smoke test: SocketCAN frames over vcan0 (candump/cansend) and, when
# can-isotp is in the guest kernel, one ISO-TP transfer (isotpsend/isotprecv).
# Run through tools/qemu/run-guest.sh.
set -u
fail() { echo "smoke_can: FAIL: $*"; exit 1; }

# Waits until at least WANT CAN receivers are registered on vcan0, so a frame
# sent next cannot overtake a listener's bind.
wait_rx() {
	local want=$1
	for _ in $(seq 1 100); do
		[ "$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')" -ge "$want" ] && return 0
		sleep 0.05
	done
	cat /proc/net/can/rcvlist_*
	fail "fewer than $want CAN receivers registered on vcan0 within 5 s"
}

# Raw frames: standard id, extended id, empty payload, remote request.
timeout 10 candump -L -n 4 vcan0 >/tmp/dump &
dump_pid=$!
wait_rx 1
cansend vcan0 123#DEADBEEF || fail "cansend 123#DEADBEEF"
cansend vcan0 1F334455#1122334455667788 || fail "cansend extended frame"
cansend vcan0 7FF# || fail "cansend empty frame"
cansend vcan0 0A5#R || fail "cansend remote frame"
wait $dump_pid || fail "candump exited with $? (timeout or error); got: $(cat /tmp/dump)"
# Log format is "(timestamp) vcan0 ID#DATA"; compare everything past the timestamp.
got=$(cut -d' ' -f2- /tmp/dump)
want='vcan0 123#DEADBEEF
vcan0 1F334455#1122334455667788
vcan0 7FF#
vcan0 0A5#R'
[ "$got" = "$want" ] || fail "candump saw:
$got
expected:
$want"
echo "smoke_can: raw frames ok"

[ -d /sys/module/can_isotp ] || fail "can-isotp module not loaded"
# 20 bytes take a first frame, a flow control and two consecutive frames;
# candump checks the exact segmentation on the wire.
payload='00 11 22 33 44 55 66 77 88 99 AA BB CC DD EE FF 01 02 03 04'
timeout 10 candump -L -n 4 vcan0 >/tmp/dump &
dump_pid=$!
wait_rx 1
timeout 10 isotprecv -s 7E8 -d 7E0 vcan0 >/tmp/isotp &
recv_pid=$!
wait_rx 2
echo "$payload" | timeout 10 isotpsend -s 7E0 -d 7E8 vcan0 || fail "isotpsend exited with $?"
wait $recv_pid || fail "isotprecv exited with $? (timeout or error)"
wait $dump_pid || fail "candump exited with $?; got: $(cat /tmp/dump)"
got=$(sed 's/ *$//' /tmp/isotp)
[ "$got" = "$payload" ] || fail "isotprecv got '$got', expected '$payload'"
got=$(cut -d' ' -f2- /tmp/dump)
want='vcan0 7E0#1014001122334455
vcan0 7E8#300000
vcan0 7E0#2166778899AABBCC
vcan0 7E0#22DDEEFF01020304'
[ "$got" = "$want" ] || fail "iso-tp frames on the wire:
$got
expected:
$want"
echo "smoke_can: iso-tp transfer ok"
echo "smoke_can: PASS"
