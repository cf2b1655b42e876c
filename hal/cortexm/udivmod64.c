/* 64-bit division for a board with a divide instruction, in place of
 * libgcc's: __udivmoddi4 and the run-time ABI's entries that the compiler
 * calls for / and % (__aeabi_uldivmod, __aeabi_ldivmod). Long division on
 * the core's own 32-bit divide: 0.6 KiB less flash than the library's, the
 * ticks within 2 % of their cost with it (docs/mcu.md). The linker takes
 * these before the library's. tests/test_udivmod64.c checks the division
 * against the host's; tests/mcu/divcheck.c the entries on the emulated
 * board, against a bitwise division of its own.
 *
 * The step that does the work divides a 64-bit (u1:u0) by a 32-bit v with
 * its top bit set, u1 < v, so that the quotient fits 32 bits: two 16-bit
 * digits, each estimated from v's top half and the numerator's top word,
 * then corrected down while it times v's lower half exceeds what the
 * estimate left. With v normalised the estimate is at most 2 too large
 * (Knuth, TAOCP vol. 2, 4.3.1, theorem B). */
#include <stdint.h>

#include "udivmod64.h"

/* Inline, as div_norm: a call each costs more than the step. */
static inline __attribute__((always_inline)) uint32_t div_digit(uint32_t u, uint32_t next,
								uint32_t v)
{
	uint32_t vh = v >> 16, vl = v & 0xffffu;
	uint32_t q = u / vh, r = u - q * vh;
	/* q * vl is only formed for q < 2^16, r << 16 only for r < 2^16. */
	while (q > 0xffffu || q * vl > ((r << 16) | next)) {
		q--;
		r += vh;
		if (r > 0xffffu)
			break;
	}
	return q;
}

static __attribute__((noinline)) uint32_t div_norm(uint32_t u1, uint32_t u0, uint32_t v,
						   uint32_t *rem)
{
	uint32_t q1 = div_digit(u1, u0 >> 16, v);
	/* What is left, below v: exact modulo 2^32. */
	uint32_t u = (u1 << 16) + (u0 >> 16) - q1 * v;
	uint32_t q0 = div_digit(u, u0 & 0xffffu, v);
	*rem = (u << 16) + (u0 & 0xffffu) - q0 * v;
	return (q1 << 16) | q0;
}

uint64_t board_udivmod64(uint64_t n, uint64_t d, uint64_t *rem)
{
	uint32_t n1 = (uint32_t)(n >> 32), n0 = (uint32_t)n, d1 = (uint32_t)(d >> 32);
	uint32_t d0 = (uint32_t)d, r;
	uint64_t q, rr;
	if (d1 == 0 && (n1 == 0 || d0 == 0)) {
		q = d0 ? n0 / d0 : 0; /* the core's own (by 0: 0, as its udiv) */
		rr = n0 - (uint32_t)q * d0;
	} else if (d1 == 0) {
		/* The high word on its own, then (its remainder : n0), both
		 * shifted left until d0's top bit is set. */
		uint32_t qh = n1 / d0, u1 = n1 - qh * d0;
		int s = __builtin_clz(d0);
		uint32_t hi = s ? (u1 << s) | (n0 >> (32 - s)) : u1;
		q = ((uint64_t)qh << 32) | div_norm(hi, n0 << s, d0 << s, &r);
		rr = r >> s;
	} else if (d > n) {
		q = 0;
		rr = n;
	} else {
		/* d >= 2^32: the quotient fits 32 bits. Dividing n / 2 by d's
		 * top 32 bits (normalised) and scaling back gives q or q + 1;
		 * one less is q - 1 or q, and one comparison settles it. */
		int s = __builtin_clz(d1);
		uint32_t v = (uint32_t)((d << s) >> 32);
		uint64_t h = n >> 1;
		uint32_t e = div_norm((uint32_t)(h >> 32), (uint32_t)h, v, &r) >> (31 - s);
		if (e)
			e--;
		rr = n - e * d;
		if (rr >= d) {
			e++;
			rr -= d;
		}
		q = e;
	}
	if (rem)
		*rem = rr;
	return q;
}

#if defined(__arm__) && defined(__ARM_FEATURE_IDIV)
/* The library's name and contract (uint64_t is unsigned long long here).
 * A core without a divide instruction (ARMv6-M) keeps the library's: each
 * 32-bit division would be a call of its own. */
unsigned long long __udivmoddi4(unsigned long long n, unsigned long long d, unsigned long long *rem)
    __attribute__((alias("board_udivmod64")));

/* The run-time ABI's entries the compiler calls for / and % on 64-bit
 * operands (n in r0:r1, d in r2:r3; quotient back in r0:r1, remainder in
 * r2:r3, which C cannot return): the remainder through a slot on the
 * stack, the signed one on magnitudes, the quotient negative when the
 * signs differ, the remainder with the numerator's sign. 0.2 KiB less than
 * the library's. A negation of hi:lo is negs lo; sbc hi, hi, hi, lsl #1. */
void __aeabi_uldivmod(void);
void __aeabi_ldivmod(void);
__attribute__((naked, used)) void __aeabi_uldivmod(void)
{
	__asm volatile("push	{r4, lr}\n"
		       "sub	sp, sp, #16\n"
		       "add	r4, sp, #8\n"
		       "str	r4, [sp]\n"
		       "bl	board_udivmod64\n"
		       "ldrd	r2, r3, [sp, #8]\n"
		       "add	sp, sp, #16\n"
		       "pop	{r4, pc}\n");
}

__attribute__((naked, used)) void __aeabi_ldivmod(void)
{
	__asm volatile("push	{r4, r5, r6, lr}\n"
		       "sub	sp, sp, #16\n"
		       "eor	r4, r1, r3\n"
		       "mov	r5, r1\n"
		       "cmp	r1, #0\n"
		       "bge	1f\n"
		       "negs	r0, r0\n"
		       "sbc	r1, r1, r1, lsl #1\n"
		       "1: cmp	r3, #0\n"
		       "bge	2f\n"
		       "negs	r2, r2\n"
		       "sbc	r3, r3, r3, lsl #1\n"
		       "2: add	r6, sp, #8\n"
		       "str	r6, [sp]\n"
		       "bl	board_udivmod64\n"
		       "ldrd	r2, r3, [sp, #8]\n"
		       "cmp	r4, #0\n"
		       "bge	3f\n"
		       "negs	r0, r0\n"
		       "sbc	r1, r1, r1, lsl #1\n"
		       "3: cmp	r5, #0\n"
		       "bge	4f\n"
		       "negs	r2, r2\n"
		       "sbc	r3, r3, r3, lsl #1\n"
		       "4: add	sp, sp, #16\n"
		       "pop	{r4, r5, r6, pc}\n");
}
#endif
