/* XML configuration loader: the shipped files, and one exact error string
 * per kind of mistake (file, line, element.attribute, what). Paths are
 * relative to the repository root, where `make check` runs the tests. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "hal/posix/config_xml.h"

/* Every non-io field equal. */
static void assert_same_settings(const vs_config_t *a, const vs_config_t *b)
{
	assert_int_equal(a->kinematics, b->kinematics);
	assert_int_equal(a->tick_hz, b->tick_hz);
	assert_true(a->wheel_diameter_mm == b->wheel_diameter_mm);
	assert_true(a->track_width_mm == b->track_width_mm);
	assert_true(a->wheel_base_mm == b->wheel_base_mm);
	assert_int_equal(a->encoder_counts_per_rev, b->encoder_counts_per_rev);
	assert_true(a->vel_limit_t_mm_s == b->vel_limit_t_mm_s);
	assert_true(a->vel_limit_r_deg_s == b->vel_limit_r_deg_s);
	assert_true(a->acc_limit_t_mm_s2 == b->acc_limit_t_mm_s2);
	assert_true(a->acc_limit_r_deg_s2 == b->acc_limit_r_deg_s2);
	assert_true(a->vel_default_t_mm_s == b->vel_default_t_mm_s);
	assert_true(a->vel_default_r_deg_s == b->vel_default_r_deg_s);
	assert_true(a->acc_default_t_mm_s2 == b->acc_default_t_mm_s2);
	assert_true(a->acc_default_r_deg_s2 == b->acc_default_r_deg_s2);
	assert_int_equal(a->jog_timeout_default_ms, b->jog_timeout_default_ms);
	assert_true(a->wheel_kp_per_s == b->wheel_kp_per_s);
	for (int i = 0; i < VS_MAX_AXES; i++)
		assert_true(a->drive_lag_ms[i] == b->drive_lag_ms[i]);
	assert_true(a->following_error_mm == b->following_error_mm);
	assert_int_equal(a->encoder_stuck_ms, b->encoder_stuck_ms);
	assert_int_equal(a->drive_timeout_ms, b->drive_timeout_ms);
	assert_true(a->cruise_blend_mm == b->cruise_blend_mm);
	assert_true(a->caution_vel_t_mm_s == b->caution_vel_t_mm_s);
	assert_true(a->battery_low_v == b->battery_low_v);
	assert_true(a->battery_critical_v == b->battery_critical_v);
	assert_int_equal(a->has_contact_sensor, b->has_contact_sensor);
	assert_int_equal(a->has_obstacle_input, b->has_obstacle_input);
	assert_int_equal(a->has_estop, b->has_estop);
	assert_int_equal(a->has_joystick, b->has_joystick);
	assert_true(a->joystick_deadband == b->joystick_deadband);
	assert_ptr_equal(a->firmware_version, b->firmware_version);
}

static void assert_io(const vs_config_t *c, int i, uint32_t id, vs_io_dir_t dir, uint8_t width,
		      const char *name)
{
	assert_int_equal(c->io[i].id, id);
	assert_int_equal(c->io[i].dir, dir);
	assert_int_equal(c->io[i].width, width);
	assert_string_equal(c->io[i].name, name);
}

static void shipped_reference_equals_defaults(void **state)
{
	(void)state;
	vs_config_t got, def;
	hal_io_map_t map;
	char err[256] = "x";
	assert_int_equal(
	    config_load("config/vehicle.xml", "config/io.xml", &got, &map, err, sizeof(err)), 0);
	assert_string_equal(err, "");
	vs_config_defaults(&def);
	assert_same_settings(&got, &def);
	assert_int_equal(vs_config_axes(&got), 2);
}

static void shipped_vehicle_without_io_keeps_default_io(void **state)
{
	(void)state;
	vs_config_t got, def;
	hal_io_map_t map;
	char err[256];
	assert_int_equal(config_load("config/vehicle.xml", NULL, &got, &map, err, sizeof(err)), 0);
	vs_config_defaults(&def);
	assert_int_equal(got.num_io, def.num_io);
	for (int i = 0; i < def.num_io; i++)
		assert_io(&got, i, def.io[i].id, def.io[i].dir, def.io[i].width, def.io[i].name);
	assert_int_equal(map.n, 0);
}

