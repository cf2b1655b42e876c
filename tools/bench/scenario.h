/* The tick-cost scenarios, shared by the host benchmark (tickcost.c, counted
 * by callgrind) and the Cortex-M4 one (mcu_tickcost.c, counted by SysTick in
 * QEMU), so that both measure the same ticks.
 *
 * Scenarios (reference configuration: 1 kHz, 500 mm/s, 500 mm/s^2):
 *   idle      powered, servo on, nothing to do, 2000 ticks
 *   line      moveForward 2000: every tick until idle
 *   cruise    the 10-waypoint moveCruiseAbs route (rig.c): every tick until idle
 *   jog       moveJog 300 mm/s, 30 deg/s, re-sent every 100 ms: 3000 ticks
 *   retarget  moveContinuousRel while moving, 20 times: the call and the tick after it
 *   line_jerk, jog_jerk   line and jog with $jerk 2000 1000 (mm/s^3, deg/s^3)
 *   cruise_jerk  cruise with $jerk 2000 1000, the main loop's planning between
 *             two ticks measured apart ("plan-ahead")
 *   speed_jerk  moveForward 3000 with $jerk 2000 1000; setVelocity 800 at tick
 *             1500 (on the hold), 300 at 2600: every tick, the three after
 *             each new speed apart
 *   retarget_jerk  retarget with $jerk 2000 1000: every tick, and the call
 *   goal_jerk  moveContinuousRel 300 200 0 from rest with $jerk 2000 1000
 *   blend_jerk  moveCruiseAbs 300,0, 300,300, 600,300, 10 ticks apart, with
 *             $jerk 2000 1000: the running line glides into each new corner;
 *             the main loop's planning between two ticks measured apart
 */
#ifndef BENCH_SCENARIO_H
#define BENCH_SCENARIO_H

#include "rig.h"

typedef struct {
	/* Runs rig_tick_firmware(r) once and measures it; the plant steps
	 * afterwards, outside the measurement. */
	void (*tick)(rig_t *r, const char *label);
	/* Runs vs_moveContinuousRel(&r->v, p) and measures it as label. */
	bool (*retarget)(rig_t *r, vs_position_t p, const char *label);
	/* Runs vehicle_plan_idle(&r->v) (the main loop's work between two
	 * ticks) and measures it as label. */
	bool (*plan)(rig_t *r, const char *label);
} bench_hooks_t;

#define BENCH_SCENARIOS                                                                            \
	"idle line cruise jog retarget line_jerk jog_jerk cruise_jerk speed_jerk retarget_jerk "   \
	"goal_jerk blend_jerk"

/* Runs one scenario on a rig fresh from rig_init. Returns the measured
 * ticks, or -1 for an unknown name; exits when an operation is refused. */
long bench_scenario(rig_t *r, const char *name, const bench_hooks_t *h);

#endif
