/* Fixed-point maths: products, square root, trigonometry, angles. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "firmware/fx.h"
#include "firmware/traj.h"

static const double Q = 4294967296.0;

static uint64_t rng = 88172645463325252ull;
static uint64_t next(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

static void test_mul_paths_agree(void **state)
{
	(void)state;
	for (int i = 0; i < 2000000; i++) {
		q32_t a = (q32_t)(next() >> (next() % 64)), b = (q32_t)(next() >> (next() % 64));
		if (i % 5 == 0)
			b = ((q32_t)1 << 31) + (q32_t)(i & 1); /* exact and near halves */
		if (next() & 1)
			a = -a;
		if (next() & 1)
			b = -b;
		assert_int_equal(fx_mul(a, b), fx_mul_portable(a, b));
	}
}

static void test_mul_rounding_and_saturation(void **state)
{
	(void)state;
	/* 1.5 * 2^-32 * 0.5 = 0.75 raw -> 1; -0.75 raw -> -1; +-0.5 raw -> half up */
	assert_int_equal(fx_mul(3, (q32_t)1 << 31), 2);	  /* 1.5 -> 2 */
	assert_int_equal(fx_mul(-3, (q32_t)1 << 31), -1); /* -1.5 -> -1 */
	assert_int_equal(fx_mul(1, (q32_t)1 << 31), 1);	  /* 0.5 -> 1 */
	assert_int_equal(fx_mul(-1, (q32_t)1 << 31), 0);  /* -0.5 -> 0 */
	assert_int_equal(fx_mul(FX_ONE * 3, FX_ONE * 7), FX_ONE * 21);
	assert_int_equal(fx_mul(INT64_MAX, FX_ONE * 4), INT64_MAX);
	assert_int_equal(fx_mul(INT64_MIN, FX_ONE * 4), INT64_MIN);
	assert_int_equal(fx_mul(-INT64_MAX, -FX_ONE * 4), INT64_MAX);
}

static void test_isqrt(void **state)
{
	(void)state;
	assert_int_equal(fx_isqrt64(0), 0);
	assert_int_equal(fx_isqrt64(15), 3);
	assert_int_equal(fx_isqrt64(16), 4);
	assert_int_equal(fx_isqrt64(UINT64_MAX), 4294967295u);
	/* the edges of the 32-bit form */
	assert_int_equal(fx_isqrt64(4294967295u), 65535);
	assert_int_equal(fx_isqrt64(4294967296u), 65536);
	assert_int_equal(fx_isqrt64(4294836225u), 65535); /* 65535^2 */
	assert_int_equal(fx_isqrt64(4294836224u), 65534);
	for (int i = 0; i < 100000; i++) {
		uint64_t v = next() >> (next() % 64);
		uint64_t r = fx_isqrt64(v);
		assert_true(r * r <= v);
		assert_true((r + 1) * (r + 1) > v || r == 4294967295u);
	}
}

static void test_udiv_small(void **state)
{
	(void)state;
	assert_int_equal(fx_udiv64_small(UINT64_MAX, 1), UINT64_MAX);
	assert_int_equal(fx_udiv64_small(UINT64_MAX, 0xffff), UINT64_MAX / 0xffff);
	assert_int_equal(fx_udiv64_small(0, 7), 0);
	assert_int_equal(fx_udiv64_small(99, 100), 0);
	assert_int_equal(fx_udiv64_small(100, 100), 1);
	for (int i = 0; i < 100000; i++) {
		uint64_t n = next() >> (next() % 64);
		uint32_t d = (uint32_t)(next() % 0xffff) + 1;
		assert_int_equal(fx_udiv64_small(n, d), n / d);
	}
}

static void test_mulhi_paths_agree(void **state)
{
	(void)state;
	static const uint64_t edge[] = {
	    0, 1, 0xffffffffu, 0x100000000u, UINT64_MAX, UINT64_MAX - 1, (uint64_t)1 << 63};
	for (size_t i = 0; i < sizeof edge / sizeof edge[0]; i++)
		for (size_t j = 0; j < sizeof edge / sizeof edge[0]; j++)
			assert_int_equal(fx_mulhi_u64_portable(edge[i], edge[j]),
					 fx_mulhi_u64(edge[i], edge[j]));
	assert_int_equal(fx_mulhi_u64_portable(UINT64_MAX, UINT64_MAX), UINT64_MAX - 1);
	for (int i = 0; i < 100000; i++) {
		uint64_t x = next() >> (next() % 64), y = next() >> (next() % 64);
		assert_int_equal(fx_mulhi_u64_portable(x, y), fx_mulhi_u64(x, y));
	}
}

