/* Configuration defaults and validation.
 *
 * Runs once at init, before anything moves; it is the only firmware code
 * besides vs_api.c that touches doubles (soft-float is fine here). Every
 * range test is written "lo <= x && x <= hi" so that NaN fails it too.
 */
#include <stddef.h>

#include "config.h"

/* Reference differential base: 150 mm wheels, 400 mm track, 4096-line
 * encoders read in quadrature, 24 V battery pack. */
void vs_config_defaults(vs_config_t *c)
{
	/* Field by field: the struct is large and firmware has no memset. */
	c->kinematics = VS_KIN_DIFF;
	c->tick_hz = 1000;

	c->wheel_diameter_mm = 150.0;
	c->track_width_mm = 400.0;
	c->wheel_base_mm = 0.0; /* unused on a differential base */
	c->encoder_counts_per_rev = 4096u * 4u;

	c->vel_limit_t_mm_s = 1000.0;
	c->vel_limit_r_deg_s = 180.0;
	c->acc_limit_t_mm_s2 = 1000.0;
	c->acc_limit_r_deg_s2 = 360.0;
	c->vel_default_t_mm_s = 500.0;
	c->vel_default_r_deg_s = 90.0;
	c->acc_default_t_mm_s2 = 500.0;
	c->acc_default_r_deg_s2 = 180.0;
	c->jog_timeout_default_ms = 500;

	c->wheel_kp_per_s = 20.0;
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		c->drive_lag_ms[i] = 20.0;
	c->following_error_mm = 50.0;
	c->encoder_stuck_ms = 300;
	c->drive_timeout_ms = 50;
	c->loop_late_ms = 20;
	c->link_timeout_ms = 1000;
	c->position_window_mm = 0.05;
	c->position_window_ms = 20;
	c->settle_timeout_ms = 1000;

	c->cruise_blend_mm = 200.0;
	c->caution_vel_t_mm_s = 200.0;

	c->battery_low_v = 22.0;
	c->battery_critical_v = 20.0;

	c->has_contact_sensor = true;
	c->has_obstacle_input = true;
	c->has_estop = true;
	c->has_joystick = true;
	c->joystick_deadband = 0.05;

	c->firmware_version = NULL;

	/* io.xml of the reference base: two inputs, two outputs. */
	static const struct {
		uint32_t id;
		uint8_t dir, width;
		const char *name;
	} io[] = {
	    {1, VS_IO_IN, 8, "din0"},
	    {2, VS_IO_IN, 1, "dock_contact"},
	    {3, VS_IO_OUT, 8, "dout0"},
	    {4, VS_IO_OUT, 1, "lamp"},
	};
	c->num_io = (uint8_t)(sizeof io / sizeof io[0]);
	for (unsigned i = 0; i < VS_MAX_IO; i++) {
		vs_io_def_t *d = &c->io[i];
		d->id = 0;
		d->dir = VS_IO_IN;
		d->width = 0;
		for (unsigned k = 0; k < VS_IO_NAME_MAX; k++)
			d->name[k] = '\0';
		if (i < c->num_io) {
			d->id = io[i].id;
			d->dir = io[i].dir;
			d->width = io[i].width;
			for (unsigned k = 0; k < VS_IO_NAME_MAX - 1 && io[i].name[k]; k++)
				d->name[k] = io[i].name[k];
		}
	}
}

static bool in_range(double x, double lo, double hi)
{
	return lo <= x && x <= hi;
}

/* 0 < x <= hi (NaN fails). */
static bool positive_upto(double x, double hi)
{
	return x > 0.0 && x <= hi;
}

#define PI_D 3.14159265358979323846

#define FAIL(code, name)                                                                           \
	do {                                                                                       \
		if (field)                                                                         \
			*field = (name);                                                           \
		return (code);                                                                     \
	} while (0)

/* Return codes: -1 a field out of its range, -2 two fields inconsistent,
 * -3 an io.xml entry invalid or duplicated. */
