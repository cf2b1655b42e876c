/* The board's 64-bit division (hal/cortexm/udivmod64.c, in place of
 * libgcc's __udivmoddi4 on the Cortex-M images): exact cases at the edges
 * of each of its paths, then the host's own division over numerators and
 * divisors of every pair of bit lengths. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "../hal/cortexm/udivmod64.c"

static uint64_t rng = 0x2545f4914f6cdd1du;

static uint64_t next(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

static void expect(uint64_t n, uint64_t d, uint64_t q, uint64_t r)
{
	uint64_t got_r = ~r;
	assert_int_equal(board_udivmod64(n, d, &got_r), q);
	assert_int_equal(got_r, r);
	assert_int_equal(board_udivmod64(n, d, NULL), q);
}

static void test_exact(void **state)
{
	(void)state;
	const uint64_t max = UINT64_MAX;
	/* both within 32 bits: the core's own division */
	expect(0, 1, 0, 0);
	expect(7, 2, 3, 1);
	expect(0xffffffffu, 0xffffffffu, 1, 0);
	/* a 32-bit divisor: the high word, then the normalised step */
	expect(max, 1, max, 0);
	expect(max, 2, max / 2, 1);
	expect(max, 0xffffffffu, 0x100000001u, 0);
	expect(max, 0x80000000u, 0x1ffffffffu, 0x7fffffffu);
	expect(0x100000000u, 3, 0x55555555u, 1);
	expect(((uint64_t)0xfffffffeu << 32) | 0xffffffffu, 0xffffffffu, 0xffffffffu, 0xfffffffeu);
	/* the step's estimates corrected: v's lower half large */
	expect(0x7fff800000000000u, 0x8000ffffu, 0xfffd0007u, 0x7ff60007u);
	/* a divisor from 2^32: the quotient within 32 bits */
	expect(max, 0x100000000u, 0xffffffffu, 0xffffffffu);
	expect(max, max, 1, 0);
	expect(max - 1, max, 0, max - 1);
	expect(max, 0x8000000000000000u, 1, 0x7fffffffffffffffu);
	expect(0x100000000u, 0x100000000u, 1, 0);
	expect(0xffffffffu, 0x100000000u, 0, 0xffffffffu);
	expect(max, 0x100000001u, 0xffffffffu, 0);
	expect(0x1000000000000000u, 0x100000001u, 0xfffffffu, 0xf0000001u);
	expect(0xfffffffe00000001u, (uint64_t)0xffffffffu << 16, 0xffffu, 0xfffeffff0001u);
}

/* n of every bit length against d of every bit length, 40 pairs each. */
static void test_against_host(void **state)
{
	(void)state;
	for (int bn = 1; bn <= 64; bn++) {
		for (int bd = 1; bd <= 64; bd++) {
			for (int k = 0; k < 40; k++) {
				uint64_t n = next() >> (64 - bn), d = next() >> (64 - bd);
				n |= (uint64_t)1 << (bn - 1);
				d |= (uint64_t)1 << (bd - 1);
				if (k & 1) /* divisors with ones below the top */
					d |= ((uint64_t)1 << (bd - 1)) - 1;
				uint64_t r = ~(uint64_t)0;
				uint64_t q = board_udivmod64(n, d, &r);
				if (q != n / d || r != n % d)
					fail_msg("%llx / %llx: %llx r %llx, not %llx r %llx",
						 (unsigned long long)n, (unsigned long long)d,
						 (unsigned long long)q, (unsigned long long)r,
						 (unsigned long long)(n / d),
						 (unsigned long long)(n % d));
			}
		}
	}
}

/* Multiples of d, and one either side: where a quotient estimate that is
 * one off would show. */
static void test_multiples(void **state)
{
	(void)state;
	for (int k = 0; k < 200000; k++) {
		uint64_t d = next() >> (next() & 63);
		if (d == 0)
			d = 1;
		uint64_t qmax = UINT64_MAX / d;
		uint64_t q = qmax ? next() % qmax + 1 : 1;
		uint64_t n = q * d;
		for (int e = -1; e <= 1; e++) {
			uint64_t m = n + (uint64_t)(int64_t)e, r;
			if (e > 0 && m < n)
				continue;
			uint64_t got = board_udivmod64(m, d, &r);
			if (got != m / d || r != m % d)
				fail_msg("%llx / %llx", (unsigned long long)m,
					 (unsigned long long)d);
		}
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_exact),
	    cmocka_unit_test(test_against_host),
	    cmocka_unit_test(test_multiples),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
