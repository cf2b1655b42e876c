/* The configuration changed at run time and saved: $config's set, diff,
 * save, defaults, reload and store on the real firmware (fake HAL), kept
 * in a file store (hal/posix/filestore.c) and read back at the next start;
 * unreadable stores at start. Every reply is written out in full. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "../firmware/config_keep.h"
#include "../firmware/config_save.h"
#include "../firmware/vehicle.h"
#include "../hal/posix/filestore.h"
#include "../proto/console.h"
#include "fake_hal.h"

static fake_hal_t fh;
static vehicle_t veh;
static console_t con;
static cfgkeep_t keep;
static filestore_t fs;
static char rep[CONSOLE_REPLY_MAX];
static char path[256];

/* A start: the base (fake_hal_config) with what the store at path holds
 * (NULL: no store). */
static void boot(const char *store_path)
{
	vs_config_t base, start;
	const char *bad = NULL;
	char err[256];
	fake_hal_config(&base);
	if (store_path)
		assert_int_equal(filestore_open(&fs, store_path, err, sizeof err), 0);
	cfgkeep_load(&keep, &base, store_path ? &fs.hs : NULL, &start);
	fake_hal_init(&fh, start.tick_hz);
	vs_hal_t hal = fake_hal_bind(&fh);
	memset(&veh, 0, sizeof veh);
	assert_int_equal(vehicle_init(&veh, &start, &hal, &bad), 0);
	cfgkeep_attach(&keep, &veh);
	console_init(&con, &veh, NULL, NULL);
	console_set_keep(&con, &keep);
}

static const char *ex(const char *line)
{
	if (!console_exec(&con, line, rep, sizeof rep))
		return "(none)";
	return rep;
}

#define EXPECT(line, want) assert_string_equal(ex(line), want)

static int setup(void **state)
{
	(void)state;
	snprintf(path, sizeof path, "/tmp/vs-cfgkeep-%ld.store", (long)getpid());
	unlink(path);
	return 0;
}

static int teardown(void **state)
{
	(void)state;
	unlink(path);
	return 0;
}

/* A unit started on this configuration, for what a change must derive. */
static void reference(vehicle_t *r, void (*edit)(vs_config_t *))
{
	vs_config_t c;
	fake_hal_t f;
	fake_hal_config(&c);
	edit(&c);
	fake_hal_init(&f, c.tick_hz);
	vs_hal_t hal = fake_hal_bind(&f);
	assert_int_equal(vehicle_init(r, &c, &hal, NULL), 0);
}

static void wheel_160(vs_config_t *c)
{
	c->wheel_diameter_mm = 160.0;
}

/* Set, see, save, start again: the saved value is in force, a RESTART
 * field's too. */
static void test_set_save_restart(void **state)
{
	static vehicle_t ref;
	(void)state;
	boot(path);
	EXPECT("$config store", "ok store empty table 0x916B11C3");
	EXPECT("$config diff", "ok unsaved 0 changed 0 pending 0");
	EXPECT("$config wheel_diameter_mm 160", "ok wheel_diameter_mm 160.000");
	/* derived again as at init: the wheel loop's scale, the supervision */
	reference(&ref, wheel_160);
	assert_true(veh.kin.p.counts_per_mm == ref.kin.p.counts_per_mm);
	assert_true(veh.following_err_max_q32 == ref.following_err_max_q32);
	assert_true(veh.window_q32 == ref.window_q32);
	EXPECT("$config tick_hz 500", "ok tick_hz 1000 pending 500");
	EXPECT("$config tick_hz", "ok tick_hz 1000 pending 500");
	EXPECT("$config diff", "ok unsaved 2 tick_hz wheel_diameter_mm changed 2 tick_hz "
			       "wheel_diameter_mm pending 1 tick_hz");
	EXPECT("$config save", "ok saved 2 tick_hz wheel_diameter_mm");
	EXPECT("$config diff",
	       "ok unsaved 0 changed 2 tick_hz wheel_diameter_mm pending 1 tick_hz");
	assert_int_equal(fs.writes, 5); /* two pages erased, payload, header, commit */
	boot(path);
	EXPECT("$config store",
	       "ok store loaded seq 1 schema 0x916B11C3 applied 2 dropped 0 table 0x916B11C3");
	EXPECT("$config tick_hz", "ok tick_hz 500");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 160.000");
	EXPECT("$config diff", "ok unsaved 0 changed 2 tick_hz wheel_diameter_mm pending 0");
	EXPECT("getActiveAlarm 1", "ok true 0 0");
	/* defaults: the base; the tick rate waits for a restart */
	EXPECT("$config defaults", "ok defaults pending 1");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000");
	EXPECT("$config tick_hz", "ok tick_hz 500 pending 1000");
	EXPECT("$config diff",
	       "ok unsaved 2 tick_hz wheel_diameter_mm changed 0 pending 1 tick_hz");
	EXPECT("$config reload", "ok reload pending 0");
	EXPECT("$config diff", "ok unsaved 0 changed 2 tick_hz wheel_diameter_mm pending 0");
	/* an empty overlay saved: the next start runs on the base */
	EXPECT("$config defaults", "ok defaults pending 1");
	EXPECT("$config save", "ok saved 0");
	boot(path);
	EXPECT("$config store",
	       "ok store loaded seq 2 schema 0x916B11C3 applied 0 dropped 0 table 0x916B11C3");
	EXPECT("$config tick_hz", "ok tick_hz 1000");
}

