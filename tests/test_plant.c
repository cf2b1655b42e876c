/* Simulated plant: motor dynamics, encoder, kinematics truth, relay,
 * battery, IO loopback and fault hooks, with numbers worked out by hand. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "host_sim/plant.h"

static vs_config_t cfg;
static plant_t pl;

#define assert_near(a, b, tol)                                                                     \
	do {                                                                                       \
		double a_ = (a), b_ = (b);                                                         \
		if (!(fabs(a_ - b_) <= (tol)))                                                     \
			fail_msg("%s = %.9f, expected %.9f +- %g", #a, a_, b_, (double)(tol));     \
	} while (0)

/* Reference base, relay closed, every drive enabled. */
static void start(const plant_params_t *p)
{
	vs_config_defaults(&cfg);
	plant_init(&pl, &cfg, p);
	assert_true(plant_power_set(&pl, true));
	for (uint8_t a = 0; a < pl.n; a++)
		plant_drive_enable(&pl, a, true);
}

static void run_ms(uint32_t ms)
{
	for (uint32_t i = 0; i < ms; i++)
		plant_step(&pl, 1000);
}

static int32_t mm_s_q8(double mm_s)
{
	return (int32_t)lround(mm_s * pl.counts_per_mm * 256.0);
}

static int32_t counts(uint8_t axis)
{
	hal_drive_state_t st;
	plant_drive_read(&pl, axis, &st);
	return st.position_counts;
}

static void first_order_response(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	p.tau_s = 0.050;
	start(&p);
	plant_drive_set_velocity(&pl, 0, 1000 * 256); /* 1000 counts/s */
	run_ms(50);
	/* One time constant: 1 - 1/e = 63.212 % of the step. */
	double frac = pl.w[0].vel_cps / 1000.0;
	assert_near(frac, 0.63212, 0.005 * 0.63212);
	assert_near(frac, 1.0 - exp(-1.0), 1e-9);
	/* Travel: 1000 * (t - tau * (1 - e^-1)) = 18.394 counts -> encoder 18. */
	assert_near(pl.w[0].pos_counts, 1000.0 * (0.05 - 0.05 * (1.0 - exp(-1.0))), 1e-9);
	assert_int_equal(counts(0), 18);
	run_ms(450); /* ten time constants */
	assert_near(pl.w[0].vel_cps, 1000.0, 0.05);
	/* The other wheel had no setpoint. */
	assert_near(pl.w[1].vel_cps, 0.0, 0.0);
}

static void ideal_motor_follows_at_once(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	start(&p);
	plant_drive_set_velocity(&pl, 1, -2560 * 256);
	plant_step(&pl, 1000);
	assert_near(pl.w[1].vel_cps, -2560.0, 0.0);
	assert_near(pl.w[1].pos_counts, -2.56, 1e-12);
}

static void encoder_quantisation(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	start(&p);
	plant_drive_set_velocity(&pl, 0, 300 * 256); /* 0.3 counts per ms */
	plant_drive_set_velocity(&pl, 1, -300 * 256);
	plant_step(&pl, 1000);
	assert_int_equal(counts(0), 0);	 /* floor(0.3) */
	assert_int_equal(counts(1), -1); /* floor(-0.3) */
	run_ms(3);
	assert_int_equal(counts(0), 1);	 /* 1.2 */
	assert_int_equal(counts(1), -2); /* -1.2 */
	run_ms(3);
	assert_int_equal(counts(0), 2);	 /* 2.1 */
	assert_int_equal(counts(1), -3); /* -2.1 */
	/* The true angle is kept unquantised. */
	assert_near(pl.w[0].pos_counts, 2.1, 1e-9);
}

static void acceleration_limit(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	p.acc_limit_mm_s2 = 1000.0;
	start(&p);
	plant_drive_set_velocity(&pl, 0, mm_s_q8(500.0));
	run_ms(100);
	assert_near(plant_wheel_mm_s(&pl, 0), 100.0, 1e-6);
	/* Distance under constant acceleration: a t^2 / 2 = 5 mm. */
	assert_near(plant_wheel_mm(&pl, 0), 5.0, 1e-6);
	run_ms(500);
	assert_near(plant_wheel_mm_s(&pl, 0), 500.0, 1e-3);
	/* Braking is limited too. */
	plant_drive_set_velocity(&pl, 0, 0);
	run_ms(100);
	assert_near(plant_wheel_mm_s(&pl, 0), 400.0, 1e-3);
}

