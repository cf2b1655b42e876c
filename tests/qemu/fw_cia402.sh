#!/bin/bash
# Guest test: vehicle-fw's CiA 402 backend (hal/linux/cia402.h) at 1 kHz with
# two drives on vcan0 against cia402-sim (nodes 1 and 2), the bus recorded by
# candump and the documented frames asserted with their payloads. Covers:
# the start-up (reset communication, boot-up, SDO configuration, NMT start),
# SYNC/RPDO/TPDO/heartbeats, the enable sequence, a move landing on its
# position; an EMCY mid-move (fault 201 with the drive's code, unit
# stopped), clearAlarm (0x80 on the bus) and moving again; a drive whose
# heartbeat and TPDOs stop (fault 202); vcan0 going down mid-move (fault
# 202, the log says so; the drives stop on the missed master heartbeat) and
# coming back (clearAlarm, moving again); a drive that restarts (configured
# again in the tick, its position kept, the position lost: motion refused
# until setPosition); SIGTERM (drives switched off, pre-operational); and
# start-up failures (SDO abort, missing boot-up, interface down).
#
# A tick overrun (fault 209) fails the test (run-guest.sh -i keeps the
# host's load out of the guest's clock). While vehicle-fw runs, the script
# starts no process, so that nothing but the code under test can hold up
# the loop: console replies come through a fifo read with the shell's own
# read, waits are read timeouts, vcan0 goes down and up through an
# "ip -batch" started beforehand, and the frames and log lines are checked
# after the run.
# Run: tools/qemu/run-guest.sh -i tests/qemu/fw_cia402.sh build/vehicle-fw build/cia402-sim
set -u
T=fw_cia402
fw=0
# On failure also the unit's active alarms.
fail() {
	local al=""
	kill -0 "$fw" 2>/dev/null && al="; alarms: $(reply 'getActiveAlarm 8')"
	echo "$T: FAIL: $*$al"
	[ -f /tmp/fw.err ] && sed 's/^/  fw: /' /tmp/fw.err
	[ -s /tmp/sim.err ] && sed 's/^/  sim: /' /tmp/sim.err
	exit 1
}
expect() { [ "$2" = "$3" ] || fail "$1: got '$2', expected '$3'"; }
mkfifo /tmp/nap
exec 5<>/tmp/nap
nap() { read -r -t "$1" -u 5; } # sleeps without starting a process
# link up|down: vcan0 through the ip started here, until the kernel says so
mkfifo /tmp/ipcmd
ip -force -batch /tmp/ipcmd >/tmp/ip.out 2>&1 &
exec 8>/tmp/ipcmd
link() {
	local want flags
	[ "$1" = up ] && want=1 || want=0
	echo "link set vcan0 $1" >&8
	for ((i = 0; i < 200; i++)); do
		read -r flags </sys/class/net/vcan0/flags
		[ $((flags & 1)) = "$want" ] && return 0
		read -r -t 0.01 -u 5
	done
	fail "vcan0 not $1 within 2 s ($(cat /tmp/ip.out))"
}
link down
link up

# CAN receivers on vcan0 (candump, simulator, vehicle-fw each add one).
wait_rcv() {
	for ((i = 0; i < 100; i++)); do
		[ "$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')" -ge "$1" ] && return 0
		nap 0.05
	done
	fail "fewer than $1 CAN receivers on vcan0 within 5 s"
}

# The bus, in candump's log format: "(time) vcan0 ID#DATA", checked after
# the run from an index made in one pass.
candump -L -D vcan0 >/tmp/can.log 2>/tmp/candump.err &
dump=$!
wait_rcv 1
declare -A FIRST SECOND COUNT
index_frames() {
	local f a b n
	awk '{ f = $3; n[f]++; if (n[f] == 1) a[f] = NR; if (n[f] == 2) b[f] = NR }
		END { for (f in n) print f, a[f], (f in b) ? b[f] : 0, n[f] }' /tmp/can.log >/tmp/can.idx
	while read -r f a b n; do
		FIRST[$f]=$a SECOND[$f]=$b COUNT[$f]=$n
	done </tmp/can.idx
}
at() { echo "${FIRST[$1]:-0}"; }
seen() { [ "$(at "$1")" -gt 0 ] || fail "frame $1 not on the bus"; }
count() { echo "${COUNT[$1]:-0}"; }
count_is() { expect "$1: $2 times" "$(count "$2")" "$3"; }
before() { # before A B: the first A comes before the first B (both seen)
	local a b
	a=$(at "$1") b=$(at "$2")
	[ "$a" -gt 0 ] && [ "$b" -gt 0 ] && [ "$a" -lt "$b" ] || fail "$1 (line $a) not before $2 (line $b)"
}