/* When a field may change, and every refusal's reply; a refused change
 * changes nothing. */
static void test_when_and_refusals(void **state)
{
	(void)state;
	boot(path);
	EXPECT("setPower on", "ok true");
	EXPECT("setServo on", "ok true");
	EXPECT("$config wheel_diameter_mm 170",
	       "error 8 $config wheel_diameter_mm: wheel_diameter_mm changes only with the servo "
	       "off and no motion queued");
	EXPECT("$config link_timeout_ms 300", "ok link_timeout_ms 300");
	assert_int_equal(vehicle_link_timeout(&veh), 300);
	EXPECT("$config battery_low_v 23", "ok battery_low_v 23.000");
	assert_int_equal(veh.battery_low_mv, 23000);
	EXPECT("$config jerk_default_t_mm_s3 2000", "ok jerk_default_t_mm_s3 2000.000");
	EXPECT("$jerk", "ok jerk 2000.000 0.000 limit 0.000 0.000");
	/* $watchdog's change is the wanted one too */
	EXPECT("$watchdog 400", "ok watchdog 400");
	EXPECT("$config link_timeout_ms", "ok link_timeout_ms 400");
	EXPECT("$config diff", "ok unsaved 3 jerk_default_t_mm_s3 link_timeout_ms battery_low_v "
			       "changed 3 jerk_default_t_mm_s3 link_timeout_ms battery_low_v "
			       "pending 0");
	/* only fields of class ANY differ: the defaults come back at once */
	EXPECT("$config defaults", "ok defaults pending 0");
	EXPECT("$config link_timeout_ms", "ok link_timeout_ms 1000");
	EXPECT("$config cruise_blend_mm 100",
	       "error 8 $config cruise_blend_mm: cruise_blend_mm "
	       "changes only with the servo off and no motion queued");
	EXPECT("setServo off", "ok true");
	EXPECT("$config cruise_blend_mm 100", "ok cruise_blend_mm 100.000");
	EXPECT("$config defaults", "ok defaults pending 0");
	EXPECT("$config vel_limit_t_mm_s 100", "error 8 $config vel_limit_t_mm_s: "
					       "vel_default_t_mm_s: rejected by the configuration "
					       "check");
	EXPECT("$config wheel_diameter_mm 5",
	       "error 8 $config wheel_diameter_mm: wheel_diameter_mm: rejected by the "
	       "configuration check");
	/* the check with the running tick rate as well: kp over tick_hz / 4 */
	EXPECT("$config tick_hz 10000", "ok tick_hz 1000 pending 10000");
	EXPECT("$config wheel_kp_per_s 400", "error 8 $config wheel_kp_per_s: wheel_kp_per_s: "
					     "rejected by the configuration check");
	EXPECT("$config tick_hz 1000", "ok tick_hz 1000");
	EXPECT("$config wheel_diameter_mm abc",
	       "error 3 $config wheel_diameter_mm: bad number abc");
	EXPECT("$config tick_hz 1.5", "error 4 $config tick_hz: 1.5 is not an integer in "
				      "0..4294967295");
	EXPECT("$config jog_timeout_default_ms 70000",
	       "error 4 $config jog_timeout_default_ms: 70000 is not an integer in 0..65535");
	EXPECT("$config has_estop maybe",
	       "error 5 $config has_estop: bad boolean maybe (true|false|1|0|on|off)");
	EXPECT("$config kinematics 2",
	       "error 4 $config kinematics: 2 is not 0 (differential) or 1 (mecanum)");
	EXPECT("$config kinematics mecanum", "error 8 $config kinematics: wheel_base_mm: rejected "
					     "by the configuration check");
	EXPECT("$config drive_lag_ms 1 2", "error 2 $config drive_lag_ms takes 4 values, got 2");
	EXPECT("$config drive_lag_ms[1] 25", "ok drive_lag_ms 0.000 25.000 0.000 0.000");
	EXPECT("$config drive_lag_ms 5 6 7 8", "ok drive_lag_ms 5.000 6.000 7.000 8.000");
	EXPECT("$config drive_lag_ms[4] 1", "error 8 $config: no field drive_lag_ms[4]");
	EXPECT("$config drive_lag_ms[x] 1", "error 8 $config: no field drive_lag_ms[x]");
	EXPECT("$config drive_lag_ms[1]", "error 2 $config drive_lag_ms takes 1 value, got 0");
	EXPECT("$config save now", "error 2 $config save takes 0 arguments, got 1");
	EXPECT("$config nosuch 1", "error 8 $config: no field nosuch");
	EXPECT("$config diff", "ok unsaved 1 drive_lag_ms changed 1 drive_lag_ms pending 0");
	/* extras never raise alarms */
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

/* A speed in force stays within its new limit, else it is the default. */
static void test_settings_in_force(void **state)
{
	(void)state;
	boot(path);
	EXPECT("setVelocity 800 100", "ok true");
	EXPECT("$config vel_limit_t_mm_s 900", "ok vel_limit_t_mm_s 900.000");
	assert_true(veh.vel_set.translation == 800.0);
	EXPECT("$config vel_limit_t_mm_s 700", "ok vel_limit_t_mm_s 700.000");
	assert_true(veh.vel_set.translation == 500.0 && veh.vel_set.rotation == 90.0);
	EXPECT("getVelocityLimit", "ok true 700.000 180.000");
	EXPECT("$config vel_default_t_mm_s 300", "ok vel_default_t_mm_s 300.000");
	EXPECT("getDefaultVelocity", "ok true 300.000 90.000");
	assert_true(veh.vel_set.translation == 300.0);
	/* the acceleration by the same rule; a jog timeout in force stays
	 * until its default changes */
	EXPECT("setAcceleration 800 300", "ok true");
	EXPECT("setJogTimeout 300", "ok true");
	EXPECT("$config acc_limit_t_mm_s2 900", "ok acc_limit_t_mm_s2 900.000");
	assert_true(veh.acc_set.translation == 800.0 && veh.acc_set.rotation == 300.0);
	assert_int_equal(veh.jog_timeout_ms, 300);
	EXPECT("$config acc_limit_r_deg_s2 200", "ok acc_limit_r_deg_s2 200.000");
	assert_true(veh.acc_set.translation == 500.0 && veh.acc_set.rotation == 180.0);
	EXPECT("$config jog_timeout_default_ms 400", "ok jog_timeout_default_ms 400");
	assert_int_equal(veh.jog_timeout_ms, 400);
	/* the unit moves by the new configuration */
	EXPECT("setPower on", "ok true");
	EXPECT("setServo on", "ok true");
	EXPECT("moveForward 10", "ok true");
	EXPECT("$config cruise_blend_mm 100",
	       "error 8 $config cruise_blend_mm: cruise_blend_mm changes only with the servo off "
	       "and no motion queued");
}

/* No store: reads and changes, no save. */
static void test_no_store(void **state)
{
	(void)state;
	boot(NULL);
	EXPECT("$config store", "ok store none table 0x916B11C3");
	EXPECT("$config wheel_diameter_mm 160", "ok wheel_diameter_mm 160.000");
	EXPECT("$config save", "error 8 $config save: this unit has no store");
	EXPECT("$config reload", "ok reload pending 0");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000");
}

static void write_file(const void *data, size_t n)
{
	FILE *f = fopen(path, "wb");
	assert_non_null(f);
	assert_int_equal(fwrite(data, 1, n, f), n);
	fclose(f);
}

/* Stores that do not read: the base, and warning 156 saying why. */
static void test_unreadable(void **state)
{
	static uint8_t junk[FILESTORE_PAGE * FILESTORE_PAGES];
	(void)state;
	memset(junk, 0x5A, sizeof junk);
	write_file(junk, sizeof junk);
	boot(path);
	EXPECT("$config store", "ok store corrupt table 0x916B11C3 torn");
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 156 warning \"saved configuration corrupt: base in use\"");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000");
	/* a save writes one slot; the other stays torn until the next */
	EXPECT("$config save", "ok saved 0");
	boot(path);
	EXPECT("$config store",
	       "ok store loaded seq 1 schema 0x916B11C3 applied 0 dropped 0 table 0x916B11C3 torn");

	/* a record the check refuses */
	vs_config_t base, bad;
	uint8_t buf[256];
	fake_hal_config(&base);
	bad = base;
	bad.wheel_diameter_mm = 5.0;
	size_t n = vs_config_encode(&bad, &base, buf, sizeof buf);
	assert_int_equal(cfgstore_save(&fs.hs, buf, (uint32_t)n, vs_config_schema()), CFGSTORE_OK);
	boot(path);
	EXPECT("$config store", "ok store rejected seq 2 schema 0x916B11C3 applied 1 dropped 0 "
				"field wheel_diameter_mm table 0x916B11C3");
	EXPECT("getActiveAlarm 1", "ok true 1 1 156 warning \"saved configuration rejected "
				   "(wheel_diameter_mm): base in use\"");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 150.000");

	/* another platform's numbers */
	buf[1] = 'Q';
	assert_int_equal(cfgstore_save(&fs.hs, buf, (uint32_t)n, vs_config_schema()), CFGSTORE_OK);
	boot(path);
	EXPECT("$config store", "ok store foreign seq 3 schema 0x916B11C3 applied 0 dropped 0 "
				"table 0x916B11C3");
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 156 warning \"saved configuration foreign: base in use\"");
}

