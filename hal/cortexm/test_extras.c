/* The test image's extras (tests/mcu, linked into vehicle-test.elf only):
 * $hang spins in the main loop, so that the watchdog runs out; $fault reads
 * an address nothing answers, a bus fault taken as a HardFault. */
#include <string.h>

#include "plant.h"

/* Nothing is mapped there on MPS2 (QEMU answers a bus error). */
#define NO_DEVICE 0x50000000u

bool board_test_extra(int argc, char **argv, char *reply, size_t cap)
{
	(void)reply;
	(void)cap;
	if (argc != 1)
		return false;
	if (strcmp(argv[0], "$hang") == 0)
		for (;;)
			__asm volatile("" ::: "memory");
	if (strcmp(argv[0], "$fault") == 0)
		return *(volatile uint32_t *)NO_DEVICE != 0;
	return false;
}