# The simulator on fds 6 (its stdin) and 7 (its stdout): a coprocess's own
# descriptors are closed in subshells.
coproc SIM { exec cia402-sim --if vcan0 --node 1 --node 2 2>/tmp/sim.err; }
simpid=$SIM_PID
exec 6>&"${SIM[1]}" 7<&"${SIM[0]}"
read -r -t 5 -u 7 line || fail "cia402-sim did not start"
expect "simulator" "$line" "cia402-sim: vcan0 nodes 1 2"
wait_rcv 2
# sim LINE [PATTERN]: one command to the simulator, its answer in SIMR
sim() {
	echo "$1" >&6
	read -r -t 5 -u 7 SIMR || fail "cia402-sim: no answer to '$1'"
	[ $# -lt 2 ] || case $SIMR in $2) ;; *) fail "cia402-sim $1: got '$SIMR', expected '$2'" ;; esac
}

write_config() { # write_config NODE_OF_AXIS_1 BOOT_TIMEOUT_MS
	cat >/tmp/vehicle.xml <<EOF
<vehicle kinematics="differential" tick_hz="1000">
  <supervision drive_timeout_ms="100"/>
  <devices contact_sensor="false" obstacle_input="false" estop="false" joystick="false"/>
  <backends>
    <canopen bus="0" interface="vcan0" heartbeat_ms="100" heartbeat_timeout_ms="300"
             sdo_timeout_ms="100" boot_timeout_ms="$2" master_node="127"/>
    <drive axis="0" type="cia402" bus="0" node="1"/>
    <drive axis="1" type="cia402" bus="0" node="$1"/>
  </backends>
</vehicle>
EOF
}
write_config 2 2000
echo '<io/>' >/tmp/io.xml
mkfifo /tmp/in /tmp/outp
: >/tmp/fw.err
start_fw() {
	vehicle-fw --config /tmp/vehicle.xml --io /tmp/io.xml --rt-priority 50 </tmp/in \
		>/tmp/outp 2>>/tmp/fw.err &
	fw=$!
	exec 3>/tmp/in 4</tmp/outp
}
stop_fw() { # SIGTERM; the exit status in FW_RC
	kill -TERM $fw
	for ((i = 0; i < 250; i++)); do kill -0 $fw 2>/dev/null || break; nap 0.02; done
	kill -0 $fw 2>/dev/null && fail "vehicle-fw still running 5 s after SIGTERM"
	wait $fw
	FW_RC=$?
	exec 3>&- 4<&-
}

# ask LINE: sends one console line, its one reply in R (8 s bound: the
# first one waits for the start-up). No subshell: that would fork.
ask() {
	R=""
	echo "$1" >&3
	read -r -t 8 -u 4 R
}
reply() { ask "$1"; echo "$R"; } # for failure messages only
cmd() { ask "$1"; expect "$1" "$R" "$2"; }
# Polls getState until it reads STATE (quoted text), within 10 s.
wait_state() {
	for ((i = 0; i < 100; i++)); do
		ask getState
		case $R in *"\"$1\"") return 0 ;; esac
		nap 0.1
	done
	fail "state $1 not reached within 10 s (last: $R)"
}
# The pose stands still: two readings 0.3 s apart are equal.
still() {
	local a
	ask getPosition
	a=$R
	nap 0.3
	ask getPosition
	expect "$1: position stands still" "$R" "$a"
}
# moves MM: moveForward MM from Ready, and the unit covers MM within two
# encoder counts (0.06 mm: at rest the wheel loop holds a wheel on either
# count next to its reference), in the shell's integer arithmetic on
# thousandths of a millimetre
moves() {
	local p0 p1 x0 y0 x1 y1 d2 lo hi
	ask getPosition
	p0=$R
	cmd "moveForward $1" 'ok true'
	nap 0.3
	wait_state Ready
	nap 0.3
	ask getPosition
	p1=$R
	read -r _ _ x0 y0 _ <<<"${p0//./}"
	read -r _ _ x1 y1 _ <<<"${p1//./}"
	d2=$(((10#${x1#-} * ${x1%%[0-9]*}1 - 10#${x0#-} * ${x0%%[0-9]*}1) ** 2 +
		(10#${y1#-} * ${y1%%[0-9]*}1 - 10#${y0#-} * ${y0%%[0-9]*}1) ** 2))
	lo=$((($1 * 1000 - 60) ** 2)) hi=$((($1 * 1000 + 60) ** 2))
	[ "$d2" -gt "$lo" ] && [ "$d2" -lt "$hi" ] || fail "moveForward $1: $p0 -> $p1"
}

# ---- start-up ----------------------------------------------------------
start_fw
# The console answers once the start-up is done (it runs before the loop).
cmd 'getState' 'ok true 25 "Unpowered"'
nap 0.5
ask '$rt'
case $R in *" canopen0 vcan0 tx "*" tx_full 0 tx_down 0 tx_errors 0 rx "*" rx_errors 0 emcy 0") ;;
*) fail "\$rt: '$R'" ;; esac

# ---- enable, move, position ------------------------------------------------
cmd 'setPower true' 'ok true'
cmd 'setServo true' 'ok true'
nap 0.3
cmd 'getServoStatus 0' 'ok true true'
cmd 'getServoStatus 1' 'ok true true'
cmd 'moveForward 300' 'ok true'
nap 0.3
cmd 'getState' 'ok true 17 "Busy"'
wait_state Ready
# 300 mm are 10430.35 counts (16384 per turn of a 150 mm wheel): the
# wheel loop holds each wheel on the counts either side, 10430
# (299.989 mm) or 10431 (300.018 mm), straight.
nap 0.5
ask getPosition
case $R in 'ok true 299.989 0.000 0.000' | 'ok true 300.018 0.000 0.000') ;;
*) fail "position after moveForward 300: '$R'" ;; esac
sim 'state 1' '1 enabled pos 1043[01] vel *'
sim 'state 2' '2 enabled pos 1043[01] vel *'

