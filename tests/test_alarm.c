/* Alarm list (firmware/alarm.c) and configuration defaults and checks
 * (firmware/config.c). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <math.h>
#include <string.h>

#include <cmocka.h>

#include "../firmware/alarm.h"
#include "../firmware/config.h"

static void test_type_from_code(void **state)
{
	(void)state;
	assert_int_equal(alarm_type_of(100), VS_ALARM_WARNING);
	assert_int_equal(alarm_type_of(120), VS_ALARM_WARNING);
	assert_int_equal(alarm_type_of(199), VS_ALARM_WARNING);
	assert_int_equal(alarm_type_of(200), VS_ALARM_FAULT);
	assert_int_equal(alarm_type_of(209), VS_ALARM_FAULT);
	assert_int_equal(alarm_type_of(299), VS_ALARM_FAULT);
	assert_int_equal(alarm_type_of(0), VS_ALARM_UNKNOWN);
	assert_int_equal(alarm_type_of(99), VS_ALARM_UNKNOWN);
	assert_int_equal(alarm_type_of(300), VS_ALARM_UNKNOWN);
	assert_int_equal(alarm_type_of(1203), VS_ALARM_UNKNOWN);
}

static void test_newest_first(void **state)
{
	(void)state;
	alarm_list_t l;
	alarm_clear(&l);
	assert_int_equal(l.n, 0);
	assert_null(alarm_newest(&l, VS_ALARM_WARNING));
	assert_false(alarm_any_fault(&l));

	alarm_raise(&l, 120, "moveTurn refused: unit not ready");
	alarm_raise(&l, 201, "drive 0 fault 0x2310");
	alarm_raise(&l, 111, "setVelocity refused: out of limits");
	assert_int_equal(l.n, 3);
	assert_int_equal(l.a[0].code, 111);
	assert_int_equal(l.a[0].type, VS_ALARM_WARNING);
	assert_string_equal(l.a[0].source, "setVelocity refused: out of limits");
	assert_int_equal(l.a[1].code, 201);
	assert_int_equal(l.a[1].type, VS_ALARM_FAULT);
	assert_int_equal(l.a[2].code, 120);
	assert_true(alarm_any_fault(&l));
	assert_int_equal(alarm_newest(&l, VS_ALARM_FAULT)->code, 201);
	assert_int_equal(alarm_newest(&l, VS_ALARM_WARNING)->code, 111);
	assert_null(alarm_newest(&l, VS_ALARM_UNKNOWN));

	alarm_clear(&l);
	assert_int_equal(l.n, 0);
	assert_false(alarm_any_fault(&l));
}

static void test_reraise_moves_to_front(void **state)
{
	(void)state;
	alarm_list_t l;
	alarm_clear(&l);
	alarm_raise(&l, 120, "moveTurn refused: unit not ready");
	alarm_raise(&l, 121, "moveJog refused: servo off");
	alarm_raise(&l, 123, "moveForward refused: fault active");
	alarm_raise(&l, 120, "moveForward refused: unit not ready");
	assert_int_equal(l.n, 3);
	assert_int_equal(l.a[0].code, 120);
	assert_string_equal(l.a[0].source, "moveForward refused: unit not ready");
	assert_int_equal(l.a[1].code, 123);
	assert_int_equal(l.a[2].code, 121);
	assert_string_equal(l.a[2].source, "moveJog refused: servo off");
}

static void test_full_drops_oldest(void **state)
{
	(void)state;
	alarm_list_t l;
	alarm_clear(&l);
	for (uint32_t i = 0; i < VS_ALARM_LIST_MAX; i++)
		alarm_raise(&l, 100 + i, "w");
	assert_int_equal(l.n, VS_ALARM_LIST_MAX);
	alarm_raise(&l, 250, "newest");
	assert_int_equal(l.n, VS_ALARM_LIST_MAX);
	assert_int_equal(l.a[0].code, 250);
	assert_int_equal(l.a[1].code, 100 + VS_ALARM_LIST_MAX - 1);
	/* 100 was the oldest and is gone; 101 is now last. */
	assert_int_equal(l.a[VS_ALARM_LIST_MAX - 1].code, 101);
	for (unsigned i = 0; i < l.n; i++)
		assert_int_not_equal(l.a[i].code, 100);

	/* Re-raising an active code when full keeps every other entry. */
	alarm_raise(&l, 101, "again");
	assert_int_equal(l.n, VS_ALARM_LIST_MAX);
	assert_int_equal(l.a[0].code, 101);
	assert_int_equal(l.a[1].code, 250);
	assert_int_equal(l.a[VS_ALARM_LIST_MAX - 1].code, 102);
}

