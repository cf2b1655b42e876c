/* proto/numparse.c's Q32 conversions, which a board built with VS_REAL_Q32
 * (firmware/real.h) uses in place of doubles: each is checked on exact
 * cases, then against an independent computation on the host (glibc's
 * strtod, printf and the compiler's own double arithmetic, 128-bit
 * integers) over value sweeps. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../proto/numparse.h"

#define ONE   (INT64_C(1) << 32)
#define SWEEP 200000

static uint64_t rng = 0x9e3779b97f4a7c15u;

static uint64_t next(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

static int64_t parse(const char *s)
{
	int64_t v = 12345;

	assert_int_equal(np_parse_q32(s, &v), NP_OK);
	return v;
}

static void test_parse_exact(void **state)
{
	(void)state;
	assert_true(parse("1") == ONE);
	assert_true(parse("0.5") == ONE / 2);
	assert_true(parse("-.25") == -ONE / 4);
	assert_true(parse("+7.") == 7 * ONE);
	assert_true(parse("1e3") == 1000 * ONE);
	assert_true(parse("1E-2") == 42949673); /* 42949672.96 */
	assert_true(parse("0") == 0);
	assert_true(parse("-0.000") == 0);
	/* 1e-10 is 0.43 units, 2e-10 is 0.86; half a unit, 2^-33, is
	 * 1.16415321826934814453125e-10: a tie needs 24 digits, and digits
	 * after the 19th are dropped, so it reads just below. */
	assert_true(parse("1e-10") == 0);
	assert_true(parse("2e-10") == 1);
	assert_true(parse("1.1641532182693482e-10") == 1);
	assert_true(parse("-1.1641532182693482e-10") == -1);
	assert_true(parse("1.1641532182693481e-10") == 0);
	assert_true(parse("1.16415321826934814453125e-10") == 0);
	/* the largest value below 2^31, and beyond it saturation */
	assert_true(parse("2147483647.99999999") == INT64_C(9223372036854775765));
	assert_true(parse("2147483648") == INT64_MAX);
	assert_true(parse("-2147483648") == -INT64_MAX);
	assert_true(parse("1e300") == INT64_MAX);
	assert_true(parse("-1e308") == -INT64_MAX);
	assert_true(parse("1e-400") == 0);
	/* more than 19 significant digits: the rest only scale */
	assert_true(parse("1000000.00000000000000000001") == 1000000 * ONE);
	assert_true(parse("12345678901234567890123") == INT64_MAX);
}

static void test_parse_rejects(void **state)
{
	static const char *const bad[] = {"",	 "-",	 ".",	  "e3",	    "1e",
					  "1e+", "0x10", "nan",	  "inf",    "1.5.",
					  "1 ",	 " 1",	 "1e400", "-1e309", "1.8e308"};
	int64_t v = 77;

	(void)state;
	for (size_t k = 0; k < sizeof(bad) / sizeof(bad[0]); k++) {
		double d;

		assert_int_equal(np_parse_q32(bad[k], &v), NP_SYNTAX);
		/* the double parser refuses the same text */
		assert_int_equal(np_parse_double(bad[k], &d), NP_SYNTAX);
	}
	assert_true(v == 77);
	/* DBL_MAX itself is a number */
	assert_true(parse("1.7976931348623157e308") == INT64_MAX);
}

/* A decimal m * 10^-k, |value| < 2^31: np_parse_q32 against the exact
 * rounding in 128-bit integers. */
static void test_parse_sweep(void **state)
{
	(void)state;
	for (int i = 0; i < SWEEP; i++) {
		uint64_t m = next() % UINT64_C(1000000000000000); /* up to 15 digits */
		int k = (int)(next() % 28);
		bool neg = next() & 1u;
		__int128 p10 = 1;
		char s[64];

		for (int j = 0; j < k; j++)
			p10 *= 10;
		if ((__int128)m >= p10 * ((__int128)1 << 31))
			continue;
		snprintf(s, sizeof(s), "%s%llue-%d", neg ? "-" : "", (unsigned long long)m, k);
		__int128 num = (__int128)m << 32;
		__int128 q = num / p10, r = num % p10;
		if (2 * r >= p10)
			q++;
		int64_t want = neg ? -(int64_t)q : (int64_t)q;
		int64_t got = parse(s);
		if (got != want)
			fail_msg("%s: %lld, want %lld", s, (long long)got, (long long)want);
	}
}

static void check_fmt(int64_t v)
{
	char got[NP_FIXED3_MAX], dbl[NP_FIXED3_MAX], glibc[NP_FIXED3_MAX];
	double d = (double)v / 4294967296.0;

	np_fmt_q32_fixed3(v, got);
	np_fmt_fixed3(d, dbl);
	snprintf(glibc, sizeof(glibc), "%.3f", d);
	if (strcmp(got, dbl) != 0 || strcmp(got, glibc) != 0)
		fail_msg("%lld: %s, double path %s, glibc %s", (long long)v, got, dbl, glibc);
}