# ---- EMCY mid-move: fault 201 with the drive's code --------------------------
cmd 'moveForward 2000' 'ok true'
nap 0.5
sim 'fault 1 2310 01 A1B2C3D4E5' ok
nap 0.3
cmd 'getActiveAlarm 1' 'ok true 1 1 201 fault "drive 0 fault 0x2310"'
cmd 'getState' 'ok true 19 "Alarm-201"'
sim 'state 1' '1 fault pos * vel 0'
sim 'state 2' '2 ready pos * vel 0'
still "after the EMCY"
cmd 'getServoStatus 0' 'ok true false'
# clearAlarm: fault reset (0x80, rising edge; on the bus, checked
# below), the drive back to ready to switch on, moving again
cmd 'clearAlarm' 'ok true'
nap 0.3
sim 'state 1' '1 ready pos * vel 0'
cmd 'getActiveAlarm 1' 'ok true 0 0'
cmd 'setServo true' 'ok true'
nap 0.2
moves 50

# ---- heartbeat and TPDO loss: fault 202 ---------------------------------------
cmd 'moveForward 2000' 'ok true'
nap 0.5
sim 'silent 2' ok
nap 0.8
cmd 'getActiveAlarm 1' 'ok true 1 1 202 fault "drive 1 not answering"'
cmd 'getState' 'ok true 19 "Alarm-202"'
sim 'state 1' '1 ready pos * vel 0'
sim 'state 2' '2 ready pos * vel 0'
still "after the heartbeat loss"
sim 'talk 2' ok
nap 0.5
cmd 'clearAlarm' 'ok true'
cmd 'setServo true' 'ok true'
nap 0.2
moves 50

# ---- vcan0 down mid-move: fault 202, the log says why ---------------------------
cmd 'moveForward 2000' 'ok true'
nap 0.5
link down
nap 1.0
ask 'getActiveAlarm 1'
case $R in 'ok true 1 1 202 fault "drive '[01]' not answering"') ;;
*) fail "alarms with vcan0 down: '$R'" ;; esac
cmd 'getState' 'ok true 19 "Alarm-202"'
ask '$rt'
case $R in *" tx_down 0 "*) fail "\$rt with vcan0 down: '$R'" ;; *" tx_down "*) ;;
*) fail "\$rt: '$R'" ;; esac
still "with vcan0 down"
# the drives stop by themselves: they miss the master's heartbeat
sim 'state 1' '1 fault pos * vel 0'
sim 'state 2' '2 fault pos * vel 0'
kill -0 $fw || fail "vehicle-fw died with vcan0 down"
# up again: the drives report their fault (the EMCY 0x8130 was lost
# while down: the generic code), clearAlarm resets them
link up
nap 1.0
ask 'getActiveAlarm 2'
case $R in 'ok true 2 2 201 fault "drive 1 fault 0x1000" 202 fault "drive '[01]' not answering"') ;;
*) fail "alarms with vcan0 up again: '$R'" ;; esac
cmd 'clearAlarm' 'ok true'
nap 0.3
sim 'state 1' '1 ready pos * vel 0'
sim 'state 2' '2 ready pos * vel 0'
cmd 'setServo true' 'ok true'
nap 0.2
moves 50