/* The planning pass's reciprocal forms return the bits of the dividing
 * ones, over the quantities a queue holds and past them. */
static void test_rate_forms_match(void **state)
{
	(void)state;
	traj_rate_t r;
	int checked = 0;
	for (int i = 0; i < 200000; i++) {
		/* acceleration 1 raw unit .. 2^40 (a tick^2 in Q32 mm) */
		q32_t a = (q32_t)(next() >> (24 + next() % 40)) + 1;
		q32_t u = (q32_t)(next() >> (14 + next() % 50));
		q32_t d = (q32_t)(next() >> (2 + next() % 50));
		traj_rate_init(&r, a);
		/* B(u) = n u - T(n) stays in range for n u below 2^62 */
		if (u / a <= (INT64_MAX / 2) / (u + 1)) {
			assert_int_equal(traj_brake_dist_r(u, &r), traj_brake_dist(u, a));
			/* whole multiples: the quotient at its edge */
			q32_t k = u / a;
			assert_int_equal(traj_brake_dist_r(k * a, &r), traj_brake_dist(k * a, a));
			checked++;
		}
		/* tri(n, a) stays in range for d / a below 2^60 */
		if ((uint64_t)d / (uint64_t)a < ((uint64_t)1 << 60))
			assert_int_equal(traj_umax_r(d, &r), traj_umax(d, a));
	}
	assert_true(checked > 100000);
	traj_rate_init(&r, 1);
	assert_int_equal(traj_brake_dist_r(1000, &r), traj_brake_dist(1000, 1));
	assert_int_equal(traj_umax_r((q32_t)1 << 40, &r), traj_umax((q32_t)1 << 40, 1));
	traj_rate_init(&r, 0);
	assert_int_equal(traj_brake_dist_r(1000, &r), 0);
	assert_int_equal(traj_umax_r(1000, &r), 1000);
	traj_rate_init(&r, 4295);
	assert_int_equal(traj_umax_r(0, &r), 0);
	assert_int_equal(traj_brake_dist_r(-5, &r), 0);
}

/* Bit-at-a-time forms of the division, square root and hypot, written
 * straight from their definitions: the firmware's faster forms must return
 * the same bits for every input. */
static int64_t ref_div(int64_t a, int64_t b)
{
	if (b == 0)
		return a >= 0 ? INT64_MAX : INT64_MIN;
	int neg = (a < 0) != (b < 0);
	uint64_t ua = a < 0 ? 0u - (uint64_t)a : (uint64_t)a;
	uint64_t ub = b < 0 ? 0u - (uint64_t)b : (uint64_t)b;
	uint64_t q = ua / ub, r = ua % ub;
	if (q >> 31)
		return neg ? INT64_MIN : INT64_MAX;
	uint64_t res = q << 32;
	for (int i = 31; i >= 0; i--) {
		r <<= 1;
		if (r >= ub) {
			r -= ub;
			res |= (uint64_t)1 << i;
		}
	}
	return neg ? -(int64_t)res : (int64_t)res;
}

static uint64_t ref_isqrt(uint64_t v)
{
	uint64_t res = 0, bit = (uint64_t)1 << 62;
	while (bit > v)
		bit >>= 2;
	while (bit) {
		if (v >= res + bit) {
			v -= res + bit;
			res = (res >> 1) + bit;
		} else {
			res >>= 1;
		}
		bit >>= 2;
	}
	return res;
}

static int64_t ref_hypot(int64_t x, int64_t y)
{
	uint64_t ax = x < 0 ? 0u - (uint64_t)x : (uint64_t)x;
	uint64_t ay = y < 0 ? 0u - (uint64_t)y : (uint64_t)y;
	int shift = 0;
	while ((ax | ay) >> 31) {
		ax >>= 1;
		ay >>= 1;
		shift++;
	}
	while (ax < (1ull << 30) && ay < (1ull << 30) && (ax | ay) && shift > -16) {
		ax <<= 1;
		ay <<= 1;
		shift--;
	}
	uint64_t r = ref_isqrt(ax * ax + ay * ay);
	return shift >= 0 ? (int64_t)(r << shift) : (int64_t)(r >> -shift);
}

