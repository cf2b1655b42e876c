/* XML configuration loader: the shipped files, and one exact error string
 * per kind of mistake (file, line, element.attribute, what). Paths are
 * relative to the repository root, where `make check` runs the tests. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

static void jerk_attributes(void **state)
{
	(void)state;
	vs_config_t got, def;
	char err[256];
	assert_int_equal(config_load("tests/data/vehicle_jerk.xml", "tests/data/io_empty.xml", &got,
				     NULL, err, sizeof(err)),
			 0);
	vs_config_defaults(&def);
	assert_true(def.jerk_limit_t_mm_s3 == 0.0 && def.jerk_default_r_deg_s3 == 0.0);
	assert_true(got.jerk_limit_t_mm_s3 == 5000.0);
	assert_true(got.jerk_limit_r_deg_s3 == 3000.0);
	assert_true(got.jerk_default_t_mm_s3 == 2000.0);
	assert_true(got.jerk_default_r_deg_s3 == 1000.0);
}

/* The shipped jerk example: the reference base with jerk limits. */
static void shipped_jerk(void **state)
{
	(void)state;
	vs_config_t got, def;
	char err[256];
	assert_int_equal(
	    config_load("config/vehicle-jerk.xml", "config/io.xml", &got, NULL, err, sizeof(err)),
	    0);
	vs_config_defaults(&def);
	assert_true(got.jerk_limit_t_mm_s3 == 5000.0 && got.jerk_limit_r_deg_s3 == 3000.0);
	assert_true(got.jerk_default_t_mm_s3 == 2000.0 && got.jerk_default_r_deg_s3 == 1000.0);
	got.jerk_limit_t_mm_s3 = got.jerk_limit_r_deg_s3 = 0.0;
	got.jerk_default_t_mm_s3 = got.jerk_default_r_deg_s3 = 0.0;
	assert_same_settings(&got, &def);
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

/* ---- a section of another reader (config_section_t) ----------------------- */

typedef struct {
	char log[512];
	bool fail_finish;
} sec_log_t;

static int log_start(void *ctx, config_reader_t *r, const char *elem, const char **atts, int depth,
		     unsigned long line)
{
	sec_log_t *l = ctx;
	size_t n = strlen(l->log);
	snprintf(l->log + n, sizeof(l->log) - n, "<%s %d %lu>", elem, depth, line);
	for (; atts[0]; atts += 2) {
		uint32_t u;
		double d;
		bool b;
		if (!strcmp(atts[0], "u") &&
		    config_attr_uint(r, line, elem, atts[0], atts[1], 0, 5, &u))
			return -1;
		if (!strcmp(atts[0], "d") && config_attr_number(r, line, elem, atts[0], atts[1],
								0.0, true, 1.0, "(0, 1]", &d))
			return -1;
		if (!strcmp(atts[0], "b") && config_attr_bool(r, line, elem, atts[0], atts[1], &b))
			return -1;
		if (!strcmp(atts[0], "x"))
			return config_fail(r, line, "%s.x: said no '%s'", elem, atts[1]);
	}
	return 0;
}

static void log_end(void *ctx, const char *elem, int depth)
{
	sec_log_t *l = ctx;
	size_t n = strlen(l->log);
	snprintf(l->log + n, sizeof(l->log) - n, "</%s %d>", elem, depth);
}

static int log_finish(void *ctx, config_reader_t *r)
{
	sec_log_t *l = ctx;
	return l->fail_finish ? config_fail(r, 2, "extra: finish said no") : 0;
}

static char sec_path[64];
static void write_text(const char *text);

/* The vehicle file from text at sec_path; loaded with the <extra> section
 * (vehicle: judged with it, NULL: the section alone). Returns the result. */
static int load_extra(const char *text, sec_log_t *l, vs_config_t *c, char *err, size_t cap)
{
	write_text(text);
	const config_section_t sec = {
	    .name = "extra", .start = log_start, .end = log_end, .finish = log_finish, .ctx = l};
	l->log[0] = '\0';
	return config_load_sections(sec_path, NULL, c, NULL, &sec, 1, err, cap);
}

static void expect_extra(const char *text, vs_config_t *c, bool fail_finish, int line,
			 const char *msg)
{
	sec_log_t l = {.fail_finish = fail_finish};
	char err[256] = "", want[256];
	assert_int_equal(load_extra(text, &l, c, err, sizeof(err)), -1);
	snprintf(want, sizeof(want), "%s:%d: %s", sec_path, line, msg);
	assert_string_equal(err, want);
}

static int sec_setup(void **state)
{
	(void)state;
	snprintf(sec_path, sizeof(sec_path), "/tmp/vs_config_sections_XXXXXX");
	int fd = mkstemp(sec_path);
	assert_true(fd >= 0);
	close(fd);
	return 0;
}

static int sec_teardown(void **state)
{
	(void)state;
	unlink(sec_path);
	return 0;
}

static void sections_one_pass(void **state)
{
	(void)state;
	vs_config_t c;
	sec_log_t l = {.fail_finish = false};
	char err[256] = "x";
	static const char ok[] = "<vehicle tick_hz=\"500\">\n"
				 "  <extra u=\"3\" d=\"0.5\">\n"
				 "    <item b=\"true\"><sub/></item>\n"
				 "    <item/>\n"
				 "  </extra>\n"
				 "  <limits vel_t_mm_s=\"900\"/>\n"
				 "</vehicle>\n";
	assert_int_equal(load_extra(ok, &l, &c, err, sizeof(err)), 0);
	assert_string_equal(err, "");
	assert_string_equal(l.log, "<extra 0 2><item 1 3><sub 2 3></sub 2></item 1><item 1 4>"
				   "</item 1></extra 0>");
	assert_int_equal(c.tick_hz, 500);
	assert_true(c.vel_limit_t_mm_s == 900.0);
	/* the section alone: the same elements */
	assert_int_equal(load_extra(ok, &l, NULL, err, sizeof(err)), 0);
	assert_string_equal(l.log, "<extra 0 2><item 1 3><sub 2 3></sub 2></item 1><item 1 4>"
				   "</item 1></extra 0>");
	/* the same file without the handler: an unknown element */
	assert_int_equal(config_load(sec_path, NULL, &c, NULL, err, sizeof(err)), -1);
	char want[256];
	snprintf(want, sizeof(want), "%s:2: extra: unknown element", sec_path);
	assert_string_equal(err, want);
}

static void sections_errors(void **state)
{
	(void)state;
	vs_config_t c;
	/* the helpers' messages, always with the line */
	expect_extra("<vehicle>\n<extra u=\"6\"/>\n</vehicle>\n", &c, false, 2,
		     "extra.u: out of range 0..5 '6'");
	expect_extra("<vehicle>\n<extra>\n<i u=\"+1\"/></extra>\n</vehicle>\n", &c, false, 3,
		     "i.u: not a number '+1'");
	expect_extra("<vehicle>\n<extra d=\"0\"/>\n</vehicle>\n", &c, false, 2,
		     "extra.d: out of range (0, 1] '0'");
	expect_extra("<vehicle>\n<extra d=\"inf\"/>\n</vehicle>\n", &c, false, 2,
		     "extra.d: not finite 'inf'");
	expect_extra("<vehicle>\n<extra b=\"yes\"/>\n</vehicle>\n", &c, false, 2,
		     "extra.b: not a boolean 'yes'");
	expect_extra("<vehicle>\n<extra/>\n</vehicle>\n", &c, true, 2, "extra: finish said no");
	/* the core's error first, wherever it is in the file */
	static const char both[] = "<vehicle>\n<extra x=\"1\"/>\n<limits vel_t_mm_s=\"abc\"/>\n"
				   "</vehicle>\n";
	expect_extra(both, &c, false, 3, "limits.vel_t_mm_s: not a number 'abc'");
	expect_extra(both, NULL, false, 2, "extra.x: said no '1'");
	/* ... and vs_config_check's */
	expect_extra("<vehicle>\n<extra x=\"1\"/>\n<defaults vel_t_mm_s=\"1500\"/>\n</vehicle>\n",
		     &c, false, 3, "defaults.vel_t_mm_s: rejected by the configuration check");
	/* the first of two section errors; a section appears once */
	expect_extra("<vehicle>\n<extra x=\"1\"/>\n<extra x=\"2\"/>\n</vehicle>\n", NULL, false, 2,
		     "extra.x: said no '1'");
	expect_extra("<vehicle>\n<extra/>\n<extra/>\n</vehicle>\n", &c, false, 3,
		     "extra: duplicate element (first at line 2)");
	/* not well-formed: the section's error too when it is read alone */
	expect_extra("<vehicle>\n<extra>\n</vehicle>\n", NULL, false, 3, "xml: mismatched tag");
	/* a file that cannot be read is an error for the section alone too */
	sec_log_t l;
	char err[256];
	assert_int_equal(config_load_sections(
			     "tests/data/no_such_file.xml", NULL, NULL, NULL,
			     &(config_section_t){.name = "extra", .start = log_start, .ctx = &l}, 1,
			     err, sizeof(err)),
			 -1);
	assert_string_equal(err, "tests/data/no_such_file.xml: cannot open: No such file or "
				 "directory");
}

/* The vehicle file text at sec_path. */
static void write_text(const char *text)
{
	FILE *f = fopen(sec_path, "w");
	assert_non_null(f);
	fputs(text, f);
	fclose(f);
}

/* One table: every row's attribute in the file reaches its member (each
 * element of an array by its index), or vs_config_check's complaint about
 * the value names that very attribute. */
static void every_row_has_its_attribute(void **state)
{
	(void)state;
	static const struct {
		const char *elem, *attr;
	} xml[] = {
#define XML_COLUMNS(m, n, t, d, lo, hi, ex, wh, el, at) {el, at},
	    VS_CONFIG_FIELDS(XML_COLUMNS)
#undef XML_COLUMNS
	};
	vs_config_t def, c;
	vs_config_defaults(&def);
	for (unsigned i = 0; i < VS_CONFIG_NFIELDS; i++) {
		const vs_config_field_t *f = &vs_config_fields[i];
		for (unsigned k = 0; k < f->n; k++) {
			double d = vs_config_get(&def, f, k), v = d > 0 ? d / 2 : d + 10;
			char attr[64], val[40], text[512], err[256], want[512];
			const char *hash = strchr(xml[i].attr, '#');
			if (hash)
				snprintf(attr, sizeof(attr), "%.*s%u%s", (int)(hash - xml[i].attr),
					 xml[i].attr, k, hash + 1);
			else
				snprintf(attr, sizeof(attr), "%s", xml[i].attr);
			if (f->type == VS_CFG_BOOL || f->type == VS_CFG_KIN)
				v = d == 0.0;
			if (f->type == VS_CFG_BOOL)
				snprintf(val, sizeof(val), "%s", v ? "true" : "false");
			else if (f->type == VS_CFG_KIN)
				snprintf(val, sizeof(val), "%s", v ? "mecanum" : "differential");
			else
				snprintf(val, sizeof(val), "%.17g",
					 f->type == VS_CFG_DOUBLE ? v : (v = (double)(long)v));
			/* a wheel base a mecanum base accepts, unless that is the row */
			const char *base = strcmp(xml[i].elem, "geometry")
					       ? "<geometry wheel_base_mm=\"100\"/>"
					       : "";
			if (!strcmp(xml[i].elem, "vehicle"))
				snprintf(text, sizeof(text), "<vehicle %s=\"%s\">%s</vehicle>\n",
					 attr, val, base);
			else
				snprintf(text, sizeof(text),
					 "<vehicle><%s %s=\"%s\"/>%s</vehicle>\n", xml[i].elem,
					 attr, val, base);
			write_text(text);
			if (config_load(sec_path, NULL, &c, NULL, err, sizeof(err)) == 0) {
				assert_true(vs_config_get(&c, f, k) == v);
				continue;
			}
			snprintf(want, sizeof(want),
				 "%s:1: %s.%s: rejected by the configuration check", sec_path,
				 xml[i].elem, attr);
			assert_string_equal(err, want);
		}
	}
	/* an array's index: one digit below its length */
	static const char *const bad[] = {"axis4_lag_ms", "axis_lag_ms", "axis01_lag_ms",
					  "axisx_lag_ms"};
	for (unsigned i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		char text[256], err[256], want[512];
		snprintf(text, sizeof(text), "<vehicle>\n<drives %s=\"5\"/>\n</vehicle>\n", bad[i]);
		write_text(text);
		assert_int_equal(config_load(sec_path, NULL, &c, NULL, err, sizeof(err)), -1);
		snprintf(want, sizeof(want), "%s:2: drives.%s: unknown attribute", sec_path,
			 bad[i]);
		assert_string_equal(err, want);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(shipped_reference_equals_defaults),
	    cmocka_unit_test(shipped_vehicle_without_io_keeps_default_io),
	    cmocka_unit_test(shipped_io),
	    cmocka_unit_test(shipped_omni),
	    cmocka_unit_test(omitted_attributes_keep_defaults),
	    cmocka_unit_test(jerk_attributes),
	    cmocka_unit_test(shipped_jerk),
	    cmocka_unit_test(error_missing_file),
	    cmocka_unit_test(error_malformed),
	    cmocka_unit_test(error_unknown_element),
	    cmocka_unit_test(error_unknown_attribute),
	    cmocka_unit_test(error_bad_number),
	    cmocka_unit_test(error_not_finite),
	    cmocka_unit_test(error_out_of_range),
	    cmocka_unit_test(error_io_ids),
	    cmocka_unit_test(error_buffer_bounded),
	    cmocka_unit_test_setup_teardown(sections_one_pass, sec_setup, sec_teardown),
	    cmocka_unit_test_setup_teardown(sections_errors, sec_setup, sec_teardown),
	    cmocka_unit_test_setup_teardown(every_row_has_its_attribute, sec_setup, sec_teardown),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
