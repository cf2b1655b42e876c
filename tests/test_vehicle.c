/* VehicleService core without moving the unit: lifecycle, state codes,
 * setServo table 8, power, alarms, IO, settings, argument checks, refusal
 * rules and supervision (faults, lock, stuck, battery, overrun).
 * Tests that need motion to run are in test_vehicle_motion.c. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "fake_hal.h"
#include "../firmware/vehicle.h"

static fake_hal_t F;
static vehicle_t V;
static vs_config_t C;

static int setup(void **state)
{
	(void)state;
	fake_hal_init(&F, 1000);
	fake_hal_config(&C);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	C.link_timeout_ms = 0;
	vs_hal_t h = fake_hal_bind(&F);
	const char *bad = NULL;
	memset(&V, 0x5A, sizeof V);
	return vehicle_init(&V, &C, &h, &bad);
}

/* ---- helpers ---------------------------------------------------------- */

static void expect_state(int16_t code, const char *msg)
{
	int16_t s = 0;
	char m[VS_STATE_MSG_MAX];
	assert_true(vs_getState(&V, &s, m));
	assert_string_equal(m, msg);
	assert_int_equal(s, code);
}

static int16_t alarm_count(void)
{
	int16_t n = -1;
	uint16_t len = 0;
	assert_true(vs_getActiveAlarm(&V, 0, &n, NULL, &len));
	return n;
}

/* The newest alarm is exactly this. */
static void expect_newest(uint32_t code, uint8_t type, const char *source)
{
	vs_alarm_t a[1];
	int16_t n = 0;
	uint16_t len = 0;
	assert_true(vs_getActiveAlarm(&V, 1, &n, a, &len));
	assert_int_equal(len, 1);
	assert_int_equal(a[0].code, code);
	assert_int_equal(a[0].type, type);
	assert_string_equal(a[0].source, source);
}

static void expect_warning(uint32_t code, const char *source)
{
	expect_newest(code, VS_ALARM_WARNING, source);
}

static void expect_fault(uint32_t code, const char *source)
{
	expect_newest(code, VS_ALARM_FAULT, source);
}

static void power_up(void)
{
	assert_true(vs_setPower(&V, true));
	fake_run(&F, &V, 1);
	assert_true(vs_setServo(&V, true));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_READY, "Ready");
}

static void expect_servo_off(void)
{
	bool st = true;
	assert_false(V.servo);
	for (uint32_t i = 0; i < 2; i++) {
		assert_false(F.enabled[i]);
		assert_true(vs_getServoStatus(&V, i, &st));
		assert_false(st);
	}
}

/* Nothing queued, nothing moving, every wheel setpoint zero. */
static void expect_no_motion(void)
{
	assert_false(motion_has_work(&V.motion));
	assert_int_equal(motion_queue_len(&V.motion), 0);
	fake_run(&F, &V, 5);
	assert_int_equal(F.cmd_cps_q8[0], 0);
	assert_int_equal(F.cmd_cps_q8[1], 0);
}

static const vs_position_t P0 = {100.0, 0.0, 0.0};
static const vs_point_t C0 = {0.0, 200.0};

/* Every move* operation with valid arguments. */
typedef bool (*move_fn)(void);
static bool mv_forward(void)
{
	return vs_moveForward(&V, 100.0);
}
static bool mv_turn(void)
{
	return vs_moveTurn(&V, 45.0);
}
static bool mv_linrel(void)
{
	return vs_moveLinearRel(&V, P0);
}
static bool mv_circ(void)
{
	return vs_moveCircularRel(&V, C0, 30.0);
}
static bool mv_linabs(void)
{
	return vs_moveLinearAbs(&V, P0);
}
static bool mv_cruise(void)
{
	return vs_moveCruiseAbs(&V, (vs_point_t){100.0, 0.0});
}
static bool mv_cont(void)
{
	return vs_moveContinuousRel(&V, P0);
}
static bool mv_jog(void)
{
	return vs_moveJog(&V, 100.0, 0.0, 0.0);
}

static const struct {
	move_fn fn;
	const char *name;
} MOVES[] = {
    {mv_forward, "moveForward"},    {mv_turn, "moveTurn"},	  {mv_linrel, "moveLinearRel"},
    {mv_circ, "moveCircularRel"},   {mv_linabs, "moveLinearAbs"}, {mv_cruise, "moveCruiseAbs"},
    {mv_cont, "moveContinuousRel"}, {mv_jog, "moveJog"},
};
#define NMOVES (sizeof MOVES / sizeof MOVES[0])

/* Every move* is refused with this code and "<op> refused: <reason>". */
static void expect_all_moves_refused(uint32_t code, const char *reason)
{
	char text[VS_ALARM_SOURCE_MAX];
	for (unsigned i = 0; i < NMOVES; i++) {
		assert_false(MOVES[i].fn());
		snprintf(text, sizeof text, "%s refused: %s", MOVES[i].name, reason);
		expect_warning(code, text);
		assert_false(motion_has_work(&V.motion));
	}
	expect_no_motion();
}

/* ---- lifecycle and constant queries ----------------------------------- */

static void test_init_unpowered(void **state)
{
	(void)state;
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
	assert_int_equal(alarm_count(), 0);
	/* Start-up puts the hardware in the same state. */
	assert_int_equal(F.power_set_calls, 1);
	assert_false(F.last_power_set);
	assert_int_equal(F.enable_calls[0], 1);
	assert_int_equal(F.enable_calls[1], 1);
	assert_false(F.enabled[0]);
	bool st = true;
	assert_true(vs_getServoStatus(&V, 0, &st));
	assert_false(st);
	fake_run(&F, &V, 10);
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
	assert_int_equal(alarm_count(), 0);
	/* The tick writes every axis every period, zero while servo is off. */
	assert_int_equal(F.set_velocity_calls[0], 10);
	assert_int_equal(F.set_velocity_calls[1], 10);
	assert_int_equal(F.set_velocity_calls[2], 0);
	assert_int_equal(F.cmd_cps_q8[0], 0);
	vs_diag_t d;
	vehicle_diag(&V, &d);
	assert_int_equal(d.ticks, 10);
	assert_int_equal(d.overruns, 0);
}