static void current_limit(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	p.current_limit_a = 1.0;
	p.amp_per_mm_s2 = 0.002; /* 1 A buys 500 mm/s^2 */
	p.amp_per_mm_s = 0.0;
	start(&p);
	plant_drive_set_velocity(&pl, 0, mm_s_q8(400.0));
	run_ms(200);
	assert_near(plant_wheel_mm_s(&pl, 0), 100.0, 1e-6);
	assert_near(pl.w[0].current_a, 1.0, 1e-9);
}

static void disabled_motor_coasts(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	p.tau_s = 0.020;
	start(&p);
	plant_drive_set_velocity(&pl, 0, 1000 * 256);
	run_ms(400);
	assert_near(pl.w[0].vel_cps, 1000.0, 1e-3);
	plant_drive_enable(&pl, 0, false);
	run_ms(20);
	assert_near(pl.w[0].vel_cps, 1000.0 * exp(-1.0), 1e-3);
	hal_drive_state_t st;
	plant_drive_read(&pl, 0, &st);
	assert_false(st.enabled);
	assert_true(st.fresh);
}

static void relay_failure_and_drop(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	vs_config_defaults(&cfg);
	plant_init(&pl, &cfg, &p);

	/* A relay that fails stays open; the drives cannot enable. */
	plant_set_relay_mode(&pl, PLANT_RELAY_FAIL);
	assert_false(plant_power_set(&pl, true));
	assert_false(pl.relay_closed);
	plant_drive_enable(&pl, 0, true);
	plant_drive_set_velocity(&pl, 0, 1000 * 256);
	run_ms(10);
	assert_false(plant_drive_enabled(&pl, 0));
	assert_near(pl.w[0].vel_cps, 0.0, 0.0);

	/* Repaired: closes, drive runs. */
	plant_set_relay_mode(&pl, PLANT_RELAY_OK);
	assert_true(plant_power_set(&pl, true));
	plant_drive_enable(&pl, 0, true);
	run_ms(10);
	assert_true(plant_drive_enabled(&pl, 0));
	assert_near(pl.w[0].vel_cps, 1000.0, 0.0);

	/* Drops mid-run: contact opens, drives lose their enable and stop. */
	plant_set_relay_mode(&pl, PLANT_RELAY_DROP);
	assert_false(pl.relay_closed);
	run_ms(1);
	assert_false(plant_drive_enabled(&pl, 0));
	assert_false(pl.w[0].enable_cmd);
	assert_near(pl.w[0].vel_cps, 0.0, 0.0);

	/* Opening on command always works. */
	assert_true(plant_power_set(&pl, true));
	assert_true(plant_power_set(&pl, false));
	assert_false(pl.relay_closed);
}

static void io_loopback(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_default(&p);
	/* Default io table: inputs 1 (8 bits), 2 (1 bit); outputs 3 (8), 4 (1). */
	start(&p);
	uint32_t v = 0;
	assert_true(plant_io_write(&pl, 3, 0x1a5));
	assert_true(plant_io_read(&pl, 3, &v));
	assert_int_equal(v, 0xa5); /* masked to the output's 8 bits */
	assert_true(plant_io_read(&pl, 1, &v));
	assert_int_equal(v, 0xa5); /* n-th output wired to the n-th input */
	assert_true(plant_io_write(&pl, 4, 3));
	assert_true(plant_io_read(&pl, 2, &v));
	assert_int_equal(v, 1);

	/* Rewire output 3 to input 2 (1 bit); unwire output 4. */
	assert_true(plant_wire(&pl, 3, 2));
	assert_true(plant_wire(&pl, 4, 0));
	assert_true(plant_io_write(&pl, 4, 0));
	assert_true(plant_io_read(&pl, 2, &v));
	assert_int_equal(v, 1); /* unchanged: 4 no longer wired */
	assert_true(plant_io_write(&pl, 3, 0x02));
	assert_true(plant_io_read(&pl, 2, &v));
	assert_int_equal(v, 0);

	/* Injection, and ids that are not there or the wrong way round. */
	assert_true(plant_set_input(&pl, 1, 0x7f));
	assert_true(plant_io_read(&pl, 1, &v));
	assert_int_equal(v, 0x7f);
	assert_false(plant_set_input(&pl, 3, 1));
	assert_false(plant_io_write(&pl, 1, 1));
	assert_false(plant_io_write(&pl, 0, 1));
	assert_false(plant_io_read(&pl, 0, &v));
	assert_false(plant_io_read(&pl, 99, &v));
	assert_false(plant_wire(&pl, 1, 2));
	assert_false(plant_wire(&pl, 3, 4));

	/* Loopback off: outputs stay on their own. */
	p.io_loopback = false;
	start(&p);
	assert_true(plant_io_write(&pl, 3, 0x55));
	assert_true(plant_io_read(&pl, 1, &v));
	assert_int_equal(v, 0);
}

