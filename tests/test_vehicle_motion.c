/* VehicleService with the motion engine running on the fake plant: Busy,
 * pause/resume, stop, queueing, refusals while moving, and that no state
 * change restarts motion by itself. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
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
	if (vehicle_init(&V, &C, &h, NULL) != 0)
		return -1;
	if (!vs_setPower(&V, true) || !vs_setServo(&V, true))
		return -1;
	fake_run(&F, &V, 1);
	return 0;
}

static void expect_state(int16_t code, const char *msg)
{
	int16_t s = 0;
	char m[VS_STATE_MSG_MAX];
	assert_true(vs_getState(&V, &s, m));
	assert_string_equal(m, msg);
	assert_int_equal(s, code);
}

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

static int16_t alarm_count(void)
{
	int16_t n = -1;
	assert_true(vs_getActiveAlarm(&V, 0, &n, NULL, NULL));
	return n;
}

/* At rest: the wheel loop only dithers by a count around a reference that
 * lies between two encoder counts (below 50 counts/s = 1.4 mm/s). */
static bool wheels_still(void)
{
	const int32_t lim = 50 * 256;
	return abs(F.cmd_cps_q8[0]) < lim && abs(F.cmd_cps_q8[1]) < lim;
}

/* Ticks until the unit has no motion work left (bounded). */
static unsigned run_until_idle(unsigned max)
{
	for (unsigned i = 0; i < max; i++) {
		fake_run(&F, &V, 1);
		if (!motion_has_work(&V.motion))
			return i + 1;
	}
	return max;
}

static vs_position_t pos(void)
{
	vs_position_t p;
	assert_true(vs_getPosition(&V, &p));
	return p;
}

static void test_forward_busy_ready(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 500.0));
	expect_state(VS_STATE_BUSY, "Busy");
	fake_run(&F, &V, 10);
	expect_state(VS_STATE_BUSY, "Busy");
	assert_true(F.cmd_cps_q8[0] > 0 && F.cmd_cps_q8[1] > 0);
	unsigned n = run_until_idle(10000);
	assert_true(n < 10000);
	fake_run(&F, &V, 200); /* wheel loop settles */
	expect_state(VS_STATE_READY, "Ready");
	vs_position_t p = pos();
	assert_true(fabs(p.x - 500.0) < 0.5);
	assert_true(fabs(p.y) < 0.5);
	assert_true(fabs(p.theta) < 0.1);
	assert_int_equal(alarm_count(), 0);
}

/* In position: after the reference's last step the unit stays Busy, and
 * Ready-only moves are refused, until every wheel has been within the
 * window (0.05 mm) for the window time (20 ms = 20 ticks): on this drive,
 * which follows at once, the wheels are there with the reference. */
static void test_ready_after_the_window_time(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 100.0));
	unsigned n = run_until_idle(10000);
	assert_true(n < 10000);
	/* the last reference tick was the window's first */
	for (unsigned k = 1; k < 19; k++) {
		expect_state(VS_STATE_BUSY, "Busy");
		fake_run(&F, &V, 1);
	}
	assert_false(vs_moveForward(&V, 10.0));
	expect_newest(120, VS_ALARM_WARNING, "moveForward refused: unit not ready");
	assert_true(vs_clearAlarm(&V));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_READY, "Ready");
	assert_true(fabs(pos().x - 100.0) <= 0.05); /* the window */
}

/* A wheel that does not reach its reference (its encoder stops 1 mm before
 * the end, far below the following-error limit): Busy until
 * settle_timeout_ms after the reference stopped (100 ms here: below the
 * 300 ms after which a wheel commanded to move and not moving is fault
 * 203), then warning 154 once; the wheel freed, it settles and the unit
 * takes new work. */
