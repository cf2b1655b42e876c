/* Motion engine on its own: exact endpoints, limits, blending, modes.
 * The reference pose is fed back as the measured pose (a perfect plant). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cmocka.h>

#include "firmware/kin.h"
#include "firmware/motion.h"

#define HZ 1000
static const double Q = 4294967296.0;

static q32_t q(double v)
{
	return (q32_t)llround(v * Q);
}
static double d(q32_t v)
{
	return (double)v / Q;
}

typedef struct {
	motion_t m;
	/* Per-tick history of the commanded body velocity (per second). */
	double vx, w, ax_max, aw_max, v_max, w_max;
	uint32_t ticks;
} rig_t;

static void rig_init(rig_t *r, motion_kin_t kin)
{
	motion_params_t p = {
	    .tick_hz = HZ,
	    .kin = kin,
	    .vel_limit_t = q(1000),
	    .vel_limit_r = q(180),
	    .acc_limit_t = q(1000),
	    .acc_limit_r = q(360),
	    .cruise_blend_mm = q(200),
	};
	*r = (rig_t){0};
	motion_init(&r->m, &p);
	motion_set_velocity(&r->m, q(500), q(90));
	motion_set_accel(&r->m, q(500), q(180));
}

static void rig_tick(rig_t *r)
{
	fx_twist_t t;
	fx_pose_t meas = r->m.ref;
	motion_tick(&r->m, &meas, &t);
	double vx = hypot(d(t.vx_pt), d(t.vy_pt)) * HZ, w = d(t.w_pt) * HZ;
	double ax = fabs(vx - r->vx) * HZ, aw = fabs(w - r->w) * HZ;
	if (ax > r->ax_max)
		r->ax_max = ax;
	if (aw > r->aw_max)
		r->aw_max = aw;
	if (fabs(vx) > r->v_max)
		r->v_max = fabs(vx);
	if (fabs(w) > r->w_max)
		r->w_max = fabs(w);
	r->vx = vx;
	r->w = w;
	r->ticks++;
}

static void run_until_idle(rig_t *r, uint32_t max_ticks)
{
	for (uint32_t i = 0; i < max_ticks; i++) {
		rig_tick(r);
		if (!motion_has_work(&r->m))
			return;
	}
	fail_msg("still moving after %u ticks", max_ticks);
}

static void test_forward_lands_exactly(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_forward(&r.m, q(10000)));
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, q(10000));
	assert_int_equal(r.m.ref.y_mm, 0);
	assert_int_equal(r.m.ref.th_deg, 0);
	assert_true(r.v_max <= 500.0);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	/* 10 m at 500 mm/s with 500 mm/s^2 ramps: 20 s + 1 s. */
	assert_in_range(r.ticks, 20990, 21010);
}

static void test_turn_full_circle(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_turn(&r.m, q(360)));
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.th_deg, 0);
	assert_int_equal(r.m.ref.x_mm, 0);
	assert_true(r.w_max <= 90.0);
	assert_true(r.aw_max <= 180.0 * 1.0000001);
}

static void test_linear_abs_square(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	double pts[4][3] = {{1000, 0, 90}, {1000, 1000, 180}, {0, 1000, -90}, {0, 0, 0}};
	for (int i = 0; i < 4; i++) {
		fx_pose_t p = {q(pts[i][0]), q(pts[i][1]), q(pts[i][2])};
		assert_true(motion_linear_abs(&r.m, &p));
	}
	run_until_idle(&r, 60000);
	assert_true(fabs(d(r.m.ref.x_mm)) < 1e-6);
	assert_true(fabs(d(r.m.ref.y_mm)) < 1e-6);
	assert_int_equal(r.m.ref.th_deg, 0);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	assert_true(r.aw_max <= 180.0 * 1.0000001);
}