static void shipped_io(void **state)
{
	(void)state;
	vs_config_t c;
	hal_io_map_t m;
	char err[256];
	assert_int_equal(
	    config_load("config/vehicle.xml", "config/io.xml", &c, &m, err, sizeof(err)), 0);
	assert_int_equal(c.num_io, 8);
	assert_io(&c, 0, 1, VS_IO_IN, 1, "dock");
	assert_io(&c, 1, 2, VS_IO_IN, 1, "charger");
	assert_io(&c, 2, 3, VS_IO_IN, 1, "lid_open");
	assert_io(&c, 3, 4, VS_IO_IN, 4, "selector");
	assert_io(&c, 4, 5, VS_IO_OUT, 1, "lamp");
	assert_io(&c, 5, 6, VS_IO_OUT, 1, "buzzer");
	assert_io(&c, 6, 7, VS_IO_OUT, 1, "beacon");
	assert_io(&c, 7, 8, VS_IO_OUT, 4, "indicator");

	assert_int_equal(m.n, 8);
	static const uint32_t lines[8] = {0, 1, 2, 4, 8, 9, 10, 12};
	for (int i = 0; i < 8; i++) {
		assert_int_equal(m.e[i].id, c.io[i].id);
		assert_int_equal(m.e[i].dir, c.io[i].dir);
		assert_int_equal(m.e[i].width, c.io[i].width);
		assert_true(m.e[i].mapped);
		assert_string_equal(m.e[i].chip, "gpiochip0");
		assert_int_equal(m.e[i].line, lines[i]);
		assert_int_equal(m.e[i].active_low, i == 2);
	}
}

static void shipped_omni(void **state)
{
	(void)state;
	vs_config_t c;
	char err[256];
	assert_int_equal(
	    config_load("config/vehicle-omni.xml", "config/io.xml", &c, NULL, err, sizeof(err)), 0);
	assert_int_equal(c.kinematics, VS_KIN_OMNI);
	assert_int_equal(vs_config_axes(&c), 4);
	assert_true(c.wheel_diameter_mm == 100.0);
	assert_true(c.track_width_mm == 450.0);
	assert_true(c.wheel_base_mm == 400.0);
	assert_int_equal(c.encoder_counts_per_rev, 8192);
	assert_true(c.vel_limit_t_mm_s == 800.0);
	assert_true(c.vel_default_r_deg_s == 60.0);
	assert_true(c.caution_vel_t_mm_s == 150.0);
	for (int i = 0; i < 4; i++)
		assert_true(c.drive_lag_ms[i] == 20.0);
	assert_int_equal(c.num_io, 8);
}

static void omitted_attributes_keep_defaults(void **state)
{
	(void)state;
	vs_config_t got, def;
	char err[256];
	assert_int_equal(config_load("tests/data/vehicle_partial.xml", "tests/data/io_empty.xml",
				     &got, NULL, err, sizeof(err)),
			 0);
	vs_config_defaults(&def);
	assert_true(got.vel_limit_t_mm_s == 1200.0);
	assert_false(got.has_joystick);
	got.vel_limit_t_mm_s = def.vel_limit_t_mm_s;
	got.has_joystick = def.has_joystick;
	assert_same_settings(&got, &def);
	assert_int_equal(got.num_io, 0);
}

/* Loads a vehicle file (with the shipped io.xml) or an io file (with the
 * shipped vehicle.xml) and expects exactly this error. */
static void expect_error(const char *vehicle, const char *io, const char *want)
{
	vs_config_t c;
	hal_io_map_t m;
	char err[256] = "";
	assert_int_equal(config_load(vehicle, io, &c, &m, err, sizeof(err)), -1);
	assert_string_equal(err, want);
}

#define VEH_ERR(file, msg) expect_error("tests/data/" file, "config/io.xml", "tests/data/" file msg)
#define IO_ERR(file, msg)                                                                          \
	expect_error("config/vehicle.xml", "tests/data/" file, "tests/data/" file msg)

static void error_missing_file(void **state)
{
	(void)state;
	VEH_ERR("no_such_file.xml", ": cannot open: No such file or directory");
	IO_ERR("no_such_io.xml", ": cannot open: No such file or directory");
}

static void error_malformed(void **state)
{
	(void)state;
	VEH_ERR("bad_malformed.xml", ":4: xml: mismatched tag");
	VEH_ERR("bad_doctype.xml", ":2: xml: DOCTYPE not allowed");
	VEH_ERR("bad_text.xml", ":3: vehicle: unexpected text");
}