int vs_config_check(const vs_config_t *c, const char **field)
{
	if (c->kinematics != VS_KIN_DIFF && c->kinematics != VS_KIN_OMNI)
		FAIL(-1, "kinematics");
	if (c->tick_hz < 100 || c->tick_hz > 10000)
		FAIL(-1, "tick_hz");

	if (!in_range(c->wheel_diameter_mm, 10.0, 2000.0))
		FAIL(-1, "wheel_diameter_mm");
	if (!in_range(c->track_width_mm, 50.0, 5000.0))
		FAIL(-1, "track_width_mm");
	if (c->kinematics == VS_KIN_OMNI ? !in_range(c->wheel_base_mm, 50.0, 5000.0)
					 : !in_range(c->wheel_base_mm, 0.0, 5000.0))
		FAIL(-1, "wheel_base_mm");
	if (c->encoder_counts_per_rev < 1 || c->encoder_counts_per_rev > (1u << 24))
		FAIL(-1, "encoder_counts_per_rev");

	if (!positive_upto(c->vel_limit_t_mm_s, 10000.0))
		FAIL(-1, "vel_limit_t_mm_s");
	if (!positive_upto(c->vel_limit_r_deg_s, 3600.0))
		FAIL(-1, "vel_limit_r_deg_s");
	if (!positive_upto(c->acc_limit_t_mm_s2, 100000.0))
		FAIL(-1, "acc_limit_t_mm_s2");
	if (!positive_upto(c->acc_limit_r_deg_s2, 100000.0))
		FAIL(-1, "acc_limit_r_deg_s2");
	if (!positive_upto(c->vel_default_t_mm_s, c->vel_limit_t_mm_s))
		FAIL(-2, "vel_default_t_mm_s");
	if (!positive_upto(c->vel_default_r_deg_s, c->vel_limit_r_deg_s))
		FAIL(-2, "vel_default_r_deg_s");
	if (!positive_upto(c->acc_default_t_mm_s2, c->acc_limit_t_mm_s2))
		FAIL(-2, "acc_default_t_mm_s2");
	if (!positive_upto(c->acc_default_r_deg_s2, c->acc_limit_r_deg_s2))
		FAIL(-2, "acc_default_r_deg_s2");
	/* setJogTimeout takes a short. */
	if (c->jog_timeout_default_ms < 1 || c->jog_timeout_default_ms > 32767)
		FAIL(-1, "jog_timeout_default_ms");

	if (!positive_upto(c->wheel_kp_per_s, 1000.0))
		FAIL(-1, "wheel_kp_per_s");
	/* Per-tick loop gain at most 1/4 keeps the discrete loop well damped. */
	if (c->wheel_kp_per_s * 4.0 > (double)c->tick_hz)
		FAIL(-2, "wheel_kp_per_s");
	for (unsigned i = 0; i < VS_MAX_AXES; i++)
		if (!in_range(c->drive_lag_ms[i], 0.0, 1000.0))
			FAIL(-1, "drive_lag_ms");
	if (!positive_upto(c->following_error_mm, 10000.0))
		FAIL(-1, "following_error_mm");
	if (c->encoder_stuck_ms < 10 || c->encoder_stuck_ms > 60000)
		FAIL(-1, "encoder_stuck_ms");
	if (c->drive_timeout_ms < 1 || c->drive_timeout_ms > 60000)
		FAIL(-1, "drive_timeout_ms");
	if (c->loop_late_ms < 1 || c->loop_late_ms > 1000)
		FAIL(-1, "loop_late_ms");
	if (c->link_timeout_ms > 60000)
		FAIL(-1, "link_timeout_ms");
	if (!positive_upto(c->position_window_mm, 100.0))
		FAIL(-1, "position_window_mm");
	if (c->position_window_ms > 1000)
		FAIL(-1, "position_window_ms");
	if (c->settle_timeout_ms < 10 || c->settle_timeout_ms > 60000)
		FAIL(-1, "settle_timeout_ms");

	if (!in_range(c->cruise_blend_mm, 0.0, 10000.0))
		FAIL(-1, "cruise_blend_mm");
	if (!in_range(c->caution_vel_t_mm_s, 0.0, c->vel_limit_t_mm_s))
		FAIL(-2, "caution_vel_t_mm_s");

	if (!positive_upto(c->battery_critical_v, 1000.0))
		FAIL(-1, "battery_critical_v");
	if (!in_range(c->battery_low_v, 0.0, 1000.0))
		FAIL(-1, "battery_low_v");
	if (!(c->battery_low_v > c->battery_critical_v))
		FAIL(-2, "battery_low_v");

	if (!in_range(c->joystick_deadband, 0.0, 0.5))
		FAIL(-1, "joystick_deadband");

	if (c->firmware_version) {
		unsigned k = 0;
		while (k < 32 && c->firmware_version[k] != '\0')
			k++;
		if (k == 0 || k >= 32)
			FAIL(-1, "firmware_version");
	}

	/* The fastest wheel setpoint (counts/s, Q8, plus the same again for
	 * the position loop's correction) must fit the HAL's int32. */
	double counts_per_mm = (double)c->encoder_counts_per_rev / (PI_D * c->wheel_diameter_mm);
	double half = c->kinematics == VS_KIN_OMNI ? (c->wheel_base_mm + c->track_width_mm) / 2.0
						   : c->track_width_mm / 2.0;
	double wheel_mm_s = c->vel_limit_t_mm_s * (c->kinematics == VS_KIN_OMNI ? 2.0 : 1.0) +
			    c->vel_limit_r_deg_s * half * PI_D / 180.0;
	if (wheel_mm_s * counts_per_mm * 256.0 * 2.0 > 2147483647.0)
		FAIL(-2, "encoder_counts_per_rev");

	if (c->num_io > VS_MAX_IO)
		FAIL(-1, "num_io");
	for (unsigned i = 0; i < c->num_io; i++) {
		const vs_io_def_t *d = &c->io[i];
		if (d->id == 0)
			FAIL(-3, "io.id");
		if (d->dir != VS_IO_IN && d->dir != VS_IO_OUT)
			FAIL(-3, "io.dir");
		if (d->width < 1 || d->width > 32)
			FAIL(-3, "io.width");
		bool terminated = false;
		for (unsigned k = 0; k < VS_IO_NAME_MAX; k++)
			terminated = terminated || d->name[k] == '\0';
		if (!terminated)
			FAIL(-3, "io.name");
		for (unsigned j = 0; j < i; j++) {
			if (c->io[j].id == d->id)
				FAIL(-3, "io.id");
		}
	}
	return 0;
}