# ---- a drive restarts: configured again in the tick ------------------------------
# servo off, so the wheels stand still; its position counts from 0 again,
# the reported count goes on from the last one, and the unit refuses
# motion until the host says where it is
cmd 'setServo false' 'ok true'
nap 0.3
ask getPosition
p0=$R
sim 'reboot 1' ok
nap 1.0
cmd 'getActiveAlarm 2' 'ok true 2 2 155 warning "drive 0 position lost: setPosition required" 202 fault "drive 0 not answering"'
cmd getPosition "$p0"
sim 'state 1' '1 ready pos 0 vel 0'
cmd 'clearAlarm' 'ok true'
cmd 'setServo true' 'ok true'
nap 0.2
cmd 'moveForward 50' 'ok false'
cmd "setPosition ${p0#ok true }" 'ok true'
cmd 'clearAlarm' 'ok true' # the refusal's warning 132
moves 50

# ---- SIGTERM: drives switched off, pre-operational ----------------------------------
stop_fw
expect "exit status" "$FW_RC" 0
nap 0.5 # past the consumer time: no fault, the consumer is off
sim 'state 1' '1 ready pos * vel 0'
sim 'state 2' '2 ready pos * vel 0'

# ---- the log --------------------------------------------------------------------------
mapfile -t LOG </tmp/fw.err
logged() {
	local l
	for l in "${LOG[@]}"; do [ "$l" = "$1" ] && return 0; done
	fail "not logged: $1"
}
P='vehicle-fw: canopen bus 0 (vcan0):'
logged "$P nodes 1 (axis 0), 2 (axis 1) configured (profile velocity, heartbeat 100 ms, timeout 300 ms, master heartbeat consumed) and started"
logged "$P node 1 (axis 0): operational"
logged "vehicle-fw: error: canopen bus 0 (vcan0): node 1 (axis 0): EMCY 0x2310, error register 0x01, manufacturer bytes A1 B2 C3 D4 E5"
logged "$P node 1 (axis 0): EMCY 0x0000 (error reset), error register 0x00"
logged "vehicle-fw: error: canopen bus 0 (vcan0): node 2 (axis 1): lost: no heartbeat for more than 300 ms"
logged "$P node 2 (axis 1): operational again"
logged "vehicle-fw: error: canopen bus 0 (vcan0): interface is down: no frames go out or arrive"
logged "$P interface is up again"
logged "$P node 1 (axis 0): operational again"
logged "vehicle-fw: warning: canopen bus 0 (vcan0): node 1 (axis 0): boot-up message (the drive restarted): configuring it again"
logged "$P node 1 (axis 0): configured again and started"
logged "$P 2 of 2 drives switched off and pre-operational"
logged 'vehicle-fw: final state: unpowered, relay open, servo off, stopped'
# the counters; EMCYs: 0x2310, its reset, both resets after vcan0 came back
c=0
for l in "${LOG[@]}"; do
	case $l in 'vehicle-fw: exit: canopen0 vcan0 tx '*' tx_full 0 tx_down '[1-9]*' tx_errors 0 rx '*' rx_errors 0 emcy 4') c=1 ;; esac
done
[ $c = 1 ] || fail "exit counters: $(grep 'exit: canopen' /tmp/fw.err)"