static void battery_sag_under_load(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p); /* 25.2 V, 0.1 ohm, 0.5 A idle, 2 mA per mm/s and mm/s^2 */
	p.acc_limit_mm_s2 = 1000.0;
	start(&p);
	plant_step(&pl, 1000);
	/* Still: only the electronics draw. */
	assert_int_equal(plant_battery_mv(&pl), 25150);
	/* Both wheels accelerating at 1000 mm/s^2, at 250 mm/s:
	 * I = 0.5 + 2 * (2.0 + 0.5) = 5.5 A -> 25.2 - 0.55 V. */
	plant_drive_set_velocity(&pl, 0, mm_s_q8(1000.0));
	plant_drive_set_velocity(&pl, 1, mm_s_q8(-1000.0));
	run_ms(249);
	assert_int_equal(plant_battery_mv(&pl), 24650);
	/* Cruising at 1000 mm/s: I = 0.5 + 2 * 2.0 = 4.5 A. */
	run_ms(1000);
	assert_int_equal(plant_battery_mv(&pl), 24750);
	/* A discharged pack. */
	plant_set_battery_ocv(&pl, 21.0);
	assert_int_equal(plant_battery_mv(&pl), 20550);
}

static void drive_fault_hooks(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	start(&p);
	hal_drive_state_t st;

	/* Fault: reported and latched; the power stage goes off. */
	assert_true(plant_drive_fault(&pl, 1, 0x2310));
	plant_drive_read(&pl, 1, &st);
	assert_int_equal(st.fault_code, 0x2310);
	assert_false(st.enabled);
	plant_drive_reset_fault(&pl, 1); /* condition still present */
	plant_drive_read(&pl, 1, &st);
	assert_int_equal(st.fault_code, 0x2310);
	assert_true(plant_drive_ok(&pl, 1));
	plant_drive_read(&pl, 1, &st);
	assert_int_equal(st.fault_code, 0x2310); /* latched until reset */
	plant_drive_reset_fault(&pl, 1);
	plant_drive_read(&pl, 1, &st);
	assert_int_equal(st.fault_code, 0);
	assert_true(st.enabled);

	/* Encoder stuck: the wheel turns, the count does not. */
	plant_drive_set_velocity(&pl, 0, 1000 * 256);
	run_ms(10);
	assert_int_equal(counts(0), 10);
	assert_true(plant_drive_stuck(&pl, 0, true));
	run_ms(10);
	assert_int_equal(counts(0), 10);
	assert_near(pl.w[0].pos_counts, 20.0, 1e-9);
	plant_drive_ok(&pl, 0);
	assert_int_equal(counts(0), 20);

	/* Silent: replies lost, the last one repeats with fresh = false. */
	assert_true(plant_drive_silent(&pl, 0, true));
	run_ms(10);
	plant_drive_read(&pl, 0, &st);
	assert_false(st.fresh);
	assert_int_equal(st.position_counts, 20);
	plant_drive_ok(&pl, 0);
	plant_drive_read(&pl, 0, &st);
	assert_true(st.fresh);
	assert_int_equal(st.position_counts, 30);

	/* Axes the base does not have. */
	assert_false(plant_drive_fault(&pl, 2, 1));
	assert_false(plant_drive_stuck(&pl, 2, true));
	assert_false(plant_drive_silent(&pl, 7, true));
	assert_false(plant_drive_ok(&pl, 2));
	plant_drive_read(&pl, 2, &st);
	assert_false(st.fresh);
}