static void test_init_rejects(void **state)
{
	(void)state;
	static vehicle_t v2;
	vs_config_t c = C;
	vs_hal_t h = fake_hal_bind(&F);
	const char *bad = NULL;
	c.tick_hz = 50;
	assert_true(vehicle_init(&v2, &c, &h, &bad) < 0);
	assert_string_equal(bad, "tick_hz");

	c = C;
	vs_hal_ops_t ops = fake_hal_ops;
	ops.estop = NULL;
	vs_hal_t h2 = {&ops, &F};
	bad = NULL;
	assert_int_equal(vehicle_init(&v2, &c, &h2, &bad), -4);
	assert_string_equal(bad, "hal");
	/* Without an e-stop input configured the op is not needed. */
	c.has_estop = false;
	assert_int_equal(vehicle_init(&v2, &c, &h2, &bad), 0);
}

static void test_constant_queries(void **state)
{
	(void)state;
	const char *s = NULL;
	assert_true(vs_getIFVersion(&V, &s));
	assert_string_equal(s, "RTC VehicleService interface: ver.2.0.0");
	assert_true(vs_getVersion(&V, &s));
	assert_string_equal(s, "Ver.1.0.0");
	double t = 0, r = 0;
	assert_true(vs_getVelocityLimit(&V, &t, &r));
	assert_true(t == 1000.0 && r == 180.0);
	assert_true(vs_getAccelerationLimit(&V, &t, &r));
	assert_true(t == 1000.0 && r == 360.0);
	vs_velocity_t vel;
	assert_true(vs_getDefaultVelocity(&V, &vel));
	assert_true(vel.translation == 500.0 && vel.rotation == 90.0);
	assert_true(vs_getDefaultAcceleration(&V, &vel));
	assert_true(vel.translation == 500.0 && vel.rotation == 180.0);
	/* Changing the settings does not change the defaults. */
	assert_true(vs_setVelocity(&V, (vs_velocity_t){250.0, 45.0}));
	assert_true(vs_getDefaultVelocity(&V, &vel));
	assert_true(vel.translation == 500.0 && vel.rotation == 90.0);

	static vehicle_t v2;
	vs_config_t c = C;
	c.firmware_version = "Ver.1.4.2";
	vs_hal_t h = fake_hal_bind(&F);
	assert_int_equal(vehicle_init(&v2, &c, &h, NULL), 0);
	assert_true(vs_getVersion(&v2, &s));
	assert_string_equal(s, "Ver.1.4.2");
}

static void test_battery_voltage(void **state)
{
	(void)state;
	double volt = 0;
	assert_true(vs_getBatteryVoltage(&V, &volt));
	assert_true(volt == 240.0); /* sampled at init: 24.0 V */
	F.battery_mv = 24300;
	fake_run(&F, &V, 1);
	assert_true(vs_getBatteryVoltage(&V, &volt));
	assert_true(volt == 243.0);
	F.battery_mv = 55000;
	fake_run(&F, &V, 1);
	assert_true(vs_getBatteryVoltage(&V, &volt));
	assert_true(volt == 550.0);
}

/* ---- power and servo --------------------------------------------------- */

static void test_power_on_off(void **state)
{
	(void)state;
	assert_true(vs_setPower(&V, true));
	assert_true(F.relay);
	expect_state(VS_STATE_POWERED, "Powered");
	assert_true(vs_setPower(&V, true)); /* already on */
	fake_run(&F, &V, 3);
	expect_state(VS_STATE_POWERED, "Powered");
	assert_true(vs_setServo(&V, true));
	expect_state(VS_STATE_READY, "Ready");
	assert_true(vs_setPower(&V, false));
	assert_false(F.relay);
	expect_servo_off();
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
	assert_int_equal(alarm_count(), 0);
	/* Power back: servo stays off until asked. */
	assert_true(vs_setPower(&V, true));
	expect_state(VS_STATE_POWERED, "Powered");
	assert_false(V.servo);
}

static void test_power_relay_failure(void **state)
{
	(void)state;
	F.relay_fail = true;
	assert_false(vs_setPower(&V, true));
	expect_fault(205, "main relay did not close");
	expect_state(VS_STATE_ALARM, "Alarm-205");
	assert_false(F.last_power_set); /* commanded open again */
	assert_false(vs_setServo(&V, true));
	expect_servo_off();
	/* Fault cleared: back to Unpowered; a working relay powers up. */
	assert_true(vs_clearAlarm(&V));
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
	F.relay_fail = false;
	assert_true(vs_setPower(&V, true));
	expect_state(VS_STATE_POWERED, "Powered");
}

static void test_power_lost(void **state)
{
	(void)state;
	power_up();
	F.feedback_lost = true;
	fake_run(&F, &V, 1);
	expect_fault(206, "main power lost");
	expect_state(VS_STATE_ALARM, "Alarm-206");
	expect_servo_off();
	assert_false(V.powered);
	fake_run(&F, &V, 5);
	assert_int_equal(alarm_count(), 1); /* raised once */
	assert_true(vs_clearAlarm(&V));
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
}

/* Source table 8, every cell. */
static void test_servo_table8(void **state)
{
	(void)state;
	unsigned en0;
	/* Power off, true: false, stays off. */
	assert_false(vs_setServo(&V, true));
	expect_warning(128, "setServo refused: power off");
	expect_servo_off();
	/* Power off, false: false, stays off. */
	assert_true(vs_clearAlarm(&V));
	assert_false(vs_setServo(&V, false));
	expect_warning(128, "setServo refused: power off");
	expect_servo_off();
	expect_state(VS_STATE_UNPOWERED, "Unpowered");

	assert_true(vs_setPower(&V, true));
	assert_true(vs_clearAlarm(&V));
	/* Power on, servo off, no alarm, false: true, stays off. */
	en0 = F.enable_calls[0];
	assert_true(vs_setServo(&V, false));
	expect_servo_off();
	/* Power on, servo off, no alarm, true: true, servo on. */
	assert_true(vs_setServo(&V, true));
	assert_true(V.servo);
	assert_true(F.enabled[0] && F.enabled[1]);
	assert_true(F.enable_calls[0] > en0);
	bool st = false;
	assert_true(vs_getServoStatus(&V, 1, &st));
	assert_true(st);
	fake_run(&F, &V, 1);
	assert_true(vs_getServoStatus(&V, 0, &st));
	assert_true(st);
	/* Power on, servo on, true: true, stays on. */
	en0 = F.enable_calls[0];
	assert_true(vs_setServo(&V, true));
	assert_true(V.servo);
	assert_int_equal(F.enable_calls[0], en0);
	/* Power on, servo on, false: true, servo off. */
	assert_true(vs_setServo(&V, false));
	expect_servo_off();
	expect_state(VS_STATE_POWERED, "Powered");
	assert_int_equal(alarm_count(), 0);

	/* Power on, servo off, with a fault: true -> false, false -> true. */
	F.estop = true;
	fake_run(&F, &V, 1);
	F.estop = false;
	expect_state(VS_STATE_ALARM, "Alarm-208");
	assert_false(vs_setServo(&V, true));
	expect_warning(123, "setServo refused: fault active");
	expect_servo_off();
	assert_true(vs_setServo(&V, false));
	expect_servo_off();
	/* A warning alone is no alarm in the sense of table 8. */
	assert_true(vs_clearAlarm(&V));
	assert_false(vs_setVelocity(&V, (vs_velocity_t){0.0, 10.0}));
	assert_true(vs_setServo(&V, true));
	assert_true(V.servo);
}

