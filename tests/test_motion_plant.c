/* Motion checks on the ideal simulated plant, driven through the console as
 * a host would and asserted from a per-tick trace (commanded velocity,
 * odometry pose, true plant pose). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "host_sim/sim.h"

#define HZ 1000.0
static const double Q = 4294967296.0;

/* Set speeds used throughout (console setVelocity / setAcceleration). */
#define VT 400.0
#define VR 60.0
#define AT 300.0
#define AR 120.0

typedef struct {
	double v, w;	    /* commanded, per second */
	double x, y, th;    /* odometry */
	double tx, ty, tth; /* true plant pose */
	int16_t state;
} sample_t;

typedef struct {
	sim_t sim;
	sample_t *s;
	size_t n, cap;
} rig_t;

static void on_tick(void *ctx, sim_t *sim)
{
	rig_t *r = ctx;
	vs_diag_t d;
	vehicle_diag(sim_vehicle(sim), &d);
	if (r->n == r->cap) {
		r->cap = r->cap ? r->cap * 2 : 65536;
		r->s = realloc(r->s, r->cap * sizeof *r->s);
		assert_non_null(r->s);
	}
	sample_t *s = &r->s[r->n++];
	s->v = hypot((double)d.cmd_twist_pt.vx_pt, (double)d.cmd_twist_pt.vy_pt) / Q * HZ;
	if (d.cmd_twist_pt.vx_pt < 0)
		s->v = -s->v;
	s->w = (double)d.cmd_twist_pt.w_pt / Q * HZ;
	s->x = (double)d.odom_pose.x_mm / Q;
	s->y = (double)d.odom_pose.y_mm / Q;
	s->th = (double)d.odom_pose.th_deg / Q;
	plant_pose(sim_plant(sim), &s->tx, &s->ty, &s->tth);
	char msg[VS_STATE_MSG_MAX];
	vs_getState(sim_vehicle(sim), &s->state, msg);
}

static void exec_ok(rig_t *r, const char *line, const char *want)
{
	char reply[CONSOLE_REPLY_MAX];
	assert_true(sim_exec(&r->sim, line, reply, sizeof reply));
	if (strcmp(reply, want) != 0)
		fail_msg("'%s' -> '%s', want '%s'", line, reply, want);
}

/* Starts the firmware on the ideal plant with cfg, powered and servoed,
 * at the set speeds used throughout, with an empty trace. */
static void rig_start(rig_t *r, const vs_config_t *cfg_in)
{
	plant_params_t pp;
	vs_config_t cfg = *cfg_in;
	plant_params_ideal(&pp);
	plant_config_lag(&pp, &cfg);
	const char *bad = NULL;
	if (sim_init_ex(&r->sim, &cfg, &pp, &bad) != 0)
		fail_msg("configuration refused: %s", bad ? bad : "?");
	sim_set_tick_cb(&r->sim, on_tick, r);
	exec_ok(r, "setPower true", "ok true");
	exec_ok(r, "setServo true", "ok true");
	exec_ok(r, "setVelocity 400 60", "ok true");
	exec_ok(r, "setAcceleration 300 120", "ok true");
	r->n = 0;
}

static int setup(void **state)
{
	rig_t *r = calloc(1, sizeof *r);
	vs_config_t cfg;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
	rig_start(r, &cfg);
	*state = r;
	return 0;
}

static int teardown(void **state)
{
	rig_t *r = *state;
	free(r->s);
	free(r);
	return 0;
}

/* Largest commanded acceleration over the trace, translation and rotation. */
static void max_acc(const rig_t *r, double *at, double *ar)
{
	*at = *ar = 0;
	for (size_t i = 1; i < r->n; i++) {
		double a = fabs(r->s[i].v - r->s[i - 1].v) * HZ;
		double b = fabs(r->s[i].w - r->s[i - 1].w) * HZ;
		if (a > *at)
			*at = a;
		if (b > *ar)
			*ar = b;
	}
}

static void assert_acc_within_1pct(const rig_t *r)
{
	double at, ar;
	max_acc(r, &at, &ar);
	if (at > AT * 1.01 || ar > AR * 1.01)
		fail_msg("acceleration %.3f mm/s^2, %.3f deg/s^2 over the set %.0f, %.0f", at, ar,
			 AT, AR);
}

/* Runs until the unit is Ready again (or the limit). */
static void run_until_ready(rig_t *r, uint32_t max_ms)
{
	for (uint32_t t = 0; t < max_ms; t += 10) {
		sim_run_ms(&r->sim, 10);
		if (r->n > 0 && r->s[r->n - 1].state == VS_STATE_READY)
			return;
	}
	fail_msg("not Ready after %u ms", max_ms);
}

