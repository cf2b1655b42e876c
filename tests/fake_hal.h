/* A fake plant for unit tests: ideal drives whose encoders integrate the
 * commanded velocity exactly, and settable sensors, faults and failures.
 * Everything is a plain field: a test sets what it needs and reads back
 * what the firmware commanded.
 */
#ifndef FAKE_HAL_H
#define FAKE_HAL_H

#include <stdbool.h>
#include <stdint.h>

#include "../firmware/vehicle.h"

#define FAKE_IO_IDS 64 /* io ids 0..63 */

typedef struct {
	uint32_t tick_hz;
	uint32_t now_us; /* clock handed to vehicle_tick by fake_run */

	/* Drives. */
	int32_t counts[VS_MAX_AXES];
	int64_t rem[VS_MAX_AXES];	 /* sub-count remainder, units of 1/(256*tick_hz) */
	int32_t cmd_cps_q8[VS_MAX_AXES]; /* last setpoint */
	bool enabled[VS_MAX_AXES];	 /* as commanded by drive_enable */
	bool frozen[VS_MAX_AXES];	 /* encoder stops counting */
	uint16_t fault_code[VS_MAX_AXES];
	bool silent[VS_MAX_AXES]; /* replies missing: fresh = false */
	unsigned set_velocity_calls[VS_MAX_AXES];
	unsigned enable_calls[VS_MAX_AXES];
	unsigned reset_fault_calls[VS_MAX_AXES];

	/* Main relay. */
	bool relay;	    /* closed */
	bool relay_fail;    /* commanding it on does not close it */
	bool feedback_lost; /* feedback contact reads open although commanded on */
	unsigned power_set_calls;
	bool last_power_set;

	/* Sensors. */
	bool contact, obstacle, caution, estop;
	hal_joystick_t js;
	uint32_t battery_mv;

	/* Digital IO by id; unserved ids make io_read/io_write fail. */
	uint32_t io_in[FAKE_IO_IDS];
	uint32_t io_out[FAKE_IO_IDS];
	bool io_unserved[FAKE_IO_IDS];
	unsigned io_write_calls;
	uint32_t last_write_id, last_write_value;
} fake_hal_t;

extern const vs_hal_ops_t fake_hal_ops;

/* Everything idle, battery 24.0 V, relay open, joystick present. */
void fake_hal_init(fake_hal_t *f, uint32_t tick_hz);
vs_hal_t fake_hal_bind(fake_hal_t *f);
/* The reference configuration for this drive, which follows its setpoint
 * at once: no drive lag for the wheel loop to lead. */
void fake_hal_config(vs_config_t *c);
/* Runs n control ticks, the clock advancing one period each. */
void fake_run(fake_hal_t *f, vehicle_t *v, unsigned n);
/* Period of the configured tick, microseconds. */
uint32_t fake_period_us(const fake_hal_t *f);

#endif