/* fx_mul_q30's split form (the one without 128-bit integers). */
static int64_t ref_mul_q30(int64_t a, int32_t b)
{
	int64_t hi = a >> 32;
	int64_t lo = (int64_t)(uint32_t)(uint64_t)a;
	return hi * b * 4 + ((lo * b + ((int64_t)1 << 29)) >> 30);
}

static int64_t any64(void)
{
	/* Every magnitude, both signs, and the edges. */
	switch (next() % 8) {
	case 0:
		return INT64_MIN + (int64_t)(next() % 3);
	case 1:
		return INT64_MAX - (int64_t)(next() % 3);
	case 2:
		return (int64_t)(next() % 5) - 2;
	default:
		return (int64_t)(next() >> (next() % 64)) * ((next() & 1) ? -1 : 1);
	}
}

static void test_fast_forms_match_bitwise(void **state)
{
	(void)state;
	assert_int_equal(fx_div(1, INT64_MIN), ref_div(1, INT64_MIN));
	assert_int_equal(fx_div(INT64_MAX, INT64_MIN), ref_div(INT64_MAX, INT64_MIN));
	assert_int_equal(fx_div(-INT64_MAX, INT64_MAX), -FX_ONE);
	for (int i = 0; i < 300000; i++) {
		int64_t a = any64(), b = any64();
		/* |INT64_MIN| is not an int64: both forms leave it out of range. */
		if (a == INT64_MIN || b == INT64_MIN)
			continue;
		assert_int_equal(fx_div(a, b), ref_div(a, b));
		assert_int_equal(fx_hypot(a >> 2, b >> 2), ref_hypot(a >> 2, b >> 2));
		/* Products whose result fits: |a| < 2^62 with |b| <= 2^30. */
		int32_t q30 = (int32_t)(b % (FX_Q30_ONE + 1LL));
		assert_int_equal(fx_mul_q30(a >> 2, q30), ref_mul_q30(a >> 2, q30));
		uint64_t v = (uint64_t)a ^ ((uint64_t)b << 1);
		assert_int_equal(fx_isqrt64(v), ref_isqrt(v));
	}
	for (uint64_t v = 0; v < 70000; v++)
		assert_int_equal(fx_isqrt64(v), ref_isqrt(v));
	for (int k = 1; k < 64; k++) {
		uint64_t p = (uint64_t)1 << k;
		assert_int_equal(fx_isqrt64(p - 1), ref_isqrt(p - 1));
		assert_int_equal(fx_isqrt64(p), ref_isqrt(p));
		uint64_t r = ref_isqrt(p);
		assert_int_equal(fx_isqrt64(r * r - 1), r - 1);
	}
}

static void test_sin_cos_precision(void **state)
{
	(void)state;
	double worst = 0;
	for (uint64_t k = 0; k < (1u << 20); k++) {
		uint32_t bam = (uint32_t)(k << 12) + (uint32_t)(next() & 0xfff);
		double a = (double)bam / 4294967296.0 * 2 * M_PI;
		double es = fabs(fx_sin_bam(bam) / 1073741824.0 - sin(a));
		double ec = fabs(fx_cos_bam(bam) / 1073741824.0 - cos(a));
		worst = fmax(worst, fmax(es, ec));
	}
	assert_true(worst < 4e-9); /* a few Q30 steps */
	for (int i = 0; i < 100000; i++) {
		uint32_t bam = (uint32_t)next();
		int32_t s, c;
		fx_sincos_bam(bam, &s, &c);
		assert_int_equal(s, fx_sin_bam(bam));
		assert_int_equal(c, fx_cos_bam(bam));
	}
	assert_int_equal(fx_sin_bam(0), 0);
	assert_int_equal(fx_cos_bam(0), FX_Q30_ONE);
	assert_int_equal(fx_sin_bam(1u << 30), FX_Q30_ONE);
	assert_int_equal(fx_cos_bam(1u << 31), -FX_Q30_ONE);
}