static void test_cruise_keeps_moving(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	double pts[4][2] = {{1000, 0}, {2000, 1000}, {3000, 1000}, {3000, 2000}};
	for (int i = 0; i < 4; i++)
		assert_true(motion_cruise_abs(&r.m, q(pts[i][0]), q(pts[i][1])));
	double min_speed_mid = 1e9;
	uint32_t stops = 0;
	bool started = false;
	for (uint32_t i = 0; i < 60000 && motion_has_work(&r.m); i++) {
		rig_tick(&r);
		if (r.vx > 1)
			started = true;
		if (started && motion_has_work(&r.m) && r.vx == 0 && r.w == 0)
			stops++;
		double x = d(r.m.ref.x_mm), y = d(r.m.ref.y_mm);
		/* Near the intermediate waypoints the unit is still moving. */
		if ((hypot(x - 1000, y) < 150 || hypot(x - 2000, y - 1000) < 150 ||
		     hypot(x - 3000, y - 1000) < 150) &&
		    r.vx < min_speed_mid)
			min_speed_mid = r.vx;
	}
	assert_false(motion_has_work(&r.m));
	printf("cruise: min speed near waypoints %.1f mm/s, ax %.2f aw %.2f, %u ticks\n",
	       min_speed_mid, r.ax_max, r.aw_max, r.ticks);
	assert_true(min_speed_mid > 10.0);
	assert_int_equal(stops, 0);
	assert_true(fabs(d(r.m.ref.x_mm) - 3000) < 1e-6);
	assert_true(fabs(d(r.m.ref.y_mm) - 2000) < 1e-6);
	assert_true(r.ax_max <= 500.0 * 1.00001);
	assert_true(r.aw_max <= 180.0 * 1.00001);
	assert_true(r.w_max <= 90.0 * 1.001);
}

/* A corner too tight to enter at speed (its rotation caps the speed
 * within two ticks of the line's braking: the step in may carry one): the
 * unit stops on the waypoint and turns there, within the rotation's
 * acceleration. Found by fuzz_ops on a mecanum base (a 0.5 mm leg: a
 * corner entered at 0.55 mm/tick over its 0.32 cap, the rotation 20 %
 * over its limit). */
static void test_tight_corner_not_blended(void **state)
{
	(void)state;
	for (int omni = 0; omni < 2; omni++) {
		rig_t r;
		rig_init(&r, omni ? MOTION_KIN_OMNI : MOTION_KIN_DIFF);
		assert_true(motion_cruise_abs(&r.m, q(100), q(0)));
		assert_true(motion_cruise_abs(&r.m, q(100), q(0.5)));
		assert_true(motion_cruise_abs(&r.m, q(200), q(0.5)));
		uint32_t stops = 0;
		bool started = false;
		for (uint32_t i = 0; i < 60000 && motion_has_work(&r.m); i++) {
			rig_tick(&r);
			started = started || r.vx > 1;
			if (started && motion_has_work(&r.m) && r.vx == 0 && r.w == 0)
				stops++;
		}
		assert_false(motion_has_work(&r.m));
		assert_true(fabs(d(r.m.ref.x_mm) - 200) < 1e-6);
		assert_true(fabs(d(r.m.ref.y_mm) - 0.5) < 1e-6);
		/* At rest on the first waypoint (the corner into the short leg
		 * is too tight); the second one's is fitted. */
		assert_true(stops >= 1);
		assert_true(r.ax_max <= 500.0 * 1.00001);
		assert_true(r.aw_max <= 180.0 * 1.00001);
	}
}

static void test_jog_watchdog(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	motion_set_jog_timeout_ms(&r.m, 200);
	assert_true(motion_jog(&r.m, q(300), 0, 0));
	uint32_t t = 0;
	while (motion_has_work(&r.m) && t < 10000) {
		rig_tick(&r);
		t++;
	}
	/* 200 ms at speed, then 300 mm/s at 500 mm/s^2: 600 ms more. */
	assert_true(t <= 200 + 600 + 2);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
}

static void test_continuous_retarget(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	fx_pose_t g1 = {q(2000), 0, 0};
	assert_true(motion_continuous_rel(&r.m, &g1));
	for (int i = 0; i < 1500; i++)
		rig_tick(&r);
	fx_pose_t g2 = {q(1000), q(500), 0};
	assert_true(motion_continuous_rel(&r.m, &g2));
	run_until_idle(&r, 60000);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	assert_true(r.aw_max <= 180.0 * 1.0000001);
}

/* A retarget to a point close by, off the heading (300, 200 then, 400 ms
 * later, 100, -100 from where the unit is): the forward speed never exceeds
 * what the turn can bring the goal round at (v <= w d / (2 sin e)), so the
 * unit does not orbit the goal: it lands on it exactly within 5.5 s
 * (5,055 ticks), turning less than one full turn in all (224 degrees;
 * before, it circled the goal for 19,284 ticks, 1,618 degrees). */
