/* Fixed point, trajectory and kinematics paths the plant tests never reach:
 * saturation, degenerate arguments, the mecanum (omni) wheel equations of
 * kin.h, and the optional outputs of kin_step. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <stdint.h>

#include <cmocka.h>

#include "firmware/fx.h"
#include "firmware/kin.h"
#include "firmware/traj.h"

static void test_mul_portable_saturates(void **state)
{
	(void)state;
	/* ~2 * ~2^31 and 1.5 * (2^31 - 1) are past the Q32 range although the
	 * high partial product fits in 31 bits: the sum of the parts saturates. */
	q32_t a = ((q32_t)1 << 32) | 0xffffffff, b = (q32_t)0x7fffffff << 32;
	assert_int_equal(fx_mul_portable(a, b), INT64_MAX);
	assert_int_equal(fx_mul_portable(-a, b), INT64_MIN);
	assert_int_equal(fx_mul_portable((q32_t)3 << 31, (q32_t)0x7fffffff << 32), INT64_MAX);
}

static void test_angles_far_out(void **state)
{
	(void)state;
	/* -190 deg wraps to 170 deg; -540 to -180 (the range is [-180, 180)). */
	assert_int_equal(fx_wrap_deg(fx_from_int(-190)), fx_from_int(170));
	assert_int_equal(fx_wrap_deg(fx_from_int(-540)), -FX_DEG_180);
	assert_int_equal(fx_wrap_deg(fx_from_int(540)), -FX_DEG_180);
	/* Operands beyond 2^60 are scaled down first: still 45 and -135 deg,
	 * within 1e-6 deg. */
	int64_t big = INT64_MAX - 5, tol = 4295;
	q32_t r = fx_atan2_deg(big, big);
	assert_true(r > fx_from_int(45) - tol && r < fx_from_int(45) + tol);
	r = fx_atan2_deg(-big, -big);
	assert_true(r > fx_from_int(-135) - tol && r < fx_from_int(-135) + tol);
}

static void test_div_saturates(void **state)
{
	(void)state;
	assert_int_equal(fx_div(fx_from_int(3), fx_from_int(2)), FX_ONE + FX_ONE / 2);
	assert_int_equal(fx_div(fx_from_int(-3), fx_from_int(2)), -(FX_ONE + FX_ONE / 2));
	/* Division by zero: the largest value of the dividend's sign. */
	assert_int_equal(fx_div(FX_ONE, 0), INT64_MAX);
	assert_int_equal(fx_div(0, 0), INT64_MAX);
	assert_int_equal(fx_div(-FX_ONE, 0), INT64_MIN);
	/* 10^6 / 2^-16 = 6.5e10, past the 2^31 integer range. */
	assert_int_equal(fx_div(fx_from_int(1000000), FX_ONE >> 16), INT64_MAX);
	assert_int_equal(fx_div(fx_from_int(-1000000), FX_ONE >> 16), INT64_MIN);
}

static void test_traj_degenerate(void **state)
{
	(void)state;
	q32_t a = FX_ONE / 1000;
	/* No acceleration: no braking distance, the whole distance in one tick. */
	assert_int_equal(traj_brake_dist(5 * a, 0), 0);
	assert_int_equal(traj_umax(fx_from_int(7), 0), fx_from_int(7));
	assert_int_equal(traj_umax(-a, a), 0);
	/* Already past the point: the speed that reaches exactly c there is c
	 * (B(3a) = 3a, so 3a + B(3a) = 6a = umax's bound). */
	assert_int_equal(traj_reach(-FX_ONE, 3 * a, a), 3 * a);
	assert_int_equal(traj_reach(0, 3 * a, a), 3 * a);
	/* Limits lowered under a unit at 10a with no room left: it still
	 * brakes by a, never harder. */
	assert_int_equal(traj_step(10 * a, 0, 10 * a, a), 9 * a);
	assert_int_equal(traj_step(10 * a, 0, 2 * a, a), 9 * a);
}