static void differential_truth_pose(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	start(&p);
	double x, y, th;

	/* Straight: both wheels alike. */
	plant_drive_set_velocity(&pl, 0, 100 * 256);
	plant_drive_set_velocity(&pl, 1, 100 * 256);
	run_ms(1000);
	plant_pose(&pl, &x, &y, &th);
	assert_near(x, 100.0 / pl.counts_per_mm, 1e-9);
	assert_near(y, 0.0, 1e-12);
	assert_near(th, 0.0, 1e-12);

	/* Arc: left l, right r mm/s for 1 s; T = 400 mm.
	 * dth = (r - l)/T, R = T/2 (r + l)/(r - l). */
	plant_set_pose(&pl, 0, 0, 0);
	plant_drive_set_velocity(&pl, 0, 100 * 256);
	plant_drive_set_velocity(&pl, 1, 300 * 256);
	run_ms(1000);
	double l = 100.0 / pl.counts_per_mm, r = 300.0 / pl.counts_per_mm;
	double dth = (r - l) / 400.0, R = 200.0 * (r + l) / (r - l);
	plant_pose(&pl, &x, &y, &th);
	assert_near(x, R * sin(dth), 1e-9);
	assert_near(y, R * (1.0 - cos(dth)), 1e-9);
	assert_near(th, dth * 180.0 / M_PI, 1e-9);

	/* Half a turn and more on the spot: theta reported in (-180, 180]. */
	plant_set_pose(&pl, 0, 0, 170);
	plant_drive_set_velocity(&pl, 0, -mm_s_q8(200.0 * M_PI / 9.0)); /* 20 deg/s */
	plant_drive_set_velocity(&pl, 1, mm_s_q8(200.0 * M_PI / 9.0));
	run_ms(1000);
	plant_pose(&pl, &x, &y, &th);
	assert_near(th, -170.0, 1e-3);
	assert_near(x, 0.0, 1e-9);
}

static void mecanum_truth_pose(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	vs_config_defaults(&cfg);
	cfg.kinematics = VS_KIN_OMNI;
	cfg.wheel_base_mm = 300.0;
	plant_init(&pl, &cfg, &p);
	assert_int_equal(pl.n, 4);
	plant_power_set(&pl, true);
	for (uint8_t a = 0; a < 4; a++)
		plant_drive_enable(&pl, a, true);

	/* Sideways (kin.h: fl = -vy, fr = +vy, rl = +vy, rr = -vy). */
	int32_t s = 1000 * 256;
	plant_drive_set_velocity(&pl, 0, -s);
	plant_drive_set_velocity(&pl, 1, s);
	plant_drive_set_velocity(&pl, 2, s);
	plant_drive_set_velocity(&pl, 3, -s);
	run_ms(500);
	double x, y, th;
	plant_pose(&pl, &x, &y, &th);
	assert_near(x, 0.0, 1e-9);
	assert_near(y, 500.0 / pl.counts_per_mm, 1e-9);
	assert_near(th, 0.0, 1e-12);

	/* Rotation: w * (L + T) / 2 on each wheel, signs -, +, -, +. */
	plant_set_pose(&pl, 0, 0, 0);
	plant_drive_set_velocity(&pl, 0, -s);
	plant_drive_set_velocity(&pl, 1, s);
	plant_drive_set_velocity(&pl, 2, -s);
	plant_drive_set_velocity(&pl, 3, s);
	run_ms(100);
	plant_pose(&pl, &x, &y, &th);
	double mm = 100.0 / pl.counts_per_mm;
	assert_near(th, mm / 350.0 * 180.0 / M_PI, 1e-9);
	assert_near(x, 0.0, 1e-9);
	assert_near(y, 0.0, 1e-9);
}