/* ---- getState ---------------------------------------------------------- */

static void test_state_codes(void **state)
{
	(void)state;
	expect_state(0x019, "Unpowered");
	assert_true(vs_setPower(&V, true));
	expect_state(0x018, "Powered");
	assert_true(vs_setServo(&V, true));
	expect_state(0x010, "Ready");
	/* A warning while idle. */
	assert_false(vs_setJogTimeout(&V, 0));
	expect_state(0x012, "Warning-111");
	/* The newest warning names the state. */
	assert_false(vs_getServoStatus(&V, 7, &(bool){false}));
	expect_state(0x012, "Warning-127");
	/* A fault outranks everything. */
	F.estop = true;
	fake_run(&F, &V, 1);
	expect_state(0x013, "Alarm-208");
	F.estop = false;
	assert_true(vs_clearAlarm(&V));
	expect_state(0x018, "Powered");
	assert_true(vs_setServo(&V, true));
	expect_state(0x010, "Ready");
}

static void test_state_code_padding(void **state)
{
	(void)state;
	/* Codes outside 1xx/2xx do not occur in this firmware; the format is
	 * checked by planting entries directly. */
	alarm_raise(&V.alarms, 7, "planted");
	V.alarms.a[0].type = VS_ALARM_FAULT;
	expect_state(VS_STATE_ALARM, "Alarm-007");
	alarm_raise(&V.alarms, 1203, "planted");
	V.alarms.a[0].type = VS_ALARM_FAULT;
	expect_state(VS_STATE_ALARM, "Alarm-1203");
	assert_true(vs_clearAlarm(&V));
	assert_true(vs_setPower(&V, true));
	assert_true(vs_setServo(&V, true));
	alarm_raise(&V.alarms, 42, "planted");
	V.alarms.a[0].type = VS_ALARM_WARNING;
	expect_state(VS_STATE_WARNING, "Warning-042");
	/* An unknown-type alarm is neither: Ready. */
	assert_true(vs_clearAlarm(&V));
	alarm_raise(&V.alarms, 1203, "unknown");
	expect_state(VS_STATE_READY, "Ready");
}

/* ---- alarms ------------------------------------------------------------ */

static void test_active_alarm_counts(void **state)
{
	(void)state;
	vs_alarm_t a[8];
	int16_t n = -1;
	uint16_t len = 99;
	assert_true(vs_getActiveAlarm(&V, 5, &n, a, &len));
	assert_int_equal(n, 0);
	assert_int_equal(len, 0);

	assert_false(vs_moveTurn(&V, 10.0));		   /* 121 */
	assert_false(vs_setJogTimeout(&V, -5));		   /* 111 */
	assert_false(vs_getInput(&V, 99, &(uint32_t){0})); /* 126 */

	memset(a, 0, sizeof a);
	assert_true(vs_getActiveAlarm(&V, 0, &n, a, &len));
	assert_int_equal(n, 3);
	assert_int_equal(len, 0);
	assert_int_equal(a[0].code, 0); /* nothing written */

	assert_true(vs_getActiveAlarm(&V, 1, &n, a, &len));
	assert_int_equal(n, 3);
	assert_int_equal(len, 1);
	assert_int_equal(a[0].code, 126);
	assert_string_equal(a[0].source, "getInput refused: no such io id");
	assert_int_equal(a[1].code, 0);

	assert_true(vs_getActiveAlarm(&V, 8, &n, a, &len));
	assert_int_equal(n, 3);
	assert_int_equal(len, 3);
	assert_int_equal(a[0].code, 126);
	assert_int_equal(a[1].code, 111);
	assert_string_equal(a[1].source, "setJogTimeout refused: out of limits");
	assert_int_equal(a[2].code, 121);
	assert_string_equal(a[2].source, "moveTurn refused: servo off");
	assert_int_equal(a[2].type, VS_ALARM_WARNING);

	memset(a, 0, sizeof a);
	assert_true(vs_getActiveAlarm(&V, -1, &n, a, &len));
	assert_int_equal(n, 3);
	assert_int_equal(len, 0);
	assert_int_equal(a[0].code, 0);
	assert_true(vs_getActiveAlarm(&V, INT16_MIN, &n, a, &len));
	assert_int_equal(n, 3);
	assert_int_equal(len, 0);

	assert_true(vs_clearAlarm(&V));
	assert_true(vs_getActiveAlarm(&V, 8, &n, a, &len));
	assert_int_equal(n, 0);
	assert_int_equal(len, 0);
}

static void test_clear_alarm_resets_drives(void **state)
{
	(void)state;
	assert_true(vs_clearAlarm(&V));
	assert_int_equal(F.reset_fault_calls[0], 1);
	assert_int_equal(F.reset_fault_calls[1], 1);
	assert_int_equal(F.reset_fault_calls[2], 0);
}

/* ---- IO ---------------------------------------------------------------- */

