/* The motion figures of tools/bench/plantmetrics.c: each figure on a trace
 * written by hand, then the runner on the ideal plant where the figures
 * follow from the motion law, and the push helper. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "hal/posix/config_xml.h"
#include "tools/bench/plantmetrics.h"

#define assert_near(a, b)                                                                          \
	do {                                                                                       \
		double a_ = (a), b_ = (b);                                                         \
		if (!(fabs(a_ - b_) <= 1e-9))                                                      \
			fail_msg("%s = %.12f, expected %.12f", #a, a_, b_);                        \
	} while (0)

#define N 20

/* A 1 ms trace: ticks 0-9 command 1000 mm/s along x (the reference to
 * x = 10, the odometry 0.5 mm behind) and, in tick 5, a clockwise rotation;
 * Busy until tick 11, Ready from tick 12 (3 ms after the reference's end at
 * 10 ms). The truth passes the target by 0.3 mm and 0.02 deg at tick 11,
 * is 0.1 mm past at Ready, 0.06 at tick 13, and 0.04 with the wheels at
 * 0.05 mm/s from tick 14 on. */
static pm_trace_t hand_trace(void)
{
	static pm_sample_t s[N];
	memset(s, 0, sizeof(s));
	for (int i = 0; i < N; i++) {
		pm_sample_t *p = &s[i];
		p->t_s = (i + 1) * 0.001;
		p->state = i < 12 ? VS_STATE_BUSY : VS_STATE_READY;
		if (i < 10) {
			p->cmd_vx = 1000.0;
			p->ref.x = i + 1;
			p->odom.x = i + 0.5;
			p->truth.x = i + 0.4;
			p->wheel_mm_s = 1000.0;
		} else {
			static const double truth[] = {10.2, 10.3, 10.1, 10.06};
			p->ref.x = 10.0;
			p->odom.x = 10.02;
			p->truth.x = i < 14 ? truth[i - 10] : 10.04;
			p->wheel_mm_s = i < 14 ? 50.0 : 0.05;
		}
	}
	s[5].cmd_w = -10.0;
	s[11].truth.th = -0.02;
	return (pm_trace_t){s, N, N};
}

static void figures_of_a_hand_trace(void **state)
{
	(void)state;
	pm_trace_t tr = hand_trace();
	pm_limits_t lim;
	pm_limits_default(&lim);
	lim.drift_s = 0.005; /* Ready at 13 ms: the window ends at tick 17 */
	/* A heading a turn away is the same heading. */
	pm_goal_t goal = {{10.0, 0.0, 360.0}, false};
	pm_result_t r;
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), 0);
	assert_near(r.ref_end_s, 0.010);
	assert_near(r.ready_s, 0.013);
	assert_near(r.ready_ms, 3.0);
	assert_near(r.err_odom_mm, 0.02);
	assert_near(r.err_odom_deg, 0.0);
	assert_near(r.err_true_mm, 0.1);
	assert_near(r.err_true_deg, 0.0);
	assert_near(r.over_mm, 0.3);
	assert_near(r.over_deg, 0.02);
	assert_near(r.settle_ms, 5.0); /* in the band for good from tick 14 */
	assert_near(r.drift_true_mm, 0.06);
	assert_near(r.drift_odom_mm, 0.0);
	assert_near(r.follow_mm, 0.5);
	assert_near(r.follow_deg, 0.0);

	/* The reference's end as the target (a stop). */
	goal = (pm_goal_t){{0.0, 0.0, 0.0}, true};
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), 0);
	assert_near(r.target.x, 10.0);
	assert_near(r.err_true_mm, 0.1);

	/* Faster wheels than the rest speed at the window's end: not settled. */
	tr.s[17].wheel_mm_s = 0.2;
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), 0);
	assert_true(isnan(r.settle_ms));
	tr.s[17].wheel_mm_s = 0.05;
	/* In the band and at rest from the reference's end: settled at once. */
	for (int i = 9; i < 14; i++) {
		tr.s[i].truth.x = 10.0;
		tr.s[i].wheel_mm_s = 0.05;
	}
	tr.s[11].truth.th = 0.0;
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), 0);
	assert_near(r.settle_ms, 0.0);
	assert_near(r.over_mm, 0.04);
	assert_near(r.over_deg, 0.0);

	/* The trace ends inside the window, or has no Ready. */
	tr.n = 17;
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), -1);
	tr.n = 12;
	assert_int_equal(pm_measure(&tr, 0, &goal, &lim, &r), -1);
}

static const pm_move_t *move(const char *name)
{
	for (size_t i = 0; i < pm_num_moves; i++)
		if (!strcmp(pm_moves[i].name, name))
			return &pm_moves[i];
	fail_msg("no move '%s'", name);
	return NULL;
}

