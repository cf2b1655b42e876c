/* vs_config_check: every rule rejects its bad value with the documented
 * code and field name, also when the caller passes no field pointer, and
 * both ends of each range are enforced. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "firmware/config.h"

typedef struct {
	int rc;
	const char *field;
} expect_t;

/* Case i of the table: break the defaults in one way. */
static expect_t mutate(int i, vs_config_t *c)
{
	switch (i) {
	case 0:
		c->kinematics = (vs_kinematics_t)7;
		return (expect_t){-1, "kinematics"};
	case 1:
		c->tick_hz = 10001;
		return (expect_t){-1, "tick_hz"};
	case 2:
		c->wheel_diameter_mm = 2000.5;
		return (expect_t){-1, "wheel_diameter_mm"};
	case 3:
		c->track_width_mm = 49.0;
		return (expect_t){-1, "track_width_mm"};
	case 4:
		c->wheel_base_mm = -1.0;
		return (expect_t){-1, "wheel_base_mm"};
	case 5:
		c->kinematics = VS_KIN_OMNI;
		c->wheel_base_mm = 49.0;
		return (expect_t){-1, "wheel_base_mm"};
	case 6:
		c->encoder_counts_per_rev = 0;
		return (expect_t){-1, "encoder_counts_per_rev"};
	case 7:
		c->encoder_counts_per_rev = (1u << 24) + 1;
		return (expect_t){-1, "encoder_counts_per_rev"};
	case 8:
		c->vel_limit_t_mm_s = 10000.5;
		return (expect_t){-1, "vel_limit_t_mm_s"};
	case 9:
		c->vel_limit_r_deg_s = 0.0;
		return (expect_t){-1, "vel_limit_r_deg_s"};
	case 10:
		c->acc_limit_t_mm_s2 = -1.0;
		return (expect_t){-1, "acc_limit_t_mm_s2"};
	case 11:
		c->acc_limit_r_deg_s2 = 100001.0;
		return (expect_t){-1, "acc_limit_r_deg_s2"};
	case 12:
		c->vel_default_t_mm_s = 1000.5;
		return (expect_t){-2, "vel_default_t_mm_s"};
	case 13:
		c->vel_default_r_deg_s = 180.5;
		return (expect_t){-2, "vel_default_r_deg_s"};
	case 14:
		c->acc_default_t_mm_s2 = 0.0;
		return (expect_t){-2, "acc_default_t_mm_s2"};
	case 15:
		c->acc_default_r_deg_s2 = 360.5;
		return (expect_t){-2, "acc_default_r_deg_s2"};
	case 16:
		c->jog_timeout_default_ms = 0;
		return (expect_t){-1, "jog_timeout_default_ms"};
	case 17:
		c->jog_timeout_default_ms = 32768;
		return (expect_t){-1, "jog_timeout_default_ms"};
	case 18:
		c->wheel_kp_per_s = 1000.5;
		return (expect_t){-1, "wheel_kp_per_s"};
	/* 1 kHz: a gain above 250/s is more than 1/4 per tick */
	case 19:
		c->wheel_kp_per_s = 250.5;
		return (expect_t){-2, "wheel_kp_per_s"};
	case 20:
		c->following_error_mm = 0.0;
		return (expect_t){-1, "following_error_mm"};
	case 21:
		c->encoder_stuck_ms = 9;
		return (expect_t){-1, "encoder_stuck_ms"};
	case 22:
		c->encoder_stuck_ms = 60001;
		return (expect_t){-1, "encoder_stuck_ms"};
	case 23:
		c->drive_timeout_ms = 0;
		return (expect_t){-1, "drive_timeout_ms"};
	case 24:
		c->drive_timeout_ms = 60001;
		return (expect_t){-1, "drive_timeout_ms"};
	case 25:
		c->cruise_blend_mm = -0.5;
		return (expect_t){-1, "cruise_blend_mm"};
	case 26:
		c->caution_vel_t_mm_s = 1000.5;
		return (expect_t){-2, "caution_vel_t_mm_s"};
	case 27:
		c->battery_critical_v = 0.0;
		return (expect_t){-1, "battery_critical_v"};
	case 28:
		c->battery_low_v = 1000.5;
		return (expect_t){-1, "battery_low_v"};
	case 29:
		c->battery_low_v = 20.0;
		return (expect_t){-2, "battery_low_v"};
	case 30:
		c->joystick_deadband = 0.51;
		return (expect_t){-1, "joystick_deadband"};
	case 31:
		c->firmware_version = "";
		return (expect_t){-1, "firmware_version"};
	case 32:
		c->firmware_version = "0123456789012345678901234567890123";
		return (expect_t){-1, "firmware_version"};
	/* 10000 mm/s on 16384-count 10 mm wheels overflows the int32 setpoint */
	case 33:
		c->vel_limit_t_mm_s = 10000.0;
		c->wheel_diameter_mm = 10.0;
		return (expect_t){-2, "encoder_counts_per_rev"};
	case 34:
		c->num_io = VS_MAX_IO + 1;
		return (expect_t){-1, "num_io"};
	case 35:
		c->io[1].id = 0;
		return (expect_t){-3, "io.id"};
	case 36:
		c->io[1].dir = 9;
		return (expect_t){-3, "io.dir"};
	case 37:
		c->io[1].width = 33;
		return (expect_t){-3, "io.width"};
	case 38:
		for (unsigned k = 0; k < VS_IO_NAME_MAX; k++)
			c->io[1].name[k] = 'x';
		return (expect_t){-3, "io.name"};
	case 39:
		c->io[3].id = c->io[0].id;
		return (expect_t){-3, "io.id"};
	case 40:
		c->drive_lag_ms[3] = 1000.5;
		return (expect_t){-1, "drive_lag_ms"};
	case 41:
		c->drive_lag_ms[0] = -0.5;
		return (expect_t){-1, "drive_lag_ms"};
	case 42:
		c->position_window_mm = 0.0;
		return (expect_t){-1, "position_window_mm"};
	case 43:
		c->position_window_ms = 1001;
		return (expect_t){-1, "position_window_ms"};
	case 44:
		c->settle_timeout_ms = 9;
		return (expect_t){-1, "settle_timeout_ms"};
	case 45:
		c->settle_timeout_ms = 60001;
		return (expect_t){-1, "settle_timeout_ms"};
	case 46:
		c->jerk_limit_t_mm_s3 = 1e7 + 1;
		return (expect_t){-1, "jerk_limit_t_mm_s3"};
	/* 1 kHz: 0.01 mm/s^3 is 43 raw units a tick^3, under the 64 held */
	case 47:
		c->jerk_limit_r_deg_s3 = 0.01;
		return (expect_t){-2, "jerk_limit_r_deg_s3"};
	case 48:
		c->jerk_limit_t_mm_s3 = 5000.0;
		c->jerk_default_t_mm_s3 = 5000.5;
		return (expect_t){-2, "jerk_default_t_mm_s3"};
	case 49:
		c->jerk_default_r_deg_s3 = -1.0;
		return (expect_t){-1, "jerk_default_r_deg_s3"};
	/* 10 kHz: 1000 mm/s^3 is 4.3 raw units a tick^3 */
	case 50:
		c->tick_hz = 10000;
		c->wheel_kp_per_s = 20.0;
		c->jerk_default_t_mm_s3 = 1000.0;
		return (expect_t){-2, "jerk_default_t_mm_s3"};
	default:
		return (expect_t){0, NULL};
	}
}