static void test_get_input(void **state)
{
	(void)state;
	uint32_t in = 0;
	F.io_in[1] = 0x1A5; /* 8-bit input: upper bits are not part of it */
	assert_true(vs_getInput(&V, 1, &in));
	assert_int_equal(in, 0xA5);
	F.io_in[2] = 3; /* 1-bit input */
	assert_true(vs_getInput(&V, 2, &in));
	assert_int_equal(in, 1);
	assert_int_equal(alarm_count(), 0);

	in = 77;
	assert_false(vs_getInput(&V, 0, &in));
	expect_warning(126, "getInput refused: no such io id");
	assert_false(vs_getInput(&V, 3, &in)); /* an output */
	assert_false(vs_getInput(&V, 5, &in)); /* not in io.xml */
	assert_false(vs_getInput(&V, UINT32_MAX, &in));
	F.io_unserved[1] = true; /* the backend does not serve it */
	assert_false(vs_getInput(&V, 1, &in));
	assert_int_equal(in, 77);
	assert_int_equal(alarm_count(), 1);
}

static void test_set_output(void **state)
{
	(void)state;
	/* id 0 is reserved for the unit. */
	assert_false(vs_setOutput(&V, 0, 1, 1));
	expect_warning(126, "setOutput refused: io id 0 reserved");
	assert_false(vs_setOutput(&V, 1, 1, 1)); /* an input */
	expect_warning(126, "setOutput refused: no such io id");
	assert_false(vs_setOutput(&V, 42, 1, 1));
	assert_int_equal(F.io_write_calls, 0);

	/* Masked writes keep the other bits; the value goes out at once. */
	assert_true(vs_setOutput(&V, 3, 0xF0, 0xFF));
	assert_int_equal(F.io_out[3], 0xF0);
	assert_true(vs_setOutput(&V, 3, 0x0F, 0x0C));
	assert_int_equal(F.io_out[3], 0xFC);
	assert_true(vs_setOutput(&V, 3, 0x00, 0x80));
	assert_int_equal(F.io_out[3], 0x7C);
	assert_true(vs_setOutput(&V, 3, 0xFFFFFFFF, 0)); /* empty mask: unchanged */
	assert_int_equal(F.io_out[3], 0x7C);
	/* Only the 8 bits of this output exist. */
	assert_true(vs_setOutput(&V, 3, 0xFFFF, 0xFFFF));
	assert_int_equal(F.io_out[3], 0xFF);
	assert_int_equal(F.io_write_calls, 5);
	/* A 1-bit output. */
	assert_true(vs_setOutput(&V, 4, 0xFFFFFFFF, 0xFFFFFFFF));
	assert_int_equal(F.io_out[4], 1);
	assert_true(vs_setOutput(&V, 4, 0, 1));
	assert_int_equal(F.io_out[4], 0);
	/* Works in every state, also Unpowered. */
	expect_state(VS_STATE_UNPOWERED, "Unpowered");

	/* A write the backend rejects changes nothing. */
	F.io_unserved[3] = true;
	assert_false(vs_setOutput(&V, 3, 0x00, 0xFF));
	expect_warning(126, "setOutput refused: no such io id");
	F.io_unserved[3] = false;
	assert_true(vs_setOutput(&V, 3, 0x01, 0x01));
	assert_int_equal(F.io_out[3], 0xFF);
}

static void test_servo_status_axes(void **state)
{
	(void)state;
	bool st = true;
	assert_true(vs_getServoStatus(&V, 0, &st));
	assert_true(vs_getServoStatus(&V, 1, &st));
	assert_false(vs_getServoStatus(&V, 2, &st));
	expect_warning(127, "getServoStatus refused: no such axis");
	assert_false(vs_getServoStatus(&V, UINT32_MAX, &st));
}

/* ---- settings ---------------------------------------------------------- */

static void test_set_velocity(void **state)
{
	(void)state;
	assert_true(vs_setVelocity(&V, (vs_velocity_t){1000.0, 180.0})); /* = limits */
	assert_true(vs_setVelocity(&V, (vs_velocity_t){0.001, 0.001}));
	assert_int_equal(alarm_count(), 0);
	const vs_velocity_t bad[] = {
	    {0.0, 90.0},  {-1.0, 90.0},	  {1000.001, 90.0},
	    {500.0, 0.0}, {500.0, -90.0}, {500.0, 180.5},
	};
	for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		assert_true(vs_clearAlarm(&V));
		assert_false(vs_setVelocity(&V, bad[i]));
		expect_warning(111, "setVelocity refused: out of limits");
		assert_int_equal(alarm_count(), 1);
	}
	const vs_velocity_t nan_[] = {
	    {NAN, 90.0}, {500.0, NAN}, {INFINITY, 90.0}, {500.0, -INFINITY}, {1e300, 90.0}};
	for (unsigned i = 0; i < sizeof nan_ / sizeof nan_[0]; i++) {
		assert_false(vs_setVelocity(&V, nan_[i]));
		expect_warning(i == 4 ? 111 : 110, i == 4
						       ? "setVelocity refused: out of limits"
						       : "setVelocity refused: invalid argument");
	}
	/* The last accepted value is still in force. */
	assert_true(V.vel_set.translation == 0.001);
}

static void test_set_acceleration(void **state)
{
	(void)state;
	assert_true(vs_setAcceleration(&V, (vs_velocity_t){1000.0, 360.0}));
	assert_true(vs_setAcceleration(&V, (vs_velocity_t){1.0, 1.0}));
	assert_false(vs_setAcceleration(&V, (vs_velocity_t){0.0, 1.0}));
	expect_warning(111, "setAcceleration refused: out of limits");
	assert_false(vs_setAcceleration(&V, (vs_velocity_t){1.0, 360.01}));
	expect_warning(111, "setAcceleration refused: out of limits");
	assert_false(vs_setAcceleration(&V, (vs_velocity_t){1.0, NAN}));
	expect_warning(110, "setAcceleration refused: invalid argument");
	assert_false(vs_setAcceleration(&V, (vs_velocity_t){-INFINITY, 1.0}));
	expect_warning(110, "setAcceleration refused: invalid argument");
	assert_true(V.acc_set.translation == 1.0 && V.acc_set.rotation == 1.0);
}

static void test_set_jog_timeout(void **state)
{
	(void)state;
	assert_true(vs_setJogTimeout(&V, 1));
	assert_true(vs_setJogTimeout(&V, INT16_MAX));
	assert_int_equal(V.jog_timeout_ms, INT16_MAX);
	assert_false(vs_setJogTimeout(&V, 0));
	expect_warning(111, "setJogTimeout refused: out of limits");
	assert_false(vs_setJogTimeout(&V, -1));
	assert_false(vs_setJogTimeout(&V, INT16_MIN));
	assert_int_equal(V.jog_timeout_ms, INT16_MAX);
}

