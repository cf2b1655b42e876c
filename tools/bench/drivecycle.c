/* make bench: the Modbus drive cycle (hal/modbus/mbmaster.h) of the
 * generic profile, 2 and 4 drives, 8N1 (the board's frame) at the usual
 * rates: mbd_cycle_us, which counts a 3.5-character gap per request, and
 * the cycle with the gap the master waits (mbm's gap_us: 1750 us above
 * 19200 baud, as the standard fixes it), each with MBD_TURNAROUND_US per
 * answer. */
#include <stdio.h>

#include "../../hal/modbus/mbmaster.h"

#define FRAME_BITS 10u

static size_t rd_none(void *ctx, uint8_t *b, size_t n)
{
	(void)ctx;
	(void)b;
	(void)n;
	return 0;
}

int main(void)
{
	static const uint32_t bauds[] = {9600, 19200, 38400, 57600, 115200};
	const mb_profile_t *g = mbp_builtin("generic");
	const mbm_port_t port = {rd_none, NULL, NULL, NULL, NULL};

	printf("  %7s  %6s  %14s  %14s  %16s\n", "baud", "drives", "mbd_cycle_us", "with the gap",
	       "cycles a second");
	for (unsigned i = 0; i < sizeof bauds / sizeof bauds[0]; i++)
		for (unsigned nd = 2; nd <= 4; nd += 2) {
			mbm_t m;
			mbm_init(&m, &port, bauds[i], FRAME_BITS, 100000u, 1, 0);
			uint32_t c = mbd_cycle_us(g, nd, bauds[i], FRAME_BITS, MBD_TURNAROUND_US);
			uint32_t ch = mbm_char_us(bauds[i], FRAME_BITS);
			/* per request: the master's gap instead of 3.5 characters */
			uint32_t req = nd * MBD_GENERIC_REQUESTS;
			uint32_t gap35 = (7u * ch + 1u) / 2u;
			uint32_t w = c - req * gap35 + req * m.gap_us;
			printf("  %7u  %6u  %11u us  %11u us  %16.1f\n", bauds[i], nd, c, w,
			       1e6 / (double)w);
		}
	return 0;
}