static void test_continuous_no_orbit(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	fx_pose_t g1 = {q(300), q(200), 0};
	assert_true(motion_continuous_rel(&r.m, &g1));
	for (int i = 0; i < 400; i++)
		rig_tick(&r);
	fx_pose_t g2 = {q(100), q(-100), 0};
	assert_true(motion_continuous_rel(&r.m, &g2));
	fx_pose_t goal = r.m.goal;
	double turned = 0, th = d(r.m.ref.th_deg);
	uint32_t t0 = r.ticks;
	for (int i = 0; i < 30000 && motion_has_work(&r.m); i++) {
		rig_tick(&r);
		double dth = d(r.m.ref.th_deg) - th;
		dth -= 360.0 * floor((dth + 180.0) / 360.0);
		turned += fabs(dth);
		th = d(r.m.ref.th_deg);
	}
	printf("retarget close by: %u ticks, turned %.1f deg\n", r.ticks - t0, turned);
	assert_false(motion_has_work(&r.m));
	assert_int_equal(r.m.ref.x_mm, goal.x_mm);
	assert_int_equal(r.m.ref.y_mm, goal.y_mm);
	assert_int_equal(r.m.ref.th_deg, goal.th_deg);
	assert_true(r.ticks - t0 < 5500);
	assert_true(turned < 360.0);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	assert_true(r.aw_max <= 180.0 * 1.0000001);
}

static void test_pause_resume_stop(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_forward(&r.m, q(2000)));
	for (int i = 0; i < 1500; i++)
		rig_tick(&r);
	motion_pause(&r.m);
	for (int i = 0; i < 1000; i++)
		rig_tick(&r);
	assert_false(motion_is_moving(&r.m));
	assert_true(motion_has_work(&r.m));
	motion_resume(&r.m);
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, q(2000));
	/* pause decelerates at the limit: 1000 mm/s^2 */
	assert_true(r.ax_max <= 1000.0 * 1.0000001);

	assert_true(motion_forward(&r.m, q(2000)));
	for (int i = 0; i < 1500; i++)
		rig_tick(&r);
	motion_stop(&r.m);
	run_until_idle(&r, 2000);
	assert_int_equal(motion_queue_len(&r.m), 0);
}

static void test_omni_linear(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_OMNI);
	fx_pose_t p = {q(500), q(-700), q(45)};
	assert_true(motion_linear_abs(&r.m, &p));
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, q(500));
	assert_int_equal(r.m.ref.y_mm, q(-700));
	assert_int_equal(r.m.ref.th_deg, q(45));
	/* Clockwise heading change on the way, and back through +-180. */
	fx_pose_t p2 = {q(-300), q(200), q(-120)};
	assert_true(motion_linear_abs(&r.m, &p2));
	fx_pose_t p3 = {q(0), q(0), q(170)};
	assert_true(motion_linear_abs(&r.m, &p3));
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, 0);
	assert_int_equal(r.m.ref.y_mm, 0);
	assert_int_equal(r.m.ref.th_deg, q(170));
	assert_true(r.aw_max <= 180.0 * 1.0000001);
	assert_true(r.w_max <= 90.0 * 1.0000001);
}

static void test_arc_quarter(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_circular_rel(&r.m, 0, q(1000), q(90)));
	run_until_idle(&r, 30000);
	assert_true(fabs(d(r.m.ref.x_mm) - 1000) < 1e-5);
	assert_true(fabs(d(r.m.ref.y_mm) - 1000) < 1e-5);
	assert_int_equal(r.m.ref.th_deg, q(90));
	assert_true(r.v_max <= 500.0 * 1.0000001);
	assert_true(r.w_max <= 90.0 * 1.0000001);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	assert_false(motion_circular_rel(&r.m, q(10), q(1000), q(90)));
}

/* The active piece's limits follow every change made while it runs: a lower
 * speed, a caution cap inside a corner, a waypoint queued behind the line. */
