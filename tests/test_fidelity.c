/* Motion on the default simulated plant (20 ms drive lag, acceleration and
 * current limits, the configured encoders), as `make run` starts it, for
 * both shipped configurations: every point-to-point move at up to the
 * acceleration limit ends in position without overshoot, Ready comes
 * promptly after the reference ends, and nothing drifts after it (and
 * the same with the jerk-limited example configuration). The
 * figures come from tools/bench/plantmetrics (the bench's section 2b), from
 * a trace of every tick.
 *
 * Targets (docs/performance.md, section 2b): overshoot <= 0.05 mm and
 * <= 0.01 deg; pose at Ready (odometry and true plant pose) within 0.05 mm
 * and 0.01 deg of the target; Ready at most 50 ms after the reference's last
 * step; at most 0.05 mm / 0.01 deg of drift in the 0.5 s after Ready.
 */
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

static void load(const char *path, vs_config_t *cfg)
{
	char err[256] = "";
	if (config_load(path, "config/io.xml", cfg, NULL, err, sizeof(err)) != 0)
		fail_msg("%s: %s", path, err);
}

static void check(const char *cfgname, const pm_move_t *m, const vs_config_t *cfg)
{
	plant_params_t pp;
	pm_limits_t lim;
	pm_trace_t tr;
	pm_result_t r;
	size_t from = 0;
	const char *bad = NULL;

	plant_params_default(&pp);
	pm_limits_default(&lim);
	pm_trace_init(&tr);
	int rc = pm_run(m, cfg, &pp, &lim, &tr, &from, &r, &bad);
	pm_trace_free(&tr);
	if (rc != PM_OK)
		fail_msg("%s, %s: run failed (%d%s%s)", cfgname, m->name, rc, bad ? ": " : "",
			 bad ? bad : "");
	printf("  %-10s %-40s Ready %3.0f ms  odom %.4f mm %.4f deg  true %.4f mm %.4f deg  "
	       "over %.4f mm %.4f deg  drift %.4f mm\n",
	       cfgname, m->name, r.ready_ms, r.err_odom_mm, r.err_odom_deg, r.err_true_mm,
	       r.err_true_deg, r.over_mm, r.over_deg, r.drift_true_mm);
	if (!(r.ready_ms >= 0.0 && r.ready_ms <= 50.0))
		fail_msg("%s: Ready %.1f ms after the reference", m->name, r.ready_ms);
	if (!(r.err_odom_mm <= 0.05 && r.err_true_mm <= 0.05 && r.err_odom_deg <= 0.01 &&
	      r.err_true_deg <= 0.01))
		fail_msg("%s: off the target at Ready", m->name);
	if (!(r.over_mm <= 0.05 && r.over_deg <= 0.01))
		fail_msg("%s: overshoot", m->name);
	if (!(r.drift_true_mm <= 0.05 && r.drift_true_deg <= 0.01 && r.drift_odom_mm <= 0.05 &&
	      r.drift_odom_deg <= 0.01))
		fail_msg("%s: drift after Ready", m->name);
}

/* The bench's moves, and the straight move and the turn at the
 * configuration's acceleration limit. */
static void all_moves(const char *path, const char *name)
{
	vs_config_t cfg;
	static char acc[64];
	load(path, &cfg);
	snprintf(acc, sizeof(acc), "setAcceleration %.0f %.0f", cfg.acc_limit_t_mm_s2,
		 cfg.acc_limit_r_deg_s2);
	for (size_t i = 0; i < pm_num_moves; i++) {
		/* the bench's 1000 mm/s^2 is over the mecanum base's limit: the
		 * move at the limit below stands for it */
		if (cfg.acc_limit_t_mm_s2 < 1000.0 && strstr(pm_moves[i].name, "1000 mm/s^2"))
			continue;
		check(name, &pm_moves[i], &cfg);
	}
	const pm_move_t at_limit[] = {
	    {.name = "moveForward 1000 at the limit",
	     .setup = {acc},
	     .cmd = {"moveForward 1000"},
	     .goal = {{1000, 0, 0}, false}},
	    {.name = "moveTurn 90 at the limit",
	     .setup = {acc},
	     .cmd = {"moveTurn 90"},
	     .goal = {{0, 0, 90}, false}},
	    {.name = "moveTurn -180 at the limit",
	     .setup = {acc},
	     .cmd = {"moveTurn -180"},
	     .goal = {{0, 0, 180}, false}},
	};
	for (size_t i = 0; i < sizeof(at_limit) / sizeof(at_limit[0]); i++)
		check(name, &at_limit[i], &cfg);
}

static void test_differential(void **state)
{
	(void)state;
	all_moves("config/vehicle.xml", "diff");
}

/* The same on the jerk-limited example (docs/jerk.md): the moves from rest
 * to rest on the S-curve, the rest as without. */
static void test_jerk_limited(void **state)
{
	(void)state;
	all_moves("config/vehicle-jerk.xml", "jerk");
}