static void test_corner_refused_and_ends(void **state)
{
	(void)state;
	traj_corner_t c;
	q32_t ar = FX_ONE / 1000;
	assert_false(traj_corner_plan(&c, fx_from_int(171), fx_from_int(100), ar));
	assert_false(traj_corner_plan(&c, fx_from_int(-171), fx_from_int(100), ar));
	assert_false(traj_corner_plan(&c, fx_from_int(90), 0, ar));
	assert_false(traj_corner_plan(&c, fx_from_int(90), fx_from_int(100), 0));
	assert_true(traj_corner_plan(&c, fx_from_int(90), fx_from_int(100), ar));
	/* Before the start no turn, past the end the whole deflection. */
	assert_int_equal(traj_corner_heading(&c, -FX_ONE), 0);
	assert_int_equal(traj_corner_heading(&c, 0), 0);
	assert_int_equal(traj_corner_heading(&c, 2 * c.lh_mm), fx_from_int(90));
	assert_int_equal(traj_corner_heading(&c, 2 * c.lh_mm + FX_ONE), fx_from_int(90));
	/* Half way: half the deflection (the two clothoid halves meet). s / Lh
	 * comes from the truncated reciprocal, at most one Q30 unit low, so
	 * psi u^2 is low by at most 2 psi 2^-30 (360 raw units, 8e-8 deg). */
	q32_t mid = traj_corner_heading(&c, c.lh_mm);
	assert_true(mid >= fx_from_int(45) - 362 && mid <= fx_from_int(45));
	/* Across the join, Lh / 1000 either side: the heading change is
	 * 2 psi (2e - e^2) with e = 1/1000, to 1e-7 deg (the reciprocal of Lh
	 * with 22 significant bits put a 2.5e-5 deg step here). */
	q32_t x = c.lh_mm / 1000;
	double e = (double)x / (double)c.lh_mm;
	double step =
	    (double)(traj_corner_heading(&c, c.lh_mm + x) - traj_corner_heading(&c, c.lh_mm - x)) /
	    FX_ONE;
	assert_true(fabs(step - 90.0 * (2 * e - e * e)) < 1e-7);
	/* The smallest corner the reciprocal allows: 2^20 raw of half length. */
	traj_corner_t small;
	assert_false(traj_corner_plan(&small, fx_from_int(90), 1 << 19, ar));
}

/* mm_per_deg 2, deg_per_mm 0.5, one count per mm, 1 kHz, no feedback. */
static kin_params_t params(uint8_t kin)
{
	kin_params_t p = {
	    .kin = kin,
	    .n = kin == MOTION_KIN_OMNI ? 4 : 2,
	    .tick_hz = 1000,
	    .counts_per_mm = FX_ONE,
	    .mm_per_deg = 2 * FX_ONE,
	    .deg_per_mm = FX_ONE / 2,
	    .kp_q16 = 0,
	};
	return p;
}

static void test_kin_equations(void **state)
{
	(void)state;
	/* kin.h: left = vx - w*T/2, right = vx + w*T/2 (w*T/2 = 3 * 2 = 6 mm) */
	kin_params_t d = params(MOTION_KIN_DIFF);
	fx_twist_t b = {fx_from_int(10), 0, fx_from_int(3)};
	q32_t w[KIN_MAX_WHEELS] = {0};
	kin_body_to_wheels(&d, &b, w);
	assert_int_equal(w[0], fx_from_int(4));
	assert_int_equal(w[1], fx_from_int(16));
	fx_twist_t back;
	kin_wheels_to_body(&d, w, &back);
	assert_int_equal(back.vx_pt, fx_from_int(10));
	assert_int_equal(back.vy_pt, 0);
	assert_int_equal(back.w_pt, fx_from_int(3));

	/* mecanum: fl = vx - vy - r, fr = vx + vy + r, rl = vx + vy - r,
	 * rr = vx - vy + r, r = 6 mm */
	kin_params_t o = params(MOTION_KIN_OMNI);
	b = (fx_twist_t){fx_from_int(10), fx_from_int(4), fx_from_int(3)};
	kin_body_to_wheels(&o, &b, w);
	assert_int_equal(w[0], 0);
	assert_int_equal(w[1], fx_from_int(20));
	assert_int_equal(w[2], fx_from_int(8));
	assert_int_equal(w[3], fx_from_int(12));
	kin_wheels_to_body(&o, w, &back);
	assert_int_equal(back.vx_pt, fx_from_int(10));
	assert_int_equal(back.vy_pt, fx_from_int(4));
	assert_int_equal(back.w_pt, fx_from_int(3));
}