static void test_source_truncated(void **state)
{
	(void)state;
	alarm_list_t l;
	char longtext[200];
	memset(longtext, 'x', sizeof longtext - 1);
	longtext[sizeof longtext - 1] = '\0';
	alarm_clear(&l);
	alarm_raise(&l, 150, longtext);
	assert_int_equal(strlen(l.a[0].source), VS_ALARM_SOURCE_MAX - 1);
	alarm_raise(&l, 151, NULL);
	assert_string_equal(l.a[0].source, "");
	alarm_raise(&l, 1203, "other");
	assert_int_equal(l.a[0].type, VS_ALARM_UNKNOWN);
}

/* ---- configuration ---------------------------------------------------- */

static void test_defaults(void **state)
{
	(void)state;
	vs_config_t c;
	memset(&c, 0xA5, sizeof c);
	vs_config_defaults(&c);
	const char *field = "untouched";
	assert_int_equal(vs_config_check(&c, &field), 0);
	assert_string_equal(field, "untouched");
	assert_int_equal(c.kinematics, VS_KIN_DIFF);
	assert_int_equal(c.tick_hz, 1000);
	assert_true(c.wheel_diameter_mm == 150.0);
	assert_true(c.track_width_mm == 400.0);
	assert_int_equal(c.encoder_counts_per_rev, 16384);
	assert_true(c.vel_limit_t_mm_s == 1000.0);
	assert_true(c.vel_limit_r_deg_s == 180.0);
	assert_true(c.acc_limit_t_mm_s2 == 1000.0);
	assert_true(c.acc_limit_r_deg_s2 == 360.0);
	assert_true(c.vel_default_t_mm_s == 500.0);
	assert_true(c.vel_default_r_deg_s == 90.0);
	assert_true(c.acc_default_t_mm_s2 == 500.0);
	assert_true(c.acc_default_r_deg_s2 == 180.0);
	assert_int_equal(c.jog_timeout_default_ms, 500);
	assert_true(c.wheel_kp_per_s == 20.0);
	assert_true(c.following_error_mm == 50.0);
	assert_int_equal(c.encoder_stuck_ms, 300);
	assert_int_equal(c.drive_timeout_ms, 50);
	assert_true(c.cruise_blend_mm == 200.0);
	assert_true(c.battery_low_v == 22.0);
	assert_true(c.battery_critical_v == 20.0);
	assert_true(c.has_contact_sensor && c.has_obstacle_input && c.has_estop && c.has_joystick);
	assert_true(c.joystick_deadband == 0.05);
	assert_null(c.firmware_version);
	assert_int_equal(c.num_io, 4);
	for (unsigned i = 0; i < c.num_io; i++)
		assert_int_equal(c.io[i].id, i + 1);
	assert_int_equal(c.io[0].dir, VS_IO_IN);
	assert_int_equal(c.io[2].dir, VS_IO_OUT);
	assert_int_equal(vs_config_axes(&c), 2);
}

typedef void (*mutate_fn)(vs_config_t *c);

static void expect_bad(mutate_fn fn, int rc, const char *name)
{
	vs_config_t c;
	vs_config_defaults(&c);
	fn(&c);
	const char *field = NULL;
	assert_int_equal(vs_config_check(&c, &field), rc);
	assert_non_null(field);
	assert_string_equal(field, name);
}