static double angle_err(double a, double b)
{
	double e = fmod(a - b + 540.0, 360.0) - 180.0;
	return fabs(e);
}

static void test_forward_10m(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "moveForward 10000", "ok true");
	run_until_ready(r, 60000);
	sim_run_ms(&r->sim, 200);
	sample_t *e = &r->s[r->n - 1];
	printf("moveForward 10000: odometry %.4f %.4f %.4f, true %.4f %.4f\n", e->x, e->y, e->th,
	       e->tx, e->ty);
	assert_true(fabs(e->x - 10000.0) <= 0.05 && fabs(e->y) <= 0.05);
	assert_true(fabs(e->tx - 10000.0) <= 0.05 && fabs(e->ty) <= 0.05);
	exec_ok(r, "getPosition", "ok true 10000.000 0.000 0.000");
	for (size_t i = 0; i < r->n; i++)
		assert_true(r->s[i].v <= VT * 1.0000001);
	assert_acc_within_1pct(r);
}

static void test_turn_360(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "moveTurn 360", "ok true");
	run_until_ready(r, 60000);
	sim_run_ms(&r->sim, 200);
	sample_t *e = &r->s[r->n - 1];
	printf("moveTurn 360: odometry %.5f deg, true %.5f deg\n", e->th, e->tth);
	assert_true(angle_err(e->th, 0) <= 0.01);
	assert_true(angle_err(e->tth, 0) <= 0.01);
	double peak = 0;
	for (size_t i = 0; i < r->n; i++)
		peak = fmax(peak, fabs(r->s[i].w));
	assert_true(peak <= VR * 1.0000001 && peak >= VR * 0.999);
	assert_acc_within_1pct(r);
}

static void test_linear_abs_square(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "moveLinearAbs 1000 0 90", "ok true");
	exec_ok(r, "moveLinearAbs 1000 1000 180", "ok true");
	exec_ok(r, "moveLinearAbs 0 1000 -90", "ok true");
	exec_ok(r, "moveLinearAbs 0 0 0", "ok true");
	run_until_ready(r, 120000);
	sim_run_ms(&r->sim, 200);
	sample_t *e = &r->s[r->n - 1];
	printf("square: back at %.4f %.4f %.4f (true %.4f %.4f)\n", e->x, e->y, e->th, e->tx,
	       e->ty);
	assert_true(hypot(e->x, e->y) <= 0.1);
	assert_true(hypot(e->tx, e->ty) <= 0.1);
	assert_true(angle_err(e->th, 0) <= 0.01);
	/* At each corner the translation speed reaches zero. */
	const double corner[4][2] = {{1000, 0}, {1000, 1000}, {0, 1000}, {0, 0}};
	for (int c = 0; c < 4; c++) {
		bool stopped = false;
		for (size_t i = 0; i < r->n; i++)
			if (hypot(r->s[i].x - corner[c][0], r->s[i].y - corner[c][1]) < 0.5 &&
			    r->s[i].v == 0.0)
				stopped = true;
		if (!stopped)
			fail_msg("no stop at corner %d", c);
	}
	assert_acc_within_1pct(r);
}

static void test_cruise_does_not_stop(void **state)
{
	rig_t *r = *state;
	const double wp[5][2] = {{1000, 0}, {2000, 500}, {3000, 0}, {4000, 800}, {5000, 800}};
	char line[64];
	for (int i = 0; i < 5; i++) {
		snprintf(line, sizeof line, "moveCruiseAbs %.0f %.0f", wp[i][0], wp[i][1]);
		exec_ok(r, line, "ok true");
	}
	run_until_ready(r, 120000);
	sim_run_ms(&r->sim, 200);
	/* From the first translation to the end: speed stays above zero until
	 * the final approach, and near each intermediate waypoint it is high. */
	size_t first = 0, last = 0;
	for (size_t i = 0; i < r->n; i++)
		if (r->s[i].v > 0) {
			if (!first)
				first = i;
			last = i;
		}
	for (size_t i = first; i < last; i++)
		if (r->s[i].v <= 0)
			fail_msg("speed %.3f at tick %zu between waypoints", r->s[i].v, i);
	for (int k = 1; k < 4; k++) {
		double vmin = 1e9;
		for (size_t i = first; i < last; i++)
			if (hypot(r->s[i].x - wp[k - 1][0], r->s[i].y - wp[k - 1][1]) < 50)
				vmin = fmin(vmin, r->s[i].v);
		printf("cruise: slowest %.1f mm/s within 50 mm of waypoint %d\n", vmin, k);
		assert_true(vmin > 50.0);
	}
	sample_t *e = &r->s[r->n - 1];
	assert_true(hypot(e->x - 5000, e->y - 800) <= 0.1);
	assert_acc_within_1pct(r);
	for (size_t i = 0; i < r->n; i++)
		assert_true(fabs(r->s[i].w) <= VR * 1.0000001);
}

