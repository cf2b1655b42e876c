/* Benchmark rig (see rig.h). */
#include "rig.h"

#include <stdio.h>
#include <stdlib.h>

/* Corners from 22 to 117 degrees, both senses, legs of 0.7 to 1.4 m. */
const int32_t route_mm[ROUTE_N][2] = {
    {1000, 0},	  {2000, 400},	{3000, 0},    {3800, 800}, {3800, 1800},
    {2800, 2300}, {1800, 1800}, {1000, 2400}, {0, 1800},   {0, 800},
};

static void die(const char *what)
{
	fprintf(stderr, "bench rig: %s failed\n", what);
	exit(2);
}

void rig_init(rig_t *r)
{
	const char *bad = NULL;
	vs_config_defaults(&r->cfg);
	/* Scenarios run without a host: no link watchdog. */
	r->cfg.link_timeout_ms = 0;
	/* The loopback's drives follow their setpoints at once. */
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		r->cfg.drive_lag_ms[i] = 0.0;
	loop_hal_init(&r->plant, r->cfg.tick_hz);
	r->hal = (vs_hal_t){&loop_hal_ops, &r->plant};
	if (vehicle_init(&r->v, &r->cfg, &r->hal, &bad) != 0) {
		fprintf(stderr, "bench rig: configuration field %s\n", bad ? bad : "?");
		exit(2);
	}
	r->now_us = 1000000u;
	rig_tick(r);
	if (!vs_setPower(&r->v, true))
		die("setPower");
	rig_tick(r);
	if (!vs_setServo(&r->v, true))
		die("setServo");
	rig_tick(r);
}

void rig_tick_firmware(rig_t *r)
{
	r->now_us += 1000000u / r->cfg.tick_hz;
	vehicle_tick(&r->v, r->now_us);
}

void rig_tick(rig_t *r)
{
	rig_tick_firmware(r);
	loop_hal_step(&r->plant);
}

uint32_t rig_run_idle(rig_t *r, uint32_t max)
{
	for (uint32_t i = 1; i <= max; i++) {
		rig_tick(r);
		if (!motion_has_work(&r->v.motion))
			return i;
	}
	die("run to idle");
	return 0;
}
