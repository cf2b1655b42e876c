/* The firmware on the loopback plant, for the benchmarks: a vehicle with the
 * reference configuration, powered and servo on, ticked with an ideal clock. */
#ifndef BENCH_RIG_H
#define BENCH_RIG_H

#include <stdint.h>

#include "firmware/vehicle.h"
#include "hal/cortexm/loop_hal.h"

typedef struct {
	vs_config_t cfg;
	loop_hal_t plant;
	vs_hal_t hal;
	vehicle_t v;
	uint32_t now_us;
} rig_t;

/* Reference configuration (vs_config_defaults); exits on failure. */
void rig_init(rig_t *r);
/* One control period: the firmware's tick, then the plant's step. */
void rig_tick(rig_t *r);
/* The firmware's tick alone (what the benchmarks measure). */
void rig_tick_firmware(rig_t *r);
/* Ticks until the unit has no motion work left; returns the ticks run, or
 * exits when max is reached. */
uint32_t rig_run_idle(rig_t *r, uint32_t max);

/* A 10-waypoint moveCruiseAbs route from (0, 0) heading 0, whole mm. */
#define ROUTE_N 10
extern const int32_t route_mm[ROUTE_N][2];

#endif