static void assert_pose(double x, double y, double th_rad)
{
	assert_near(pl.x_mm, x, 1e-9);
	assert_near(pl.y_mm, y, 1e-9);
	assert_near(pl.th_rad, th_rad, 1e-12);
}

/* A push moves the truth by exactly the push, in the base's frame, and
 * turns the wheels by the travel of the steady twist that ends there. The
 * reference base: 150 mm wheels, 16384 counts (34.7679 a mm), 200 mm half
 * track (90 deg: 314.159 mm a wheel, 10922.667 counts). */
static void push_differential(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	start(&p);
	plant_set_pose(&pl, 100, 50, 90);
	assert_true(plant_push(&pl, 100, 0, 0)); /* forward, heading +y */
	assert_pose(100, 150, M_PI / 2);
	assert_int_equal(counts(0), 3476); /* 3476.79 */
	assert_int_equal(counts(1), 3476);
	assert_true(plant_push(&pl, 0, 0, 90));
	assert_pose(100, 150, M_PI);
	assert_int_equal(counts(0), -7446); /* 3476.79 - 10922.67 */
	assert_int_equal(counts(1), 14399);
	/* Sideways the truth moves (to the left of heading 180: -y) and the
	 * wheels skid. */
	assert_true(plant_push(&pl, 0, 50, 0));
	assert_pose(100, 100, M_PI);
	assert_int_equal(counts(0), -7446);
	assert_int_equal(counts(1), 14399);

	/* 100 mm forward while turned 60 deg: the twist's forward part is
	 * dx h / tan h = 90.690 mm (h = 30 deg), its rotation 209.440 mm a
	 * wheel: -118.750 and 300.130 mm; its lateral -52.360 mm skids. */
	start(&p);
	assert_true(plant_push(&pl, 100, 0, 60));
	assert_pose(100, 0, M_PI / 3);
	assert_int_equal(counts(0), -4129);	/* -4128.68 */
	assert_int_equal(counts(1), 10434);	/* 10434.88 */
	assert_near(pl.w[0].vel_cps, 0.0, 0.0); /* the speeds stay */

	/* Out of bounds or not a number: nothing moves. */
	assert_false(plant_push(&pl, 1000.001, 0, 0));
	assert_false(plant_push(&pl, 0, -1000.5, 0));
	assert_false(plant_push(&pl, 0, 0, 180.01));
	assert_false(plant_push(&pl, NAN, 0, 0));
	assert_false(plant_push(&pl, 0, 0, INFINITY));
	assert_pose(100, 0, M_PI / 3);
	assert_int_equal(counts(0), -4129);
	assert_int_equal(counts(1), 10434);
	assert_true(plant_push(&pl, -1000, 1000, -180)); /* the bounds themselves */
	assert_pose(100 - 1000 * cos(M_PI / 3) - 1000 * sin(M_PI / 3),
		    -1000 * sin(M_PI / 3) + 1000 * cos(M_PI / 3), M_PI / 3 - M_PI);
}

/* Mecanum (the base of config/vehicle-omni.xml: 100 mm wheels, 8192
 * counts, 26.0759 a mm, (L + T) / 2 = 425 mm): every part of a push rolls. */