static void test_limits_change_mid_piece(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	const q32_t a = q(500) / HZ / HZ;
	assert_true(motion_forward(&r.m, q(3000)));
	for (int i = 0; i < 1500; i++)
		rig_tick(&r);
	assert_int_equal(r.m.v, q(500) / HZ);
	/* 500 -> 200 mm/s at a per tick: 600 whole steps, then the cap. */
	motion_set_velocity(&r.m, q(200), q(90));
	for (int i = 0; i < 600; i++)
		rig_tick(&r);
	assert_int_equal(r.m.v, q(500) / HZ - 600 * a);
	rig_tick(&r);
	assert_int_equal(r.m.v, q(200) / HZ);
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, q(3000));

	/* Caution cap set inside a corner: the speed falls every tick until it
	 * is at the cap, and stays there. */
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_cruise_abs(&r.m, q(1000), 0));
	assert_true(motion_cruise_abs(&r.m, q(1000), q(1000)));
	uint32_t guard = 0;
	while (r.m.seg.kind != SEG_CORNER && guard++ < 10000)
		rig_tick(&r);
	assert_int_equal(r.m.seg.kind, SEG_CORNER);
	q32_t cap = q(50) / HZ;
	assert_true(r.m.v > cap);
	motion_set_caution(&r.m, q(50));
	q32_t prev = r.m.v;
	bool reached = false;
	for (int i = 0; i < 2000; i++) {
		rig_tick(&r);
		if (!reached) {
			assert_true(r.m.v < prev);
			reached = r.m.v <= cap;
		} else if (r.m.seg.kind == SEG_LINE && r.m.seg.len - r.m.seg.s > q(100)) {
			assert_int_equal(r.m.v, cap);
		}
		prev = r.m.v;
	}
	assert_true(reached);
	run_until_idle(&r, 60000);
	assert_int_equal(r.m.ref.x_mm, q(1000));
	assert_int_equal(r.m.ref.y_mm, q(1000));

	/* A waypoint queued while the last line runs: the unit blends into it
	 * instead of stopping at the old end. */
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_cruise_abs(&r.m, q(2000), 0));
	while (d(r.m.ref.x_mm) < 500)
		rig_tick(&r);
	assert_true(motion_cruise_abs(&r.m, q(2000), q(1000)));
	uint32_t stops = 0;
	double closest = 1e9;
	while (motion_has_work(&r.m)) {
		rig_tick(&r);
		if (r.m.v == 0 && hypot(d(r.m.ref.x_mm) - 2000, d(r.m.ref.y_mm) - 1000) > 1)
			stops++;
		closest = fmin(closest, hypot(d(r.m.ref.x_mm) - 2000, d(r.m.ref.y_mm)));
	}
	assert_int_equal(stops, 0);
	assert_true(closest > 10);
	assert_int_equal(r.m.ref.x_mm, q(2000));
	assert_int_equal(r.m.ref.y_mm, q(1000));
	assert_true(r.ax_max <= 500.0 * 1.00001);
	assert_true(r.aw_max <= 180.0 * 1.00001);

	/* Queued too late to slow down for a corner (20 mm before the end at
	 * 500 mm/s): the unit stops on the old end, then goes on. */
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_cruise_abs(&r.m, q(2000), 0));
	while (d(r.m.ref.x_mm) < 1980)
		rig_tick(&r);
	assert_true(motion_cruise_abs(&r.m, q(2000), q(1000)));
	bool stopped_on_end = false;
	while (motion_has_work(&r.m)) {
		rig_tick(&r);
		if (r.m.v == 0 && r.m.ref.x_mm == q(2000) && r.m.ref.y_mm == 0)
			stopped_on_end = true;
	}
	assert_true(stopped_on_end);
	assert_int_equal(r.m.ref.x_mm, q(2000));
	assert_int_equal(r.m.ref.y_mm, q(1000));
	assert_true(r.ax_max <= 500.0 * 1.00001);
}

/* Queues cruise waypoints (x, y) while paused, sets the acceleration
 * (mm/s^2, deg/s^2), checks that nothing moves for 10 ticks, resumes and runs
 * to the end. Returns the ticks at rest before the end: 0 when the unit
 * blended through every corner. */
static uint32_t run_retuned_while_paused(rig_t *r, const double (*wp)[2], int n, double at,
					 double ar)
{
	motion_pause(&r->m);
	for (int i = 0; i < n; i++)
		assert_true(motion_cruise_abs(&r->m, q(wp[i][0]), q(wp[i][1])));
	motion_set_accel(&r->m, q(at), q(ar));
	for (int i = 0; i < 10; i++)
		rig_tick(r);
	assert_int_equal(r->m.ref.x_mm, 0);
	assert_int_equal(r->m.ref.y_mm, 0);
	motion_resume(&r->m);
	uint32_t stops = 0;
	while (motion_has_work(&r->m) && r->ticks < 60000) {
		rig_tick(r);
		if (motion_has_work(&r->m) && r->vx == 0 && r->w == 0)
			stops++;
	}
	assert_false(motion_has_work(&r->m));
	assert_int_equal(r->m.ref.x_mm, q(wp[n - 1][0]));
	assert_int_equal(r->m.ref.y_mm, q(wp[n - 1][1]));
	return stops;
}