static void test_continuous_retarget_is_smooth(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "moveContinuousRel 3000 0 0", "ok true");
	sim_run_ms(&r->sim, 2500);
	size_t at_retarget = r->n;
	assert_true(r->s[r->n - 1].v > 100);
	exec_ok(r, "moveContinuousRel 1000 400 30", "ok true");
	sim_run_ms(&r->sim, 1500);
	exec_ok(r, "moveContinuousRel 500 -300 0", "ok true");
	run_until_ready(r, 60000);
	/* No velocity step larger than acceleration x period, anywhere. */
	for (size_t i = 1; i < r->n; i++) {
		double dv = fabs(r->s[i].v - r->s[i - 1].v), dw = fabs(r->s[i].w - r->s[i - 1].w);
		if (dv > AT / HZ * 1.0000001 || dw > AR / HZ * 1.0000001)
			fail_msg("step %.6f mm/s, %.6f deg/s at tick %zu (retarget at %zu)", dv, dw,
				 i, at_retarget);
	}
}

/* A retarget closer than the stopping distance: the unit brakes at the set
 * acceleration, passes the goal, and backs along the same line to it. It
 * never turns (the goal stays dead ahead or dead astern) and never steps
 * its velocity by more than the acceleration allows. */
static void test_continuous_retarget_inside_stopping_distance(void **state)
{
	rig_t *r = *state;
	vs_diag_t d;
	exec_ok(r, "moveContinuousRel 3000 0 0", "ok true");
	sim_run_ms(&r->sim, 1500);
	assert_true(fabs(r->s[r->n - 1].v - VT) < 1e-6); /* cruising */
	vehicle_diag(sim_vehicle(&r->sim), &d);
	double x0 = (double)d.ref_pose.x_mm / Q;
	exec_ok(r, "moveContinuousRel 100 0 0", "ok true");
	size_t from = r->n;
	run_until_ready(r, 5000);
	double xmax = -1e9, vmin = 1e9;
	for (size_t i = from; i < r->n; i++) {
		xmax = fmax(xmax, r->s[i].x);
		vmin = fmin(vmin, r->s[i].v);
		assert_true(r->s[i].w == 0.0 && r->s[i].th == 0.0 && r->s[i].y == 0.0);
		double dv = fabs(r->s[i].v - r->s[i - 1].v);
		if (dv > AT / HZ * 1.0000001)
			fail_msg("step %.6f mm/s at tick %zu", dv, i);
	}
	/* Braking from 400 mm/s at 300 mm/s^2 takes 266.7 mm: 166.7 past. */
	assert_true(fabs(xmax - (x0 + VT * VT / (2 * AT))) < VT / HZ);
	assert_true(vmin < -100.0);
	sample_t *e = &r->s[r->n - 1];
	printf("continuous: braked %.4f mm past the call, backed at up to %.1f mm/s, ended at "
	       "%.4f (true %.4f) for 100, %zu ms\n",
	       xmax - x0, -vmin, e->x - x0, e->tx - x0, r->n - from);
	/* the odometry's and the plant's resolution, as moveForward's test */
	assert_true(fabs(e->x - (x0 + 100.0)) <= 0.05 && fabs(e->tx - (x0 + 100.0)) <= 0.05);
	assert_true(e->th == 0.0 && e->y == 0.0 && fabs(e->ty) <= 0.05);
	/* over within the braking, the return and the last approach */
	assert_true(r->n - from < 4000);
}

static void test_jog_watchdog(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "setJogTimeout 300", "ok true");
	exec_ok(r, "moveJog 200 0 0", "ok true");
	sim_run_ms(&r->sim, 250);
	exec_ok(r, "moveJog 200 0 0", "ok true");
	size_t last_cmd = r->n;
	sim_run_ms(&r->sim, 3000);
	/* Stopping time from 200 mm/s at 300 mm/s^2: 667 ms. */
	size_t stop = 0;
	for (size_t i = last_cmd; i < r->n; i++)
		if (r->s[i].v == 0 && r->s[i].w == 0) {
			stop = i;
			break;
		}
	assert_true(stop > last_cmd);
	double elapsed_ms = (double)(stop - last_cmd);
	printf("jog: stopped %.0f ms after the last command (bound %.0f)\n", elapsed_ms,
	       300 + 200.0 / AT * 1000 + 2);
	assert_true(elapsed_ms <= 300 + ceil(200.0 / AT * 1000) + 2);
	assert_true(elapsed_ms >= 300);
	assert_int_equal(r->s[r->n - 1].state, VS_STATE_READY);
}