static void push_mecanum(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p);
	vs_config_defaults(&cfg);
	cfg.kinematics = VS_KIN_OMNI;
	cfg.wheel_diameter_mm = 100;
	cfg.track_width_mm = 450;
	cfg.wheel_base_mm = 400;
	cfg.encoder_counts_per_rev = 8192;
	plant_init(&pl, &cfg, &p);
	/* 100 mm to the left: fl -, fr +, rl +, rr - (kin.h), 2607.59 counts. */
	assert_true(plant_push(&pl, 0, 100, 0));
	assert_pose(0, 100, 0);
	int32_t want1[4] = {-2608, 2607, 2607, -2608};
	for (uint8_t a = 0; a < 4; a++)
		assert_int_equal(counts(a), want1[a]);
	/* 30 deg: 425 mm * pi / 6 = 222.529 mm a wheel, 5802.667 counts. */
	plant_init(&pl, &cfg, &p);
	assert_true(plant_push(&pl, 0, 0, 30));
	assert_pose(0, 0, M_PI / 6);
	int32_t want2[4] = {-5803, 5802, -5803, 5802};
	for (uint8_t a = 0; a < 4; a++)
		assert_int_equal(counts(a), want2[a]);
	/* All three at heading 90: twist (110.795, 22.672) mm and 30 deg. */
	plant_init(&pl, &cfg, &p);
	plant_set_pose(&pl, 0, 0, 90);
	assert_true(plant_push(&pl, 100, 50, 30));
	assert_pose(-50, 100, M_PI / 2 + M_PI / 6);
	int32_t want3[4] = {-3505, 9282, -2323, 8100}; /* -3504.79 9282.95 -2322.38 8100.54 */
	for (uint8_t a = 0; a < 4; a++)
		assert_int_equal(counts(a), want3[a]);

	/* The same wheel travel driven by the motors over one step lands the
	 * base where the push put it (plant_step's kinematics, the setpoints
	 * rounded to 1/256 count). */
	plant_t pushed = pl;
	plant_init(&pl, &cfg, &p);
	plant_set_pose(&pl, 0, 0, 90);
	plant_power_set(&pl, true);
	for (uint8_t a = 0; a < 4; a++) {
		plant_drive_enable(&pl, a, true);
		plant_drive_set_velocity(&pl, a, (int32_t)lround(pushed.w[a].pos_counts * 256.0));
	}
	plant_step(&pl, 1000000);
	assert_near(pl.x_mm, pushed.x_mm, 1e-4);
	assert_near(pl.y_mm, pushed.y_mm, 1e-4);
	assert_near(pl.th_rad, pushed.th_rad, 1e-6);
}

static void contact_from_wall_and_injection(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_ideal(&p); /* body radius 300 mm */
	start(&p);
	assert_false(plant_contact(&pl));
	assert_true(plant_add_wall(&pl, 1100, -500, 1000, 500)); /* corners in any order */
	plant_set_pose(&pl, 699, 0, 0);
	assert_false(plant_contact(&pl));
	plant_set_pose(&pl, 700, 0, 0);
	assert_true(plant_contact(&pl));
	/* Near a corner: distance to (1000, 500) is 300 at (820, 740). */
	plant_set_pose(&pl, 820, 740, 0);
	assert_true(plant_contact(&pl));
	plant_set_pose(&pl, 819, 741, 0);
	assert_false(plant_contact(&pl));
	pl.contact_inject = true;
	assert_true(plant_contact(&pl));
	for (int i = 1; i < PLANT_MAX_WALLS; i++)
		assert_true(plant_add_wall(&pl, 0, 0, 1, 1));
	assert_false(plant_add_wall(&pl, 0, 0, 1, 1));
}

static void joystick_injection(void **state)
{
	(void)state;
	plant_params_t p;
	plant_params_default(&p);
	start(&p);
	assert_true(pl.js.present); /* the reference base has one */
	plant_set_joystick(&pl, 0.5, -1.0, 2.0, true);
	assert_int_equal(pl.js.axis[0], 16384);
	assert_int_equal(pl.js.axis[1], -32767);
	assert_int_equal(pl.js.axis[2], 32767); /* clamped */
	plant_set_joystick(&pl, 0.5, 0, 0, false);
	assert_false(pl.js.present);
	assert_int_equal(pl.js.axis[0], 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(first_order_response),
	    cmocka_unit_test(ideal_motor_follows_at_once),
	    cmocka_unit_test(encoder_quantisation),
	    cmocka_unit_test(acceleration_limit),
	    cmocka_unit_test(current_limit),
	    cmocka_unit_test(disabled_motor_coasts),
	    cmocka_unit_test(relay_failure_and_drop),
	    cmocka_unit_test(io_loopback),
	    cmocka_unit_test(battery_sag_under_load),
	    cmocka_unit_test(drive_fault_hooks),
	    cmocka_unit_test(differential_truth_pose),
	    cmocka_unit_test(mecanum_truth_pose),
	    cmocka_unit_test(push_differential),
	    cmocka_unit_test(push_mecanum),
	    cmocka_unit_test(contact_from_wall_and_injection),
	    cmocka_unit_test(joystick_injection),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
