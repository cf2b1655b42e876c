/* make bench: the Modbus drive cycle (hal/modbus/mbmaster.h, mbd_cycle_us)
 * of the generic profile, 2 and 4 drives, 8N1 (the board's frame) at the
 * usual rates: the frames' characters, the gap the master waits before
 * each request (MBM_GAP_US: 1750 us above 19200 baud, as the standard
 * fixes it) and MBD_TURNAROUND_US per answer. */
#include <stdio.h>

#include "../../hal/modbus/mbmaster.h"

#define FRAME_BITS 10u

int main(void)
{
	static const uint32_t bauds[] = {9600, 19200, 38400, 57600, 115200};
	const mb_profile_t *g = mbp_builtin("generic");

	printf("  %7s  %6s  %14s  %16s\n", "baud", "drives", "mbd_cycle_us", "cycles a second");
	for (unsigned i = 0; i < sizeof bauds / sizeof bauds[0]; i++)
		for (unsigned nd = 2; nd <= 4; nd += 2) {
			uint32_t c = mbd_cycle_us(g, nd, bauds[i], FRAME_BITS, MBD_TURNAROUND_US);
			printf("  %7u  %6u  %11u us  %16.1f\n", bauds[i], nd, c, 1e6 / (double)c);
		}
	return 0;
}
