/* A self-contained plant for boards without drives attached: ideal wheel
 * drives whose encoders integrate the commanded velocity exactly, a relay
 * that always closes, a constant battery and quiet sensors. The Cortex-M
 * image runs on it (so a bare evaluation board answers the console and
 * "moves"), and the host benchmarks use it so that tick costs are those of
 * the firmware, not of a plant model. Plain C, no libc.
 */
#ifndef LOOP_HAL_H
#define LOOP_HAL_H

#include <stdbool.h>
#include <stdint.h>

#include "../hal.h"

#define LOOP_HAL_AXES 4

typedef struct {
	uint32_t tick_hz;
	int32_t counts[LOOP_HAL_AXES];
	int64_t rem[LOOP_HAL_AXES];    /* sub-count remainder, 1/(256 tick_hz) counts */
	int32_t cps_q8[LOOP_HAL_AXES]; /* last setpoint, counts/s Q8 */
	bool enabled[LOOP_HAL_AXES];
	bool relay;
	uint32_t battery_mv;
} loop_hal_t;

extern const vs_hal_ops_t loop_hal_ops;

/* Relay open, drives disabled, battery 24.0 V. */
void loop_hal_init(loop_hal_t *h, uint32_t tick_hz);
/* One control period of the world: each enabled drive's encoder advances by
 * its setpoint. Called after each control tick, outside it, as the wheels
 * of a real unit move between two ticks. */
void loop_hal_step(loop_hal_t *h);

#endif
