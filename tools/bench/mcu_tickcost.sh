#!/bin/sh
# Tick cost on a Cortex-M4: runs BUILD/cortex-m4/bench.elf (mcu_tickcost.c,
# the scenarios of scenario.h) on QEMU's mps2-an386 with -icount shift=6, so
# that each instruction takes 64 ns of the board's time whatever the host's
# load, and prints instructions per call next to the host's table, with the
# share of a 1 ms period the worst tick takes at 25 and 168 MHz.
#   tools/bench/mcu_tickcost.sh BUILD/cortex-m4/bench.elf
set -eu
elf=$1
shift=6
command -v qemu-system-arm >/dev/null || { echo "mcu tickcost: qemu-system-arm missing (tools/deps.sh)"; exit 1; }
out=$(timeout 600 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial stdio \
	-semihosting-config enable=on,target=native -icount shift=$shift,sleep=off -kernel "$elf") ||
	{ printf '%s\n' "$out"; echo "mcu tickcost: the image failed"; exit 1; }
# Lines "SCENARIO LABEL calls sum min max" in cycles of the 25 MHz SysTick:
# cycles * 40 ns / 2^shift ns = instructions.
printf '%s\n' "$out" | tr -d '\r' | awk -v k="$((1 << shift))" '
	function ins(c) { return c * 40 / k }
	NF == 6 {
		seen[$1 " " $2] = 1
		printf "  %-9s %-15s %6d calls  mean %6.0f  min %6.0f  max %6.0f  worst: %4.1f %% of 1 ms at 25 MHz, %4.1f %% at 168 MHz\n",
			$1, $2, $3, ins($4) / $3, ins($5), ins($6), ins($6) / 250, ins($6) / 1680
		if ($2 != "cmd" && ins($6) > worst) { worst = ins($6); where = $1 " " $2 }
		if ($2 == "cmd") cmd = ins($6)
		if ($2 == "tick-after-cmd") rt = ins($6)
	}
	END {
		split("idle tick,line tick,cruise tick,jog tick,retarget cmd,retarget tick-after-cmd", want, ",")
		for (i in want)
			if (!(want[i] in seen)) { print "mcu tickcost: no figures for " want[i]; exit 1 }
		printf "  target: worst tick < 10 %% of the 1 ms period at 168 MHz: %d instructions (%s) = %.1f %% at one\n", worst, where, worst / 1680
		printf "          cycle per instruction, %.1f %% at 1.6 -> %s\n", worst * 1.6 / 1680, (worst * 1.6 < 16800 ? "met" : "missed")
		printf "  retarget call + tick, worst: %d instructions = %.1f %% of 1 ms at 25 MHz, %.1f %% at 168 MHz\n", cmd + rt, (cmd + rt) / 250, (cmd + rt) / 1680
	}'