/* A lower translational rate set while paused re-plans the queued corner
 * speeds: a 20 degree turn onto a 300 mm leg, whose corner speed is set by
 * braking to a stop on that leg, not by the rotation limits, still brakes
 * within the new rate. */
static void test_accel_lowered_while_paused(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	const double wp[2][2] = {{1000, 0}, {1282, 103}};
	assert_int_equal(run_retuned_while_paused(&r, wp, 2, 100, 180), 0);
	assert_true(r.ax_max <= 100.0 * 1.00001);
}

/* A lower rotational rate set while paused: the queued 90 degree corner
 * keeps its shape and its caps follow the new rate. The design splits the
 * rate between curvature change and path acceleration (traj.h), so the peak
 * sits at about half of it; with the caps left at 180 deg/s^2 it is 88. */
static void test_rot_accel_lowered_while_paused(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	const double wp[2][2] = {{1000, 0}, {1000, 1000}};
	assert_int_equal(run_retuned_while_paused(&r, wp, 2, 500, 30), 0);
	printf("rotational rate lowered to 30 deg/s^2: aw %.3f deg/s^2\n", r.aw_max);
	assert_true(r.aw_max <= 30.0 * 1.00001);
	assert_true(r.ax_max <= 500.0 * 1.00001);
}

/* Redefining the pose mid-move keeps the motion's physical course: no
 * velocity step, and the end lands where it would have, in the new frame. */
static void test_set_pose_while_moving(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_forward(&r.m, q(2000)));
	for (int i = 0; i < 1500; i++)
		rig_tick(&r);
	double x_before = d(r.m.ref.x_mm);
	/* New frame: the unit is now at (100, 200) heading 90. */
	fx_pose_t np = {q(100), q(200), q(90)};
	motion_set_pose(&r.m, &np);
	run_until_idle(&r, 30000);
	assert_true(r.ax_max <= 500.0 * 1.0000001);
	assert_true(r.aw_max == 0.0);
	/* 2000 - x_before further along the new heading (+y). */
	assert_true(fabs(d(r.m.ref.x_mm) - 100.0) < 1e-6);
	assert_true(fabs(d(r.m.ref.y_mm) - (200.0 + 2000.0 - x_before)) < 1e-6);
	assert_true(fabs(d(r.m.ref.th_deg) - 90.0) < 1e-6);
}

/* setPosition on a cruise route's first line: the corners still ahead
 * (their exits were planned in the old frame) follow the new frame, with no
 * stop and no velocity step, and the route ends on its last waypoint mapped. */
static void test_set_pose_during_cruise(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	double pts[4][2] = {{1000, 0}, {2000, 1000}, {3000, 1000}, {3000, 2000}};
	for (int i = 0; i < 4; i++)
		assert_true(motion_cruise_abs(&r.m, q(pts[i][0]), q(pts[i][1])));
	for (int i = 0; i < 1000; i++)
		rig_tick(&r);
	double xb = d(r.m.ref.x_mm);
	assert_int_equal(r.m.ref.y_mm, 0);
	assert_int_equal(r.m.ref.th_deg, 0);
	/* New frame: the unit is now at (100, 200) heading 90. */
	fx_pose_t np = {q(100), q(200), q(90)};
	motion_set_pose(&r.m, &np);
	uint32_t stops = 0;
	double step_max = 0;
	while (motion_has_work(&r.m) && r.ticks < 60000) {
		fx_pose_t before = r.m.ref;
		rig_tick(&r);
		if (motion_has_work(&r.m) && r.vx == 0 && r.w == 0)
			stops++;
		/* The reference moves continuously, at most the speed cap. */
		step_max = fmax(
		    step_max, hypot(d(r.m.ref.x_mm - before.x_mm), d(r.m.ref.y_mm - before.y_mm)));
	}
	assert_false(motion_has_work(&r.m));
	assert_int_equal(stops, 0);
	assert_true(step_max <= 500.0 / HZ * 1.000001);
	/* (3000, 2000) - (xb, 0) turned by 90 degrees, from (100, 200). */
	assert_true(fabs(d(r.m.ref.x_mm) - (100.0 - 2000.0)) < 1e-6);
	assert_true(fabs(d(r.m.ref.y_mm) - (200.0 + 3000.0 - xb)) < 1e-6);
	assert_true(fabs(d(r.m.ref.th_deg) - 180.0) < 1e-6 ||
		    fabs(d(r.m.ref.th_deg) + 180.0) < 1e-6);
	assert_true(r.ax_max <= 500.0 * 1.01);
	assert_true(r.aw_max <= 180.0 * 1.01);
}

