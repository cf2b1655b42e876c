/* 64-bit unsigned division on a 32-bit divide (udivmod64.c). */
#ifndef UDIVMOD64_H
#define UDIVMOD64_H

#include <stdint.h>

/* n / d, and n % d through rem unless it is null; d = 0 gives 0 and n's
 * low word's remainder, and no trap. */
uint64_t board_udivmod64(uint64_t n, uint64_t d, uint64_t *rem);

#endif
