/* Control tick cost, counted in instructions by callgrind.
 *
 * Run under
 *   valgrind --tool=callgrind --collect-atstart=no \
 *     --toggle-collect=bench_tick --toggle-collect=bench_cmd ./tickcost SCENARIO
 * Every measured call (one whole vehicle_tick, or one interface operation)
 * is followed by a callgrind dump labelled "tick", "cmd" or "tick-after-cmd",
 * so tools/bench/tickcost.sh can report the mean and the largest single tick.
 * Outside valgrind the client requests do nothing and the program only runs.
 *
 * Scenarios (reference configuration: 1 kHz, 500 mm/s, 500 mm/s^2):
 *   idle      powered, servo on, nothing to do, 2000 ticks
 *   line      moveForward 2000: every tick until idle
 *   cruise    the 10-waypoint moveCruiseAbs route (rig.c): every tick until idle
 *   jog       moveJog 300 mm/s, 30 deg/s, re-sent every 100 ms: 3000 ticks
 *   retarget  moveContinuousRel while moving, 20 times: the call and the tick after it
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <valgrind/callgrind.h>

#include "rig.h"

static rig_t rig;

__attribute__((noinline)) void bench_tick(rig_t *r);
__attribute__((noinline)) bool bench_cmd_retarget(rig_t *r, vs_position_t p);

/* The measured functions: nothing but the call itself. The plant steps
 * after the measured tick (loop_hal.h). */
__attribute__((noinline)) void bench_tick(rig_t *r)
{
	rig_tick_firmware(r);
}

__attribute__((noinline)) bool bench_cmd_retarget(rig_t *r, vs_position_t p)
{
	return vs_moveContinuousRel(&r->v, p);
}

static unsigned long measured;
static bool dump_each = true; /* BENCH_NODUMP=1: one total for the whole run */

static void dump(const char *label)
{
	if (dump_each)
		CALLGRIND_DUMP_STATS_AT(label);
}

static void tick_dump(const char *label)
{
	bench_tick(&rig);
	dump(label);
	loop_hal_step(&rig.plant);
	measured++;
}

static void need(bool ok, const char *what)
{
	if (!ok) {
		fprintf(stderr, "tickcost: %s refused\n", what);
		exit(2);
	}
}

int main(int argc, char **argv)
{
	const char *sc = argc > 1 ? argv[1] : "";
	const char *nd = getenv("BENCH_NODUMP");
	dump_each = !(nd && strcmp(nd, "1") == 0);
	rig_init(&rig);
	if (strcmp(sc, "idle") == 0) {
		for (int i = 0; i < 2000; i++)
			tick_dump("tick");
	} else if (strcmp(sc, "line") == 0) {
		need(vs_moveForward(&rig.v, 2000.0), "moveForward");
		do
			tick_dump("tick");
		while (motion_has_work(&rig.v.motion));
	} else if (strcmp(sc, "cruise") == 0) {
		for (int i = 0; i < ROUTE_N; i++)
			need(vs_moveCruiseAbs(&rig.v, (vs_point_t){route_mm[i][0], route_mm[i][1]}),
			     "moveCruiseAbs");
		do
			tick_dump("tick");
		while (motion_has_work(&rig.v.motion));
	} else if (strcmp(sc, "jog") == 0) {
		for (int i = 0; i < 3000; i++) {
			if (i % 100 == 0)
				need(vs_moveJog(&rig.v, 300.0, 0.0, 30.0), "moveJog");
			tick_dump("tick");
		}
	} else if (strcmp(sc, "retarget") == 0) {
		need(vs_moveContinuousRel(&rig.v, (vs_position_t){3000.0, 0.0, 0.0}),
		     "moveContinuousRel");
		for (int k = 0; k < 20; k++) {
			for (int i = 0; i < 250; i++)
				rig_tick(&rig);
			/* Alternate left and right goals ahead: a new bearing each time. */
			double side = (k & 1) ? -400.0 : 400.0;
			need(bench_cmd_retarget(&rig, (vs_position_t){1500.0, side, side / 20.0}),
			     "moveContinuousRel");
			dump("cmd");
			tick_dump("tick-after-cmd");
		}
	} else {
		fprintf(stderr, "usage: tickcost idle|line|cruise|jog|retarget\n");
		return 2;
	}
	printf("%s: %lu measured calls, unit state %d\n", sc, measured,
	       motion_has_work(&rig.v.motion) ? 1 : 0);
	return 0;
}
