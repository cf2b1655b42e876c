/* Where modes meet: the regressions of an outside run against the state
 * machine (docs/states.md), each on the lockstep simulator through the
 * console as a host would drive it, on the default plant.
 *
 *   1. the joystick flag does not let a host route outlive its link;
 *   2. a path command queued behind a jog or goal does not survive the
 *      joystick taking over, and setJoystick(false) drives nothing;
 *   3. under the joystick, a stop and a fault hold until the stick has come
 *      back to neutral;
 *   4. the position hold is bounded by the set velocity and acceleration;
 *   5. a mecanum base's jog and joystick speed is a vector bound;
 *   6. stop ends a pause: Ready;
 *  11. servo on completes only when every drive reports enabled, else a
 *      fault naming the drive and its state; a drive leaving Operation
 *      enabled stops the unit; no wheel drives alone;
 *  12. a drive that restarted: the odometry keeps its pose, motion is
 *      refused until setPosition.
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

static int setup_base(bool omni)
{
	vs_config_t cfg;
	plant_params_t pp;
	vs_config_defaults(&cfg);
	if (omni) {
		cfg.kinematics = VS_KIN_OMNI;
		cfg.wheel_diameter_mm = 100;
		cfg.track_width_mm = 450;
		cfg.wheel_base_mm = 400;
	}
	plant_params_default(&pp);
	return sim_init(&S, &cfg, &pp);
}

static int setup_diff(void **state)
{
	(void)state;
	return setup_base(false);
}

static int setup_omni(void **state)
{
	(void)state;
	return setup_base(true);
}

static const char *ex(const char *line)
{
	if (!sim_exec(&S, line, rep, sizeof(rep)))
		return "(none)";
	return rep;
}

#define EXPECT(line, reply) assert_string_equal(ex(line), reply)

static double hz(void)
{
	return S.cfg.tick_hz;
}

static double q32(int64_t x)
{
	return (double)x / 4294967296.0;
}

/* Commanded translation speed (vector), mm/s. */
static double cmd_speed(void)
{
	return hypot(q32(S.vehicle.cmd.vx_pt), q32(S.vehicle.cmd.vy_pt)) * hz();
}

static double odom_x(void)
{
	return q32(S.vehicle.odom.x_mm);
}

static void ready(void)
{
	EXPECT("setPower true", "ok true");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* 1: a route, then setJoystick(true), then 20 s without a request: the
 * route ends where the hand-over's stop brings it (at 250 mm/s, braking at
 * the 1000 mm/s^2 limit: 31.25 mm; 31.15 mm measured with the plant's
 * lag), not 8 m on. */
static void test_joystick_flag_keeps_link_watchdog(void **state)
{
	(void)state;
	ready();
	EXPECT("moveForward 8000", "ok true");
	sim_run_ms(&S, 500); /* 500 ms at 500 mm/s^2: 250 mm/s, 62.5 mm */
	assert_true(fabs(cmd_speed() - 250.0) < 1e-3);
	double x0 = odom_x();
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 20000);
	assert_in_range((long)((odom_x() - x0) * 100), 3100, 3150);
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("getActiveAlarm 4", "ok true 0 0");
}

/* 2: a jog with a path command queued behind it; the joystick takes over:
 * the queue is gone (Ready at rest, no work), and setJoystick(false) drives
 * nothing. */