static void test_not_in_position_warns(void **state)
{
	(void)state;
	C.settle_timeout_ms = 100;
	vs_hal_t h = fake_hal_bind(&F);
	assert_int_equal(vehicle_init(&V, &C, &h, NULL), 0);
	assert_true(vs_setPower(&V, true) && vs_setServo(&V, true));
	assert_true(vs_moveForward(&V, 100.0));
	while (pos().x < 99.0)
		fake_run(&F, &V, 1);
	F.frozen[0] = true;
	assert_true(run_until_idle(10000) < 10000);
	fake_run(&F, &V, 99);
	expect_state(VS_STATE_BUSY, "Busy");
	assert_int_equal(alarm_count(), 0);
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_WARNING, "Warning-154");
	vs_alarm_t a[1];
	int16_t n = 0;
	uint16_t len = 0;
	assert_true(vs_getActiveAlarm(&V, 1, &n, a, &len));
	assert_int_equal(a[0].code, 154);
	assert_memory_equal(a[0].source, "not in position: ", 17);
	fake_run(&F, &V, 100);
	assert_int_equal(alarm_count(), 1); /* once */
	F.frozen[0] = false;
	fake_run(&F, &V, 500);			    /* kp 20/s: 1 mm to well under a count */
	assert_true(fabs(pos().x - 100.0) <= 0.05); /* the window */
	assert_true(vs_moveForward(&V, -50.0));
	assert_int_equal(alarm_count(), 1);
}

static void test_turn(void **state)
{
	(void)state;
	assert_true(vs_moveTurn(&V, 90.0));
	assert_true(run_until_idle(20000) < 20000);
	fake_run(&F, &V, 200);
	vs_position_t p = pos();
	assert_true(fabs(p.theta - 90.0) < 0.1);
	assert_true(fabs(p.x) < 0.5 && fabs(p.y) < 0.5);
}

static void test_ready_only_refused_while_busy(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 300.0));
	fake_run(&F, &V, 50);
	assert_false(vs_moveTurn(&V, 10.0));
	expect_newest(120, VS_ALARM_WARNING, "moveTurn refused: unit not ready");
	assert_false(vs_moveForward(&V, 10.0));
	expect_newest(120, VS_ALARM_WARNING, "moveForward refused: unit not ready");
	assert_false(vs_moveLinearRel(&V, (vs_position_t){10, 0, 0}));
	assert_false(vs_moveCircularRel(&V, (vs_point_t){0, 100}, 10));
	expect_newest(120, VS_ALARM_WARNING, "moveCircularRel refused: unit not ready");
	/* A warning does not show while Busy. */
	expect_state(VS_STATE_BUSY, "Busy");
	/* Servo-on commands queue behind it. */
	uint8_t q0 = motion_queue_len(&V.motion);
	assert_true(vs_moveLinearAbs(&V, (vs_position_t){300.0, 300.0, 90.0}));
	assert_int_equal(motion_queue_len(&V.motion), q0 + 1);
	/* A refused call never loses queued work. */
	assert_false(vs_moveLinearAbs(&V, (vs_position_t){NAN, 0, 0}));
	assert_false(vs_moveTurn(&V, 5.0));
	assert_int_equal(motion_queue_len(&V.motion), q0 + 1);
	assert_true(run_until_idle(30000) < 30000);
	fake_run(&F, &V, 300);
	vs_position_t p = pos();
	assert_true(fabs(p.x - 300.0) < 1.0);
	assert_true(fabs(p.y - 300.0) < 1.0);
	assert_true(fabs(p.theta - 90.0) < 0.2);
	expect_state(VS_STATE_WARNING, "Warning-120");
}

static void test_pause_idle_and_queue(void **state)
{
	(void)state;
	assert_true(vs_pause(&V));
	expect_state(VS_STATE_PAUSED, "Paused");
	assert_false(vs_moveForward(&V, 100.0));
	expect_newest(120, VS_ALARM_WARNING, "moveForward refused: unit not ready");
	assert_false(vs_moveJog(&V, 100.0, 0, 0));
	expect_newest(129, VS_ALARM_WARNING, "moveJog refused: unit paused");
	assert_true(vs_moveLinearAbs(&V, (vs_position_t){200.0, 0.0, 0.0}));
	assert_true(vs_moveCruiseAbs(&V, (vs_point_t){400.0, 0.0}));
	assert_int_equal(motion_queue_len(&V.motion), 2);
	fake_run(&F, &V, 500);
	assert_true(wheels_still());
	expect_state(VS_STATE_PAUSED, "Paused");
	/* setAcceleration is allowed while paused at rest. */
	assert_true(vs_setAcceleration(&V, (vs_velocity_t){800.0, 300.0}));
	assert_true(vs_resume(&V));
	fake_run(&F, &V, 5);
	expect_state(VS_STATE_BUSY, "Busy");
	assert_true(run_until_idle(20000) < 20000);
	fake_run(&F, &V, 300);
	assert_true(fabs(pos().x - 400.0) < 1.0);
}

