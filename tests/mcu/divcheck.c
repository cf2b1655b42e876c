/* The Cortex-M4 image's 64-bit division (hal/cortexm/udivmod64.c: the
 * run-time ABI's __aeabi_uldivmod and __aeabi_ldivmod, and __udivmoddi4)
 * on QEMU's mps2-an386, against a bitwise restoring division written here:
 * / and % on operands of every pair of bit lengths, both signs, and the
 * edges. Ends through semihosting: status 0 when every result matched
 * (tests/mcu/mcu_test.py, c_div_check). */
#include <stdint.h>

/* hal/cortexm/semihost.c: the semihosting exit. */
void _exit(int code);

static uint64_t rng = 0x9e3779b97f4a7c15u;

static uint64_t next(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return rng;
}

/* One quotient bit a step, no division at all. */
static uint64_t ref_div(uint64_t n, uint64_t d, uint64_t *rem)
{
	uint64_t q = 0, r = 0;
	for (int b = 63; b >= 0; b--) {
		r = (r << 1) | ((n >> b) & 1u);
		if (r >= d) {
			r -= d;
			q |= (uint64_t)1 << b;
		}
	}
	*rem = r;
	return q;
}

/* Through volatiles: the compiler must call the entries, not fold. */
static int check(uint64_t n, uint64_t d)
{
	volatile uint64_t vn = n, vd = d;
	uint64_t r, q = ref_div(n, d, &r);
	if (vn / vd != q || vn % vd != r)
		return 1;
	/* Signed, C's rules: the quotient towards zero, the remainder with
	 * the numerator's sign. INT64_MIN stays out (its magnitude does not
	 * fit). */
	int64_t sn = (int64_t)(n >> 1), sd = (int64_t)(d >> 1);
	if (sd == 0)
		return 0;
	for (int s = 0; s < 4; s++) {
		int64_t a = s & 1 ? -sn : sn, b = s & 2 ? -sd : sd;
		volatile int64_t va = a, vb = b;
		uint64_t sr, sq = ref_div((uint64_t)sn, (uint64_t)sd, &sr);
		int64_t eq = (s == 1 || s == 2) ? -(int64_t)sq : (int64_t)sq;
		int64_t er = s & 1 ? -(int64_t)sr : (int64_t)sr;
		if (va / vb != eq || va % vb != er)
			return 1;
	}
	return 0;
}

int main(void)
{
	static const uint64_t edge[][2] = {
	    {UINT64_MAX, 1},
	    {UINT64_MAX, 0xffffffffu},
	    {UINT64_MAX, 0x100000000u},
	    {UINT64_MAX, UINT64_MAX},
	    {0, 7},
	    {0xffffffffu, 0x100000000u},
	    {0x100000000u, 3},
	    {0x7fff800000000000u, 0x8000ffffu},
	    {UINT64_MAX, 0x100000001u},
	    {0x8000000000000000u, 0x8000000000000001u},
	};
	int bad = 0;
	for (unsigned i = 0; i < sizeof edge / sizeof edge[0]; i++)
		bad |= check(edge[i][0], edge[i][1]);
	for (int bn = 1; bn <= 64; bn++)
		for (int bd = 1; bd <= 64; bd++)
			for (int k = 0; k < 4; k++) {
				uint64_t n = next() >> (64 - bn), d = next() >> (64 - bd);
				n |= (uint64_t)1 << (bn - 1);
				d |= (uint64_t)1 << (bd - 1);
				if (k & 1)
					d |= ((uint64_t)1 << (bd - 1)) - 1;
				bad |= check(n, d);
			}
	_exit(bad);
}
