/* HAL backend over the simulated plant. The relay settles at once, so
 * power_set never waits; inputs are the plant's values at the call. */
#include "sim_hal.h"

static void drive_set_velocity(void *ctx, uint8_t axis, int32_t cps_q8)
{
	plant_drive_set_velocity(ctx, axis, cps_q8);
}

static void drive_enable(void *ctx, uint8_t axis, bool on)
{
	plant_drive_enable(ctx, axis, on);
}

static void drive_read(void *ctx, uint8_t axis, hal_drive_state_t *st)
{
	plant_drive_read(ctx, axis, st);
}

static void drive_reset_fault(void *ctx, uint8_t axis)
{
	plant_drive_reset_fault(ctx, axis);
}

static bool power_set(void *ctx, bool on)
{
	return plant_power_set(ctx, on);
}

static bool power_feedback(void *ctx)
{
	return ((plant_t *)ctx)->relay_closed;
}

static bool io_read(void *ctx, uint32_t ioid, uint32_t *value)
{
	return plant_io_read(ctx, ioid, value);
}

static bool io_write(void *ctx, uint32_t ioid, uint32_t value)
{
	return plant_io_write(ctx, ioid, value);
}

static bool contact(void *ctx)
{
	return plant_contact(ctx);
}

static bool obstacle(void *ctx)
{
	return ((plant_t *)ctx)->obstacle;
}

static bool obstacle_caution(void *ctx)
{
	return ((plant_t *)ctx)->caution;
}

static bool estop(void *ctx)
{
	return ((plant_t *)ctx)->estop;
}

static void joystick(void *ctx, hal_joystick_t *js)
{
	*js = ((plant_t *)ctx)->js;
}

static uint32_t battery_mv(void *ctx)
{
	return plant_battery_mv(ctx);
}

const vs_hal_ops_t sim_hal_ops = {
    .drive_set_velocity = drive_set_velocity,
    .drive_enable = drive_enable,
    .drive_read = drive_read,
    .drive_reset_fault = drive_reset_fault,
    .power_set = power_set,
    .power_feedback = power_feedback,
    .io_read = io_read,
    .io_write = io_write,
    .contact = contact,
    .obstacle = obstacle,
    .obstacle_caution = obstacle_caution,
    .estop = estop,
    .joystick = joystick,
    .battery_mv = battery_mv,
};

void sim_hal_bind(vs_hal_t *hal, plant_t *pl)
{
	hal->ops = &sim_hal_ops;
	hal->ctx = pl;
}