static void test_pause_while_moving(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 1000.0));
	fake_run(&F, &V, 600);
	assert_false(vs_setAcceleration(&V, (vs_velocity_t){800.0, 300.0}));
	expect_newest(122, VS_ALARM_WARNING, "setAcceleration refused: unit moving");
	/* setVelocity is taken while moving. */
	assert_true(vs_setVelocity(&V, (vs_velocity_t){400.0, 90.0}));
	assert_true(vs_pause(&V));
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_BUSY, "Busy"); /* still decelerating */
	fake_run(&F, &V, 1500);
	expect_state(VS_STATE_PAUSED, "Paused");
	double x = pos().x;
	assert_true(x > 100.0 && x < 1000.0);
	fake_run(&F, &V, 500);
	assert_true(fabs(pos().x - x) < 0.1);
	assert_true(vs_resume(&V));
	assert_true(run_until_idle(20000) < 20000);
	fake_run(&F, &V, 300);
	assert_true(fabs(pos().x - 1000.0) < 1.0);
}

static void test_stop_discards(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 2000.0));
	assert_true(vs_moveLinearAbs(&V, (vs_position_t){0, 0, 0}));
	fake_run(&F, &V, 800);
	assert_true(vs_stop(&V));
	assert_int_equal(motion_queue_len(&V.motion), 0);
	assert_true(run_until_idle(5000) < 5000);
	fake_run(&F, &V, 300);
	expect_state(VS_STATE_READY, "Ready");
	double x = pos().x;
	assert_true(x > 100.0 && x < 2000.0);
	fake_run(&F, &V, 1000);
	assert_true(fabs(pos().x - x) < 0.1);
	assert_true(wheels_still());
}

static void test_fault_halts_and_does_not_restart(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 2000.0));
	fake_run(&F, &V, 500);
	assert_false(wheels_still());
	F.estop = true;
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_ALARM, "Alarm-208");
	assert_true(wheels_still());
	assert_false(motion_has_work(&V.motion));
	assert_false(F.enabled[0] || F.enabled[1]);
	F.estop = false;
	assert_true(vs_clearAlarm(&V));
	assert_true(vs_setServo(&V, true));
	fake_run(&F, &V, 1000);
	expect_state(VS_STATE_READY, "Ready");
	assert_true(wheels_still());
}

static void test_contact_locks_while_moving(void **state)
{
	(void)state;
	assert_true(vs_setDigitalSensorLock(&V, true));
	assert_true(vs_moveForward(&V, 2000.0));
	assert_true(vs_moveLinearAbs(&V, (vs_position_t){0, 0, 0}));
	fake_run(&F, &V, 800);
	F.contact = true;
	fake_run(&F, &V, 1);
	/* braking: Busy; Locked once stopped and in position */
	expect_state(VS_STATE_BUSY, "Busy");
	assert_int_equal(motion_queue_len(&V.motion), 0);
	run_until_idle(5000);
	fake_run(&F, &V, 30);
	expect_state(VS_STATE_LOCKED, "Locked");
	fake_run(&F, &V, 300);
	double x = pos().x;
	assert_true(vs_unlock(&V));
	F.contact = false;
	fake_run(&F, &V, 1000);
	expect_state(VS_STATE_WARNING, "Warning-150");
	assert_true(fabs(pos().x - x) < 0.1);
	assert_true(wheels_still());
}

static void test_obstacle_stuck_while_moving(void **state)
{
	(void)state;
	assert_true(vs_moveForward(&V, 2000.0));
	fake_run(&F, &V, 800);
	F.obstacle = true;
	fake_run(&F, &V, 1);
	expect_state(VS_STATE_BUSY, "Busy");
	run_until_idle(5000);
	fake_run(&F, &V, 300);
	expect_state(VS_STATE_STUCK, "Stuck");
	double x = pos().x;
	F.obstacle = false;
	fake_run(&F, &V, 1000);
	expect_state(VS_STATE_WARNING, "Warning-151");
	assert_true(fabs(pos().x - x) < 0.1);
	assert_false(motion_has_work(&V.motion));
}

