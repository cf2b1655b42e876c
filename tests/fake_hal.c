/* Fake plant for unit tests (see fake_hal.h). */
#include "fake_hal.h"

#include <string.h>

static bool axis_ok(uint8_t axis)
{
	return axis < VS_MAX_AXES;
}

static void f_drive_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8)
{
	fake_hal_t *f = ctx;
	if (!axis_ok(axis))
		return;
	f->cmd_cps_q8[axis] = cps_q8;
	f->set_velocity_calls[axis]++;
	/* An ideal drive: the wheel turns exactly as commanded for one period,
	 * when powered and enabled. */
	if (!f->relay || !f->enabled[axis] || f->frozen[axis])
		return;
	int64_t unit = 256 * (int64_t)f->tick_hz;
	int64_t acc = f->rem[axis] + cps_q8;
	f->counts[axis] = (int32_t)((uint32_t)f->counts[axis] + (uint32_t)(int32_t)(acc / unit));
	f->rem[axis] = acc % unit;
}

static void f_drive_enable(void *ctx, uint8_t axis, bool on)
{
	fake_hal_t *f = ctx;
	if (!axis_ok(axis))
		return;
	f->enabled[axis] = on;
	f->enable_calls[axis]++;
}

static void f_drive_read(void *ctx, uint8_t axis, hal_drive_state_t *st)
{
	fake_hal_t *f = ctx;
	if (!axis_ok(axis))
		return;
	st->position_counts = f->counts[axis];
	st->fault_code = f->fault_code[axis];
	st->enabled = f->enabled[axis] && f->relay;
	st->fresh = !f->silent[axis];
}

static void f_drive_reset_fault(void *ctx, uint8_t axis)
{
	fake_hal_t *f = ctx;
	if (!axis_ok(axis))
		return;
	f->fault_code[axis] = 0;
	f->reset_fault_calls[axis]++;
}

static bool f_power_set(void *ctx, bool on)
{
	fake_hal_t *f = ctx;
	f->power_set_calls++;
	f->last_power_set = on;
	f->relay = on && !f->relay_fail;
	return true;
}

static bool f_power_feedback(void *ctx)
{
	fake_hal_t *f = ctx;
	return f->relay && !f->feedback_lost;
}

static bool f_io_read(void *ctx, uint32_t ioid, uint32_t *value)
{
	fake_hal_t *f = ctx;
	if (ioid >= FAKE_IO_IDS || f->io_unserved[ioid])
		return false;
	*value = f->io_in[ioid];
	return true;
}

static bool f_io_write(void *ctx, uint32_t ioid, uint32_t value)
{
	fake_hal_t *f = ctx;
	if (ioid >= FAKE_IO_IDS || f->io_unserved[ioid])
		return false;
	f->io_out[ioid] = value;
	f->io_write_calls++;
	f->last_write_id = ioid;
	f->last_write_value = value;
	return true;
}

static bool f_contact(void *ctx)
{
	return ((fake_hal_t *)ctx)->contact;
}

static bool f_obstacle(void *ctx)
{
	return ((fake_hal_t *)ctx)->obstacle;
}

static bool f_caution(void *ctx)
{
	return ((fake_hal_t *)ctx)->caution;
}

static bool f_estop(void *ctx)
{
	return ((fake_hal_t *)ctx)->estop;
}

static void f_joystick(void *ctx, hal_joystick_t *js)
{
	*js = ((fake_hal_t *)ctx)->js;
}

static uint32_t f_battery_mv(void *ctx)
{
	return ((fake_hal_t *)ctx)->battery_mv;
}

const vs_hal_ops_t fake_hal_ops = {
    .drive_set_velocity = f_drive_set_velocity,
    .drive_enable = f_drive_enable,
    .drive_read = f_drive_read,
    .drive_reset_fault = f_drive_reset_fault,
    .power_set = f_power_set,
    .power_feedback = f_power_feedback,
    .io_read = f_io_read,
    .io_write = f_io_write,
    .contact = f_contact,
    .obstacle = f_obstacle,
    .obstacle_caution = f_caution,
    .estop = f_estop,
    .joystick = f_joystick,
    .battery_mv = f_battery_mv,
};

void fake_hal_init(fake_hal_t *f, uint32_t tick_hz)
{
	memset(f, 0, sizeof *f);
	f->tick_hz = tick_hz;
	f->now_us = 1000000u;
	f->battery_mv = 24000;
	f->js.present = true;
}

vs_hal_t fake_hal_bind(fake_hal_t *f)
{
	vs_hal_t h = {&fake_hal_ops, f};
	return h;
}

uint32_t fake_period_us(const fake_hal_t *f)
{
	return 1000000u / f->tick_hz;
}

void fake_run(fake_hal_t *f, vehicle_t *v, unsigned n)
{
	for (unsigned i = 0; i < n; i++) {
		f->now_us += fake_period_us(f);
		vehicle_tick(v, f->now_us);
	}
}

void fake_hal_config(vs_config_t *c)
{
	vs_config_defaults(c);
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		c->drive_lag_ms[i] = 0.0;
}