static void test_always_true_ops(void **state)
{
	(void)state;
	/* In the Unpowered state, where nothing can move. */
	assert_true(vs_pause(&V));
	assert_true(vs_resume(&V));
	assert_true(vs_stop(&V));
	assert_true(vs_unlock(&V));
	assert_true(vs_clearAlarm(&V));
	assert_true(vs_setDigitalSensorLock(&V, true));
	assert_true(vs_setDigitalSensorLock(&V, false));
	assert_true(vs_setJoystick(&V, true));
	assert_true(vs_setJoystick(&V, false));
	assert_true(vs_setPosition(&V, (vs_position_t){1.0, 2.0, 3.0}));
	assert_int_equal(alarm_count(), 0);
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
}

/* ---- position ----------------------------------------------------------- */

static void expect_pos(double x, double y, double th)
{
	vs_position_t p;
	assert_true(vs_getPosition(&V, &p));
	assert_true(fabs(p.x - x) < 1e-6);
	assert_true(fabs(p.y - y) < 1e-6);
	assert_true(fabs(p.theta - th) < 1e-6);
}

static void test_set_get_position(void **state)
{
	(void)state;
	expect_pos(0, 0, 0);
	assert_true(vs_setPosition(&V, (vs_position_t){1500.25, -320.5, 90.0}));
	expect_pos(1500.25, -320.5, 90.0);
	/* theta is reported in (-180, 180]. */
	assert_true(vs_setPosition(&V, (vs_position_t){0, 0, 180.0}));
	expect_pos(0, 0, 180.0);
	assert_true(vs_setPosition(&V, (vs_position_t){0, 0, -180.0}));
	expect_pos(0, 0, 180.0);
	assert_true(vs_setPosition(&V, (vs_position_t){0, 0, 190.0}));
	expect_pos(0, 0, -170.0);
	assert_true(vs_setPosition(&V, (vs_position_t){0, 0, -725.0}));
	expect_pos(0, 0, -5.0);
	assert_true(vs_setPosition(&V, (vs_position_t){-1e6, 1e6, 36000.0}));
	expect_pos(-1e6, 1e6, 0.0);
	/* Refused: not finite or out of range; the pose keeps its value. */
	assert_true(vs_setPosition(&V, (vs_position_t){10, 20, 30}));
	const vs_position_t bad[] = {{NAN, 0, 0},     {0, INFINITY, 0}, {0, 0, -INFINITY},
				     {1e6 + 1, 0, 0}, {0, -2e6, 0},	{0, 0, 36000.5}};
	for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		assert_false(vs_setPosition(&V, bad[i]));
		expect_warning(110, "setPosition refused: invalid argument");
		expect_pos(10, 20, 30);
	}
	/* The motion engine's reference moves with it. */
	assert_true(V.motion.ref.x_mm == V.odom.x_mm);
	/* Ticks while idle keep the pose. */
	fake_run(&F, &V, 10);
	expect_pos(10, 20, 30);
}

static void test_odometry_pushed_by_hand(void **state)
{
	(void)state;
	/* Servo off: wheels turned by hand still count. One wheel revolution
	 * (16384 counts) of 150 mm is 471.2389 mm. The first sample after
	 * start-up is the origin, whatever the counts are. */
	F.counts[0] = -123456;
	F.counts[1] = INT32_MAX - 5000; /* wraps below */
	fake_run(&F, &V, 1);
	expect_pos(0, 0, 0);
	F.counts[0] += 16384;
	F.counts[1] = (int32_t)((uint32_t)F.counts[1] + 16384u);
	fake_run(&F, &V, 1);
	vs_position_t p;
	assert_true(vs_getPosition(&V, &p));
	assert_true(fabs(p.x - 471.238898) < 1e-3);
	assert_true(fabs(p.y) < 1e-6);
	assert_true(fabs(p.theta) < 1e-6);
	/* Opposite wheels: rotation in place. Right wheel forward by d turns
	 * CCW by d / (T/2) rad. */
	F.counts[0] -= 1000;
	F.counts[1] += 1000;
	fake_run(&F, &V, 1);
	assert_true(vs_getPosition(&V, &p));
	double d_mm = 1000.0 * M_PI * 150.0 / 16384.0;
	assert_true(fabs(p.theta - d_mm / 200.0 * 180.0 / M_PI) < 1e-4);
	assert_true(fabs(p.x - 471.238898) < 1e-3);
	/* Nothing was commanded. */
	assert_int_equal(F.cmd_cps_q8[0], 0);
}

/* ---- argument checks ---------------------------------------------------- */

static void test_bad_arguments_refused(void **state)
{
	(void)state;
	power_up();
	const double bad[] = {NAN, INFINITY, -INFINITY, 1e6 + 0.001, -1e7, 1e300};
	for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
		double b = bad[i];
		assert_false(vs_moveForward(&V, b));
		expect_warning(110, "moveForward refused: invalid argument");
		assert_false(vs_moveLinearRel(&V, (vs_position_t){b, 0, 0}));
		expect_warning(110, "moveLinearRel refused: invalid argument");
		assert_false(vs_moveLinearRel(&V, (vs_position_t){0, b, 0}));
		assert_false(vs_moveLinearAbs(&V, (vs_position_t){0, b, 0}));
		expect_warning(110, "moveLinearAbs refused: invalid argument");
		assert_false(vs_moveContinuousRel(&V, (vs_position_t){b, 0, 0}));
		expect_warning(110, "moveContinuousRel refused: invalid argument");
		assert_false(vs_moveCruiseAbs(&V, (vs_point_t){0, b}));
		expect_warning(110, "moveCruiseAbs refused: invalid argument");
		assert_false(vs_moveCircularRel(&V, (vs_point_t){0, b}, 10.0));
		expect_warning(110, "moveCircularRel refused: invalid argument");
		assert_false(vs_moveCircularRel(&V, (vs_point_t){b, 0}, 10.0));
		expect_warning(110, "moveCircularRel refused: invalid argument");
	}
	const double bad_angle[] = {NAN, INFINITY, -INFINITY, 36000.001, -1e9};
	for (unsigned i = 0; i < sizeof bad_angle / sizeof bad_angle[0]; i++) {
		double b = bad_angle[i];
		assert_false(vs_moveTurn(&V, b));
		expect_warning(110, "moveTurn refused: invalid argument");
		assert_false(vs_moveLinearRel(&V, (vs_position_t){0, 0, b}));
		assert_false(vs_moveLinearAbs(&V, (vs_position_t){0, 0, b}));
		assert_false(vs_moveContinuousRel(&V, (vs_position_t){0, 0, b}));
		assert_false(vs_moveCircularRel(&V, (vs_point_t){0, 100}, b));
		expect_warning(110, "moveCircularRel refused: invalid argument");
	}
	const double bad_vel[] = {NAN, INFINITY, -INFINITY};
	for (unsigned i = 0; i < 3; i++) {
		assert_false(vs_moveJog(&V, bad_vel[i], 0, 0));
		expect_warning(110, "moveJog refused: invalid argument");
		assert_false(vs_moveJog(&V, 0, bad_vel[i], 0));
		assert_false(vs_moveJog(&V, 0, 0, bad_vel[i]));
		expect_warning(110, "moveJog refused: invalid argument");
	}
	expect_no_motion();
	expect_pos(0, 0, 0);
	/* Warnings only: the unit is idle and Ready apart from them. */
	expect_state(VS_STATE_WARNING, "Warning-110");
}