static void test_mecanum(void **state)
{
	(void)state;
	all_moves("config/vehicle-omni.xml", "mecanum");
	vs_config_t cfg;
	load("config/vehicle-omni.xml", &cfg);
	const pm_move_t omni[] = {
	    {.name = "moveLinearRel 0 500 0",
	     .cmd = {"moveLinearRel 0 500 0"},
	     .goal = {{0, 500, 0}, false}},
	    {.name = "moveLinearRel 500 300 45",
	     .cmd = {"moveLinearRel 500 300 45"},
	     .goal = {{500, 300, 45}, false}},
	    {.name = "moveCircularRel 300 0 90",
	     .cmd = {"moveCircularRel 300 0 90"},
	     .goal = {{300, -300, 90}, false}},
	};
	for (size_t i = 0; i < sizeof(omni) / sizeof(omni[0]); i++)
		check("mecanum", &omni[i], &cfg);
}

/* A unit at rest with the servo on, on the default plant, after a move. */
static sim_t *at_rest(const char *path)
{
	vs_config_t cfg;
	plant_params_t pp;
	char reply[CONSOLE_REPLY_MAX];
	sim_t *s = calloc(1, sizeof(*s));
	assert_non_null(s);
	load(path, &cfg);
	cfg.link_timeout_ms = 0;
	plant_params_default(&pp);
	assert_int_equal(sim_init(s, &cfg, &pp), 0);
	static const char *const lines[] = {"setPower true", "setServo true", "moveForward 200"};
	for (size_t i = 0; i < 3; i++) {
		assert_true(sim_exec(s, lines[i], reply, sizeof(reply)));
		assert_string_equal(reply, "ok true");
	}
	sim_run_ms(s, 2000);
	assert_true(sim_exec(s, "getState", reply, sizeof(reply)));
	assert_string_equal(reply, "ok true 16 \"Ready\"");
	return s;
}

static double dist(pm_pose_t a, pm_pose_t b)
{
	return hypot(a.x - b.x, a.y - b.y);
}

static double dth(pm_pose_t a, pm_pose_t b)
{
	return fabs(remainder(a.th - b.th, 360.0));
}

/* Pushed at rest, the unit returns to its pose (the wheel loop holds the
 * pose the motion ended on), or raises the following-error fault when the
 * push is larger than following_error_mm: it never drifts silently. */
static void push_returns(const char *path, double dx, double dy, double dthe)
{
	sim_t *s = at_rest(path);
	pm_push_t p;
	assert_true(pm_push(s, dx, dy, dthe, 1500, &p));
	printf("  %s push %g %g %g: pushed %.3f mm %.3f deg, after 1.5 s %.4f mm %.4f deg off "
	       "(odometry %.4f mm), state %d\n",
	       path, dx, dy, dthe, dist(p.truth_pushed, p.truth_before),
	       dth(p.truth_pushed, p.truth_before), dist(p.truth_after, p.truth_before),
	       dth(p.truth_after, p.truth_before), dist(p.odom_after, p.odom_before),
	       p.state_after);
	assert_true(dist(p.truth_pushed, p.truth_before) > 1.0 ||
		    dth(p.truth_pushed, p.truth_before) > 1.0);
	assert_true(dist(p.truth_after, p.truth_before) <= 0.05);
	assert_true(dth(p.truth_after, p.truth_before) <= 0.01);
	assert_true(dist(p.odom_after, p.odom_before) <= 0.05);
	assert_int_equal(p.state_after, VS_STATE_READY);
	free(s);
}

static void test_push_at_rest(void **state)
{
	(void)state;
	push_returns("config/vehicle.xml", 10.0, 0.0, 0.0);
	push_returns("config/vehicle.xml", 0.0, 0.0, -3.0);
	push_returns("config/vehicle-omni.xml", 0.0, 10.0, 0.0);
	push_returns("config/vehicle-omni.xml", 5.0, -5.0, 0.0);
	push_returns("config/vehicle-omni.xml", 0.0, 0.0, 2.0);
	push_returns("config/vehicle-omni.xml", 5.0, -5.0, 2.0);
}

static void test_push_past_the_following_error(void **state)
{
	(void)state;
	sim_t *s = at_rest("config/vehicle.xml");
	pm_push_t p;
	char reply[CONSOLE_REPLY_MAX];
	assert_true(pm_push(s, 80.0, 0.0, 0.0, 100, &p));
	assert_int_equal(p.state_after, VS_STATE_ALARM);
	assert_true(sim_exec(s, "getActiveAlarm 1", reply, sizeof(reply)));
	assert_memory_equal(reply, "ok true 1 1 204 fault \"following error ", 38);
	free(s);
}

/* A sideways push skids a differential base: its wheels do not turn, so
 * nothing on the unit sees it (no sensor measures it); the odometry and the
 * wheels stay where they were. Known and documented, not a silent drift of
 * the unit's own making. */
static void test_sideways_push_skids_a_differential_base(void **state)
{
	(void)state;
	sim_t *s = at_rest("config/vehicle.xml");
	pm_push_t p;
	assert_true(pm_push(s, 0.0, 10.0, 0.0, 500, &p));
	assert_true(fabs(dist(p.truth_after, p.truth_before) - 10.0) < 0.05);
	assert_true(dist(p.odom_after, p.odom_before) <= 0.05); /* the window */
	assert_int_equal(p.state_after, VS_STATE_READY);
	free(s);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_differential),
	    cmocka_unit_test(test_mecanum),
	    cmocka_unit_test(test_jerk_limited),
	    cmocka_unit_test(test_push_at_rest),
	    cmocka_unit_test(test_push_past_the_following_error),
	    cmocka_unit_test(test_sideways_push_skids_a_differential_base),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
