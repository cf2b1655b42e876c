# Shared helpers of the CAN guest tests (sourced). The simulator and
# vehiclectl are in /test, the configuration in /test/config.
fail() { echo "$T: FAIL: $*"; [ -f /tmp/sim.err ] && sed 's/^/  sim: /' /tmp/sim.err; exit 1; }
pass() { echo "$T: PASS: $*"; }

# Waits until at least WANT CAN receivers are registered on vcan0.
wait_rx() {
	local want=$1
	for _ in $(seq 1 100); do
		[ "$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')" -ge "$want" ] && return 0
		sleep 0.05
	done
	fail "fewer than $want CAN receivers on vcan0 within 5 s"
}

start_sim() { # start_sim [vehicle-sim options...]
	local before
	before=$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')
	# The guest's configuration unless the caller names its own (the last
	# --config wins).
	vehicle-sim --can vcan0 --config /test/config/vehicle.xml --io /test/config/io.xml "$@" \
		</dev/null >/tmp/sim.out 2>/tmp/sim.err &
	SIM=$!
	wait_rx $((before + 1))
}

stop_sim() { # prints the counter line
	kill -TERM "$SIM" 2>/dev/null
	wait "$SIM"
	local rc=$?
	[ $rc -eq 0 ] || fail "vehicle-sim exited with $rc"
	COUNTERS=$(sed -n 's/^vehicle-sim: CAN counters: //p' /tmp/sim.err)
	[ -n "$COUNTERS" ] || fail "vehicle-sim printed no counters"
}

counter() { # counter NAME -> value from the last stop_sim
	printf '%s\n' "$COUNTERS" | tr ' ' '\n' | sed -n "/^$1\$/{n;p;q}"
}

alive() { kill -0 "$SIM" 2>/dev/null || fail "vehicle-sim died ($*)"; }

# vc OP ARGS... : vehiclectl over CAN, output in $OUT, status in $RC
vc() {
	OUT=$(vehiclectl --can vcan0 --timeout 300 "$@" 2>&1)
	RC=$?
}
expect() { # expect "OP ARGS" "output" [rc]
	# shellcheck disable=SC2086
	vc $1
	[ "$OUT" = "$2" ] || fail "vehiclectl $1: got '$OUT', expected '$2'"
	[ "$RC" = "${3:-0}" ] || fail "vehiclectl $1: exit $RC, expected ${3:-0}"
}

# Polls getState until it reads CODE, within SECONDS.
wait_state() {
	local code=$1 secs=$2
	for _ in $(seq 1 $((secs * 10))); do
		vc getState
		case $OUT in "true state=$code "*) return 0 ;; esac
		sleep 0.1
	done
	fail "state $code not reached within $secs s (last: $OUT)"
}

# x of getPosition, exactly as vehiclectl prints it
pos() {
	vc getPosition
	[ "$RC" = 0 ] || fail "getPosition: $OUT"
	printf '%s\n' "$OUT"
}

near() { # near VALUE WANT TOL
	awk -v v="$1" -v w="$2" -v t="$3" 'BEGIN { d = v - w; if (d < 0) d = -d; exit !(d <= t) }'
}

# iso REQUEST-HEX RESPONSE-HEX [isotprecv options]: one request through
# the kernel's ISO-TP (isotpsend), its response through isotprecv, both on
# the identifiers of node ISO_NODE (default 1).
iso() {
	local req=$1 want=$2 before got n=${ISO_NODE:-1}
	shift 2
	local s d
	s=$(printf '%X' $((0x600 + n))) d=$(printf '%X' $((0x580 + n)))
	before=$(cat /proc/net/can/rcvlist_* | grep -cE '^ +vcan0 ')
	timeout 5 isotprecv "$@" -s "$s" -d "$d" vcan0 >/tmp/iso.out 2>/tmp/iso.err &
	local rcv=$!
	wait_rx $((before + 1))
	# A single-frame request needs no flow control: the sender then listens
	# elsewhere (7FF), so that only isotprecv answers the response.
	local rx=$d
	[ ${#req} -le 20 ] && rx=7FF
	echo "$req" | timeout 5 isotpsend -b -s "$s" -d $rx vcan0 ||
		fail "isotpsend '$req' failed: $(cat /tmp/iso.err)"
	wait $rcv || fail "isotprecv: no response to '$req' ($(cat /tmp/iso.err))"
	got=$(tr -s ' ' </tmp/iso.out | sed 's/ *$//')
	[ "$got" = "$want" ] || fail "request $req: got '$got', expected '$want'"
}