# ---- the frames on the bus ------------------------------------------------------------
nap 0.2
kill $dump
wait $dump 2>/dev/null
index_frames
# start-up: reset communication, boot-up, then SDO (device type, shutdown,
# mode 3, PDO mappings with the PDO invalid meanwhile, heartbeat, consumer
# of the master's heartbeat), then NMT start; then SYNC, heartbeats, RPDOs
# and TPDOs (statusword, position, mode display 3)
for f in 000#8201 000#8202 601#4000100000000000 581#4300100092010200 \
	601#2B40600006000000 581#6040600000000000 \
	601#2F60600003000000 581#6060600000000000 602#2F60600003000000 582#6060600000000000 \
	601#2300140101020080 601#2F00160000000000 601#2300160110004060 601#230016022000FF60 \
	601#2F00160002000000 601#2F00140201000000 601#2300140101020000 \
	601#2300180181010080 601#23001A0110004160 601#23001A0220006460 601#23001A0308006160 \
	601#2F001A0003000000 \
	601#2F00180201000000 601#2300180181010000 601#2B17100064000000 581#6017100000000000 \
	601#231610012C017F00 000#0101 000#0102 080# 77F#05 701#05 702#05 \
	201#060000000000 202#060000000000 181#31020000000003 182#31020000000003 \
	181#37020000000003; do
	seen "$f"
done
count_is "boot-up messages of node 1 (start, reset, restart)" 701#00 3
a=$(at 000#8201) b=${SECOND[701#00]}
[ "$b" -gt "$a" ] || fail "boot-up (line $b) not after reset communication (line $a)"
before 601#4000100000000000 601#2F60600003000000
before 601#2300140101020080 601#2300160110004060
before 601#2300160110004060 601#2F00160002000000
before 601#2F00160002000000 601#2300140101020000
before 601#2B17100064000000 601#231610012C017F00
before 602#231610012C017F00 000#0101
before 000#0102 080#
[ "$(count 080#)" -gt 1000 ] || fail "SYNC: $(count 080#) frames"
# enable sequence: shutdown, switch on, enable operation; velocities
before 201#060000000000 201#070000000000
before 201#070000000000 201#0F0000000000
grep -E ' vcan0 201#0F00[0-9A-F]{8}$' /tmp/can.log | grep -qv '201#0F0000000000$' ||
	fail "no RPDO with a velocity"
# EMCY, the fault in the statusword, the fault reset, the drive's EMCY 0000
seen 081#102301A1B2C3D4E5
grep -qE ' vcan0 181#1802[0-9A-F]{8}03$' /tmp/can.log || fail "no TPDO with the fault statusword"
before 081#102301A1B2C3D4E5 201#800000000000
before 201#800000000000 081#0000000000000000
# fault resets (bit 7 held until the drive leaves fault: counted as rising
# edges): node 1 after the EMCY and after vcan0 came back, node 2 then
edges() {
	awk -v id="$1" '{ split($3, p, "#"); if (p[1] != id) next
		hi = substr(p[2], 1, 2) == "80"; if (hi && !last) n++; last = hi } END { print n + 0 }' /tmp/can.log
}
expect "fault resets of node 1" "$(edges 201)" 2
expect "fault resets of node 2" "$(edges 202)" 1
# the restart: configured again and started again
count_is "mode writes to node 1" 601#2F60600003000000 2
count_is "NMT start of node 1" 000#0101 2
# exit: shutdown, consumer off, pre-operational
seen 601#2316100100000000
seen 000#8001
seen 000#8002

# ---- start-up failures ----------------------------------------------------------------
start_fails() { # start_fails MESSAGE: vehicle-fw exits 1 with MESSAGE
	timeout 10 vehicle-fw --config /tmp/vehicle.xml --io /tmp/io.xml --rt-priority 0 \
		</dev/null >/dev/null 2>/tmp/fw.err
	expect "exit status ($1)" "$?" 1
	grep -qxF "$1" /tmp/fw.err || fail "not logged: $1"
}
echo quit >&6
exec 6>&- 7<&-
wait "$simpid" 2>/dev/null
coproc SIM { exec cia402-sim --if vcan0 --node 1 --node 2 --missing 0x6060 2>/tmp/sim.err; }
exec 6>&"${SIM[1]}" 7<&"${SIM[0]}"
read -r -t 5 -u 7 line || fail "cia402-sim did not start again"
start_fails 'vehicle-fw: error: canopen bus 0 (vcan0): node 1 (axis 0): SDO write 0x6060:00 aborted with 0x06020000 (object does not exist in the object dictionary)'
write_config 3 300
start_fails 'vehicle-fw: error: canopen bus 0 (vcan0): node 3 (axis 1): no boot-up message within 300 ms of reset communication'
link down
start_fails 'vehicle-fw: error: canopen bus 0 (vcan0): interface is down'
link up
echo quit >&6
echo "$T: PASS"