static void error_unknown_element(void **state)
{
	(void)state;
	VEH_ERR("bad_unknown_element.xml", ":3: wheels: unknown element");
	VEH_ERR("bad_nested.xml", ":2: max: unknown element");
	VEH_ERR("bad_root.xml", ":1: robot: unknown element (expected <vehicle>)");
	VEH_ERR("bad_duplicate_section.xml", ":3: limits: duplicate element (first at line 2)");
	IO_ERR("io_unknown_element.xml", ":2: analog: unknown element");
	/* A vehicle file given as io.xml is the wrong root. */
	expect_error("config/vehicle.xml", "config/vehicle.xml",
		     "config/vehicle.xml:5: vehicle: unknown element (expected <io>)");
}

static void error_unknown_attribute(void **state)
{
	(void)state;
	VEH_ERR("bad_unknown_attr.xml", ":2: limits.speed_mm_s: unknown attribute");
	IO_ERR("io_unknown_attr.xml", ":2: input.pin: unknown attribute");
}

static void error_bad_number(void **state)
{
	(void)state;
	VEH_ERR("bad_number.xml", ":3: limits.vel_t_mm_s: not a number 'abc'");
	VEH_ERR("bad_trailing.xml", ":2: limits.vel_t_mm_s: not a number '1000mm'");
	VEH_ERR("bad_hex.xml", ":2: supervision.drive_timeout_ms: not a number '0x20'");
	VEH_ERR("bad_integer.xml", ":2: geometry.encoder_counts_per_rev: not an integer '1.5'");
	VEH_ERR("bad_bool.xml", ":2: devices.estop: not a boolean 'yes'");
	VEH_ERR("bad_kinematics.xml",
		":1: vehicle.kinematics: not differential|mecanum 'tricycle'");
}

static void error_not_finite(void **state)
{
	(void)state;
	VEH_ERR("bad_nan.xml", ":2: limits.vel_r_deg_s: not finite 'nan'");
	VEH_ERR("bad_inf.xml", ":2: battery.low_v: not finite '1e999'");
}

static void error_out_of_range(void **state)
{
	(void)state;
	VEH_ERR("bad_range.xml", ":1: vehicle.tick_hz: out of range '20000' (allowed 100..10000)");
	VEH_ERR("bad_lag.xml", ":2: drives.axis1_lag_ms: out of range '1500' (allowed 0..1000)");
	VEH_ERR("bad_zero_limit.xml",
		":2: limits.vel_t_mm_s: out of range '0' (allowed >0..10000)");
	IO_ERR("io_width.xml", ":2: input.width: out of range '33' (allowed 1..32)");
	IO_ERR("io_negative_id.xml", ":2: output.id: out of range '-4' (allowed 1..4294967295)");
	IO_ERR("io_name_long.xml",
	       ":2: input.name: longer than 23 characters 'a_name_that_is_far_too_long'");
	/* In range alone, but a default above its limit: vs_config_check. */
	VEH_ERR("bad_check.xml", ":3: defaults.vel_t_mm_s: rejected by the configuration check");
}

static void error_io_ids(void **state)
{
	(void)state;
	IO_ERR("io_duplicate_id.xml", ":5: output.id: duplicate id 2 (first at line 3)");
	IO_ERR("io_id_zero.xml", ":3: input.id: id 0 is reserved for the unit");
	IO_ERR("io_missing_id.xml", ":2: output.id: missing");
	IO_ERR("io_chip_no_line.xml", ":2: input.line: chip and line go together");
}

static void error_buffer_bounded(void **state)
{
	(void)state;
	vs_config_t c;
	char err[16];
	memset(err, 'z', sizeof(err));
	assert_int_equal(config_load("tests/data/bad_number.xml", NULL, &c, NULL, err, 12), -1);
	assert_string_equal(err, "tests/data/");
	assert_int_equal(err[12], 'z');
	/* No buffer at all is allowed too. */
	assert_int_equal(config_load("tests/data/bad_number.xml", NULL, &c, NULL, NULL, 0), -1);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(shipped_reference_equals_defaults),
	    cmocka_unit_test(shipped_vehicle_without_io_keeps_default_io),
	    cmocka_unit_test(shipped_io),
	    cmocka_unit_test(shipped_omni),
	    cmocka_unit_test(omitted_attributes_keep_defaults),
	    cmocka_unit_test(error_missing_file),
	    cmocka_unit_test(error_malformed),
	    cmocka_unit_test(error_unknown_element),
	    cmocka_unit_test(error_unknown_attribute),
	    cmocka_unit_test(error_bad_number),
	    cmocka_unit_test(error_not_finite),
	    cmocka_unit_test(error_out_of_range),
	    cmocka_unit_test(error_io_ids),
	    cmocka_unit_test(error_buffer_bounded),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