static void test_joystick_drops_queued_route(void **state)
{
	(void)state;
	ready();
	EXPECT("moveJog 200 0 0", "ok true");
	EXPECT("moveLinearAbs 1000 0 0", "ok true");
	sim_run_ms(&S, 100);
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 2000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	double x0 = odom_x();
	EXPECT("setJoystick false", "ok true");
	sim_run_ms(&S, 3000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	assert_true(fabs(odom_x() - x0) < 0.1);
	assert_true(cmd_speed() == 0.0);
	/* The same for a continuous goal. */
	EXPECT("moveContinuousRel 2000 0 0", "ok true");
	EXPECT("moveCruiseAbs 3000 0", "ok true");
	sim_run_ms(&S, 300);
	EXPECT("setJoystick true", "ok true");
	EXPECT("setJoystick false", "ok true");
	sim_run_ms(&S, 3000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	x0 = odom_x();
	sim_run_ms(&S, 3000);
	assert_true(fabs(odom_x() - x0) < 0.1);
}

/* 3: under the joystick, stop holds while the stick stays over; after an
 * e-stop, clearAlarm and setServo(true) do not drive either. */
static void test_stick_must_return_to_neutral(void **state)
{
	(void)state;
	ready();
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 1);
	EXPECT("$sim joystick 1 0 0", "ok joystick 32767 0 0");
	sim_run_ms(&S, 1500);
	assert_true(fabs(cmd_speed() - 500.0) < 1e-6);
	EXPECT("stop", "ok true");
	sim_run_ms(&S, 1000); /* braking at the limit: 500 ms */
	double x0 = odom_x();
	sim_run_ms(&S, 1000);
	assert_true(fabs(odom_x() - x0) < 0.1);
	assert_true(cmd_speed() == 0.0);
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* Back to neutral: it drives again. */
	EXPECT("$sim joystick 0 0 0", "ok joystick 0 0 0");
	sim_run_ms(&S, 1);
	EXPECT("$sim joystick 0.5 0 0", "ok joystick 16384 0 0");
	sim_run_ms(&S, 1000);
	assert_true(cmd_speed() > 200.0);
	/* An emergency stop while driving. */
	EXPECT("$sim estop on", "ok estop on");
	sim_run_ms(&S, 1000);
	EXPECT("$sim estop off", "ok estop off");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	sim_run_ms(&S, 1);
	x0 = odom_x();
	sim_run_ms(&S, 2000);
	assert_true(fabs(odom_x() - x0) < 0.1);
	assert_true(cmd_speed() == 0.0);
}

/* 4: a 45 mm push at rest with setVelocity 100: every tick each wheel's
 * setpoint stays within 100 mm/s and rises by at most the set acceleration
 * (500 mm/s^2: 0.5 mm/s a tick); the unit comes back. */
static void test_hold_is_bounded(void **state)
{
	(void)state;
	ready();
	EXPECT("setVelocity 100 90", "ok true");
	EXPECT("$sim push 45 0 0", "ok push 45.000 0.000 0.000");
	double cpm = S.cfg.encoder_counts_per_rev / (M_PI * S.cfg.wheel_diameter_mm);
	double prev[2] = {0, 0}, top = 0;
	for (int t = 0; t < 4000; t++) {
		sim_tick(&S);
		for (int i = 0; i < 2; i++) {
			double mm_s = S.vehicle.wheel_cps_q8[i] / 256.0 / cpm;
			assert_true(fabs(mm_s) <= 100.0 + 1e-3);
			/* Within a millimetre (the loop gain times it: 20 mm/s)
			 * the wheel loop settles as after any move. */
			if (fabs(mm_s) > 20.0)
				assert_true(fabs(mm_s) - fabs(prev[i]) <= 0.5 + 1e-3);
			prev[i] = mm_s;
			top = fmax(top, fabs(mm_s));
		}
	}
	/* It did move back, at speed. */
	assert_true(top > 90.0);
	double x, y, th;
	plant_pose(&S.plant, &x, &y, &th);
	assert_true(fabs(x) < 0.5);
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* 5: on the mecanum base, a diagonal jog runs at the set velocity as a
 * vector, and at the caution cap under caution; so does the joystick. */
static void test_mecanum_speed_is_a_vector(void **state)
{
	(void)state;
	ready();
	EXPECT("moveJog 500 500 0", "ok true");
	for (int i = 0; i < 15; i++) {
		sim_run_ms(&S, 200);
		EXPECT("moveJog 500 500 0", "ok true");
	}
	assert_true(fabs(cmd_speed() - 500.0) < 1e-3);
	EXPECT("$sim caution on", "ok caution on");
	for (int i = 0; i < 15; i++) {
		sim_run_ms(&S, 200);
		EXPECT("moveJog 500 500 0", "ok true");
	}
	assert_true(fabs(cmd_speed() - 200.0) < 1e-3);
	EXPECT("stop", "ok true");
	sim_run_ms(&S, 2000);
	EXPECT("$sim caution off", "ok caution off");
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 1);
	EXPECT("$sim joystick 1 1 0", "ok joystick 32767 32767 0");
	sim_run_ms(&S, 3000);
	assert_true(fabs(cmd_speed() - 500.0) < 1e-3);
}

/* 6: pause, then stop: Ready, a Ready-only move is taken, a queued one
 * runs. */
static void test_stop_ends_pause(void **state)
{
	(void)state;
	ready();
	EXPECT("moveForward 1000", "ok true");
	sim_run_ms(&S, 300);
	EXPECT("pause", "ok true");
	sim_run_ms(&S, 1000);
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("stop", "ok true");
	sim_run_ms(&S, 500);
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("moveForward 100", "ok true");
	sim_run_ms(&S, 3000);
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* Found by the differential harness: stop during a jog with a route
 * queued behind it drops the route too (it ran once the jog had braked). */
static void test_stop_in_jog_drops_queued_route(void **state)
{
	(void)state;
	ready();
	EXPECT("moveJog 200 0 0", "ok true");
	EXPECT("moveLinearAbs 1000 0 0", "ok true");
	sim_run_ms(&S, 100);
	EXPECT("stop", "ok true");
	sim_run_ms(&S, 900);
	EXPECT("getState", "ok true 16 \"Ready\"");
	double x0 = odom_x();
	sim_run_ms(&S, 900);
	assert_true(fabs(odom_x() - x0) < 0.1);
	/* A stop at rest refuses nothing sent next. */
	EXPECT("stop", "ok true");
	EXPECT("moveJog 100 0 0", "ok true");
}

/* Found by the differential harness: a jog paused before it ever moved,
 * then stopped, has nothing to brake: Ready at once, and the next command
 * is not refused for a stop still under way. The same for a goal; and a
 * jog paused before it moved is over, resumed or not. */
static void test_stop_at_rest_is_ready_at_once(void **state)
{
	(void)state;
	ready();
	EXPECT("moveJog 300 0 40", "ok true");
	EXPECT("pause", "ok true");
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("stop", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("moveContinuousRel 500 0 0", "ok true");
	EXPECT("pause", "ok true");
	EXPECT("stop", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("moveForward 10", "ok true");
	sim_run_ms(&S, 1000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	assert_true(fabs(odom_x() - 10.0) < 0.05);
	/* stop under the joystick at rest, then the joystick let go: nothing
	 * is left to brake, a goal sent next is taken (found by fuzz_model:
	 * it was refused 122). */
	EXPECT("$sim joystick 0 0 0", "ok joystick 0 0 0");
	EXPECT("setJoystick true", "ok true");
	sim_tick(&S);
	EXPECT("stop", "ok true");
	EXPECT("setJoystick false", "ok true");
	EXPECT("moveContinuousRel 0 0 0", "ok true");
	sim_run_ms(&S, 100);
	/* A pause ends a jog that has not moved yet: resume finds Ready. */
	EXPECT("moveJog 300 0 40", "ok true");
	EXPECT("pause", "ok true");
	EXPECT("resume", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	sim_run_ms(&S, 200);
	assert_true(fabs(odom_x() - 10.0) < 0.05);
}

/* Found by fuzz_model: with the servo off and the joystick enabled, the
 * reference followed the wheels only when idle, not while the joystick
 * waited; a push, setJoystick(false) and setServo(true) in one period then
 * started the hold from where the unit had been before the push: the next
 * wheel movement at rest pulled it back there (past 50 mm: fault 204). */
static void test_servo_on_after_push_under_joystick(void **state)
{
	(void)state;
	EXPECT("setPower true", "ok true");
	EXPECT("$sim joystick 0 0 0", "ok joystick 0 0 0");
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 10);
	EXPECT("$sim push 40 0 0", "ok push 40.000 0.000 0.000");
	sim_run_ms(&S, 100);
	EXPECT("setJoystick false", "ok true");
	EXPECT("setServo true", "ok true");
	sim_run_ms(&S, 100);
	/* Pushed again, now held: the hold brings it back to where the
	 * servo came on (40 mm), not to where it stood before (0). */
	EXPECT("$sim push 1 0 0", "ok push 41.000 0.000 0.000");
	sim_run_ms(&S, 3000);
	EXPECT("getState", "ok true 16 \"Ready\"");
	assert_true(fabs(odom_x() - 40.0) < 0.05);
}

/* 11: drive 0's power stage held off (an STO): servo on waits, the other
 * wheel never drives, and 500 ms on it is fault 211 naming drive 0 and its
 * state. */
static void test_servo_on_waits_for_every_drive(void **state)
{
	(void)state;
	EXPECT("setPower true", "ok true");
	EXPECT("$sim drive 0 hold", "ok drive 0 hold");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 17 \"Busy\"");
	EXPECT("getServoStatus 0", "ok true false");
	EXPECT("getServoStatus 1", "ok true true");
	/* Busy, nothing queued: the accelerations stay (spec 5 #24). */
	EXPECT("setAcceleration 500 90", "ok false");
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 122 warning \"setAcceleration refused: unit moving\"");
	EXPECT("moveForward 100", "ok false");
	EXPECT("getActiveAlarm 1",
	       "ok true 2 1 120 warning \"moveForward refused: unit not ready\"");
	EXPECT("moveLinearAbs 100 0 0", "ok true"); /* queued: it waits */
	for (int t = 0; t < 500; t++) {
		sim_tick(&S);
		assert_int_equal(S.vehicle.wheel_cps_q8[0], 0);
		assert_int_equal(S.vehicle.wheel_cps_q8[1], 0);
	}
	EXPECT("getState", "ok true 17 \"Busy\"");
	sim_tick(&S); /* the 501st tick: past servo_on_timeout_ms */
	EXPECT("getActiveAlarm 1", "ok true 3 1 211 fault \"drive 0 not enabled: Switched on\"");
	EXPECT("getState", "ok true 19 \"Alarm-211\"");
	EXPECT("$sim pose", "ok pose 0.000 0.000 0.000");
	/* Released: servo on completes at once, the queue went with the fault. */
	EXPECT("$sim drive 0 ok", "ok drive 0 ok");
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("getServoStatus 0", "ok true true");
}

/* 11: a drive that leaves Operation enabled while the unit moves: fault 212
 * in that tick, both wheels get zero. */
static void test_drive_leaving_enabled_stops_all(void **state)
{
	(void)state;
	ready();
	vehicle_set_link_timeout(&S.vehicle, 0);
	EXPECT("moveForward 2000", "ok true");
	sim_run_ms(&S, 1000);
	EXPECT("$sim drive 1 hold", "ok drive 1 hold");
	sim_tick(&S);
	EXPECT("getActiveAlarm 4",
	       "ok true 1 1 212 fault \"drive 1 left Operation enabled: Switched on\"");
	assert_int_equal(S.vehicle.wheel_cps_q8[0], 0);
	assert_int_equal(S.vehicle.wheel_cps_q8[1], 0);
	EXPECT("getServoStatus 0", "ok true false");
}

/* 12: a drive restarts (its count starts at 0): warning 155, the pose does
 * not jump, motion is refused (132) until setPosition. */
static void test_drive_restart_loses_position(void **state)
{
	(void)state;
	ready();
	vehicle_set_link_timeout(&S.vehicle, 0); /* long waits without requests */
	EXPECT("moveForward 300", "ok true");
	sim_run_ms(&S, 3000);
	EXPECT("setServo false", "ok true");
	char before[CONSOLE_REPLY_MAX];
	snprintf(before, sizeof before, "%s", ex("getPosition"));
	assert_true(fabs(odom_x() - 300.0) < 0.05);
	EXPECT("$sim drive 1 reboot", "ok drive 1 reboot");
	sim_run_ms(&S, 10);
	EXPECT("getActiveAlarm 1",
	       "ok true 1 1 155 warning \"drive 1 position lost: setPosition required\"");
	EXPECT("getPosition", before); /* no jump of 300 mm on wheel 1 */
	EXPECT("setServo true", "ok true");
	EXPECT("moveForward 100", "ok false");
	EXPECT("getActiveAlarm 1",
	       "ok true 2 1 132 warning \"moveForward refused: position lost\"");
	EXPECT("moveJog 100 0 0", "ok false");
	EXPECT("setPosition 0 0 0", "ok true");
	EXPECT("moveForward 100", "ok true");
	sim_run_ms(&S, 3000);
	assert_true(fabs(odom_x() - 100.0) < 0.05);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup(test_joystick_flag_keeps_link_watchdog, setup_diff),
	    cmocka_unit_test_setup(test_joystick_drops_queued_route, setup_diff),
	    cmocka_unit_test_setup(test_stick_must_return_to_neutral, setup_diff),
	    cmocka_unit_test_setup(test_hold_is_bounded, setup_diff),
	    cmocka_unit_test_setup(test_mecanum_speed_is_a_vector, setup_omni),
	    cmocka_unit_test_setup(test_stop_ends_pause, setup_diff),
	    cmocka_unit_test_setup(test_stop_in_jog_drops_queued_route, setup_diff),
	    cmocka_unit_test_setup(test_stop_at_rest_is_ready_at_once, setup_diff),
	    cmocka_unit_test_setup(test_servo_on_after_push_under_joystick, setup_diff),
	    cmocka_unit_test_setup(test_servo_on_waits_for_every_drive, setup_diff),
	    cmocka_unit_test_setup(test_drive_leaving_enabled_stops_all, setup_diff),
	    cmocka_unit_test_setup(test_drive_restart_loses_position, setup_diff),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