static void test_angles(void **state)
{
	(void)state;
	assert_int_equal(fx_wrap_deg(FX_DEG_180), -FX_DEG_180);
	assert_int_equal(fx_wrap_deg(-FX_DEG_180), -FX_DEG_180);
	assert_int_equal(fx_wrap_deg(fx_from_int(540)), -FX_DEG_180);
	assert_int_equal(fx_wrap_deg(fx_from_int(-190)), fx_from_int(170));
	assert_int_equal(fx_wrap_deg(fx_from_int(36000 + 45)), fx_from_int(45));
	/* Each branch at its edges: in range, one turn out either way (no
	 * division), further out, and the extremes of int64 (no overflow). */
	assert_int_equal(fx_wrap_deg(FX_DEG_180 - 1), FX_DEG_180 - 1);
	assert_int_equal(fx_wrap_deg(fx_from_int(540) - 1), FX_DEG_180 - 1);
	assert_int_equal(fx_wrap_deg(-FX_DEG_180 - 1), FX_DEG_180 - 1);
	assert_int_equal(fx_wrap_deg(fx_from_int(-540)), -FX_DEG_180);
	assert_int_equal(fx_wrap_deg(fx_from_int(-540) - 1), FX_DEG_180 - 1);
	assert_int_equal(fx_wrap_deg(fx_from_int(-36000 - 45)), -fx_from_int(45));
	/* +-2^31 degrees is 5,965,232 turns and 128 degrees. */
	assert_int_equal(fx_wrap_deg(INT64_MAX), fx_from_int(128) - 1);
	assert_int_equal(fx_wrap_deg(INT64_MIN), -fx_from_int(128));
	assert_int_equal(fx_deg_to_bam(fx_from_int(90)), 1u << 30);
	assert_int_equal(fx_deg_to_bam(fx_from_int(-90)), 3u << 30);
	/* atan2: the axes exactly, elsewhere within the last CORDIC step,
	 * atan(2^-31) = 2.7e-8 degrees */
	assert_int_equal(fx_atan2_deg(0, FX_ONE), 0);
	assert_int_equal(fx_atan2_deg(0, -FX_ONE), -FX_DEG_180);
	assert_int_equal(fx_atan2_deg(FX_ONE, 0), fx_from_int(90));
	assert_int_equal(fx_atan2_deg(-FX_ONE, 0), -fx_from_int(90));
	for (int i = 0; i < 100000; i++) {
		int64_t y = (int64_t)(next() >> 20) - (1ll << 43),
			x = (int64_t)(next() >> 20) - (1ll << 43);
		double want = atan2((double)y, (double)x) * 180 / M_PI;
		double got = (double)fx_atan2_deg(y, x) / Q;
		double e = fabs(got - want);
		if (e > 180)
			e = 360 - e;
		assert_true(e < 3e-8);
	}
	assert_int_equal(fx_hypot(fx_from_int(3000), fx_from_int(4000)), fx_from_int(5000));
}

static void test_profile_lands_exactly(void **state)
{
	(void)state;
	/* traj_step: from rest over many distances, never more than a per
	 * step, never above vmax, landing on the exact raw endpoint. */
	for (int i = 0; i < 2000; i++) {
		q32_t d = (q32_t)(next() % (10000ull << 32)) + 1;
		/* 1 mm/s^2 .. 2000 mm/s^2 and up to 2 m/s at 1 kHz */
		q32_t a = (q32_t)(next() % 8590000) + 4295,
		      vmax = (q32_t)(next() % (1ull << 33)) + a;
		q32_t s = 0, v = 0;
		for (int k = 0; k < 10000000 && (s < d || v != 0); k++) {
			q32_t u = traj_step(v, d - s, vmax, a);
			assert_true(u - v <= a && v - u <= a);
			assert_true(u <= vmax || u <= v);
			s += u;
			v = u;
			if (s == d && v > 0)
				v = traj_step(v, 0, vmax, a);
		}
		assert_int_equal(s, d);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_mul_paths_agree),
	    cmocka_unit_test(test_mul_rounding_and_saturation),
	    cmocka_unit_test(test_isqrt),
	    cmocka_unit_test(test_udiv_small),
	    cmocka_unit_test(test_mulhi_paths_agree),
	    cmocka_unit_test(test_rate_forms_match),
	    cmocka_unit_test(test_fast_forms_match_bitwise),
	    cmocka_unit_test(test_sin_cos_precision),
	    cmocka_unit_test(test_angles),
	    cmocka_unit_test(test_profile_lands_exactly),
	};
	return cmocka_run_group_tests_name("fixed point", tests, NULL, NULL);
}
