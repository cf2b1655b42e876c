/* Conformance: every VehicleService operation driven through the console as
 * a host would, on the simulated plant, against spec sections 4-7. Each
 * expectation is the exact reply line.
 *
 * The wheel in most tests resolves 1/32 mm per encoder count (diameter
 * 16384 / (32 pi) mm), so that straight targets land on whole counts and
 * odometry reads back to the thousandth; the reference wheel is checked to
 * within one count.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <math.h>

#include "../host_sim/sim.h"
#include "../proto/console.h"

static sim_t S;
static char rep[CONSOLE_REPLY_MAX];

static void boot(double wheel_diameter_mm)
{
	vs_config_t cfg;
	plant_params_t pp;

	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	if (wheel_diameter_mm > 0)
		cfg.wheel_diameter_mm = wheel_diameter_mm;
	plant_params_default(&pp);
	assert_int_equal(sim_init(&S, &cfg, &pp), 0);
}

static int setup(void **state)
{
	(void)state;
	boot(16384.0 / (32.0 * 3.14159265358979323846));
	return 0;
}

static const char *ex(const char *line)
{
	if (!sim_exec(&S, line, rep, sizeof(rep)))
		return "(none)";
	return rep;
}

static const char *exf(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static const char *exf(const char *fmt, ...)
{
	char line[CONSOLE_LINE_MAX + 1];
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(line, sizeof(line), fmt, ap);
	va_end(ap);
	return ex(line);
}

#define EXPECT(line, reply) assert_string_equal(ex(line), reply)
#define WAIT(ms)	    assert_string_equal(exf("$wait %d", ms), "ok wait " #ms)
#define PREFIX(s, p)	    assert_memory_equal(s, p, sizeof(p) - 1)

static void ready(void)
{
	EXPECT("setPower true", "ok true");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

static double pos_x(void)
{
	double x = 0, y = 0, th = 0;

	assert_int_equal(sscanf(ex("getPosition"), "ok true %lf %lf %lf", &x, &y, &th), 3);
	return x;
}

/* ---- boot and the always-true queries -------------------------------------- */