static void test_jog_limits(void **state)
{
	(void)state;
	power_up();
	assert_false(vs_moveJog(&V, 1000.001, 0, 0));
	expect_warning(111, "moveJog refused: out of limits");
	assert_false(vs_moveJog(&V, -1000.001, 0, 0));
	assert_false(vs_moveJog(&V, 0, 0, 180.001));
	assert_false(vs_moveJog(&V, 0, 0, -181));
	expect_warning(111, "moveJog refused: out of limits");
	assert_false(vs_moveJog(&V, 0, 1001, 0));
	expect_warning(111, "moveJog refused: out of limits");
	/* y motion on a differential base. */
	assert_false(vs_moveJog(&V, 0, 10.0, 0));
	expect_warning(112, "moveJog refused: not possible on this base");
	assert_false(vs_moveJog(&V, 100.0, -0.5, 0));
	expect_warning(112, "moveJog refused: not possible on this base");
	expect_no_motion();
}

static void test_circular_center_x(void **state)
{
	(void)state;
	power_up();
	assert_false(vs_moveCircularRel(&V, (vs_point_t){1.0, 500.0}, 90.0));
	expect_warning(112, "moveCircularRel refused: not possible on this base");
	assert_false(vs_moveCircularRel(&V, (vs_point_t){-0.001, 500.0}, 90.0));
	expect_warning(112, "moveCircularRel refused: not possible on this base");
	expect_no_motion();
}

/* ---- refusal by state --------------------------------------------------- */

static void test_moves_refused_unpowered(void **state)
{
	(void)state;
	expect_all_moves_refused(121, "servo off");
	expect_state(VS_STATE_UNPOWERED, "Unpowered");
}

static void test_moves_refused_servo_off(void **state)
{
	(void)state;
	assert_true(vs_setPower(&V, true));
	expect_all_moves_refused(121, "servo off");
	expect_state(VS_STATE_POWERED, "Powered");
}

static void test_moves_refused_fault(void **state)
{
	(void)state;
	power_up();
	F.fault_code[1] = 0x2310;
	fake_run(&F, &V, 1);
	expect_fault(201, "drive 1 fault 0x2310");
	expect_state(VS_STATE_ALARM, "Alarm-201");
	expect_servo_off();
	expect_all_moves_refused(123, "fault active");
	/* Still the fault names the state. */
	expect_state(VS_STATE_ALARM, "Alarm-201");
	/* clearAlarm resets the drive; servo on again; moves accepted. */
	assert_true(vs_clearAlarm(&V));
	assert_int_equal(F.fault_code[1], 0);
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_POWERED, "Powered");
	assert_true(vs_setServo(&V, true));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_READY, "Ready");
	assert_true(vs_moveForward(&V, 10.0));
}

static void test_moves_refused_locked(void **state)
{
	(void)state;
	power_up();
	/* Contact sensor disabled: nothing happens. */
	F.contact = true;
	fake_run(&F, &V, 2);
	expect_state(VS_STATE_READY, "Ready");
	F.contact = false;
	fake_run(&F, &V, 1);
	assert_true(vs_setDigitalSensorLock(&V, true));
	F.contact = true;
	fake_run(&F, &V, 1);
	expect_warning(150, "contact detected");
	expect_state(VS_STATE_LOCKED, "Locked");
	assert_true(V.servo); /* a lock is no fault */
	expect_all_moves_refused(124, "unit locked");
	expect_state(VS_STATE_LOCKED, "Locked");
	/* unlock while still pressed: the unit may back away (edge-triggered). */
	assert_true(vs_unlock(&V));
	fake_run(&F, &V, 3);
	expect_state(VS_STATE_WARNING, "Warning-124");
	assert_true(vs_clearAlarm(&V));
	expect_state(VS_STATE_READY, "Ready");
	/* A new contact locks again. */
	F.contact = false;
	fake_run(&F, &V, 1);
	F.contact = true;
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_LOCKED, "Locked");
	expect_warning(150, "contact detected");
}

static void test_moves_refused_stuck(void **state)
{
	(void)state;
	power_up();
	F.obstacle = true;
	fake_run(&F, &V, 1);
	expect_warning(151, "obstacle detected");
	expect_state(VS_STATE_STUCK, "Stuck");
	expect_all_moves_refused(130, "unit stuck");
	expect_state(VS_STATE_STUCK, "Stuck");
	/* Clears when the input clears; the warnings remain until clearAlarm. */
	F.obstacle = false;
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_WARNING, "Warning-130");
	assert_true(vs_clearAlarm(&V));
	expect_state(VS_STATE_READY, "Ready");
	assert_true(vs_moveTurn(&V, 5.0));
}

static void test_moves_refused_joystick(void **state)
{
	(void)state;
	power_up();
	assert_true(vs_setJoystick(&V, true));
	fake_run(&F, &V, 1);
	expect_all_moves_refused(131, "joystick in use");
	assert_true(vs_setJoystick(&V, false));
	fake_run(&F, &V, 1);
	assert_true(vs_moveForward(&V, 10.0));
}