static void test_fmt(void **state)
{
	char b[NP_FIXED3_MAX];

	(void)state;
	assert_int_equal(np_fmt_q32_fixed3(1000 * ONE, b), 8);
	assert_string_equal(b, "1000.000");
	assert_int_equal(np_fmt_q32_fixed3(-ONE / 2, b), 6);
	assert_string_equal(b, "-0.500");
	np_fmt_q32_fixed3(-1, b);
	assert_string_equal(b, "-0.000");
	/* 1/16 is 62.5 thousandths: a tie, to even */
	np_fmt_q32_fixed3(ONE / 16, b);
	assert_string_equal(b, "0.062");
	np_fmt_q32_fixed3(3 * ONE / 16, b);
	assert_string_equal(b, "0.188");
	np_fmt_q32_fixed3(INT64_MAX, b);
	assert_string_equal(b, "2147483648.000");
	np_fmt_q32_fixed3(INT64_MIN, b);
	assert_string_equal(b, "nan");
	/* Values a double holds exactly (below 2^53): the same text as the
	 * double path and as glibc. */
	for (int i = 0; i < SWEEP; i++) {
		int64_t v = (int64_t)(next() >> (11 + next() % 40));

		check_fmt(next() & 1u ? -v : v);
	}
	for (int64_t t = -5000; t <= 5000; t++) /* every tie near zero */
		check_fmt(t * ONE / 2000);
}

/* round(d * 2^32), half away from zero, in long double (64-bit mantissa:
 * exact for a double's 53 bits). */
static int64_t ref_from(double d)
{
	return (int64_t)roundl((long double)d * 4294967296.0L);
}

static uint64_t bits_of(double d)
{
	uint64_t b;

	memcpy(&b, &d, sizeof(b));
	return b;
}

static void test_from_ieee(void **state)
{
	(void)state;
	assert_true(np_q32_from_ieee(bits_of(1.0)) == ONE);
	assert_true(np_q32_from_ieee(bits_of(-2.5)) == -5 * ONE / 2);
	assert_true(np_q32_from_ieee(bits_of(0.0)) == 0);
	assert_true(np_q32_from_ieee(bits_of(-0.0)) == 0);
	assert_true(np_q32_from_ieee(bits_of(DBL_MIN)) == 0);
	assert_true(np_q32_from_ieee(bits_of(0x1p-33)) == 1); /* half: away */
	assert_true(np_q32_from_ieee(bits_of(-0x1p-33)) == -1);
	assert_true(np_q32_from_ieee(bits_of(0x1.fffffffffffffp-34)) == 0); /* below half */
	assert_true(np_q32_from_ieee(bits_of(0x1.fffffffffffffp+30)) ==
		    (int64_t)(UINT64_C(0x1fffffffffffff) << 10));
	assert_true(np_q32_from_ieee(bits_of(2147483648.0)) == INT64_MAX);
	assert_true(np_q32_from_ieee(bits_of(-1e300)) == -INT64_MAX);
	assert_true(np_q32_from_ieee(bits_of(INFINITY)) == INT64_MIN);
	assert_true(np_q32_from_ieee(bits_of(-INFINITY)) == INT64_MIN);
	assert_true(np_q32_from_ieee(bits_of(NAN)) == INT64_MIN);
	for (int i = 0; i < SWEEP; i++) {
		/* exponents from 2^-40 to 2^30, any mantissa and sign */
		uint64_t b = (next() & UINT64_C(0x800fffffffffffff)) |
			     (UINT64_C(1023 - 40) + next() % 71) << 52;
		double d;

		memcpy(&d, &b, sizeof(d));
		if (np_q32_from_ieee(b) != ref_from(d))
			fail_msg("%a: %lld, want %lld", d, (long long)np_q32_from_ieee(b),
				 (long long)ref_from(d));
	}
}

static void test_to_ieee(void **state)
{
	(void)state;
	assert_true(np_q32_to_ieee(0) == 0);
	assert_true(np_q32_to_ieee(ONE) == bits_of(1.0));
	assert_true(np_q32_to_ieee(-3 * ONE / 4) == bits_of(-0.75));
	assert_true(np_q32_to_ieee(1) == bits_of(0x1p-32));
	assert_true(np_q32_to_ieee(INT64_MAX) == bits_of(2147483648.0)); /* rounds up */
	/* 2^53 + 1 and + 3: ties to even */
	assert_true(np_q32_to_ieee((INT64_C(1) << 53) + 1) == bits_of(0x1p21));
	assert_true(np_q32_to_ieee((INT64_C(1) << 53) + 3) == bits_of(0x1.0000000000002p21));
	for (int i = 0; i < SWEEP; i++) {
		int64_t v = (int64_t)(next() >> (1 + next() % 63));

		v = next() & 1u ? -v : v;
		if (np_q32_to_ieee(v) != bits_of((double)v / 4294967296.0))
			fail_msg("%lld: %a", (long long)v, (double)v / 4294967296.0);
		/* and back: within half a unit of what a double holds */
		if (v > -(INT64_C(1) << 53) && v < INT64_C(1) << 53)
			assert_true(np_q32_from_ieee(np_q32_to_ieee(v)) == v);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_parse_exact), cmocka_unit_test(test_parse_rejects),
	    cmocka_unit_test(test_parse_sweep), cmocka_unit_test(test_fmt),
	    cmocka_unit_test(test_from_ieee),	cmocka_unit_test(test_to_ieee),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
