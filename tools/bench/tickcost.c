/* Control tick cost, counted in instructions by callgrind.
 *
 * Run under
 *   valgrind --tool=callgrind --collect-atstart=no \
 *     --toggle-collect=bench_tick --toggle-collect=bench_cmd_retarget \
 *     --toggle-collect=bench_plan ./tickcost SCENARIO
 * Every measured call (one whole vehicle_tick, or one interface operation)
 * is followed by a callgrind dump labelled "tick", "cmd" or "tick-after-cmd",
 * so tools/bench/tickcost.sh can report the mean and the largest single tick.
 * Outside valgrind the client requests do nothing and the program only runs.
 * The scenarios are those of scenario.h (also run on the Cortex-M4 image).
 * BENCH_BBOX=1 gives the unit a black box of 2 s recording every tick (as
 * on the vehicle computer; the rig has none otherwise): run with
 * --toggle-collect=vehicle_bbox_record, each tick's dump is its recording.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <valgrind/callgrind.h>

#include "scenario.h"

static rig_t rig;
static bbox_sample_t bbox_ring[2000];

__attribute__((noinline)) void bench_tick(rig_t *r);
__attribute__((noinline)) bool bench_cmd_retarget(rig_t *r, vs_position_t p);
__attribute__((noinline)) bool bench_plan(rig_t *r);

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

__attribute__((noinline)) bool bench_plan(rig_t *r)
{
	return vehicle_plan_idle(&r->v);
}

static bool dump_each = true; /* BENCH_NODUMP=1: one total for the whole run */

static void dump(const char *label)
{
	if (dump_each)
		CALLGRIND_DUMP_STATS_AT(label);
}

static void tick_dump(rig_t *r, const char *label)
{
	bench_tick(r);
	dump(label);
}

static bool retarget_dump(rig_t *r, vs_position_t p, const char *label)
{
	bool ok = bench_cmd_retarget(r, p);
	dump(label);
	return ok;
}

static bool plan_dump(rig_t *r, const char *label)
{
	bool did = bench_plan(r);
	dump(label);
	return did;
}

int main(int argc, char **argv)
{
	static const bench_hooks_t hooks = {tick_dump, retarget_dump, plan_dump};
	const char *sc = argc > 1 ? argv[1] : "";
	if (strcmp(sc, "--list") == 0) { /* for tools/bench/tickcost.sh */
		puts(BENCH_SCENARIOS);
		return 0;
	}
	const char *nd = getenv("BENCH_NODUMP");
	dump_each = !(nd && strcmp(nd, "1") == 0);
	rig_init(&rig);
	const char *bb = getenv("BENCH_BBOX");
	if (bb && strcmp(bb, "1") == 0)
		vehicle_blackbox(&rig.v, bbox_ring, 2000, 1);
	long measured = bench_scenario(&rig, sc, &hooks);
	if (measured < 0) {
		fprintf(stderr, "usage: tickcost --list | SCENARIO, one of: %s\n", BENCH_SCENARIOS);
		return 2;
	}
	printf("%s: %ld measured calls, unit state %d\n", sc, measured,
	       motion_has_work(&rig.v.motion) ? 1 : 0);
	return 0;
}