static void test_joystick_lost(void **state)
{
	(void)state;
	power_up();
	assert_true(vs_setJoystick(&V, true));
	fake_run(&F, &V, 2);
	assert_int_equal(alarm_count(), 0);
	F.js.present = false;
	fake_run(&F, &V, 1);
	expect_warning(152, "joystick lost");
	assert_false(V.joystick_on);
	/* Back again: the joystick stays off until the host asks for it. */
	F.js.present = true;
	F.js.axis[0] = 30000;
	fake_run(&F, &V, 50);
	assert_int_equal(F.cmd_cps_q8[0], 0);
	assert_int_equal(alarm_count(), 1);
	assert_true(vs_moveForward(&V, 10.0));
}

static void test_joystick_absent(void **state)
{
	(void)state;
	static vehicle_t v2;
	vs_config_t c = C;
	c.has_joystick = false;
	vs_hal_ops_t ops = fake_hal_ops;
	ops.joystick = NULL;
	vs_hal_t h = {&ops, &F};
	assert_int_equal(vehicle_init(&v2, &c, &h, NULL), 0);
	assert_true(vs_setJoystick(&v2, true));
	F.now_us += 1000;
	vehicle_tick(&v2, F.now_us);
	assert_false(v2.joystick_on);
	assert_int_equal(v2.alarms.a[0].code, 152);
}

/* ---- supervision -------------------------------------------------------- */

static void test_estop(void **state)
{
	(void)state;
	power_up();
	F.estop = true;
	fake_run(&F, &V, 1);
	expect_fault(208, "emergency stop");
	expect_state(VS_STATE_ALARM, "Alarm-208");
	expect_servo_off();
	fake_run(&F, &V, 5);
	assert_int_equal(alarm_count(), 1);
	/* Still pressed: clearing it brings it straight back. */
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_ALARM, "Alarm-208");
	F.estop = false;
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_POWERED, "Powered");
}

static void test_drive_fault_text(void **state)
{
	(void)state;
	power_up();
	F.fault_code[0] = 0x00AB;
	fake_run(&F, &V, 3);
	expect_fault(201, "drive 0 fault 0x00AB");
	assert_int_equal(alarm_count(), 1);
	/* A second drive's fault is listed too, newest first. */
	F.fault_code[1] = 0x7F01;
	fake_run(&F, &V, 1);
	expect_fault(201, "drive 1 fault 0x7F01");
	fake_run(&F, &V, 5);
	expect_fault(201, "drive 1 fault 0x7F01");
	assert_int_equal(alarm_count(), 1);
	/* Cleared while both persist: both come back, one after the other. */
	assert_true(vs_clearAlarm(&V));
	F.fault_code[0] = 0x00AB;
	F.fault_code[1] = 0x7F01;
	fake_run(&F, &V, 3);
	expect_fault(201, "drive 1 fault 0x7F01");
	assert_int_equal(alarm_count(), 1);
	/* Drive faults while unpowered are not supervised. */
	assert_true(vs_setPower(&V, false));
	assert_true(vs_clearAlarm(&V));
	F.fault_code[0] = 0x1234;
	fake_run(&F, &V, 3);
	assert_int_equal(alarm_count(), 0);
}

static void test_drive_timeout(void **state)
{
	(void)state;
	power_up();
	F.silent[1] = true;
	fake_run(&F, &V, 50); /* 50 ms of silence is allowed */
	assert_int_equal(alarm_count(), 0);
	fake_run(&F, &V, 1);
	expect_fault(202, "drive 1 not answering");
	expect_servo_off();
	fake_run(&F, &V, 10);
	assert_int_equal(alarm_count(), 1);
	/* Replies back: clearAlarm clears it for good. */
	F.silent[1] = false;
	fake_run(&F, &V, 1);
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 100);
	expect_state(VS_STATE_POWERED, "Powered");
	/* Silence while unpowered is expected (drives lose their supply). */
	assert_true(vs_setPower(&V, false));
	F.silent[0] = true;
	fake_run(&F, &V, 200);
	assert_int_equal(alarm_count(), 0);
}

static void test_following_error(void **state)
{
	(void)state;
	power_up();
	/* 50 mm is 1738.6 counts: a 1700-count disturbance is tolerated and
	 * the position loop pulls it back. */
	F.counts[0] += 1700;
	fake_run(&F, &V, 1);
	assert_int_equal(alarm_count(), 0);
	assert_true(F.cmd_cps_q8[0] < 0);
	fake_run(&F, &V, 2000);
	assert_int_equal(alarm_count(), 0);
	/* 1800 counts beyond the reference is a fault (the hold left the
	 * wheel a fraction of a count past its reference: 1799 and a bit). */
	F.counts[1] -= 1800;
	fake_run(&F, &V, 1);
	expect_fault(204, "following error 1799 counts");
	expect_servo_off();
	expect_state(VS_STATE_ALARM, "Alarm-204");
}

static void test_encoder_stuck(void **state)
{
	(void)state;
	power_up();
	/* The loop commands the wheel back; its encoder does not move. */
	F.frozen[0] = true;
	F.counts[0] += 1500;
	/* The hold ramps the setpoint at the set acceleration (docs/states.md):
	 * it passes the stuck threshold on its fourth tick, so the fault
	 * comes encoder_stuck_ms after that. */
	fake_run(&F, &V, 302);
	assert_int_equal(alarm_count(), 0);
	assert_true(F.cmd_cps_q8[0] < 0);
	fake_run(&F, &V, 2);
	expect_fault(203, "encoder 0 stuck");
	expect_servo_off();
}

static void test_battery_thresholds(void **state)
{
	(void)state;
	power_up();
	F.battery_mv = 22000; /* at the threshold: fine */
	fake_run(&F, &V, 1);
	assert_int_equal(alarm_count(), 0);
	F.battery_mv = 21900;
	fake_run(&F, &V, 1);
	expect_warning(140, "battery below 22.0 V");
	expect_state(VS_STATE_WARNING, "Warning-140");
	assert_true(V.servo); /* a warning does not stop anything */
	/* Once per crossing. */
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 100);
	assert_int_equal(alarm_count(), 0);
	F.battery_mv = 22050; /* inside the hysteresis: not re-armed */
	fake_run(&F, &V, 1);
	F.battery_mv = 21950;
	fake_run(&F, &V, 1);
	assert_int_equal(alarm_count(), 0);
	F.battery_mv = 24000;
	fake_run(&F, &V, 1);
	F.battery_mv = 21000;
	fake_run(&F, &V, 1);
	expect_warning(140, "battery below 22.0 V");
	assert_int_equal(alarm_count(), 1);
	/* Critical: a fault, held while the battery stays low. */
	F.battery_mv = 19999;
	fake_run(&F, &V, 1);
	expect_fault(207, "battery below 20.0 V");
	expect_state(VS_STATE_ALARM, "Alarm-207");
	expect_servo_off();
	fake_run(&F, &V, 10);
	assert_int_equal(alarm_count(), 2);
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 1);
	expect_fault(207, "battery below 20.0 V");
	F.battery_mv = 20000;
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_POWERED, "Powered");
}