/* Mecanum velocity modes: a diagonal jog accelerates as a vector within the
 * set acceleration; a continuous goal with y lands; a rotation-dominant
 * straight move turns first and lands exactly. */
static void test_omni_modes(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_OMNI);
	motion_set_jog_timeout_ms(&r.m, 300);
	assert_true(motion_jog(&r.m, q(300), q(300), 0));
	double vxp = 0, vyp = 0, amax = 0;
	for (int i = 0; i < 3000 && motion_has_work(&r.m); i++) {
		fx_twist_t t;
		fx_pose_t meas = r.m.ref;
		motion_tick(&r.m, &meas, &t);
		double vx = d(t.vx_pt) * HZ, vy = d(t.vy_pt) * HZ;
		amax = fmax(amax, hypot(vx - vxp, vy - vyp) * HZ);
		vxp = vx;
		vyp = vy;
	}
	assert_false(motion_has_work(&r.m));
	assert_true(amax <= 500.0 * 1.0001);
	assert_true(amax >= 499.0);

	/* The jog did not turn, so the goal's vehicle frame is the world's. */
	assert_int_equal(r.m.ref.th_deg, 0);
	fx_pose_t start = r.m.ref;
	fx_pose_t goal = {q(400), q(-250), q(30)};
	assert_true(motion_continuous_rel(&r.m, &goal));
	run_until_idle(&r, 30000);
	assert_true(fabs(d(r.m.ref.x_mm - start.x_mm) - 400.0) < 1e-6);
	assert_true(fabs(d(r.m.ref.y_mm - start.y_mm) + 250.0) < 1e-6);
	assert_true(fabs(d(r.m.ref.th_deg) - 30.0) < 1e-6);

	fx_pose_t here = r.m.ref;
	fx_pose_t p = {here.x_mm + q(0.5), here.y_mm, q(-150)};
	assert_true(motion_linear_abs(&r.m, &p));
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, p.x_mm);
	assert_int_equal(r.m.ref.y_mm, p.y_mm);
	assert_int_equal(r.m.ref.th_deg, q(-150));
}

/* setPosition during an arc keeps its course: no velocity step. */
static void test_set_pose_during_arc(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_circular_rel(&r.m, 0, q(500), q(90)));
	for (int i = 0; i < 1200; i++)
		rig_tick(&r);
	double swept = d(r.m.ref.th_deg);
	fx_pose_t np = {q(10), q(20), q(-45)};
	motion_set_pose(&r.m, &np);
	run_until_idle(&r, 30000);
	/* The landing step carries the mapping's nanometre rounding: the
	 * spec's 1 % bound (without a redefinition it holds exactly, above). */
	assert_true(r.ax_max <= 500.0 * 1.01);
	assert_true(r.aw_max <= 180.0 * 1.01);
	/* The rest of the sweep, from the redefined heading. */
	assert_true(fabs(d(r.m.ref.th_deg) - (-45.0 + 90.0 - swept)) < 1e-6);
}

/* A command with no piece (a forward of zero) in front of a cruise route
 * leaves nothing behind: the route starts along its first line from rest
 * (fuzz_ops finding: the empty line was taken for the route's first line,
 * which jumped straight into the first corner). */
static void test_empty_command_before_cruise(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_forward(&r.m, 0));
	assert_true(motion_cruise_abs(&r.m, q(1000), 0));
	assert_true(motion_cruise_abs(&r.m, q(2000), q(1000)));
	rig_tick(&r);
	/* first tick: one step of the set acceleration (500 mm/s^2), straight */
	assert_true(fabs(r.vx - 0.5) < 1e-6);
	assert_true(r.w == 0.0);
	/* the first line runs straight up to its corner entry (800 mm) */
	while (d(r.m.ref.x_mm) < 790.0 && r.ticks < 10000) {
		rig_tick(&r);
		assert_int_equal(r.m.ref.y_mm, 0);
		assert_true(r.w == 0.0);
	}
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, q(2000));
	assert_int_equal(r.m.ref.y_mm, q(1000));
	assert_true(r.ax_max <= 500.0 + 1e-3);
}