static void ideal(vs_config_t *cfg, plant_params_t *pp)
{
	plant_params_ideal(pp);
	cfg->encoder_counts_per_rev = plant_hires_counts_per_rev(cfg);
	plant_config_lag(pp, cfg);
}

/* On the ideal plant the reference's timing is the motion law's: 300 mm
 * at 500 mm/s^2 without reaching 500 mm/s takes 2 sqrt(300 / 500) s; a
 * stop after 1 s (at 500 mm/s, 250 mm) brakes at the 1000 mm/s^2 limit,
 * 0.5 s and 125 mm more. */
static void runner_on_the_ideal_plant(void **state)
{
	(void)state;
	vs_config_t cfg;
	plant_params_t pp;
	vs_config_defaults(&cfg);
	ideal(&cfg, &pp);
	pm_limits_t lim;
	pm_limits_default(&lim);
	pm_trace_t tr;
	pm_trace_init(&tr);
	size_t from;
	pm_result_t r;
	const char *bad = NULL;

	assert_int_equal(pm_run(move("moveForward 300"), &cfg, &pp, &lim, &tr, &from, &r, &bad),
			 PM_OK);
	assert_int_equal(from, 0);
	assert_true(fabs(r.ref_end_s - 2.0 * sqrt(0.6)) <= 0.001);
	assert_near(tr.s[tr.n - 1].t_s - tr.s[0].t_s + 0.001, r.ready_s + lim.drift_s);
	assert_true(r.err_true_mm <= 0.05);

	assert_int_equal(
	    pm_run(move("stop 1 s into moveForward 1000"), &cfg, &pp, &lim, &tr, &from, &r, &bad),
	    PM_OK);
	assert_true(fabs(r.ref_end_s - 1.5) <= 0.002);
	assert_true(fabs(r.target.x - 375.0) <= 1.0 && r.target.y == 0.0);

	/* The second move is measured from its own command, 1 ms after Ready. */
	assert_int_equal(pm_run(move("moveLinearAbs 1000 300 0, 1 ms after Ready"), &cfg, &pp, &lim,
				&tr, &from, &r, &bad),
			 PM_OK);
	assert_int_equal(tr.s[from - 2].state, VS_STATE_READY);
	assert_int_equal(tr.s[from].state, VS_STATE_BUSY);
	assert_true(fabs(tr.s[from - 1].odom.x - 300.0) <= 0.05);

	/* Every move reaches Ready on both bases but one: the mecanum base's
	 * acceleration limit is 800 mm/s^2. */
	static const char *const files[] = {"config/vehicle.xml", "config/vehicle-omni.xml"};
	for (int f = 0; f < 2; f++) {
		char err[256];
		assert_int_equal(
		    config_load(files[f], "config/io.xml", &cfg, NULL, err, sizeof(err)), 0);
		ideal(&cfg, &pp);
		for (size_t i = 0; i < pm_num_moves; i++) {
			int rc = pm_run(&pm_moves[i], &cfg, &pp, &lim, &tr, &from, &r, &bad);
			if (f == 1 &&
			    !strcmp(pm_moves[i].name, "moveForward 1000 at 1000 mm/s^2")) {
				assert_int_equal(rc, PM_REFUSED);
				assert_string_equal(bad, "setAcceleration 1000 180");
			} else if (rc != PM_OK) {
				fail_msg("%s: %s: %d", files[f], pm_moves[i].name, rc);
			}
		}
	}
	pm_trace_free(&tr);
}

/* The push helper moves the truth by the push in the base's frame; what
 * the unit does next is the firmware's and not asserted here. */
static void push_helper(void **state)
{
	(void)state;
	vs_config_t cfg;
	plant_params_t pp;
	vs_config_defaults(&cfg);
	cfg.link_timeout_ms = 0;
	ideal(&cfg, &pp);
	sim_t *s = calloc(1, sizeof(*s));
	assert_non_null(s);
	assert_int_equal(sim_init(s, &cfg, &pp), 0);
	char reply[CONSOLE_REPLY_MAX];
	assert_true(sim_exec(s, "setPower true", reply, sizeof(reply)));
	assert_true(sim_exec(s, "setServo true", reply, sizeof(reply)));
	plant_set_pose(sim_plant(s), 100, 200, 90);
	pm_push_t p;
	assert_true(pm_push(s, 10, 5, 2, 300, &p));
	assert_near(p.truth_before.x, 100);
	assert_near(p.truth_pushed.x, 95); /* forward is +y, left is -x */
	assert_near(p.truth_pushed.y, 210);
	assert_near(p.truth_pushed.th, 92);
	assert_near(sim_time_s(s), 0.3);
	assert_false(pm_push(s, 2000, 0, 0, 300, &p));
	assert_near(sim_time_s(s), 0.3);
	free(s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(figures_of_a_hand_trace),
	    cmocka_unit_test(runner_on_the_ideal_plant),
	    cmocka_unit_test(push_helper),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