/* setPower(true) may wait up to 50 ms for the relay (hal.h) between two
 * ticks: the next tick is not late, a stall after it still is. */
static void test_stall_not_after_relay_wait(void **state)
{
	(void)state;
	fake_run(&F, &V, 3);
	assert_true(vs_setPower(&V, true));
	F.now_us += 51000; /* the command's wait, then the tick */
	vehicle_tick(&V, F.now_us);
	vs_diag_t d;
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 0);
	assert_int_equal(alarm_count(), 0);
	F.now_us += 1000;
	vehicle_tick(&V, F.now_us);
	F.now_us += 21001;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 1);
	assert_int_equal(d.max_late_us, 20001);
	expect_fault(210, "control loop stalled 20 ms");
}

/* Lateness is counted; only a stall over loop_late_ms (20 ms) is a fault. */
static void test_late_ticks(void **state)
{
	(void)state;
	power_up();
	vs_diag_t d;
	/* 1.5 periods after the previous tick is on time. */
	F.now_us += 1500;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 0);
	assert_int_equal(d.max_late_us, 0);
	F.now_us += 1501;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 1);
	assert_int_equal(d.max_late_us, 501);
	assert_int_equal(d.overruns, 0);
	assert_int_equal(alarm_count(), 0);
	/* Exactly loop_late_ms late: counted, the unit stays on. */
	F.now_us += 21000;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 2);
	assert_int_equal(d.max_late_us, 20000);
	assert_int_equal(alarm_count(), 0);
	expect_state(VS_STATE_READY, "Ready");
	/* One microsecond more is a stall. */
	F.now_us += 21001;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 3);
	assert_int_equal(d.max_late_us, 20001);
	expect_fault(210, "control loop stalled 20 ms");
	expect_servo_off();
	/* The clock wraps without a false late tick. */
	assert_true(vs_clearAlarm(&V));
	F.now_us = UINT32_MAX - 400;
	vehicle_tick(&V, F.now_us); /* a jump backwards is not late */
	F.now_us += 1000;	    /* wraps past zero */
	vehicle_tick(&V, F.now_us);
	fake_run(&F, &V, 3);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 3);
	assert_int_equal(alarm_count(), 0);
	/* Late across the wrap. */
	F.now_us = UINT32_MAX - 100;
	vehicle_tick(&V, F.now_us);
	F.now_us += 5000;
	vehicle_tick(&V, F.now_us);
	vehicle_diag(&V, &d);
	assert_int_equal(d.late_ticks, 4);
	assert_int_equal(d.max_late_us, 20001);
	assert_int_equal(alarm_count(), 0);
}

/* The loop's own work over a period is the overrun fault, however on time
 * the ticks came. */
static void test_overrun(void **state)
{
	(void)state;
	power_up();
	vs_diag_t d;
	vehicle_tick_busy(&V, 1000);
	vehicle_diag(&V, &d);
	assert_int_equal(d.overruns, 0);
	assert_int_equal(alarm_count(), 0);
	vehicle_tick_busy(&V, 1001);
	vehicle_diag(&V, &d);
	assert_int_equal(d.overruns, 1);
	assert_int_equal(d.late_ticks, 0);
	expect_fault(209, "control tick overrun");
	expect_servo_off();
}

static void test_caution_input(void **state)
{
	(void)state;
	power_up();
	assert_true(V.motion.cap_t_pt == 0);
	F.caution = true;
	fake_run(&F, &V, 1);
	/* 200 mm/s at 1 kHz: 0.2 mm per tick. */
	assert_true(llabs(V.motion.cap_t_pt - (q32_t)(0.2 * 4294967296.0)) < 2);
	expect_state(VS_STATE_READY, "Ready");
	F.caution = false;
	fake_run(&F, &V, 1);
	assert_true(V.motion.cap_t_pt == 0);
}

static void test_warnings_do_not_block(void **state)
{
	(void)state;
	power_up();
	assert_false(vs_setVelocity(&V, (vs_velocity_t){-1, 1}));
	assert_false(vs_getInput(&V, 0, &(uint32_t){0}));
	expect_state(VS_STATE_WARNING, "Warning-126");
	assert_true(vs_moveTurn(&V, 30.0));
	assert_int_equal(alarm_count(), 2);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup(f, setup)
	const struct CMUnitTest tests[] = {
	    T(test_init_unpowered),
	    T(test_init_rejects),
	    T(test_constant_queries),
	    T(test_battery_voltage),
	    T(test_power_on_off),
	    T(test_power_relay_failure),
	    T(test_power_lost),
	    T(test_servo_table8),
	    T(test_state_codes),
	    T(test_state_code_padding),
	    T(test_active_alarm_counts),
	    T(test_clear_alarm_resets_drives),
	    T(test_get_input),
	    T(test_set_output),
	    T(test_servo_status_axes),
	    T(test_set_velocity),
	    T(test_set_acceleration),
	    T(test_set_jog_timeout),
	    T(test_always_true_ops),
	    T(test_set_get_position),
	    T(test_odometry_pushed_by_hand),
	    T(test_bad_arguments_refused),
	    T(test_jog_limits),
	    T(test_circular_center_x),
	    T(test_moves_refused_unpowered),
	    T(test_moves_refused_servo_off),
	    T(test_moves_refused_fault),
	    T(test_moves_refused_locked),
	    T(test_moves_refused_stuck),
	    T(test_moves_refused_joystick),
	    T(test_joystick_lost),
	    T(test_joystick_absent),
	    T(test_estop),
	    T(test_drive_fault_text),
	    T(test_drive_timeout),
	    T(test_following_error),
	    T(test_encoder_stuck),
	    T(test_battery_thresholds),
	    T(test_overrun),
	    T(test_stall_not_after_relay_wait),
	    T(test_late_ticks),
	    T(test_caution_input),
	    T(test_warnings_do_not_block),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
