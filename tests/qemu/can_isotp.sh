#!/bin/bash
# Guest test: the kernel's ISO 15765-2 stack (can-isotp, through can-utils'
# isotpsend and isotprecv) as the peer of the unit's CAN link, for every
# operation whose request or response takes more than one frame, with the
# exact bytes of docs/can.md's message layout. The unit answers the kernel's
# first frames with flow control and takes the kernel's flow control for its
# own long responses (block size, none of it counted as bad input). Run by
# tests/run_qemu_tests.sh.
set -u
T=can_isotp
. /test/can_lib.sh

start_sim --node 1 --status-hz 0

# seq 0x41.. in order; the unit is set up, paused, then every multi-frame
# request runs (results as the console gives them in this state), then every
# multi-frame response is read.
iso "41 1E 01" "41 1E 00 01"                               # setPower true
iso "42 1F 01" "42 1F 00 01"                               # setServo true
iso "43 18 00 00 00 00 00 00 79 40 00 00 00 00 00 00 5E 40" "43 18 00 01"  # setAcceleration 400 120
iso "44 20 00 00 00 00 00 C0 72 40 00 00 00 00 00 00 4E 40" "44 20 00 01"  # setVelocity 300 60
iso "45 1D 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" "45 1D 00 01" # setPosition 0 0 0
iso "46 1C 05 00 00 00 01 00 00 00 01 00 00 00" "46 1C 00 01"  # setOutput 5 1 1
iso "47 16" "47 16 00 01"                                  # pause
iso "48 11 00 00 00 00 00 00 59 40" "48 11 00 00"          # moveForward 100: not ready
iso "49 15 00 00 00 00 00 00 24 40" "49 15 00 00"          # moveTurn 10: not ready
iso "4A 13 00 00 00 00 00 00 59 40 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" "4A 13 00 01" # moveLinearAbs 100 0 0: queued
iso "4B 14 00 00 00 00 00 00 24 40 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" "4B 14 00 00" # moveLinearRel 10 0 0
iso "4C 0E 00 00 00 00 00 00 00 00 00 00 00 00 00 00 59 40 00 00 00 00 00 80 56 40" "4C 0E 00 00" # moveCircularRel 0 100 90
iso "4D 10 00 00 00 00 00 00 69 40 00 00 00 00 00 00 00 00" "4D 10 00 01" # moveCruiseAbs 200 0: queued
iso "4E 0F 00 00 00 00 00 00 24 40 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" "4E 0F 00 00" # moveContinuousRel 10 0 0
iso "4F 12 00 00 00 00 00 00 24 40 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" "4F 12 00 00" # moveJog 10 0 0: paused
pass "12 multi-frame requests from isotpsend: flow control, exact answers"

iso "50 09" "50 09 00 01 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" # getPosition
iso "51 0B" "51 0B 00 01 15 00 06 50 61 75 73 65 64"      # getState: 21 "Paused"
iso "52 08 01 00 00 00" "52 08 00 01 01 00 00 00"          # getInput 1: 1 (the lamp, output 5, is wired to it)
iso "53 04" "53 04 00 01 00 00 00 00 00 70 6F 40"          # getBatteryVoltage: 251.5
iso "54 02" "54 02 00 01 00 00 00 00 00 40 8F 40 00 00 00 00 00 80 76 40" # getAccelerationLimit 1000 360
iso "55 05" "55 05 00 01 00 00 00 00 00 40 7F 40 00 00 00 00 00 80 66 40" # getDefaultAcceleration 500 180
iso "56 06" "56 06 00 01 00 00 00 00 00 40 7F 40 00 00 00 00 00 80 56 40" # getDefaultVelocity 500 90
iso "57 0C" "57 0C 00 01 00 00 00 00 00 40 8F 40 00 00 00 00 00 80 66 40" # getVelocityLimit 1000 180
iso "58 0D" "58 0D 00 01 09 56 65 72 2E 31 2E 30 2E 30"   # getVersion "Ver.1.0.0"
# getActiveAlarm 1: 3 active, the newest: 129 warning "moveJog refused: unit paused"
iso "59 03 01 00" "59 03 00 01 03 00 01 81 00 00 00 02 1C 6D 6F 76 65 4A 6F 67 20 72 65 66 75 73 65 64 3A 20 75 6E 69 74 20 70 61 75 73 65 64"
iso "5A 7F" "5A 7F 00 01 09 1F 22 18 00 54 04"             # protocol information
IFV="01 27 52 54 43 20 56 65 68 69 63 6C 65 53 65 72 76 69 63 65 20 69 6E 74 65 72 66 61 63 65 3A 20 76 65 72 2E 32 2E 30 2E 30"
iso "5B 07" "5B 07 00 $IFV"                                # getIFVersion, 7 frames
pass "12 multi-frame responses to isotprecv: exact bytes"

# The receiver's block size and STmin: 2 frames per block, 5 ms apart, the
# kernel's flow control after the first frame and after each block.
timeout 5 candump -L -n 4 vcan0,601:7FF >/tmp/fc.log &
dump=$!
wait_rx 2
iso "5C 07" "5C 07 00 $IFV" -b 2 -m 05
wait $dump || fail "candump saw fewer than 4 frames on 601: $(cat /tmp/fc.log)"
fcs=$(cut -d'#' -f2 /tmp/fc.log | sed -n '2,$p' | tr '\n' ' ')
[ "$fcs" = "300205 300205 300205 " ] ||
	fail "host flow control frames '$fcs', expected three 300205 (block size 2, STmin 5 ms)"
pass "block size 2, STmin 5 ms from isotprecv: 7-frame response in 3 blocks"

# Longer than the unit takes: flow control "overflow" stops the kernel's
# sender at once, and the unit's NAK 2 (oversize) reaches the receiver.
before=$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')
timeout 5 isotprecv -s 601 -d 581 vcan0 >/tmp/iso.out 2>/tmp/iso.err &
rcv=$!
wait_rx $((before + 1))
if echo "5D 11 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00" |
	timeout 5 isotpsend -b -s 601 -d 581 vcan0 2>/tmp/send.err; then
	fail "isotpsend of 30 bytes succeeded against an overflow flow control"
fi
wait $rcv || fail "no NAK after the overflow"
[ "$(tr -s ' ' </tmp/iso.out | sed 's/ *$//')" = "5D 11 02" ] ||
	fail "oversize: got '$(cat /tmp/iso.out)', expected '5D 11 02'"
pass "30-byte request: overflow flow control stops isotpsend, NAK 2"

stop_sim
[ "$(counter bad_pci)" = 0 ] || fail "bad_pci $(counter bad_pci), expected 0 ($COUNTERS)"
[ "$(counter bad_dlc)" = 0 ] || fail "bad_dlc $(counter bad_dlc), expected 0 ($COUNTERS)"
[ "$(counter flow_rx)" = 15 ] || fail "flow_rx $(counter flow_rx), expected 15 ($COUNTERS)"
[ "$(counter flow_tx)" = 13 ] || fail "flow_tx $(counter flow_tx), expected 13 ($COUNTERS)"
[ "$(counter requests)" = 28 ] || fail "requests $(counter requests), expected 28 ($COUNTERS)"
[ "$(counter naks)" = 1 ] || fail "naks $(counter naks), expected 1 ($COUNTERS)"
pass "unit counters: 28 requests, 1 NAK, flow control taken and sent, no bad frames"
echo "$T: all passed"
