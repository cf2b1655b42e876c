#!/bin/bash
# Guest test: independent peers prove the documented CAN layout
# (docs/can.md). cansend/candump (can-utils) exchange hand-written frames
# with vehicle-sim and compare the answers byte for byte; then python-can
# (Debian's python3-can, can_python.py) implements the protocol from the
# document and drives the unit. Run by tests/run_qemu_tests.sh.
set -u
T=can_peers
. /test/can_lib.sh

# The checks below wait silently for a move to end: no link watchdog here
# (can_watchdog.sh tests it).
sed 's/link_timeout_ms="1000"/link_timeout_ms="0"/' /test/config/vehicle.xml >/tmp/vehicle-nowd.xml
start_sim --node 1 --status-hz 10 --config /tmp/vehicle-nowd.xml --io /test/config/io.xml

# exchange N REQUEST-FRAME... : sends the frames, captures N response frames
exchange() {
	local n=$1; shift
	local before
	before=$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')
	timeout 5 candump -L -n "$n" vcan0,581:7FF >/tmp/rsp &
	local dump=$!
	wait_rx $((before + 1))
	for f in "$@"; do cansend vcan0 "$f" || fail "cansend $f"; done
	wait $dump || fail "candump: fewer than $n response frames to $*: $(cat /tmp/rsp)"
	GOT=$(cut -d' ' -f2- /tmp/rsp)
}
check() { # check WHAT WANT
	[ "$GOT" = "$2" ] || fail "$1: candump saw
$GOT
expected
$2"
}

# getPosition (opcode 9), seq 0x05: 28-byte answer, five frames, pose 0 0 0;
# the host's flow control (go on, block size 0, STmin 0) lets the unit send
# the frames after the first
exchange 5 601#020509 601#300000
check getPosition 'vcan0 581#101C050900010000
vcan0 581#2100000000000000
vcan0 581#2200000000000000
vcan0 581#2300000000000000
vcan0 581#2400'
pass "getPosition: first frame + 4 consecutive frames as documented"

# getState (11), seq 0x06: "Unpowered", state 0x0019
exchange 3 601#02060B 601#300000
check getState 'vcan0 581#1010060B00011900
vcan0 581#2109556E706F7765
vcan0 581#22726564'
# setPower true (30 = 0x1E), seq 0x07; setServo true (31 = 0x1F), seq 0x08
exchange 1 601#03071E01
check setPower 'vcan0 581#04071E0001'
exchange 1 601#03081F01
check setServo 'vcan0 581#04081F0001'
# a retransmission of seq 0x08 is answered again from the cache
exchange 1 601#03081F01
check "setServo repeated" 'vcan0 581#04081F0001'
# moveForward (17 = 0x11) 250.0 = 0x406F400000000000, seq 0x09, two frames;
# the unit answers the first frame with flow control
exchange 2 601#100A091100000000 601#2100406F40
check moveForward 'vcan0 581#300000
vcan0 581#0409110001'
pass "getState, setPower, setServo, retransmission, two-frame moveForward"

# NAKs: unknown opcode 0x50 (4), stray byte after getPosition (3),
# boolean 2 (5), oversize first frame (2)
exchange 1 601#020A50
check "unknown opcode" 'vcan0 581#030A5004'
exchange 1 601#030B0900
check "wrong length" 'vcan0 581#030B0903'
exchange 1 601#030C1E02
check "bad boolean" 'vcan0 581#030C1E05'
exchange 2 601#10400D1100000000
check "oversize" 'vcan0 581#320000
vcan0 581#030D1102'
# a first frame left hanging: NAK 6 (truncated) after 250 ms
exchange 2 601#10140E1100000000
check "truncated" 'vcan0 581#300000
vcan0 581#030E1106'
pass "NAK reasons 4, 3, 5, 2, 6 as documented"

# heartbeat: three frames per group at 10 Hz; the 250 mm move is done by
# now: Ready (0x0010), x = 250.0 mm
sleep 1.5
timeout 5 candump -L -n 3 vcan0,181:7FF,281:7FF,381:7FF >/tmp/st ||
	fail "no status group: $(cat /tmp/st)"
a=$(grep -m1 ' vcan0 181#' /tmp/st | cut -d'#' -f2)
b=$(grep -m1 ' vcan0 281#' /tmp/st | cut -d'#' -f2)
case $a in 1000????????0000) ;; *) fail "status A $a: expected Ready, no alarm, speed 0" ;; esac
# x = 2500 (0.1 mm) = 0x09C4, y = 0
case $b in C409000000000000) ;;
*) fail "status B $b: expected x = 2500 (0x09C4), y = 0" ;; esac
pass "status frames A/B: Ready, x 250.0 mm"

stop_sim
# the repeated setServo was answered from the cache, not run again; the
# hanging first frame timed out once
[ "$(counter replays)" = 1 ] || fail "replays $(counter replays), expected 1 ($COUNTERS)"
[ "$(counter timeouts)" = 1 ] || fail "timeouts $(counter timeouts), expected 1"
[ "$(counter requests)" = 5 ] || fail "requests $(counter requests), expected 5 ($COUNTERS)"
pass "unit counters: 5 requests run, 1 replay, 1 timeout"

# python-can against a fresh unit
# The checks below wait silently for a move to end: no link watchdog here
# (can_watchdog.sh tests it).
sed 's/link_timeout_ms="1000"/link_timeout_ms="0"/' /test/config/vehicle.xml >/tmp/vehicle-nowd.xml
start_sim --node 1 --status-hz 10 --config /tmp/vehicle-nowd.xml --io /test/config/io.xml
PYTHONDONTWRITEBYTECODE=1 timeout 60 python3 /test/can_python.py || fail "can_python.py failed"
stop_sim
pass "python-can peer"

# the vehicleservice package over CAN, against vehiclectl
# The checks below wait silently for a move to end: no link watchdog here
# (can_watchdog.sh tests it).
sed 's/link_timeout_ms="1000"/link_timeout_ms="0"/' /test/config/vehicle.xml >/tmp/vehicle-nowd.xml
start_sim --node 1 --status-hz 10 --config /tmp/vehicle-nowd.xml --io /test/config/io.xml
PYTHONDONTWRITEBYTECODE=1 timeout 60 python3 /test/can_vs.py || fail "can_vs.py failed"
stop_sim
pass "vehicleservice (Python client) over CAN"
echo "$T: all passed"
