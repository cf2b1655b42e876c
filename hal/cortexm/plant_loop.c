/* The loopback plant (loop_hal.h) as the board's plant; see plant.h. */
#include "loop_hal.h"
#include "plant.h"
#include "wdog.h"

static loop_hal_t plant;

void plant_config(vs_config_t *cfg)
{
	/* The loopback's drives follow their setpoints at once. */
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		cfg->drive_lag_ms[i] = 0;
}

vs_hal_t plant_hal(const vs_config_t *cfg)
{
	loop_hal_init(&plant, cfg->tick_hz);
	return (vs_hal_t){&loop_hal_ops, &plant};
}

void plant_start(vehicle_t *v)
{
	char s[VS_ALARM_SOURCE_MAX];
	if (wdog_restart_text(s, sizeof s))
		alarm_raise(&v->alarms, ALM_W_RESTARTED, s);
}

void plant_tick(void)
{
	wdog_feed();
	loop_hal_step(&plant);
}

void plant_poll(void) {}

bool plant_extra(void *ctx, int argc, char **argv, char *reply, size_t cap)
{
	(void)ctx;
	return board_test_extra && board_test_extra(argc, argv, reply, cap);
}

void plant_emergency_off(void)
{
	plant.relay = false;
}