static void m_kin(vs_config_t *c)
{
	c->kinematics = (vs_kinematics_t)2;
}
static void m_tick_lo(vs_config_t *c)
{
	c->tick_hz = 99;
}
static void m_tick_hi(vs_config_t *c)
{
	c->tick_hz = 10001;
}
static void m_wheel(vs_config_t *c)
{
	c->wheel_diameter_mm = 0.0;
}
static void m_wheel_nan(vs_config_t *c)
{
	c->wheel_diameter_mm = NAN;
}
static void m_track_inf(vs_config_t *c)
{
	c->track_width_mm = INFINITY;
}
static void m_base_omni(vs_config_t *c)
{
	c->kinematics = VS_KIN_OMNI;
	c->wheel_base_mm = 0.0;
}
static void m_cpr(vs_config_t *c)
{
	c->encoder_counts_per_rev = 0;
}
static void m_vlim(vs_config_t *c)
{
	c->vel_limit_t_mm_s = 0.0;
}
static void m_vlim_r(vs_config_t *c)
{
	c->vel_limit_r_deg_s = -1.0;
}
static void m_alim(vs_config_t *c)
{
	c->acc_limit_t_mm_s2 = NAN;
}
static void m_alim_r(vs_config_t *c)
{
	c->acc_limit_r_deg_s2 = 1e9;
}
static void m_vdef(vs_config_t *c)
{
	c->vel_default_t_mm_s = 1000.5;
}
static void m_vdef_r(vs_config_t *c)
{
	c->vel_default_r_deg_s = 0.0;
}
static void m_adef(vs_config_t *c)
{
	c->acc_default_t_mm_s2 = 2000.0;
}
static void m_adef_r(vs_config_t *c)
{
	c->acc_default_r_deg_s2 = 361.0;
}
static void m_jog(vs_config_t *c)
{
	c->jog_timeout_default_ms = 0;
}
static void m_jog_hi(vs_config_t *c)
{
	c->jog_timeout_default_ms = 40000;
}
static void m_kp(vs_config_t *c)
{
	c->wheel_kp_per_s = 0.0;
}
static void m_kp_tick(vs_config_t *c)
{
	c->tick_hz = 100;
	c->wheel_kp_per_s = 26.0;
}
static void m_ferr(vs_config_t *c)
{
	c->following_error_mm = 0.0;
}
static void m_stuck(vs_config_t *c)
{
	c->encoder_stuck_ms = 0;
}
static void m_dto(vs_config_t *c)
{
	c->drive_timeout_ms = 0;
}
static void m_blend(vs_config_t *c)
{
	c->cruise_blend_mm = -1.0;
}
static void m_caution(vs_config_t *c)
{
	c->caution_vel_t_mm_s = 1001.0;
}
static void m_bat_crit(vs_config_t *c)
{
	c->battery_critical_v = 0.0;
}
static void m_bat_order(vs_config_t *c)
{
	c->battery_low_v = 20.0;
}
static void m_deadband(vs_config_t *c)
{
	c->joystick_deadband = 0.6;
}
static void m_fwver(vs_config_t *c)
{
	c->firmware_version = "";
}
static void m_cpr_fast(vs_config_t *c)
{
	c->encoder_counts_per_rev = 1u << 24;
}
static void m_num_io(vs_config_t *c)
{
	c->num_io = VS_MAX_IO + 1;
}
static void m_io_zero(vs_config_t *c)
{
	c->io[1].id = 0;
}
static void m_io_dup(vs_config_t *c)
{
	c->io[3].id = 2;
}
static void m_io_width0(vs_config_t *c)
{
	c->io[0].width = 0;
}
static void m_io_width33(vs_config_t *c)
{
	c->io[2].width = 33;
}
static void m_io_dir(vs_config_t *c)
{
	c->io[2].dir = 7;
}
static void m_io_name(vs_config_t *c)
{
	memset(c->io[0].name, 'n', VS_IO_NAME_MAX);
}

