#!/bin/bash
# Guest test: VehicleService over CORBA with the gateway on CAN
# (docs/corba.md). vehicle-sim --can serves the unit on vcan0; vehicle-corba
# forwards to it through the client library's CAN transport; the omniidl
# client calls it by its IOR on loopback. Then the unit falls silent
# (SIGSTOP): TRANSIENT after every attempt, never a hang; it answers again
# after SIGCONT; SIGTERM ends the gateway cleanly. Run by
# tests/run_qemu_tests.sh.
set -u
T=can_corba
. /test/can_lib.sh

start_sim --node 1 --status-hz 10

# 500 ms per attempt, 3 retries: a silent unit costs 2 s a call.
vehicle-corba --can vcan0 --node 1 --timeout 500 --retries 3 --no-naming --ior-file /tmp/ior \
	-ORBendPoint giop:tcp:127.0.0.1: 2>/tmp/gw.err &
GW=$!
for _ in $(seq 1 600); do
	[ -s /tmp/ior ] && break
	kill -0 "$GW" 2>/dev/null || { sed 's/^/  gw: /' /tmp/gw.err; fail "vehicle-corba exited"; }
	sleep 0.1
done
[ -s /tmp/ior ] || fail "vehicle-corba wrote no IOR within 60 s"

client() { # client MODE [ARG]: output in $OUT, status in $RC
	OUT=$(vs-corba-client --ior "$(head -1 /tmp/ior)" "$@" -ORBclientCallTimeOutPeriod 60000 2>&1)
	RC=$?
	printf '%s\n' "$OUT" | grep -v '^ok ' | sed 's/^/  /'
}
summary() { printf '%s\n' "$OUT" | sed -n 's/^corba-client: //p'; }

client --basic
[ "$RC" = 0 ] || fail "CORBA over CAN: $(summary)"
pass "CORBA over CAN: versions, limits, state, alarm sequence, power, a move ($(summary))"

kill -STOP "$SIM"
client --silent 1990
kill -CONT "$SIM"
[ "$RC" = 0 ] || fail "silent unit over CAN: $(summary)"
pass "silent unit over CAN: TRANSIENT, COMPLETED_MAYBE, after all attempts ($(summary))"

client --ping 25
[ "$RC" = 0 ] || fail "after SIGCONT: $(summary)"
pass "the unit answers again through the gateway"

kill -TERM "$GW"
wait "$GW"
rc=$?
[ $rc -eq 0 ] || { sed 's/^/  gw: /' /tmp/gw.err; fail "vehicle-corba exit status $rc"; }
pass "vehicle-corba exits 0 on SIGTERM"
stop_sim