/* stop() in the last millimetres of a cruise line, at speed into its
 * corner: the unit brakes along the path through the corner at no more than
 * the acceleration limit (fuzz_ops finding, reached through the link
 * watchdog: the line used to end at speed, a step to zero), the route is gone
 * once at rest, and a command queued while braking runs after. */
static void test_stop_at_corner_brakes_along_path(void **state)
{
	(void)state;
	rig_t r;
	rig_init(&r, MOTION_KIN_DIFF);
	assert_true(motion_cruise_abs(&r.m, q(1000), 0));
	assert_true(motion_cruise_abs(&r.m, q(1000), q(1000)));
	assert_true(motion_cruise_abs(&r.m, 0, q(1000)));
	/* the corner begins at 800 mm; 790 mm in, the line ends in 10 mm */
	while (d(r.m.ref.x_mm) < 790.0 && r.ticks < 10000)
		rig_tick(&r);
	/* over 150 mm/s: more than 11 mm of braking at 1000 mm/s^2 */
	assert_true(r.vx > 150.0);
	r.ax_max = r.aw_max = 0;
	motion_stop(&r.m);
	assert_int_equal(motion_queue_len(&r.m), 0);
	fx_pose_t to = {q(500), q(500), q(90)};
	assert_true(motion_linear_abs(&r.m, &to));
	assert_int_equal(motion_queue_len(&r.m), 1);
	uint32_t n = 0;
	do {
		rig_tick(&r);
	} while (motion_is_moving(&r.m) && ++n < 5000);
	assert_true(r.ax_max <= 1000.0 + 1e-3);
	assert_true(r.aw_max <= 360.0 + 1e-3);
	/* stopped inside the corner, off the first line */
	assert_true(d(r.m.ref.y_mm) > 0.0 && d(r.m.ref.y_mm) < 200.0);
	run_until_idle(&r, 30000);
	assert_int_equal(r.m.ref.x_mm, to.x_mm);
	assert_int_equal(r.m.ref.y_mm, to.y_mm);
	assert_int_equal(r.m.ref.th_deg, to.th_deg);
	assert_int_equal(motion_queue_len(&r.m), 0);
}

/* ---- the planning pass, whole and spread -------------------------------- */

/* A dense route: straight runs of short steps (every corner speed follows
 * the braking distance to the last waypoint), gentle bends and zigzags. */
static void route_point(int k, double *x, double *y)
{
	int part = (k / 12) % 3;
	double bx = 400.0 * (k / 12), by = 0;
	int j = k % 12;
	if (part == 0) {
		*x = bx + 30.0 * (j + 1);
		*y = by;
	} else if (part == 1) {
		*x = bx + 30.0 * (j + 1);
		*y = by + 0.2 * (j + 1) * (j + 1);
	} else {
		*x = bx + 30.0 * (j + 1);
		*y = by + ((j & 1) ? 25.0 : 0.0);
	}
}

/* The plan the pass leaves in each queued command. */
static void assert_same_plan(const motion_t *a, const motion_t *b)
{
	assert_int_equal(a->q_count, b->q_count);
	for (int i = 0; i < a->q_count; i++) {
		const motion_cmd_t *x = &a->q[(a->q_head + i) % MOTION_QUEUE_LEN];
		const motion_cmd_t *y = &b->q[(b->q_head + i) % MOTION_QUEUE_LEN];
		assert_int_equal(x->vend_pt, y->vend_pt);
		/* (the head's own line length is read by no pass) */
		if (i > 0)
			assert_int_equal(x->line_mm, y->line_mm);
		if (!x->has_corner)
			continue;
		assert_int_equal(x->line_extra_mm, y->line_extra_mm);
		assert_int_equal(x->corner_extra_mm, y->corner_extra_mm);
		assert_int_equal(x->corner_vrot_pt, y->corner_vrot_pt);
		assert_int_equal(x->corner_a_pt2, y->corner_a_pt2);
	}
}

/* The pass over the whole queue, on a copy. */
static void assert_whole_pass_agrees(const motion_t *m)
{
	static motion_t full;
	full = *m;
	motion_set_velocity(&full, full.v_t_pt * HZ, full.v_r_pt * HZ);
	assert_int_equal(full.pass_todo, 0);
	assert_same_plan(m, &full);
}