/* An older table's store: its fields this table has are taken, the others
 * dropped, and the schemas differ. */
static void test_older_table(void **state)
{
	(void)state;
	uint8_t p[64];
	size_t at = 4;
	double d = 160.0;
	p[0] = 1;
	p[1] = 'D';
	p[2] = 2;
	p[3] = 0;
	const char *names[] = {"wheel_diameter_mm", "gone_field_mm"};
	for (int i = 0; i < 2; i++) {
		p[at++] = (uint8_t)strlen(names[i]);
		memcpy(p + at, names[i], strlen(names[i]));
		at += strlen(names[i]);
		p[at++] = 0;
		p[at++] = VS_CFG_DOUBLE;
		p[at++] = 8;
		memcpy(p + at, &d, 8);
		at += 8;
	}
	char err[64];
	assert_int_equal(filestore_open(&fs, path, err, sizeof err), 0);
	assert_int_equal(cfgstore_save(&fs.hs, p, (uint32_t)at, 0x12345678u), CFGSTORE_OK);
	boot(path);
	EXPECT("$config store",
	       "ok store loaded seq 1 schema 0x12345678 applied 1 dropped 1 table 0x916B11C3");
	EXPECT("$config wheel_diameter_mm", "ok wheel_diameter_mm 160.000");
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup_teardown(test_set_save_restart, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_when_and_refusals, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_settings_in_force, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_no_store, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_unreadable, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_older_table, setup, teardown),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
