#!/bin/sh
# make bench: every performance figure with what was measured and how.
#   tools/bench/bench.sh BENCH_DIR LOOP_SECONDS
set -eu
dir=$1; secs=$2
here=$(dirname "$0")
cpu=$(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo 2>/dev/null | head -1)
cc_ver=$(${CC:-cc} --version 2>/dev/null | head -1)
echo "vehicle unit benchmarks"
echo "  machine: ${cpu:-unknown} ($(nproc) CPUs), $(uname -sr)"
echo "  compiler: $cc_ver, ${OPT:-?} (the Makefile's OPT); $(valgrind --version 2>/dev/null || echo 'valgrind missing')"
echo "  unit: reference configuration (firmware/config.c: differential, 1 kHz, 500 mm/s, 90 deg/s,"
echo "        500 mm/s^2, 180 deg/s^2, blend 200 mm) on the loopback plant (hal/cortexm/loop_hal.c)"
echo

echo "== 1. control tick cost: instructions per whole vehicle_tick (callgrind Ir, one dump per tick) =="
echo "  retarget: 20 moveContinuousRel calls while moving; 'cmd' is the call, 'tick-after-cmd' the tick"
echo "  that replans toward the new goal"
"$here/tickcost.sh" "$dir/tickcost" | tee "$dir/tickcost.txt"
awk '
	$1 == "cruise" && $2 == "tick" {
		printf "  target: <= 1000 per whole tick in the blended cruise: mean %s, median %s, p99 %s, max %s -> %s\n", $6, $8, $14, $12, ($12 <= 1000 ? "met on every tick" : ($6 <= 1000 ? "met on average" : "missed"))
		if ($12 > 1000)
			printf "          %s of the ticks cost more than 1000: those in which a line blends into its corner (the line'"'"'s last\n          braking step, the corner'"'"'s setup and first step, and the odometry'"'"'s sine and cosine in one tick)\n", $16
	}
	$1 == "retarget" && $2 == "cmd" { c = $12 }
	$1 == "retarget" && $2 == "tick-after-cmd" { t = $12 }
	END { if (t != "") printf "  target: <= 5000 for the retarget tick (call + tick, worst): %d -> %s\n", c + t, (c + t <= 5000 ? "met" : "missed") }' "$dir/tickcost.txt"
echo

echo "== 1b. the same ticks on a Cortex-M4: instructions per whole vehicle_tick (arm-none-eabi-gcc -Os, QEMU mps2-an386, =="
echo "  -icount shift=6: one instruction = 64 ns of the board's 25 MHz SysTick, counted around each call; shares of the"
echo "  period at one cycle per instruction (an M4 takes 1 for most, 2 for loads, up to 4 for taken branches)"
"$here/mcu_tickcost.sh" "$(dirname "$dir")/cortex-m4/bench.elf" | tee "$dir/mcu_tickcost.txt"
echo

echo "== 1c. the telemetry stream (docs/protocol.md): instructions per poll of the serial server after each tick of the =="
echo "  blended cruise, nothing read, the port taking every byte; 'stream' is the difference from no subscription: a tick's"
echo "  share, and one frame's work (the sample read, its encoding, the frame's check, the queue)"
"$here/streamcost.sh" "$dir/streamcost" | tee "$dir/streamcost.txt"
echo

echo "== 2. trajectory accuracy: fixed-point engine (motion_tick, perfect plant) vs double reference (tools/ref) =="
"$here/accuracy.sh" "$dir/accuracy" | tee "$dir/accuracy.txt"
awk '
	/^[a-z]+: / { m = $1; sub(":", "", m) }
	/endpoint: engine - reference/ { e[m] = $5; et[m] = $7 }
	/largest path deviation/ { dv[m] = $4 }
	END {
		printf "  target: line endpoint <= 0.01 mm: %s mm -> %s\n", e["line"], (e["line"] + 0 <= 0.01 ? "met" : "missed")
		printf "  target: turn endpoint <= 0.001 deg: %s deg -> %s\n", et["turn"], (et["turn"] + 0 <= 0.001 ? "met" : "missed")
		printf "  target: cruise path deviation <= 0.1 mm: %s mm -> %s\n", dv["cruise"], (dv["cruise"] + 0 <= 0.1 ? "met" : "missed")
	}' "$dir/accuracy.txt"
echo

echo "== 2b. motion on the default plant: the whole firmware on host_sim's plant (20 ms motor lag, 3000 mm/s^2, 10 A a =="
echo "  motor, the configured encoders) and on the ideal plant (no lag or limit, the finest encoders the limits admit);"
echo "  per move from the origin: distance and heading to the target at the first Ready (odometry, true pose);"
echo "  overshoot: largest true travel past the target along the last commanded direction (of travel, of rotation);"
echo "  Ready, settle: ms from the reference's end to Ready, and until the true pose stays within 0.05 mm and"
echo "  0.01 deg of the target with every wheel under 0.1 mm/s ('never': not by 500 ms after Ready); drift: true"
echo "  pose change from Ready to 500 ms later; following: largest reference - odometry while Busy"
"$dir/plantbench" | tee "$dir/plantbench.txt"
echo

echo "== 2c. the Modbus drive cycle (hal/modbus/mbmaster.h), generic profile, 8N1, every drive answering: a speed"
echo "  write and one read per drive, 1 ms turnaround per answer (the board's figures in QEMU: tests/mcu/mcu_drives.py move) =="
"$dir/drivecycle" | tee "$dir/drivecycle.txt"
echo

echo "== 3. parse rates (wall clock, this machine, one core) =="
"$dir/parserate"
echo

echo "== 4. 1 kHz loop lateness on Linux (clock_nanosleep TIMER_ABSTIME, vehicle_tick on the cruise route) =="
"$dir/looplat" "$secs"
echo

echo "== 5. command link: getPosition round trip over a pty next to its time on a 115200 8N1 wire =="
"$(dirname "$dir")/linkbench"
