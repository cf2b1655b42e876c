/* Differential fuzz target: the firmware on the lockstep simulator against
 * the executable model of the spec (tests/model/vs_diff.h). Any divergence
 * of a reply, a refusal code, the state or the alarm list, and any broken
 * invariant (motion without a command in force, a speed or acceleration
 * over its bound as a vector, the hold included) aborts with the step. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "../model/vs_diff.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char why[512];
	if (diff_run(data, size, why, sizeof why) != 0) {
		fprintf(stderr, "fuzz_model: %s\n", why);
		abort();
	}
	return 0;
}
