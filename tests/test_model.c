/* The firmware against the executable model of the spec
 * (tests/model/vs_model.h), through the differential harness
 * (tests/model/vs_diff.h): random sequences of operations, inputs and time
 * on the lockstep simulator, every reply, refusal code, state and alarm
 * compared, and the invariants checked every tick. Each configuration a
 * user runs: the differential base and the mecanum base, on the default
 * plant and the ideal one, with and without jerk limits. The sequences come
 * from a fixed-seed generator, so a run is the same on every machine. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "model/vs_diff.h"

#define SEQ_LEN 400

static uint32_t rng = 0x2545f491u;

static uint8_t next(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 17;
	rng ^= rng << 5;
	return (uint8_t)(rng >> 11);
}

static void run_many(uint8_t mode, unsigned n)
{
	const char *scale = getenv("DIFF_SCALE"); /* a longer run: n times this */
	if (scale)
		n *= (unsigned)atoi(scale);
	static uint8_t buf[SEQ_LEN];
	char why[512];
	unsigned bad = 0;
	const char *only = getenv("DIFF_ONLY"); /* "MODE SEQ": trace that one */
	/* Every sequence's tick hash: a refactoring that changes no behaviour
	 * leaves them all as they were. */
	bool hashes = getenv("DIFF_HASH") != NULL;
	for (unsigned s = 0; s < n; s++) {
		buf[0] = mode;
		for (unsigned i = 1; i < SEQ_LEN; i++)
			buf[i] = next();
		unsigned om, os;
		if (only && (sscanf(only, "%u %u", &om, &os) != 2 || om != mode || os != s))
			continue;
		if (diff_run(buf, SEQ_LEN, why, sizeof why) != 0) {
			printf("mode %u sequence %u: %s\n", mode, s, why);
			bad++;
		}
		if (hashes)
			printf("hash %u %u %016llx\n", mode, s,
			       (unsigned long long)diff_last_hash());
	}
	assert_int_equal(bad, 0);
}

static void test_diff_default_plant(void **st)
{
	(void)st;
	run_many(0, 60);
}

static void test_omni_default_plant(void **st)
{
	(void)st;
	run_many(1, 60);
}

static void test_diff_ideal_plant(void **st)
{
	(void)st;
	run_many(2, 30);
}

static void test_omni_ideal_plant(void **st)
{
	(void)st;
	run_many(3, 30);
}

static void test_diff_jerk(void **st)
{
	(void)st;
	run_many(4, 30);
}

static void test_omni_jerk(void **st)
{
	(void)st;
	run_many(5, 30);
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_diff_default_plant), cmocka_unit_test(test_omni_default_plant),
	    cmocka_unit_test(test_diff_ideal_plant),   cmocka_unit_test(test_omni_ideal_plant),
	    cmocka_unit_test(test_diff_jerk),	       cmocka_unit_test(test_omni_jerk),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