static void test_queue_full(void **state)
{
	(void)state;
	assert_true(vs_pause(&V));
	for (int i = 0; i < MOTION_QUEUE_LEN; i++)
		assert_true(vs_moveLinearAbs(&V, (vs_position_t){10.0 * (i + 1), 0, 0}));
	assert_false(vs_moveLinearAbs(&V, (vs_position_t){999.0, 0, 0}));
	expect_newest(125, VS_ALARM_WARNING, "moveLinearAbs refused: queue full");
	assert_false(vs_moveCruiseAbs(&V, (vs_point_t){999.0, 0}));
	expect_newest(125, VS_ALARM_WARNING, "moveCruiseAbs refused: queue full");
	assert_int_equal(motion_queue_len(&V.motion), MOTION_QUEUE_LEN);
}

static void test_jog_and_timeout(void **state)
{
	(void)state;
	assert_true(vs_moveJog(&V, 200.0, 0.0, 0.0));
	fake_run(&F, &V, 100);
	expect_state(VS_STATE_BUSY, "Busy");
	assert_true(F.cmd_cps_q8[0] > 0);
	/* Re-sent within the timeout: keeps going. */
	assert_true(vs_moveJog(&V, 200.0, 0.0, 0.0));
	fake_run(&F, &V, 400);
	assert_true(F.cmd_cps_q8[0] > 0);
	/* No jog for longer than 500 ms: decelerates and stops. */
	fake_run(&F, &V, 1500);
	assert_false(motion_has_work(&V.motion));
	expect_state(VS_STATE_READY, "Ready");
	assert_true(wheels_still());
	/* All zero is a valid command. */
	assert_true(vs_moveJog(&V, 0.0, 0.0, 0.0));
	/* Negative values reverse. */
	assert_true(vs_moveJog(&V, -100.0, 0.0, -30.0));
	fake_run(&F, &V, 100);
	/* Backward and clockwise: the right wheel runs backward fastest. */
	assert_true(F.cmd_cps_q8[1] < 0);
	assert_true(F.cmd_cps_q8[1] < -abs(F.cmd_cps_q8[0]));
	/* Ready-only commands wait for the jog to end. */
	assert_false(vs_moveForward(&V, 10.0));
	expect_newest(120, VS_ALARM_WARNING, "moveForward refused: unit not ready");
}

static void test_joystick_drives(void **state)
{
	(void)state;
	assert_true(vs_setJoystick(&V, true));
	/* A stick held over at the hand-over drives nothing... */
	F.js.axis[0] = 32767;
	fake_run(&F, &V, 500);
	assert_true(wheels_still());
	/* ...until it has been seen at neutral. */
	F.js.axis[0] = 0;
	fake_run(&F, &V, 1);
	F.js.axis[0] = 32767;
	fake_run(&F, &V, 500);
	assert_true(F.cmd_cps_q8[0] > 0 && F.cmd_cps_q8[1] > 0);
	assert_false(vs_moveJog(&V, 10.0, 0, 0));
	expect_newest(131, VS_ALARM_WARNING, "moveJog refused: joystick in use");
	/* Inside the dead band: nothing. */
	assert_true(vs_setJoystick(&V, false));
	fake_run(&F, &V, 2000);
	assert_true(wheels_still());
	assert_true(vs_setJoystick(&V, true));
	F.js.axis[0] = 1000; /* 3 % < 5 % dead band */
	fake_run(&F, &V, 500);
	assert_true(wheels_still());
}

static void test_encoder_stuck_while_moving(void **state)
{
	(void)state;
	F.frozen[0] = true;
	assert_true(vs_moveForward(&V, 1000.0));
	fake_run(&F, &V, 450);
	expect_newest(203, VS_ALARM_FAULT, "encoder 0 stuck");
	expect_state(VS_STATE_ALARM, "Alarm-203");
	assert_true(wheels_still());
}

int main(void)
{
#define T(f) cmocka_unit_test_setup(f, setup)
	const struct CMUnitTest tests[] = {
	    T(test_forward_busy_ready),
	    T(test_turn),
	    T(test_ready_only_refused_while_busy),
	    T(test_pause_idle_and_queue),
	    T(test_pause_while_moving),
	    T(test_stop_discards),
	    T(test_fault_halts_and_does_not_restart),
	    T(test_ready_after_the_window_time),
	    T(test_not_in_position_warns),
	    T(test_contact_locks_while_moving),
	    T(test_obstacle_stuck_while_moving),
	    T(test_queue_full),
	    T(test_jog_and_timeout),
	    T(test_joystick_drives),
	    T(test_encoder_stuck_while_moving),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