static void test_set_velocity_while_moving(void **state)
{
	rig_t *r = *state;
	exec_ok(r, "moveForward 5000", "ok true");
	sim_run_ms(&r->sim, 3000);
	assert_true(fabs(r->s[r->n - 1].v - VT) < 1e-6);
	size_t change = r->n;
	exec_ok(r, "setVelocity 150 60", "ok true");
	sim_run_ms(&r->sim, 2000);
	/* Down from 400 to 150 mm/s at the set 300 mm/s^2: 833 ms, in steps of
	 * at most a x period, then held at 150. */
	for (size_t i = change + 1; i < r->n; i++)
		assert_true(r->s[i - 1].v - r->s[i].v <= AT / HZ * 1.0000001);
	assert_true(r->s[change + 800].v > 150.0);
	for (size_t i = change + 840; i < r->n; i++)
		assert_true(fabs(r->s[i].v - 150.0) < 1e-6);
	exec_ok(r, "setVelocity 400 60", "ok true");
	run_until_ready(r, 60000);
	sim_run_ms(&r->sim, 200);
	assert_true(fabs(r->s[r->n - 1].x - 5000.0) <= 0.05);
	assert_acc_within_1pct(r);
}

/* The mecanum base end to end: sideways and diagonal motion with a heading
 * change in one straight move, y jog, and the same commands the
 * differential base refuses. */
static void test_omni_base(void **state)
{
	rig_t *r = *state;
	vs_config_t cfg;
	vs_config_defaults(&cfg);
	/* Time passes in lockstep waits with no request; the link watchdog
	 * has its own tests. */
	cfg.link_timeout_ms = 0;
	cfg.kinematics = VS_KIN_OMNI;
	cfg.wheel_base_mm = 350;
	/* Half the fine encoder (2^19): the mecanum wheel's fastest setpoint
	 * must still fit the drive's counts/s range (vs_config_check). */
	cfg.encoder_counts_per_rev = plant_hires_counts_per_rev(&cfg);
	rig_start(r, &cfg);
	exec_ok(r, "moveLinearRel 0 500 0", "ok true");
	run_until_ready(r, 30000);
	exec_ok(r, "moveLinearAbs 800 -300 -60", "ok true");
	run_until_ready(r, 30000);
	sim_run_ms(&r->sim, 200);
	sample_t *e = &r->s[r->n - 1];
	printf("omni: at %.4f %.4f %.4f (true %.4f %.4f %.4f)\n", e->x, e->y, e->th, e->tx, e->ty,
	       e->tth);
	assert_true(hypot(e->x - 800, e->y + 300) <= 0.05);
	assert_true(hypot(e->tx - 800, e->ty + 300) <= 0.05);
	assert_true(angle_err(e->th, -60) <= 0.01 && angle_err(e->tth, -60) <= 0.01);
	assert_acc_within_1pct(r);
	/* A sideways jog moves along y in the vehicle frame. */
	exec_ok(r, "setPosition 0 0 0", "ok true");
	exec_ok(r, "setJogTimeout 200", "ok true");
	exec_ok(r, "moveJog 0 200 0", "ok true");
	run_until_ready(r, 10000);
	sim_run_ms(&r->sim, 100);
	e = &r->s[r->n - 1];
	assert_true(e->y > 10 && fabs(e->x) < 0.05 && angle_err(e->th, 0) < 0.01);
	exec_ok(r, "moveCircularRel 200 0 90", "ok true");
	run_until_ready(r, 30000);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test_setup_teardown(test_forward_10m, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_turn_360, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_linear_abs_square, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_cruise_does_not_stop, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_continuous_retarget_is_smooth, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_continuous_retarget_inside_stopping_distance,
					    setup, teardown),
	    cmocka_unit_test_setup_teardown(test_jog_watchdog, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_set_velocity_while_moving, setup, teardown),
	    cmocka_unit_test_setup_teardown(test_omni_base, setup, teardown),
	};
	return cmocka_run_group_tests_name("motion on the ideal plant", tests, NULL, NULL);
}