/* Rigs: 0 walks the whole pass in each request (hosts); 1 walks 2 commands
 * and finishes in idle calls before the next tick; 2 walks 1 command and
 * gets one idle call a tick, so a pass outlives several ticks. */
static void test_plan_spread(void **state)
{
	(void)state;
	static rig_t r[3];
	for (int k = 0; k < 3; k++) {
		rig_init(&r[k], MOTION_KIN_DIFF);
		motion_set_velocity(&r[k].m, q(1000), q(90));
		motion_set_accel(&r[k].m, q(200), q(180));
	}
	motion_set_plan_budget(&r[1].m, 2);
	motion_set_plan_budget(&r[2].m, 1);
	int sent = 0, pending_ticks = 0, walks = 0;
	double lx = 0, ly = 0;
	for (uint32_t t = 0; t < 200000; t++) {
		/* a waypoint every 5 ms while the queue has room; the speed
		 * lowered and raised on the way */
		if (t % 5 == 0 && sent < 72 && motion_queue_len(&r[0].m) < 24) {
			route_point(sent++, &lx, &ly);
			for (int k = 0; k < 3; k++)
				assert_true(motion_cruise_abs(&r[k].m, q(lx), q(ly)));
			assert_whole_pass_agrees(&r[0].m);
		}
		if (t == 3000 || t == 9000) {
			for (int k = 0; k < 3; k++)
				motion_set_velocity(&r[k].m, t == 3000 ? q(400) : q(900),
						    t == 3000 ? q(30) : q(90));
		}
		while (motion_plan_idle(&r[1].m))
			walks++;
		assert_same_plan(&r[0].m, &r[1].m);
		if (motion_plan_idle(&r[2].m))
			pending_ticks++;
		for (int k = 0; k < 3; k++)
			rig_tick(&r[k]);
		assert_int_equal(r[1].m.ref.x_mm, r[0].m.ref.x_mm);
		assert_int_equal(r[1].m.ref.y_mm, r[0].m.ref.y_mm);
		assert_int_equal(r[1].m.ref.th_deg, r[0].m.ref.th_deg);
		if (sent == 72 && !motion_has_work(&r[0].m) && !motion_has_work(&r[2].m))
			break;
	}
	assert_int_equal(sent, 72);
	for (int k = 0; k < 3; k++) {
		assert_false(motion_has_work(&r[k].m));
		assert_int_equal(r[k].m.ref.x_mm, q(lx));
		assert_int_equal(r[k].m.ref.y_mm, q(ly));
		/* never over the limits (the plans agree with the whole pass
		 * after every request, so the lowered ones hold too) */
		assert_true(r[k].ax_max <= 200.0 * 1.00001);
		assert_true(r[k].v_max <= 1000.0 * 1.00001);
	}
	printf("plan spread: %d idle walks for the 2-command rig, %d ticks with a pass "
	       "pending for the 1-command rig, %u and %u ticks\n",
	       walks, pending_ticks, r[0].ticks, r[2].ticks);
	assert_true(walks > 0);
	assert_true(pending_ticks > 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_forward_lands_exactly),
	    cmocka_unit_test(test_turn_full_circle),
	    cmocka_unit_test(test_linear_abs_square),
	    cmocka_unit_test(test_cruise_keeps_moving),
	    cmocka_unit_test(test_tight_corner_not_blended),
	    cmocka_unit_test(test_set_pose_during_cruise),
	    cmocka_unit_test(test_jog_watchdog),
	    cmocka_unit_test(test_continuous_retarget),
	    cmocka_unit_test(test_continuous_no_orbit),
	    cmocka_unit_test(test_pause_resume_stop),
	    cmocka_unit_test(test_omni_linear),
	    cmocka_unit_test(test_arc_quarter),
	    cmocka_unit_test(test_set_pose_while_moving),
	    cmocka_unit_test(test_omni_modes),
	    cmocka_unit_test(test_set_pose_during_arc),
	    cmocka_unit_test(test_limits_change_mid_piece),
	    cmocka_unit_test(test_accel_lowered_while_paused),
	    cmocka_unit_test(test_rot_accel_lowered_while_paused),
	    cmocka_unit_test(test_empty_command_before_cruise),
	    cmocka_unit_test(test_stop_at_corner_brakes_along_path),
	    cmocka_unit_test(test_plan_spread),
	};
	return cmocka_run_group_tests_name("motion", tests, NULL, NULL);
}
