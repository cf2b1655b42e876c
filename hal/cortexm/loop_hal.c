/* Loopback plant (see loop_hal.h). */
#include "loop_hal.h"

/* A drive takes its setpoint; the wheel moves when the world steps. */
static void l_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8)
{
	loop_hal_t *h = ctx;
	if (axis < LOOP_HAL_AXES)
		h->cps_q8[axis] = cps_q8;
}

void loop_hal_step(loop_hal_t *h)
{
	/* One period at cps_q8 / 256 counts per second for each enabled drive;
	 * keep the remainder so that nothing is lost to rounding. */
	int64_t unit = 256 * (int64_t)h->tick_hz;
	for (uint8_t axis = 0; axis < LOOP_HAL_AXES; axis++) {
		if (!h->relay || !h->enabled[axis])
			continue;
		int64_t acc = h->rem[axis] + h->cps_q8[axis];
		h->counts[axis] =
		    (int32_t)((uint32_t)h->counts[axis] + (uint32_t)(int32_t)(acc / unit));
		h->rem[axis] = acc % unit;
	}
}

static void l_enable(void *ctx, uint8_t axis, bool on)
{
	loop_hal_t *h = ctx;
	if (axis < LOOP_HAL_AXES)
		h->enabled[axis] = on;
}

static void l_read(void *ctx, uint8_t axis, hal_drive_state_t *st)
{
	loop_hal_t *h = ctx;
	if (axis >= LOOP_HAL_AXES)
		return;
	/* The whole report in one store: its flags are bit-fields, each a
	 * read-modify-write of its own (the tick pays it per wheel). */
	*st = (hal_drive_state_t){.position_counts = h->counts[axis],
				  .enabled = h->enabled[axis] && h->relay,
				  .fresh = true};
}

static void l_reset_fault(void *ctx, uint8_t axis)
{
	(void)ctx;
	(void)axis;
}

static bool l_power_set(void *ctx, bool on)
{
	((loop_hal_t *)ctx)->relay = on;
	return true;
}

static bool l_power_feedback(void *ctx)
{
	return ((loop_hal_t *)ctx)->relay;
}

/* No IO module on a bare board: every id is unserved. */
static bool l_io_read(void *ctx, uint32_t ioid, uint32_t *value)
{
	(void)ctx;
	(void)ioid;
	(void)value;
	return false;
}

static bool l_io_write(void *ctx, uint32_t ioid, uint32_t value)
{
	(void)ctx;
	(void)ioid;
	(void)value;
	return false;
}

static bool l_false(void *ctx)
{
	(void)ctx;
	return false;
}

static void l_joystick(void *ctx, hal_joystick_t *js)
{
	(void)ctx;
	js->axis[0] = js->axis[1] = js->axis[2] = 0;
	js->present = false;
}

static uint32_t l_battery_mv(void *ctx)
{
	return ((loop_hal_t *)ctx)->battery_mv;
}

const vs_hal_ops_t loop_hal_ops = {
    .drive_set_velocity = l_set_velocity,
    .drive_enable = l_enable,
    .drive_read = l_read,
    .drive_reset_fault = l_reset_fault,
    .power_set = l_power_set,
    .power_feedback = l_power_feedback,
    .io_read = l_io_read,
    .io_write = l_io_write,
    .contact = l_false,
    .obstacle = l_false,
    .obstacle_caution = l_false,
    .estop = l_false,
    .joystick = l_joystick,
    .battery_mv = l_battery_mv,
};

void loop_hal_init(loop_hal_t *h, uint32_t tick_hz)
{
	*h = (loop_hal_t){0};
	h->tick_hz = tick_hz;
	h->battery_mv = 24000;
}