static void test_check_rejects(void **state)
{
	(void)state;
	expect_bad(m_kin, -1, "kinematics");
	expect_bad(m_tick_lo, -1, "tick_hz");
	expect_bad(m_tick_hi, -1, "tick_hz");
	expect_bad(m_wheel, -1, "wheel_diameter_mm");
	expect_bad(m_wheel_nan, -1, "wheel_diameter_mm");
	expect_bad(m_track_inf, -1, "track_width_mm");
	expect_bad(m_base_omni, -1, "wheel_base_mm");
	expect_bad(m_cpr, -1, "encoder_counts_per_rev");
	expect_bad(m_vlim, -1, "vel_limit_t_mm_s");
	expect_bad(m_vlim_r, -1, "vel_limit_r_deg_s");
	expect_bad(m_alim, -1, "acc_limit_t_mm_s2");
	expect_bad(m_alim_r, -1, "acc_limit_r_deg_s2");
	expect_bad(m_vdef, -2, "vel_default_t_mm_s");
	expect_bad(m_vdef_r, -2, "vel_default_r_deg_s");
	expect_bad(m_adef, -2, "acc_default_t_mm_s2");
	expect_bad(m_adef_r, -2, "acc_default_r_deg_s2");
	expect_bad(m_jog, -1, "jog_timeout_default_ms");
	expect_bad(m_jog_hi, -1, "jog_timeout_default_ms");
	expect_bad(m_kp, -1, "wheel_kp_per_s");
	expect_bad(m_kp_tick, -2, "wheel_kp_per_s");
	expect_bad(m_ferr, -1, "following_error_mm");
	expect_bad(m_stuck, -1, "encoder_stuck_ms");
	expect_bad(m_dto, -1, "drive_timeout_ms");
	expect_bad(m_blend, -1, "cruise_blend_mm");
	expect_bad(m_caution, -2, "caution_vel_t_mm_s");
	expect_bad(m_bat_crit, -1, "battery_critical_v");
	expect_bad(m_bat_order, -2, "battery_low_v");
	expect_bad(m_deadband, -1, "joystick_deadband");
	expect_bad(m_fwver, -1, "firmware_version");
	expect_bad(m_cpr_fast, -2, "encoder_counts_per_rev");
	expect_bad(m_num_io, -1, "num_io");
	expect_bad(m_io_zero, -3, "io.id");
	expect_bad(m_io_dup, -3, "io.id");
	expect_bad(m_io_width0, -3, "io.width");
	expect_bad(m_io_width33, -3, "io.width");
	expect_bad(m_io_dir, -3, "io.dir");
	expect_bad(m_io_name, -3, "io.name");
}

static void test_check_accepts_edges(void **state)
{
	(void)state;
	vs_config_t c;
	vs_config_defaults(&c);
	/* Defaults equal to the limits are allowed. */
	c.vel_default_t_mm_s = c.vel_limit_t_mm_s;
	c.acc_default_r_deg_s2 = c.acc_limit_r_deg_s2;
	c.tick_hz = 100;
	c.wheel_kp_per_s = 25.0;
	c.io[0].width = 32;
	c.firmware_version = "Ver.2.3.4";
	c.kinematics = VS_KIN_OMNI;
	c.wheel_base_mm = 350.0;
	c.caution_vel_t_mm_s = 0.0;
	assert_int_equal(vs_config_check(&c, NULL), 0);
	assert_int_equal(vs_config_axes(&c), 4);
	c.tick_hz = 10000;
	assert_int_equal(vs_config_check(&c, NULL), 0);
	/* NULL field pointer is allowed on failure as well. */
	c.tick_hz = 0;
	assert_int_equal(vs_config_check(&c, NULL), -1);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_type_from_code),
	    cmocka_unit_test(test_newest_first),
	    cmocka_unit_test(test_reraise_moves_to_front),
	    cmocka_unit_test(test_full_drops_oldest),
	    cmocka_unit_test(test_source_truncated),
	    cmocka_unit_test(test_defaults),
	    cmocka_unit_test(test_check_rejects),
	    cmocka_unit_test(test_check_accepts_edges),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