static void test_kin_step_omni(void **state)
{
	(void)state;
	kin_params_t p = params(MOTION_KIN_OMNI);
	kin_t k;
	kin_init(&k, &p);
	int32_t meas[KIN_MAX_WHEELS] = {0}, out[KIN_MAX_WHEELS] = {0};
	/* 1 mm/tick sideways: wheels -1, +1, +1, -1 count/tick = 1000 counts/s
	 * (Q8: 256000); the optional outputs may be left out. */
	fx_twist_t side = {0, FX_ONE, 0};
	kin_step(&k, &side, meas, out, NULL, NULL);
	assert_int_equal(out[0], -256000);
	assert_int_equal(out[1], 256000);
	assert_int_equal(out[2], 256000);
	assert_int_equal(out[3], -256000);
	/* The wheels did not turn: one count behind each; they now report the
	 * sideways millimetre. */
	int64_t ferr = -1;
	fx_twist_t moved;
	int32_t now[KIN_MAX_WHEELS] = {-1, 1, 1, -1};
	fx_twist_t rest = {0, 0, 0};
	kin_step(&k, &rest, now, out, &moved, &ferr);
	assert_int_equal(ferr, 0);
	assert_int_equal(moved.vx_pt, 0);
	assert_int_equal(moved.vy_pt, FX_ONE);
	assert_int_equal(moved.w_pt, 0);
	kin_step(&k, &side, now, out, &moved, &ferr);
	assert_int_equal(ferr, FX_ONE); /* one count, Q32 */
	assert_int_equal(moved.vy_pt, 0);
}

static void test_kin_setpoint_saturates(void **state)
{
	(void)state;
	kin_params_t p = params(MOTION_KIN_DIFF);
	kin_t k;
	kin_init(&k, &p);
	int32_t meas[KIN_MAX_WHEELS] = {0}, out[KIN_MAX_WHEELS] = {0};
	/* 2^20 counts/tick at 1 kHz is far past int32 counts/s Q8. */
	fx_twist_t fast = {fx_from_int(1 << 20), 0, 0};
	kin_step(&k, &fast, meas, out, NULL, NULL);
	assert_int_equal(out[0], INT32_MAX);
	assert_int_equal(out[1], INT32_MAX);
	kin_init(&k, &p);
	fast.vx_pt = -fast.vx_pt;
	kin_step(&k, &fast, meas, out, NULL, NULL);
	assert_int_equal(out[0], INT32_MIN);
	assert_int_equal(out[1], INT32_MIN);
	/* No encoder scale: odometry gets no length per count, not a division
	 * by zero. */
	p.counts_per_mm = 0;
	kin_init(&k, &p);
	assert_int_equal(k.mm_per_count_q48, 0);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_mul_portable_saturates),
	    cmocka_unit_test(test_angles_far_out),
	    cmocka_unit_test(test_div_saturates),
	    cmocka_unit_test(test_traj_degenerate),
	    cmocka_unit_test(test_corner_refused_and_ends),
	    cmocka_unit_test(test_kin_equations),
	    cmocka_unit_test(test_kin_step_omni),
	    cmocka_unit_test(test_kin_setpoint_saturates),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