static void test_each_rule(void **state)
{
	(void)state;
	int i;
	for (i = 0;; i++) {
		vs_config_t c;
		vs_config_defaults(&c);
		expect_t e = mutate(i, &c);
		if (!e.field)
			break;
		const char *field = NULL;
		int rc_null = vs_config_check(&c, NULL), rc = vs_config_check(&c, &field);
		if (rc_null != e.rc || rc != e.rc || !field || strcmp(field, e.field) != 0)
			print_message("case %d (%s): got %d/%d %s\n", i, e.field, rc_null, rc,
				      field ? field : "(none)");
		assert_int_equal(rc_null, e.rc);
		assert_int_equal(rc, e.rc);
		assert_non_null(field);
		assert_string_equal(field, e.field);
	}
	assert_int_equal(i, 51);
}

static void test_range_ends_accepted(void **state)
{
	(void)state;
	vs_config_t c;
	vs_config_defaults(&c);
	c.encoder_counts_per_rev = 1;
	c.encoder_stuck_ms = 60000;
	c.drive_timeout_ms = 60000;
	c.jog_timeout_default_ms = 32767;
	c.battery_low_v = 1000.0;
	c.joystick_deadband = 0.5;
	c.cruise_blend_mm = 0.0;
	c.drive_lag_ms[0] = 0.0;
	c.drive_lag_ms[1] = 1000.0;
	c.position_window_mm = 100.0;
	c.position_window_ms = 0;
	c.settle_timeout_ms = 10;
	c.firmware_version = "0123456789012345678901234567890"; /* 31 characters */
	c.num_io = VS_MAX_IO;
	for (unsigned i = 0; i < VS_MAX_IO; i++) {
		c.io[i].id = i + 1;
		c.io[i].dir = VS_IO_IN;
		c.io[i].width = 1;
		c.io[i].name[0] = '\0';
	}
	const char *field = NULL;
	assert_int_equal(vs_config_check(&c, &field), 0);
	assert_null(field);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_each_rule),
	    cmocka_unit_test(test_range_ends_accepted),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
