/* The fault matrix of docs/faults.md, one test per row, on the simulated
 * plant (default plant: motor lag, current and acceleration limits).
 *
 * Each test brings the unit to a known motion, injects the fault the way the
 * hardware would show it (sim.h extras, or the plant directly where no extra
 * exists), then checks tick by tick: the exact alarm, the state string, how
 * the commanded speed falls (at once for a fault, at a stated deceleration
 * otherwise), servo and power afterwards, that nothing restarts by itself,
 * and the documented recovery path back to Ready and a working move.
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

/* Reference base: 1 kHz tick, set velocity 500 mm/s, set acceleration
 * 500 mm/s^2, limits 1000 mm/s and 1000 mm/s^2, jog timeout 500 ms. */
#define TICK_HZ	    1000.0
#define ACC_SET	    500.0
#define ACC_LIMIT   1000.0
#define CRUISE_MM_S 500.0

static int setup(void **state)
{
	vs_config_t cfg;
	plant_params_t pp;

	(void)state;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	return sim_init(&S, &cfg, &pp);
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

/* Commanded body speed, mm/s (the firmware's twist is mm per tick, Q32). */
static double cmd_mm_s(void)
{
	return (double)S.vehicle.cmd.vx_pt / 4294967296.0 * TICK_HZ;
}

static void ready(void)
{
	EXPECT("setPower true", "ok true");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* Ready, then a long moveForward at cruise speed (500 mm/s). */
static void cruising(void)
{
	ready();
	EXPECT("moveForward 20000", "ok true");
	sim_run_ms(&S, 1500);
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("getState", "ok true 17 \"Busy\"");
}

static void servo_is(const char *onoff)
{
	char want[32];

	snprintf(want, sizeof(want), "ok true %s", onoff);
	EXPECT("getServoStatus 0", want);
	EXPECT("getServoStatus 1", want);
}

/* The drives get zero setpoints and no enable. */
static void drives_off(void)
{
	for (uint8_t i = 0; i < S.plant.n; i++) {
		assert_int_equal(S.plant.w[i].setpoint_q8, 0);
		assert_false(S.plant.w[i].enable_cmd);
	}
}

/* A fault halts: the first tick after the cause commands zero, nothing
 * decelerates (the servo is off, there is nothing to decelerate with). */
static void expect_halt_next_tick(void)
{
	sim_tick(&S);
	assert_true(S.vehicle.cmd.vx_pt == 0 && S.vehicle.cmd.w_pt == 0);
	drives_off();
}

/* Ticks until the commanded speed is zero; checks that every tick lowers it
 * by acc (mm/s^2) to within Q32 rounding and never raises it. Returns the
 * ticks taken: v / acc * tick rate, plus one when the per-tick step, rounded
 * down to Q32, leaves a remainder of a few LSB. */
static unsigned expect_decel(double acc, unsigned max_ticks)
{
	double prev = cmd_mm_s(), step = acc / TICK_HZ;
	unsigned n = 0;

	while (cmd_mm_s() != 0.0 && n < max_ticks) {
		sim_tick(&S);
		n++;
		double now = cmd_mm_s();
		double drop = prev - now;
		/* the last tick may take less than a full step */
		if (now != 0.0)
			assert_true(fabs(drop - step) < 1e-3);
		else
			assert_true(drop > 0.0 && drop <= step + 1e-3);
		prev = now;
	}
	assert_true(cmd_mm_s() == 0.0);
	return n;
}

/* The reference has stopped: the unit is Busy until every wheel has been
 * within the position window (0.05 mm) for the window time (20 ms), which
 * takes at most 50 ms on the default plant. Returns the ticks it took. */
static unsigned settles(void)
{
	unsigned n = 0;
	EXPECT("getState", "ok true 17 \"Busy\"");
	while (strcmp(ex("getState"), "ok true 17 \"Busy\"") == 0 && n < 1000) {
		sim_tick(&S);
		n++;
	}
	assert_in_range(n, 19, 50); /* from the tick after the last reference step */
	return n;
}

/* The unit stays where it is for ms: odometry and the true plant pose move
 * by less than 1 mm (the wheel loop only settles the last counts). */
static void stays_put(uint32_t ms)
{
	double x0, y0, th0, x1, y1, th1;

	sim_run_ms(&S, 200); /* coast-down of the motors (20 ms lag) */
	plant_pose(&S.plant, &x0, &y0, &th0);
	sim_run_ms(&S, ms);
	plant_pose(&S.plant, &x1, &y1, &th1);
	assert_true(hypot(x1 - x0, y1 - y0) < 1.0);
	assert_true(fabs(th1 - th0) < 0.1);
	assert_true(S.vehicle.cmd.vx_pt == 0 && S.vehicle.cmd.w_pt == 0);
}

/* Recovery ends with a move that runs: 100 mm forward from rest. */
static void move_works(void)
{
	double x0, y0, th0, x1, y1, th1;

	plant_pose(&S.plant, &x0, &y0, &th0);
	EXPECT("moveForward 100", "ok true");
	sim_run_ms(&S, 1500);
	EXPECT("getState", "ok true 16 \"Ready\"");
	plant_pose(&S.plant, &x1, &y1, &th1);
	assert_true(fabs(hypot(x1 - x0, y1 - y0) - 100.0) < 2.0);
}

/* ---- faults (2xx): halt, servo off ------------------------------------- */

static void test_drive_fault(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim drive 1 fault 0x2310", "ok drive 1 fault 0x2310");
	expect_halt_next_tick();
	EXPECT("getActiveAlarm 16", "ok true 1 1 201 fault \"drive 1 fault 0x2310\"");
	EXPECT("getState", "ok true 19 \"Alarm-201\"");
	servo_is("false");
	assert_true(S.plant.relay_closed); /* power stays on */
	stays_put(1000);
	/* motion refused while the fault is active, also setServo(true) */
	EXPECT("moveForward 100", "ok false");
	EXPECT("setServo true", "ok false");
	/* clearAlarm resets the drive, but the condition persists: raised again */
	EXPECT("clearAlarm", "ok true");
	sim_run_ms(&S, 10);
	EXPECT("getState", "ok true 19 \"Alarm-201\"");
	/* recovery: fix the cause, clearAlarm, setServo(true) */
	EXPECT("$sim drive 1 ok", "ok drive 1 ok");
	EXPECT("clearAlarm", "ok true");
	sim_run_ms(&S, 10);
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	move_works();
}

static void test_drive_reply_timeout(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim drive 0 silent", "ok drive 0 silent");
	/* drive_timeout_ms = 50: no fault up to 50 ticks without a reply */
	sim_run_ms(&S, 50);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	/* the 51st silent tick raises it, with the halt in the same tick */
	sim_tick(&S);
	assert_true(S.vehicle.cmd.vx_pt == 0);
	drives_off();
	EXPECT("getActiveAlarm 16", "ok true 1 1 202 fault \"drive 0 not answering\"");
	EXPECT("getState", "ok true 19 \"Alarm-202\"");
	servo_is("false");
	assert_true(S.plant.relay_closed);
	/* reported once per occurrence: still one alarm while it stays silent */
	stays_put(1000);
	EXPECT("getActiveAlarm 0", "ok true 1 0");
	EXPECT("$sim drive 0 ok", "ok drive 0 ok");
	EXPECT("clearAlarm", "ok true");
	sim_run_ms(&S, 100);
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	move_works();
}

/* A frozen encoder from rest: the wheel is commanded, the count never
 * changes, and encoder_stuck_ms (300) later the fault stops it. */
static void test_encoder_stuck(void **state)
{
	unsigned t = 0;

	(void)state;
	ready();
	EXPECT("$sim drive 0 stuck", "ok drive 0 stuck");
	EXPECT("moveForward 1000", "ok true");
	while (!alarm_any_fault(&S.vehicle.alarms) && t < 1000) {
		sim_tick(&S);
		t++;
	}
	/* commanded above 20 counts per window from the 2nd tick, then 300
	 * ticks without a change */
	assert_in_range(t, 300, 310);
	assert_true(S.vehicle.cmd.vx_pt == 0);
	drives_off();
	EXPECT("getActiveAlarm 16", "ok true 1 1 203 fault \"encoder 0 stuck\"");
	EXPECT("getState", "ok true 19 \"Alarm-203\"");
	servo_is("false");
	stays_put(1000);
	EXPECT("$sim drive 0 ok", "ok drive 0 ok");
	/* the repaired encoder jumps to the true count on its next reading;
	 * the servo is switched on after that (see docs/faults.md) */
	sim_run_ms(&S, 10);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	move_works();
}

/* A frozen encoder at speed: the measured wheel falls behind the commanded
 * one at 500 mm/s, so the following error (50 mm) trips first, well before
 * the stuck window. */
static void test_encoder_stuck_at_speed(void **state)
{
	unsigned t = 0;

	(void)state;
	cruising();
	EXPECT("$sim drive 0 stuck", "ok drive 0 stuck");
	while (!alarm_any_fault(&S.vehicle.alarms) && t < 1000) {
		sim_tick(&S);
		t++;
	}
	assert_in_range(t, 60, 110);
	/* the following error is judged after this tick's command: the drives
	 * got zero in the same tick, the command is zero from the next */
	drives_off();
	sim_tick(&S);
	assert_true(S.vehicle.cmd.vx_pt == 0 && S.vehicle.cmd.w_pt == 0);
	assert_int_equal(S.vehicle.alarms.n, 1);
	assert_int_equal(S.vehicle.alarms.a[0].code, 204);
	assert_memory_equal(S.vehicle.alarms.a[0].source, "following error ", 16);
	EXPECT("getState", "ok true 19 \"Alarm-204\"");
	servo_is("false");
	stays_put(500);
	EXPECT("$sim drive 0 ok", "ok drive 0 ok");
	sim_run_ms(&S, 10);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	stays_put(500);
	move_works();
}

/* Encoder runaway: the count of wheel 0 races ahead of the wheel (100
 * counts per tick, ~2.9 m/s) while the unit is moving. */
static int runaway_counts;
static void runaway_tick(void *ctx, sim_t *s)
{
	(void)ctx;
	s->plant.w[0].pos_counts += runaway_counts;
}

static void test_encoder_runaway(void **state)
{
	unsigned t = 0;

	(void)state;
	cruising();
	runaway_counts = 100;
	sim_set_tick_cb(&S, runaway_tick, NULL);
	while (!alarm_any_fault(&S.vehicle.alarms) && t < 1000) {
		sim_tick(&S);
		t++;
	}
	/* 50 mm = 1739 counts of following error: about 18 ticks */
	assert_in_range(t, 10, 30);
	drives_off();
	sim_tick(&S);
	assert_true(S.vehicle.cmd.vx_pt == 0 && S.vehicle.cmd.w_pt == 0);
	assert_int_equal(S.vehicle.alarms.n, 1);
	assert_int_equal(S.vehicle.alarms.a[0].code, 204);
	assert_memory_equal(S.vehicle.alarms.a[0].source, "following error ", 16);
	EXPECT("getState", "ok true 19 \"Alarm-204\"");
	servo_is("false");
	sim_set_tick_cb(&S, NULL, NULL);
	/* servo off: the wheels coast to rest (servo on only at rest, see
	 * docs/faults.md) */
	stays_put(500);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	stays_put(500);
	move_works();
}

/* The same runaway while the unit stands still with the servo on. */
static void test_encoder_runaway_at_rest(void **state)
{
	(void)state;
	ready();
	runaway_counts = 100;
	sim_set_tick_cb(&S, runaway_tick, NULL);
	sim_run_ms(&S, 100);
	sim_set_tick_cb(&S, NULL, NULL);
	assert_int_equal(S.vehicle.alarms.a[0].code, 204);
	EXPECT("getState", "ok true 19 \"Alarm-204\"");
	servo_is("false");
	drives_off();
}

static void test_power_relay_drop(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim relay drop", "ok relay drop");
	expect_halt_next_tick();
	EXPECT("getActiveAlarm 16", "ok true 1 1 206 fault \"main power lost\"");
	EXPECT("getState", "ok true 19 \"Alarm-206\"");
	servo_is("false");
	assert_false(S.plant.relay_closed);
	/* no drive alarms follow: drives are not supervised without power */
	stays_put(1000);
	EXPECT("getActiveAlarm 0", "ok true 1 0");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 25 \"Unpowered\"");
	EXPECT("setServo true", "ok false");
	/* recovery: relay fixed, clearAlarm, setPower(true), setServo(true) */
	EXPECT("$sim relay ok", "ok relay ok");
	EXPECT("clearAlarm", "ok true");
	ready();
	move_works();
}

static void test_power_relay_fails_to_close(void **state)
{
	(void)state;
	EXPECT("$sim relay fail", "ok relay fail");
	EXPECT("setPower true", "ok false");
	EXPECT("getActiveAlarm 16", "ok true 1 1 205 fault \"main relay did not close\"");
	EXPECT("getState", "ok true 19 \"Alarm-205\"");
	assert_false(S.plant.relay_cmd); /* commanded open again */
	servo_is("false");
	EXPECT("$sim relay ok", "ok relay ok");
	EXPECT("clearAlarm", "ok true");
	ready();
	move_works();
}

static void test_battery_low_warning(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim battery 21500", "ok battery 21500");
	sim_tick(&S);
	EXPECT("getActiveAlarm 16", "ok true 1 1 140 warning \"battery below 22.0 V\"");
	/* a warning only: the motion goes on at its speed, servo on */
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("getState", "ok true 17 \"Busy\"");
	sim_run_ms(&S, 500);
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	servo_is("true");
	EXPECT("stop", "ok true");
	sim_run_ms(&S, 1000);
	EXPECT("getState", "ok true 18 \"Warning-140\"");
	/* raised once per crossing: clearAlarm while still low keeps it off */
	EXPECT("clearAlarm", "ok true");
	sim_run_ms(&S, 100);
	EXPECT("getState", "ok true 16 \"Ready\"");
	/* charged again (0.1 V hysteresis), then low again: raised again */
	EXPECT("$sim battery 25200", "ok battery 25200");
	sim_run_ms(&S, 10);
	EXPECT("$sim battery 21500", "ok battery 21500");
	sim_run_ms(&S, 10);
	EXPECT("getState", "ok true 18 \"Warning-140\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("$sim battery 25200", "ok battery 25200");
	sim_run_ms(&S, 10);
	move_works();
}

static void test_battery_critical(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim battery 19500", "ok battery 19500");
	expect_halt_next_tick();
	/* the low warning is crossed in the same tick, after the fault */
	EXPECT("getActiveAlarm 16", "ok true 2 2 140 warning \"battery below 22.0 V\" "
				    "207 fault \"battery below 20.0 V\"");
	EXPECT("getState", "ok true 19 \"Alarm-207\"");
	servo_is("false");
	assert_true(S.plant.relay_closed);
	stays_put(500);
	/* cleared while still critical: raised again on the next tick */
	EXPECT("clearAlarm", "ok true");
	sim_tick(&S);
	EXPECT("getState", "ok true 19 \"Alarm-207\"");
	EXPECT("setServo true", "ok false");
	EXPECT("$sim battery 25200", "ok battery 25200");
	sim_run_ms(&S, 10);
	EXPECT("clearAlarm", "ok true");
	sim_run_ms(&S, 10);
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	move_works();
}

static void test_estop(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim estop on", "ok estop on");
	expect_halt_next_tick();
	EXPECT("getActiveAlarm 16", "ok true 1 1 208 fault \"emergency stop\"");
	EXPECT("getState", "ok true 19 \"Alarm-208\"");
	servo_is("false");
	/* the firmware leaves the relay as it was; the e-stop circuit itself
	 * removes drive power in hardware */
	assert_true(S.plant.relay_closed);
	stays_put(500);
	/* held: clearAlarm does not get rid of it */
	EXPECT("clearAlarm", "ok true");
	sim_tick(&S);
	EXPECT("getState", "ok true 19 \"Alarm-208\"");
	EXPECT("setServo true", "ok false");
	EXPECT("moveForward 100", "ok false");
	/* released: still latched until clearAlarm, nothing moves */
	EXPECT("$sim estop off", "ok estop off");
	stays_put(500);
	EXPECT("getState", "ok true 19 \"Alarm-208\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 24 \"Powered\"");
	EXPECT("setServo true", "ok true");
	move_works();
}

/* A tick late_us after its period (the plant keeps moving meanwhile); the
 * simulator's period count skips the whole periods missed. */
static void late_tick(uint32_t late_us)
{
	plant_step(&S.plant, late_us);
	S.now_us += late_us;
	S.ticks += late_us / 1000u;
	sim_tick(&S);
}

/* A late wake-up is counted and the motion goes on; a stall past
 * loop_late_ms (20 ms) halts. */
static void test_loop_stall(void **state)
{
	(void)state;
	cruising();
	late_tick(5000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("getState", "ok true 17 \"Busy\"");
	late_tick(20000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	assert_memory_equal(ex("$diag"), "ok ticks ", 9);
	assert_non_null(strstr(rep, " overruns 0 late 2 max_late_us 20000 mode path "));
	sim_run_ms(&S, 10);
	late_tick(20001);
	assert_true(S.vehicle.cmd.vx_pt == 0);
	drives_off();
	EXPECT("getActiveAlarm 16", "ok true 1 1 210 fault \"control loop stalled 20 ms\"");
	EXPECT("getState", "ok true 19 \"Alarm-210\"");
	servo_is("false");
	assert_true(S.plant.relay_closed);
	stays_put(500);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	move_works();
}

/* The loop's own work over a period (measured by the platform) halts. */
static void test_tick_overrun(void **state)
{
	(void)state;
	cruising();
	vehicle_tick_busy(&S.vehicle, 1000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	vehicle_tick_busy(&S.vehicle, 1001);
	expect_halt_next_tick();
	EXPECT("getActiveAlarm 16", "ok true 1 1 209 fault \"control tick overrun\"");
	EXPECT("getState", "ok true 19 \"Alarm-209\"");
	assert_memory_equal(ex("$diag"), "ok ticks ", 9);
	assert_non_null(strstr(rep, " overruns 1 late 0 max_late_us 0 mode idle queue 0 "));
	stays_put(500);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setServo true", "ok true");
	move_works();
}

/* ---- stops at the acceleration limit, servo stays on ------------------- */

static void test_contact_sensor(void **state)
{
	(void)state;
	EXPECT("setDigitalSensorLock true", "ok true");
	cruising();
	EXPECT("moveLinearAbs 0 0 0", "ok true"); /* queued work is discarded */
	EXPECT("$sim contact on", "ok contact on");
	/* 500 mm/s at 1000 mm/s^2: 500 ticks */
	assert_in_range(expect_decel(ACC_LIMIT, 2000), 500, 501);
	EXPECT("getActiveAlarm 16", "ok true 1 1 150 warning \"contact detected\"");
	/* Locked once stopped (spec: stop, then enter Locked) */
	settles();
	EXPECT("getState", "ok true 23 \"Locked\"");
	servo_is("true");
	assert_true(S.plant.relay_closed);
	stays_put(1000);
	EXPECT("moveForward -100", "ok false");
	/* unlock: idle with the warning, nothing restarts; the unit may back
	 * away while the bumper is still pressed */
	EXPECT("unlock", "ok true");
	EXPECT("getState", "ok true 18 \"Warning-124\"");
	stays_put(500);
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("$sim contact off", "ok contact off");
	move_works();
}

static void test_contact_sensor_disabled(void **state)
{
	(void)state;
	cruising();
	EXPECT("$sim contact on", "ok contact on");
	sim_run_ms(&S, 100);
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	EXPECT("getState", "ok true 17 \"Busy\"");
}

static void test_obstacle_input(void **state)
{
	(void)state;
	cruising();
	EXPECT("moveLinearAbs 0 0 0", "ok true");
	EXPECT("$sim obstacle on", "ok obstacle on");
	assert_in_range(expect_decel(ACC_LIMIT, 2000), 500, 501);
	EXPECT("getActiveAlarm 16", "ok true 1 1 151 warning \"obstacle detected\"");
	settles();
	EXPECT("getState", "ok true 20 \"Stuck\"");
	servo_is("true");
	stays_put(1000);
	EXPECT("moveForward 100", "ok false");
	EXPECT("getActiveAlarm 1", "ok true 2 1 130 warning \"moveForward refused: unit stuck\"");
	/* input clears: idle (warning shown), queue discarded, no restart */
	EXPECT("$sim obstacle off", "ok obstacle off");
	stays_put(1000);
	EXPECT("getState", "ok true 18 \"Warning-130\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
	move_works();
}

/* ---- link and command faults ------------------------------------------- */

/* The host keeps jogging at 300 mm/s every 100 ms, then the link goes
 * quiet: 500 ms after the last moveJog the unit decelerates at the set
 * acceleration (500 mm/s^2) and stops; no alarm, Ready, servo on. */
static void test_link_loss_during_jog(void **state)
{
	unsigned t = 0;

	(void)state;
	ready();
	for (int i = 0; i < 20; i++) {
		EXPECT("moveJog 300 0 0", "ok true");
		sim_run_ms(&S, 100);
	}
	EXPECT("moveJog 300 0 0", "ok true");
	/* full speed up to the timeout */
	while (t < 500) {
		sim_tick(&S);
		t++;
		assert_true(fabs(cmd_mm_s() - 300.0) < 1e-6);
	}
	/* 300 mm/s at 500 mm/s^2: 600 ticks */
	assert_in_range(expect_decel(ACC_SET, 2000), 600, 601);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	settles();
	EXPECT("getState", "ok true 16 \"Ready\"");
	servo_is("true");
	stays_put(1000);
	/* recovery: the host jogs again */
	EXPECT("moveJog 100 0 0", "ok true");
	sim_run_ms(&S, 400);
	assert_true(fabs(cmd_mm_s() - 100.0) < 1e-6);
}

/* The link watchdog (link_timeout_ms 1000) on: the host below polls
 * getState every 500 ms while it wants the motion to go on. */
static int setup_watchdog(void **state)
{
	vs_config_t cfg;
	plant_params_t pp;

	(void)state;
	vs_config_defaults(&cfg);
	assert_int_equal(cfg.link_timeout_ms, 1000);
	plant_params_default(&pp);
	return sim_init(&S, &cfg, &pp);
}

static void keep_alive(const char *line, const char *reply, unsigned ms)
{
	for (unsigned t = 0; t < ms; t += 500) {
		if (reply)
			EXPECT(line, reply);
		else
			assert_memory_equal(ex(line), "ok ", 3);
		sim_run_ms(&S, 500);
	}
}

/* The host falls silent mid-route: 1000 ticks after its last valid
 * request the unit brakes at the acceleration limit, the queue is gone,
 * warning 153 names the link, and it never moves again by itself. */
static void test_link_watchdog_stops_route(void **state)
{
	double x0, y0, th0, x1, y1, th1;

	(void)state;
	ready();
	EXPECT("moveForward 20000", "ok true");
	EXPECT("moveLinearAbs 0 0 0", "ok true");
	/* getState and a bring-up line keep it going for 3 s */
	keep_alive("getState", "ok true 17 \"Busy\"", 2000);
	keep_alive("$version", NULL, 1000);
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("getState", "ok true 17 \"Busy\""); /* the last valid request */
	plant_pose(&S.plant, &x0, &y0, &th0);
	for (unsigned t = 1; t < 1000; t++) {
		sim_tick(&S);
		assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
		/* a line that is not a valid request does not count */
		if (t == 500)
			EXPECT("moveTurn 0 0", "error 2 moveTurn takes 1 argument, got 2");
	}
	/* tick 1000: braking at 1000 mm/s^2, 500 ticks */
	assert_in_range(expect_decel(ACC_LIMIT, 2000), 500, 501);
	sim_run_ms(&S, 200); /* the motors' lag settles */
	plant_pose(&S.plant, &x1, &y1, &th1);
	/* timeout x v + v^2 / (2 a_max) + 2 ticks of travel */
	double bound = 1.0 * CRUISE_MM_S + CRUISE_MM_S * CRUISE_MM_S / (2.0 * ACC_LIMIT) +
		       2.0 * CRUISE_MM_S / TICK_HZ;
	double travel = x1 - x0;
	assert_true(travel <= bound);
	assert_true(travel > bound - 3.0);
	EXPECT("getActiveAlarm 16",
	       "ok true 1 1 153 warning \"link lost: console silent 1000 ms\"");
	EXPECT("getState", "ok true 18 \"Warning-153\"");
	assert_memory_equal(ex("$diag"), "ok ticks ", 9);
	assert_non_null(strstr(rep, " mode idle queue 0 "));
	servo_is("true");
	stays_put(3000);
	/* a new command runs normally; the warning stays until cleared */
	plant_pose(&S.plant, &x0, &y0, &th0);
	EXPECT("moveForward 100", "ok true");
	sim_run_ms(&S, 1500);
	plant_pose(&S.plant, &x1, &y1, &th1);
	assert_true(fabs(x1 - x0 - 100.0) < 1.0);
	EXPECT("getState", "ok true 18 \"Warning-153\"");
	EXPECT("clearAlarm", "ok true");
	EXPECT("getState", "ok true 16 \"Ready\"");
}

/* Idle and paused units hold still without a host: no trip. A resumed
 * route goes on while the host polls and runs to its end. */
static void test_link_watchdog_idle_and_paused(void **state)
{
	(void)state;
	ready();
	sim_run_ms(&S, 5000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	EXPECT("moveForward 2000", "ok true");
	keep_alive("getState", "ok true 17 \"Busy\"", 1000);
	EXPECT("pause", "ok true");
	sim_run_ms(&S, 5000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	EXPECT("getState", "ok true 21 \"Paused\"");
	EXPECT("resume", "ok true");
	unsigned polls = 0;
	while (strcmp(ex("getState"), "ok true 16 \"Ready\"") != 0 && polls++ < 20) {
		assert_string_equal(rep, "ok true 17 \"Busy\"");
		sim_run_ms(&S, 500);
	}
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	double x, y, th;
	assert_int_equal(sscanf(ex("getPosition"), "ok true %lf %lf %lf", &x, &y, &th), 3);
	assert_true(fabs(x - 2000.0) < 0.05 && fabs(y) < 0.05 && fabs(th) < 0.01);
}

/* $watchdog reads and sets the timeout for this run: off, nothing stops a
 * silent route; 200 ms, the stop begins 200 ticks after the last request. */
static void test_link_watchdog_console_setting(void **state)
{
	(void)state;
	EXPECT("$watchdog", "ok watchdog 1000");
	EXPECT("$watchdog 0", "ok watchdog 0");
	EXPECT("$watchdog 60001", "error 4 $watchdog: 60001 is not a time in 0..60000 ms");
	EXPECT("$watchdog -1", "error 4 $watchdog: -1 is not a time in 0..60000 ms");
	EXPECT("$watchdog 1 2", "error 2 $watchdog takes 0 or 1 argument, got 2");
	EXPECT("$watchdog", "ok watchdog 0");
	ready();
	EXPECT("moveForward 2000", "ok true");
	sim_run_ms(&S, 6000);
	EXPECT("getActiveAlarm 0", "ok true 0 0");
	EXPECT("getState", "ok true 16 \"Ready\"");
	EXPECT("moveForward 2000", "ok true");
	sim_run_ms(&S, 1500);
	EXPECT("$watchdog 200", "ok watchdog 200");
	for (unsigned t = 1; t < 200; t++) {
		sim_tick(&S);
		assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	}
	assert_in_range(expect_decel(ACC_LIMIT, 2000), 500, 501);
	EXPECT("getActiveAlarm 1", "ok true 1 1 153 warning \"link lost: console silent 200 ms\"");
}

/* More path commands than the queue holds: the 33rd and later are refused
 * with false and 125, and the 32 accepted ones all run, in order. */
static void test_command_flood(void **state)
{
	(void)state;
	ready();
	for (int i = 1; i <= 32; i++)
		assert_string_equal(exf("moveLinearAbs %d 0 0", 20 * i), "ok true");
	for (int i = 33; i <= 200; i++)
		assert_string_equal(exf("moveLinearAbs %d 0 0", 20 * i), "ok false");
	assert_string_equal(exf("moveCruiseAbs 5000 5000"), "ok false");
	EXPECT("getActiveAlarm 16",
	       "ok true 1 1 125 warning \"moveCruiseAbs refused: queue full\"");
	assert_int_equal(motion_queue_len(&S.vehicle.motion), 32);
	EXPECT("getState", "ok true 17 \"Busy\"");
	/* a line flood on the byte stream: every line answered, nothing queued */
	{
		static const char line[] = "moveLinearAbs 9999 0 0\r\n";
		unsigned before = S.srv.con.lines;

		for (int i = 0; i < 500; i++)
			console_feed(&S.srv.con, (const uint8_t *)line, sizeof(line) - 1);
		assert_int_equal(S.srv.con.lines - before, 500);
		assert_int_equal(motion_queue_len(&S.vehicle.motion), 32);
	}
	/* 32 stops of 20 mm: each well under a second */
	sim_run_ms(&S, 32 * 1000);
	EXPECT("getState", "ok true 18 \"Warning-125\"");
	{
		double x = 0, y = 0, th = 0;

		assert_int_equal(sscanf(ex("getPosition"), "ok true %lf %lf %lf", &x, &y, &th), 3);
		/* the real plant lands within a count of each target */
		assert_true(fabs(x - 640.0) < 0.1 && fabs(y) < 0.1 && fabs(th) < 0.05);
	}
	EXPECT("clearAlarm", "ok true");
	move_works();
}

static void test_joystick_lost(void **state)
{
	(void)state;
	ready();
	EXPECT("setJoystick true", "ok true");
	sim_run_ms(&S, 1); /* the stick at neutral arms it */
	EXPECT("$sim joystick 1 0 0", "ok joystick 32767 0 0");
	sim_run_ms(&S, 1500);
	/* full stick: the set velocity */
	assert_true(fabs(cmd_mm_s() - CRUISE_MM_S) < 1e-6);
	EXPECT("$sim joystick lost", "ok joystick lost");
	assert_in_range(expect_decel(ACC_LIMIT, 2000), 500, 501);
	EXPECT("getActiveAlarm 16", "ok true 1 1 152 warning \"joystick lost\"");
	settles();
	EXPECT("getState", "ok true 18 \"Warning-152\"");
	servo_is("true");
	/* the joystick comes back: it is off now and cannot move the unit */
	EXPECT("$sim joystick 0.5 0 0", "ok joystick 16384 0 0");
	stays_put(1000);
	EXPECT("clearAlarm", "ok true");
	EXPECT("setJoystick true", "ok true");
	/* held over at the hand-over: nothing until it comes back to neutral */
	stays_put(500);
	EXPECT("$sim joystick 0 0 0", "ok joystick 0 0 0");
	sim_run_ms(&S, 1);
	EXPECT("$sim joystick 0.5 0 0", "ok joystick 16384 0 0");
	sim_run_ms(&S, 500);
	assert_true(cmd_mm_s() > 100.0);
}

int main(void)
{
#define T(f) cmocka_unit_test_setup(f, setup)
	const struct CMUnitTest tests[] = {
	    T(test_drive_fault),
	    T(test_drive_reply_timeout),
	    T(test_encoder_stuck),
	    T(test_encoder_stuck_at_speed),
	    T(test_encoder_runaway),
	    T(test_encoder_runaway_at_rest),
	    T(test_power_relay_drop),
	    T(test_power_relay_fails_to_close),
	    T(test_battery_low_warning),
	    T(test_battery_critical),
	    T(test_estop),
	    T(test_loop_stall),
	    T(test_tick_overrun),
	    T(test_contact_sensor),
	    T(test_contact_sensor_disabled),
	    T(test_obstacle_input),
	    T(test_link_loss_during_jog),
	    cmocka_unit_test_setup(test_link_watchdog_stops_route, setup_watchdog),
	    cmocka_unit_test_setup(test_link_watchdog_idle_and_paused, setup_watchdog),
	    cmocka_unit_test_setup(test_link_watchdog_console_setting, setup_watchdog),
	    T(test_command_flood),
	    T(test_joystick_lost),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