static void test_boot_and_queries(void **state)
{
	double v = 0;

	(void)state;
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("getServoStatus 1", "ok true false");
	EXPECT("getIFVersion", "ok true \"RTC VehicleService interface: ver.2.0.0\"");
	EXPECT("getVersion", "ok true \"Ver.1.0.0\"");
	EXPECT("getVelocityLimit", "ok true 1000.000 180.000");
	EXPECT("getAccelerationLimit", "ok true 1000.000 360.000");
	EXPECT("getDefaultVelocity", "ok true 500.000 90.000");
	EXPECT("getDefaultAcceleration", "ok true 500.000 180.000");
	EXPECT("getPosition", "ok true 0.000 0.000 0.000");
	EXPECT("getActiveAlarm 16", "ok true 0 0");
	/* 0.1 V units: the simulated pack idles at 25.2 V */
	EXPECT("getBatteryVoltage", "ok true 252.000");
	EXPECT("$sim battery 24000", "ok battery 24000");
	WAIT(100);
	assert_int_equal(sscanf(ex("getBatteryVoltage"), "ok true %lf", &v), 1);
	assert_true(v > 235.0 && v <= 240.0);
	/* nothing moves before setPower and setServo */
	EXPECT("moveForward 100", "ok false");
	EXPECT("getActiveAlarm 1", "ok true 1 1 121 warning \"moveForward refused: servo off\"");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

/* ---- setServo, source table 8 ----------------------------------------------- */

static void test_set_servo_table8(void **state)
{
	(void)state;
	/* power off: false both ways, servo stays off */
	EXPECT("setServo true", "ok false");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("setServo false", "ok false");
	EXPECT("getServoStatus 1", "ok true false");
	EXPECT("getActiveAlarm 2", "ok true 1 1 128 warning \"setServo refused: power off\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setPower true", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	/* power on, servo off, no alarm: false -> stays off, true -> on */
	EXPECT("setServo false", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	EXPECT("getServoStatus 0", "ok true true");
	EXPECT("getServoStatus 1", "ok true true");
	EXPECT("getServoStatus 2", "ok false false");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* power on, servo on: true -> stays on, false -> off */
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("setServo false", "ok true");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("getState", "ok true 24 \"Powered\"");
	/* power on, servo off, alarm (a fault): true refused, false accepted */
	EXPECT("setServo true", "ok true");
	EXPECT("$sim drive 1 fault 7", "ok drive 1 fault 0x0007");
	WAIT(20);
	EXPECT("getState", "ok true 19 \"Alarm-201\"");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("setServo true", "ok false");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("setServo false", "ok true");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("$sim drive 1 ok", "ok drive 1 ok");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* ---- the state strings ------------------------------------------------------ */

static void test_state_strings(void **state)
{
	(void)state;
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("setPower on", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo on", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("moveForward 500", "ok true");
	EXPECT("getState", "ok true 17 \"Busy\"");
	/* a Ready-only command while busy: refused, a warning, motion goes on */
	EXPECT("moveTurn 90", "ok false");
	EXPECT("getActiveAlarm 5", "ok true 1 1 120 warning \"moveTurn refused: unit not ready\"");
	EXPECT("getState", "ok true 17 \"Busy\"");
	WAIT(4000);
	EXPECT("getPosition", "ok true 500.000 0.000 0.000");
	EXPECT("getState", "ok true 18 \"Warning-120\"");
	/* warnings do not block Ready-only motion (spec 6.9) */
	EXPECT("moveForward -500", "ok true");
	WAIT(4000);
	EXPECT("getPosition", "ok true 0.000 0.000 0.000");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("pause", "ok true");
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("resume", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("setPower off", "ok true");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("$sim relay fail", "ok relay fail");
	EXPECT("setPower on", "ok false");
	EXPECT("getState", "ok true 19 \"Alarm-205\"");
	EXPECT("getActiveAlarm 1", "ok true 1 1 205 fault \"main relay did not close\"");
	EXPECT("$sim relay ok", "ok relay ok");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setPower on", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
}

static void test_active_alarm_count(void **state)
{
	(void)state;
	EXPECT("setServo on", "ok false");	      /* 128 */
	EXPECT("setOutput 0 1 1", "ok false");	      /* 126 */
	EXPECT("getServoStatus 9", "ok false false"); /* 127 */
	/* numOfActiveAlarm is the full count whatever numOfAlarm asks for */
	EXPECT("getActiveAlarm 0", "ok true 3 0");
	EXPECT("getActiveAlarm -1", "ok true 3 0");
	EXPECT("getActiveAlarm 1",
	       "ok true 3 1 127 warning \"getServoStatus refused: no such axis\"");
	EXPECT("getActiveAlarm 2",
	       "ok true 3 2 127 warning \"getServoStatus refused: no such axis\" "
	       "126 warning \"setOutput refused: io id 0 reserved\"");
	EXPECT(
	    "getActiveAlarm 32767",
	    "ok true 3 3 127 warning \"getServoStatus refused: no such axis\" 126 warning "
	    "\"setOutput refused: io id 0 reserved\" 128 warning \"setServo refused: power off\"");
	/* asking does not clear */
	EXPECT("getActiveAlarm 0", "ok true 3 0");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getActiveAlarm 32767", "ok true 0 0");
}

/* ---- IO ------------------------------------------------------------------- */

static void test_io(void **state)
{
	(void)state;
	/* ioid 0 is the unit itself */
	EXPECT("setOutput 0 1 1", "ok false");
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 126 warning \"setOutput refused: io id 0 reserved\"");
	EXPECT("getInput 0", "ok false 0");
	/* unknown ids, and ids of the other direction */
	EXPECT("setOutput 99 1 1", "ok false");
	EXPECT("setOutput 1 1 1", "ok false");
	EXPECT("getInput 99", "ok false 0");
	EXPECT("getInput 3", "ok false 0");
	EXPECT("clearAlarm", "ok true");
	/* masked writes, read back through a loopback from output 3 to input 1 */
	EXPECT("$sim wire 3 1", "ok wire 3 1");
	EXPECT("setOutput 3 240 255", "ok true");
	WAIT(4);
	EXPECT("getInput 1", "ok true 240");
	EXPECT("setOutput 3 15 15", "ok true");
	WAIT(4);
	EXPECT("getInput 1", "ok true 255");
	EXPECT("setOutput 3 0 16", "ok true");
	WAIT(4);
	EXPECT("getInput 1", "ok true 239");
	/* mask 0 changes nothing; bits beyond the 8-bit width are dropped */
	EXPECT("setOutput 3 0 0", "ok true");
	WAIT(4);
	EXPECT("getInput 1", "ok true 239");
	EXPECT("setOutput 3 4294967295 4294967295", "ok true");
	WAIT(4);
	EXPECT("getInput 1", "ok true 255");
	EXPECT("$sim input 2 1", "ok input 2 1");
	EXPECT("getInput 2", "ok true 1");
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

/* ---- motion ------------------------------------------------------------------ */

static void test_move_forward_position(void **state)
{
	(void)state;
	ready();
	EXPECT("moveForward 1000", "ok true");
	EXPECT("getState", "ok true 17 \"Busy\"");
	WAIT(5000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("getPosition", "ok true 1000.000 0.000 0.000");
	EXPECT("setPosition 0 0 0", "ok true");
	EXPECT("moveLinearRel 200 0 0", "ok true");
	WAIT(3000);
	EXPECT("getPosition", "ok true 200.000 0.000 0.000");
}

static void test_reference_wheel_within_one_count(void **state)
{
	double x;

	(void)state;
	boot(0); /* the reference base: 150 mm wheel, 16384 counts */
	ready();
	EXPECT("moveForward 1000", "ok true");
	WAIT(5000);
	x = pos_x();
	assert_true(x > 1000.0 - 0.03 && x < 1000.0 + 0.03);
}

static void queue_three(void)
{
	EXPECT("moveLinearAbs 300 0 0", "ok true");
	EXPECT("moveLinearAbs 600 0 0", "ok true");
	EXPECT("moveLinearAbs 900 0 0", "ok true");
}

static void test_pause_resume_keeps_queue(void **state)
{
	double x;

	(void)state;
	ready();
	queue_three();
	WAIT(600);
	EXPECT("pause", "ok true");
	WAIT(2000);
	EXPECT("getState", "ok true 21 \"Paused\"");
	x = pos_x();
	assert_true(x > 0.0 && x < 900.0);
	/* at rest the wheel loop may settle by one encoder count (1/32 mm),
	 * never along the path */
	WAIT(2000);
	assert_true(fabs(pos_x() - x) < 0.05);
	/* queued while paused, runs after resume */
	EXPECT("moveLinearAbs 1000 0 0", "ok true");
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("resume", "ok true");
	EXPECT("getState", "ok true 17 \"Busy\"");
	WAIT(15000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("getPosition", "ok true 1000.000 0.000 0.000");
	EXPECT("getActiveAlarm 1", "ok true 0 0");
}

static void test_pause_idle_then_queue(void **state)
{
	(void)state;
	ready();
	EXPECT("pause", "ok true");
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("moveLinearAbs 400 0 0", "ok true");
	WAIT(3000);
	EXPECT("getPosition", "ok true 0.000 0.000 0.000");
	EXPECT("resume", "ok true");
	WAIT(4000);
	EXPECT("getPosition", "ok true 400.000 0.000 0.000");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

static void test_stop_discards(void **state)
{
	char before[CONSOLE_REPLY_MAX];
	double x;

	(void)state;
	ready();
	queue_three();
	WAIT(500);
	EXPECT("stop", "ok true");
	WAIT(2000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	x = pos_x();
	assert_true(x > 0.0 && x < 300.0);
	strcpy(before, ex("getPosition"));
	EXPECT("resume", "ok true");
	WAIT(5000);
	/* nothing left to run */
	EXPECT("getPosition", before);
	PREFIX(ex("$diag"), "ok ticks");
	assert_non_null(strstr(rep, " mode idle queue 0 "));
}

static void test_contact_lock(void **state)
{
	char before[CONSOLE_REPLY_MAX];

	(void)state;
	ready();
	EXPECT("setDigitalSensorLock on", "ok true");
	EXPECT("moveForward 2000", "ok true");
	WAIT(500);
	EXPECT("$sim contact on", "ok contact on");
	WAIT(2000);
	EXPECT("getState", "ok true 23 \"Locked\"");
	EXPECT("getActiveAlarm 1", "ok true 1 1 150 warning \"contact detected\"");
	strcpy(before, ex("getPosition"));
	EXPECT("moveForward 100", "ok false");
	EXPECT("moveLinearAbs 0 0 0", "ok false");
	/* one entry per code: the newest refusal's text */
	EXPECT("getActiveAlarm 1",
	       "ok true 2 1 124 warning \"moveLinearAbs refused: unit locked\"");
	EXPECT("$sim contact off", "ok contact off");
	WAIT(500);
	EXPECT("getState", "ok true 23 \"Locked\"");
	EXPECT("unlock", "ok true");
	EXPECT("getState", "ok true 18 \"Warning-124\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* unlocking never restarts the aborted move */
	WAIT(2000);
	EXPECT("getPosition", before);
	EXPECT("moveForward 100", "ok true");
	WAIT(2000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* the lock disabled: contact does not lock */
	EXPECT("setDigitalSensorLock off", "ok true");
	EXPECT("$sim contact on", "ok contact on");
	WAIT(100);
	EXPECT("getState", "ok true 16 \"Ready\"");
}

static void test_obstacle_stuck(void **state)
{
	char before[CONSOLE_REPLY_MAX];

	(void)state;
	ready();
	EXPECT("moveForward 2000", "ok true");
	WAIT(500);
	EXPECT("$sim obstacle on", "ok obstacle on");
	WAIT(2000);
	EXPECT("getState", "ok true 20 \"Stuck\"");
	EXPECT("moveForward 10", "ok false");
	EXPECT("getActiveAlarm 2", "ok true 2 2 130 warning \"moveForward refused: unit stuck\" "
				   "151 warning \"obstacle detected\"");
	strcpy(before, ex("getPosition"));
	EXPECT("$sim obstacle off", "ok obstacle off");
	WAIT(100);
	EXPECT("getState", "ok true 18 \"Warning-130\"");
	WAIT(2000);
	EXPECT("getPosition", before);
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

static void test_fault_blocks_motion(void **state)
{
	char before[CONSOLE_REPLY_MAX];

	(void)state;
	ready();
	EXPECT("moveForward 2000", "ok true");
	WAIT(300);
	EXPECT("$sim drive 0 fault 9", "ok drive 0 fault 0x0009");
	WAIT(50);
	EXPECT("getState", "ok true 19 \"Alarm-201\"");
	EXPECT("getServoStatus 0", "ok true false");
	/* servo off: the wheels coast out, then nothing moves */
	WAIT(2000);
	strcpy(before, ex("getPosition"));
	EXPECT("moveForward 100", "ok false");
	EXPECT("moveLinearAbs 0 0 0", "ok false");
	EXPECT("moveJog 100 0 0", "ok false");
	EXPECT("getActiveAlarm 1", "ok true 2 1 123 warning \"moveJog refused: fault active\"");
	EXPECT("getState", "ok true 19 \"Alarm-201\"");
	WAIT(1000);
	EXPECT("getPosition", before);
	EXPECT("$sim drive 0 ok", "ok drive 0 ok");
	/* still refused until clearAlarm, and the servo must be switched on again */
	EXPECT("moveForward 100", "ok false");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("moveForward 100", "ok false");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo on", "ok true");
	EXPECT("moveForward 100", "ok true");
	WAIT(2000);
	EXPECT("getState", "ok true 16 \"Ready\"");
}

static void test_bad_lines_keep_queue(void **state)
{
	static const char *const bad[] = {
	    "moveForward",
	    "moveLinearAbs 1 2",
	    "moveLinearAbs nan 0 0",
	    "moveLinearAbs 1e999 0 0",
	    "moveLinearAbs 0x10 0 0",
	    "stopp",
	    "STOP now",
	    "pause 1",
	    "setPower maybe",
	    "setServo 2",
	    "getInput -1",
	    "setOutput 3 1 4294967296",
	    "getActiveAlarm 40000",
	    "stop\x01",
	    "$nope",
	};
	char longline[300];

	(void)state;
	ready();
	queue_three();
	for (unsigned k = 0; k < sizeof(bad) / sizeof(bad[0]); k++) {
		assert_int_equal(ex(bad[k])[0], 'e');
		PREFIX(rep, "error ");
		WAIT(10);
	}
	memset(longline, ' ', sizeof(longline));
	memcpy(longline, "stop", 4);
	longline[sizeof(longline) - 1] = '\0';
	EXPECT(longline, "error 6 line too long (max 255 bytes)");
	/* none of it reached the unit */
	EXPECT("getActiveAlarm 1", "ok true 0 0");
	EXPECT("getState", "ok true 17 \"Busy\"");
	WAIT(15000);
	EXPECT("getPosition", "ok true 900.000 0.000 0.000");
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* at rest, bad lines do not move the unit either */
	for (unsigned k = 0; k < sizeof(bad) / sizeof(bad[0]); k++)
		PREFIX(ex(bad[k]), "error ");
	WAIT(1000);
	EXPECT("getPosition", "ok true 900.000 0.000 0.000");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* The byte stream path, as a serial terminal uses it. */
static char out[8192];
static size_t out_len;
static void collect(void *ctx, const char *s, size_t n)
{
	(void)ctx;
	assert_true(out_len + n < sizeof(out));
	memcpy(out + out_len, s, n);
	out_len += n;
	out[out_len] = '\0';
}

static void test_serial_stream(void **state)
{
	static const char script[] = "# bring-up\r\n"
				     "setPower on\r\n"
				     "setServo on\r\n"
				     "\r\n"
				     "moveLinearAbs 300 0 0\r\n"
				     "moveLinearAbs 600 0 0\r\n"
				     "\x01\x02\xff garbage\r\n"
				     "moveLinearAbs 600\r\n"
				     "$wait 8000\r\n"
				     "getPosition\r\n"
				     "getState\n";

	(void)state;
	sim_set_output(&S, collect, NULL);
	console_feed(&S.srv.con, (const uint8_t *)script, sizeof(script) - 1);
	assert_string_equal(out, "ok true\n"
				 "ok true\n"
				 "ok true\n"
				 "ok true\n"
				 "error 7 binary data in line\n"
				 "error 2 moveLinearAbs takes 3 arguments, got 1\n"
				 "ok wait 8000\n"
				 "ok true 600.000 0.000 0.000\n"
				 "ok true 16 \"Ready\"\n");
}

/* ---- the remaining operations ------------------------------------------------- */

static void test_settings(void **state)
{
	(void)state;
	EXPECT("setVelocity 0 10", "ok false");
	EXPECT("setVelocity 100 -1", "ok false");
	EXPECT("setVelocity 1000.001 10", "ok false");
	EXPECT("setVelocity 1000 180", "ok true");
	EXPECT("getActiveAlarm 2",
	       "ok true 1 1 111 warning \"setVelocity refused: out of limits\"");
	EXPECT("setAcceleration 0 10", "ok false");
	EXPECT("setAcceleration 100 361", "ok false");
	EXPECT("setAcceleration 1000 360", "ok true");
	EXPECT("setJogTimeout 0", "ok false");
	EXPECT("setJogTimeout -5", "ok false");
	EXPECT("setJogTimeout 200", "ok true");
	EXPECT("setJoystick on", "ok true");
	EXPECT("setJoystick off", "ok true");
	EXPECT("setPosition 100 -50 30", "ok true");
	EXPECT("getPosition", "ok true 100.000 -50.000 30.000");
	EXPECT("setPosition 0 0 190", "ok true");
	EXPECT("getPosition", "ok true 0.000 0.000 -170.000");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setPosition 0 0 0", "ok true");
	/* setAcceleration is refused while moving, setVelocity is not */
	ready();
	EXPECT("moveForward 1000", "ok true");
	WAIT(200);
	EXPECT("setAcceleration 500 180", "ok false");
	EXPECT("setVelocity 200 90", "ok true");
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 122 warning \"setAcceleration refused: unit moving\"");
	WAIT(8000);
	EXPECT("getPosition", "ok true 1000.000 0.000 0.000");
}

static void test_other_moves(void **state)
{
	double x = 0, y = 0, th = 0;

	(void)state;
	ready();
	/* a differential base refuses y motion and an off-axis arc centre */
	EXPECT("moveJog 0 100 0", "ok false");
	EXPECT("getActiveAlarm 1", "ok true 1 1 112 warning \"moveJog refused: not possible on "
				   "this base\"");
	EXPECT("moveCircularRel 100 500 90", "ok false");
	EXPECT("moveJog 1000.5 0 0", "ok false");
	EXPECT("moveJog 0 0 -180.5", "ok false");
	EXPECT("clearAlarm", "ok true");
	/* jog: negative reverses, the watchdog stops it */
	EXPECT("setJogTimeout 100", "ok true");
	EXPECT("moveJog -200 0 0", "ok true");
	EXPECT("getState", "ok true 17 \"Busy\"");
	WAIT(2000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* 100 ms accelerating at the default 500 mm/s^2, then the same braking:
	 * 2.5 + 2.5 mm */
	EXPECT("getPosition", "ok true -5.000 0.000 0.000");
	/* all-zero jog is valid */
	EXPECT("moveJog 0 0 0", "ok true");
	WAIT(500);
	EXPECT("setPosition 0 0 0", "ok true");
	/* turn in place */
	EXPECT("moveTurn 90", "ok true");
	WAIT(3000);
	assert_int_equal(sscanf(ex("getPosition"), "ok true %lf %lf %lf", &x, &y, &th), 3);
	assert_true(th > 89.99 && th < 90.01);
	assert_true(x > -0.01 && x < 0.01 && y > -0.01 && y < 0.01);
	/* a quarter arc about a centre 500 mm to the left */
	EXPECT("setPosition 0 0 0", "ok true");
	EXPECT("moveCircularRel 0 500 90", "ok true");
	WAIT(6000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	assert_int_equal(sscanf(ex("getPosition"), "ok true %lf %lf %lf", &x, &y, &th), 3);
	assert_true(x > 499.0 && x < 501.0 && y > 499.0 && y < 501.0);
	assert_true(th > 89.9 && th < 90.1);
	/* continuous: the newest target wins */
	EXPECT("setPosition 0 0 0", "ok true");
	EXPECT("moveContinuousRel 1000 0 0", "ok true");
	WAIT(200);
	EXPECT("moveContinuousRel 100 0 0", "ok true");
	WAIT(4000);
	x = pos_x();
	assert_true(x > 50.0 && x < 400.0);
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* cruise: waypoints passed without stopping, ending at the last */
	EXPECT("setPosition 0 0 0", "ok true");
	EXPECT("moveCruiseAbs 300 0", "ok true");
	EXPECT("moveCruiseAbs 600 0", "ok true");
	WAIT(6000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	x = pos_x();
	assert_true(x > 599.9 && x < 600.1);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup(test_boot_and_queries, setup),
	    cmocka_unit_test_setup(test_set_servo_table8, setup),
	    cmocka_unit_test_setup(test_state_strings, setup),
	    cmocka_unit_test_setup(test_active_alarm_count, setup),
	    cmocka_unit_test_setup(test_io, setup),
	    cmocka_unit_test_setup(test_move_forward_position, setup),
	    cmocka_unit_test_setup(test_reference_wheel_within_one_count, setup),
	    cmocka_unit_test_setup(test_pause_resume_keeps_queue, setup),
	    cmocka_unit_test_setup(test_pause_idle_then_queue, setup),
	    cmocka_unit_test_setup(test_stop_discards, setup),
	    cmocka_unit_test_setup(test_contact_lock, setup),
	    cmocka_unit_test_setup(test_obstacle_stuck, setup),
	    cmocka_unit_test_setup(test_fault_blocks_motion, setup),
	    cmocka_unit_test_setup(test_bad_lines_keep_queue, setup),
	    cmocka_unit_test_setup(test_serial_stream, setup),
	    cmocka_unit_test_setup(test_settings, setup),
	    cmocka_unit_test_setup(test_other_moves, setup),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
