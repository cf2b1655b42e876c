/* Control tick cost on a Cortex-M4, for QEMU's mps2-an386 board run with
 * -icount (tools/bench/mcu_tickcost.sh): the scenarios of scenario.h on the
 * loopback plant, each measured call timed by systick_cycles (the 25 MHz
 * SysTick), then one line per scenario and label on the UART:
 *   SCENARIO LABEL calls SUM MIN MAX      (cycles of the 25 MHz clock)
 * and a semihosting exit. Under -icount shift=N every instruction takes
 * 2^N ns, so cycles * 40 / 2^N are instructions.
 */
#include <stdio.h>
#include <string.h>

#include "hal/cortexm/board.h"
#include "scenario.h"

typedef struct {
	const char *label;
	uint32_t n, min, max;
	uint64_t sum;
} stat_t;

static stat_t stats[3];
static rig_t rig;

static void add(const char *label, uint32_t c)
{
	for (unsigned i = 0; i < sizeof(stats) / sizeof(stats[0]); i++) {
		stat_t *s = &stats[i];
		if (s->label && strcmp(s->label, label) != 0)
			continue;
		if (!s->label)
			*s = (stat_t){label, 0, UINT32_MAX, 0, 0};
		s->n++;
		s->sum += c;
		if (c < s->min)
			s->min = c;
		if (c > s->max)
			s->max = c;
		return;
	}
}

static void tick(rig_t *r, const char *label)
{
	uint32_t t0 = systick_cycles();
	rig_tick_firmware(r);
	add(label, systick_cycles() - t0);
}

static bool retarget(rig_t *r, vs_position_t p, const char *label)
{
	uint32_t t0 = systick_cycles();
	bool ok = vs_moveContinuousRel(&r->v, p);
	add(label, systick_cycles() - t0);
	return ok;
}

static bool plan(rig_t *r, const char *label)
{
	uint32_t t0 = systick_cycles();
	bool did = vehicle_plan_idle(&r->v);
	add(label, systick_cycles() - t0);
	return did;
}

/* newlib's output: blocking, straight to the UART. */
int _write(int fd, const char *buf, int n);
int _write(int fd, const char *buf, int n)
{
	(void)fd;
	for (int k = 0; k < n;) {
		k += (int)uart_link.write(NULL, (const uint8_t *)buf + k, (size_t)(n - k));
		uart_poll_tx();
	}
	while (uart_tx_pending())
		uart_poll_tx();
	return n;
}

/* hal/cortexm/semihost.c: the semihosting exit. */
void _exit(int code);

int main(void)
{
	static const bench_hooks_t hooks = {tick, retarget, plan};
	static char names[] = BENCH_SCENARIOS; /* split in place, word by word */

	uart_init();
	systick_init(1000u);
	for (char *name = strtok(names, " "); name; name = strtok(NULL, " ")) {
		memset(stats, 0, sizeof(stats));
		rig_init(&rig);
		/* The jerk scenarios plan between ticks as the board does; the
		 * others run no idle planning, and keep the whole pass in the
		 * request, as the host's table. */
		if (strstr(name, "_jerk"))
			vehicle_set_plan_budget(&rig.v, BOARD_PLAN_BUDGET);
		if (bench_scenario(&rig, name, &hooks) < 0)
			_exit(1);
		for (unsigned i = 0; i < sizeof(stats) / sizeof(stats[0]) && stats[i].label; i++)
			printf("%s %s %lu %lu %lu %lu\n", name, stats[i].label,
			       (unsigned long)stats[i].n, (unsigned long)stats[i].sum,
			       (unsigned long)stats[i].min, (unsigned long)stats[i].max);
	}
	fflush(stdout);
	_exit(0);
}
