/* Fixed-point helpers: products without 128-bit types (so the same code
 * runs on a Cortex-M), integer square root, trigonometry. */
#include "fx.h"

q32_t fx_mul_portable(q32_t a, q32_t b)
{
	bool neg = (a < 0) != (b < 0);
	uint64_t ua = a < 0 ? 0u - (uint64_t)a : (uint64_t)a;
	uint64_t ub = b < 0 ? 0u - (uint64_t)b : (uint64_t)b;
	uint64_t ah = ua >> 32, al = ua & 0xffffffffu, bh = ub >> 32, bl = ub & 0xffffffffu;
	uint64_t hh = ah * bh, mid1 = ah * bl, mid2 = al * bh, ll = al * bl;
	/* |a b| / 2^32 = hh 2^32 + mid1 + mid2 + ll / 2^32 */
	if (hh >> 31)
		return neg ? INT64_MIN : INT64_MAX;
	uint64_t r = hh << 32, add = mid1 + mid2;
	if (add < mid1 || r + add < r)
		return neg ? INT64_MIN : INT64_MAX;
	r += add;
	uint64_t low = (ll >> 32) + ((ll >> 31) & 1u);
	/* Half-up on the signed value: an exact negative half rounds toward
	 * zero, one less in magnitude. */
	if (neg && (ll & 0xffffffffu) == 0x80000000u)
		low--;
	if (r + low < r || (r + low) >> 63)
		return neg ? INT64_MIN : INT64_MAX;
	r += low;
	return neg ? -(int64_t)r : (int64_t)r;
}

uint64_t fx_mulhi_u64_portable(uint64_t x, uint64_t y)
{
	uint64_t x0 = (uint32_t)x, x1 = x >> 32, y0 = (uint32_t)y, y1 = y >> 32;
	uint64_t p01 = x0 * y1, p10 = x1 * y0;
	uint64_t mid = ((x0 * y0) >> 32) + (uint32_t)p01 + (uint32_t)p10;
	return x1 * y1 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

/* floor(sqrt(v)) for v < 2^32, by Newton's iteration from 2^ceil(bits / 2):
 * it falls monotonically onto the root in a few steps, each a hardware
 * division on a 32-bit microcontroller. */
static FX_OUTLINE uint32_t isqrt32(uint32_t v)
{
	if (v < 2)
		return v;
	int bits = 32 - __builtin_clz(v);
	uint32_t x = (uint32_t)1 << ((bits + 1) / 2);
	for (;;) {
		uint32_t y = (x + v / x) >> 1;
		if (y >= x)
			return x;
		x = y;
	}
}

uint64_t fx_isqrt64(uint64_t v)
{
	if (v >> 32 == 0)
		return isqrt32((uint32_t)v);
	/* Start from the root of the top 32 or 31 bits, rounded up: at or above
	 * sqrt(v) and within 2^-15 of it, so the same iteration (monotone from
	 * above) ends after one or two 64-bit divisions, not six. */
	int k = (64 - __builtin_clzll(v) - 31) / 2;
	uint64_t x = ((uint64_t)isqrt32((uint32_t)(v >> (2 * k))) + 1) << k;
	for (;;) {
		uint64_t y = (x + v / x) >> 1;
		if (y >= x)
			return x;
		x = y;
	}
}

/* n / d for a divisor below 2^16, in four 32-bit divisions of 16 bits
 * each: the same quotient as the 64-bit division, which on a 32-bit
 * microcontroller is a library call of some 100 instructions. */
FX_OUTLINE uint64_t fx_udiv64_small(uint64_t n, uint32_t d)
{
	uint64_t q = 0;
	uint32_t r = 0;
	for (int sh = 48; sh >= 0; sh -= 16) {
		uint32_t cur = (r << 16) | (uint32_t)((n >> sh) & 0xffffu);
		q = (q << 16) | (cur / d);
		r = cur % d;
	}
	return q;
}

/* The polynomials' Q30 values fit 32 bits (the same bits for every
 * argument they see): where code size counts, each product is one
 * 32 x 32 -> 64-bit multiply, which 64-bit operands make three (176 bytes
 * of flash); a 64-bit host is faster with 64-bit operands. */
#ifdef __OPTIMIZE_SIZE__
typedef int32_t poly_t;
#else
typedef int64_t poly_t;
#endif

static inline poly_t mul_q30_poly(poly_t a, poly_t b)
{
	return (poly_t)(((int64_t)a * b) >> 30);
}

/* Taylor series on |x| <= pi/4 (Q30 radians), Horner form with Q30
 * coefficients: the first omitted terms are below 2e-9 (two Q30 steps). */
static int32_t sin_poly(poly_t x)
{
	poly_t x2 = mul_q30_poly(x, x);
	poly_t p = 2959;		      /* 1/9! */
	p = -213044 + mul_q30_poly(x2, p);    /* -1/7! */
	p = 8947849 + mul_q30_poly(x2, p);    /* 1/5! */
	p = -178956971 + mul_q30_poly(x2, p); /* -1/3! */
	p = FX_Q30_ONE + mul_q30_poly(x2, p);
	return (int32_t)mul_q30_poly(x, p);
}

static int32_t cos_poly(poly_t x)
{
	poly_t x2 = mul_q30_poly(x, x);
	poly_t p = -296;		      /* -1/10! */
	p = 26630 + mul_q30_poly(x2, p);      /* 1/8! */
	p = -1491308 + mul_q30_poly(x2, p);   /* -1/6! */
	p = 44739243 + mul_q30_poly(x2, p);   /* 1/4! */
	p = -536870912 + mul_q30_poly(x2, p); /* -1/2! */
	return (int32_t)(FX_Q30_ONE + mul_q30_poly(x2, p));
}

#define HALF_PI_Q30 1686629713LL /* pi/2 * 2^30 */

/* sin over the first quadrant; r is the Q30 fraction of a quarter turn. */
static int32_t sin_quadrant(uint32_t r)
{
	if (r <= (1u << 29))
		return sin_poly((poly_t)(((int64_t)r * HALF_PI_Q30) >> 30));
	return cos_poly((poly_t)(((int64_t)((1u << 30) - r) * HALF_PI_Q30) >> 30));
}

int32_t fx_sin_bam(uint32_t bam)
{
	uint32_t quadrant = bam >> 30, r = bam & 0x3fffffffu;
	switch (quadrant) {
	case 0:
		return sin_quadrant(r);
	case 1:
		return sin_quadrant((1u << 30) - r);
	case 2:
		return -sin_quadrant(r);
	default:
		return -sin_quadrant((1u << 30) - r);
	}
}

int32_t fx_cos_bam(uint32_t bam)
{
	return fx_sin_bam(bam + (1u << 30));
}

void fx_sincos_bam(uint32_t bam, int32_t *s, int32_t *c)
{
	/* One reduction for both: the octant picks which polynomial gives
	 * which function, the quadrant gives the signs. */
	uint32_t quadrant = bam >> 30, r = bam & 0x3fffffffu;
	int32_t s0, c0;
	if (r <= (1u << 29)) {
		poly_t x = (poly_t)(((int64_t)r * HALF_PI_Q30) >> 30);
		s0 = sin_poly(x);
		c0 = cos_poly(x);
	} else {
		poly_t x = (poly_t)(((int64_t)((1u << 30) - r) * HALF_PI_Q30) >> 30);
		s0 = cos_poly(x);
		c0 = sin_poly(x);
	}
	switch (quadrant) {
	case 0:
		*s = s0;
		*c = c0;
		break;
	case 1:
		*s = c0;
		*c = -s0;
		break;
	case 2:
		*s = -s0;
		*c = -c0;
		break;
	default:
		*s = -c0;
		*c = s0;
		break;
	}
}

q32_t fx_wrap_deg_any(q32_t deg)
{
	/* The remainder has the sign of deg and is under a turn: no overflow
	 * for any input. */
	q32_t r = deg % FX_DEG_360;
	if (r >= FX_DEG_180)
		r -= FX_DEG_360;
	else if (r < -FX_DEG_180)
		r += FX_DEG_360;
	return r;
}

/* atan(2^-i) in Q32 degrees. */
#define CORDIC_ATAN_DEG(X)                                                                         \
	X(193273528320), X(114096026022), X(60285206653), X(30601712202), X(15360239180),          \
	    X(7687607525), X(3844741810), X(1922488225), X(961258780), X(480631223), X(240315841), \
	    X(120157949), X(60078978), X(30039490), X(15019745), X(7509872), X(3754936),           \
	    X(1877468), X(938734), X(469367), X(234684), X(117342), X(58671), X(29335), X(14668),  \
	    X(7334), X(3667), X(1833), X(917), X(458), X(229), X(115)
#ifdef __OPTIMIZE_SIZE__
/* Where code size counts, the low 32 bits and the byte above them: 96
 * bytes of flash less than 64-bit entries. */
#define ATAN_LO(v) (uint32_t)(v)
#define ATAN_HI(v) (uint8_t)((int64_t)(v) >> 32)
static const uint32_t cordic_atan_lo[32] = {CORDIC_ATAN_DEG(ATAN_LO)};
static const uint8_t cordic_atan_hi[32] = {CORDIC_ATAN_DEG(ATAN_HI)};
#define CORDIC_ATAN(i) ((int64_t)((uint64_t)cordic_atan_hi[i] << 32 | cordic_atan_lo[i]))
#else
#define ATAN_ALL(v)    (v)
static const int64_t cordic_atan_deg[32] = {CORDIC_ATAN_DEG(ATAN_ALL)};
#define CORDIC_ATAN(i) cordic_atan_deg[i]
#endif

q32_t fx_atan2_deg(int64_t y, int64_t x)
{
	/* The axes exactly: CORDIC would leave a residue of a few raw units. */
	if (y == 0)
		return x >= 0 ? 0 : -FX_DEG_180;
	if (x == 0)
		return y > 0 ? fx_from_int(90) : -fx_from_int(90);
	/* Scale into +-2^60 so the CORDIC additions cannot overflow, then
	 * rotate into the right half plane. */
	while (fx_abs64(x) > ((int64_t)1 << 60) || fx_abs64(y) > ((int64_t)1 << 60)) {
		x >>= 1;
		y >>= 1;
	}
	while (fx_abs64(x) < ((int64_t)1 << 40) && fx_abs64(y) < ((int64_t)1 << 40)) {
		x *= 2;
		y *= 2;
	}
	q32_t angle = 0;
	if (x < 0) {
		/* rotate by 180 degrees */
		x = -x;
		y = -y;
		angle = FX_DEG_180;
	}
	for (int i = 0; i < 32; i++) {
		int64_t xs = x >> i, ys = y >> i;
		if (y > 0) {
			x += ys;
			y -= xs;
			angle += CORDIC_ATAN(i);
		} else {
			x -= ys;
			y += xs;
			angle -= CORDIC_ATAN(i);
		}
	}
	return fx_wrap_deg(angle);
}

q32_t fx_hypot(q32_t x, q32_t y)
{
	uint64_t ax = (uint64_t)fx_abs64(x), ay = (uint64_t)fx_abs64(y);
	uint64_t m = ax | ay;
	if (m == 0)
		return 0;
	/* Normalise so the larger component has 31 significant bits (its
	 * square sum fits in 64), scaling small vectors up by at most 2^16. */
	int shift = 33 - __builtin_clzll(m); /* bit length - 31 */
	if (shift < -16)
		shift = -16;
	if (shift > 0) {
		ax >>= shift;
		ay >>= shift;
	} else {
		ax <<= -shift;
		ay <<= -shift;
	}
	uint64_t r = fx_isqrt64(ax * ax + ay * ay);
	return shift >= 0 ? (q32_t)(r << shift) : (q32_t)(r >> -shift);
}

q32_t fx_div(q32_t a, q32_t b)
{
	/* Magnitudes in unsigned arithmetic: |INT64_MIN| is 2^63, not UB. */
	uint64_t ua = a < 0 ? 0u - (uint64_t)a : (uint64_t)a;
	uint64_t ub = b < 0 ? 0u - (uint64_t)b : (uint64_t)b;
	if (ub == 0)
		return a >= 0 ? INT64_MAX : INT64_MIN;
	bool neg = (a < 0) != (b < 0);
	uint64_t q = ua / ub, r = ua % ub;
	if (q >> 31)
		return neg ? INT64_MIN : INT64_MAX;
	/* The 32 fraction bits by long division, as many bits per step as the
	 * remainder can be shifted without overflow (r < ub, so clz(ub) bits):
	 * one hardware division for a divisor below 2^32, two or three for the
	 * lengths of a floor. The bits are those of the bitwise long division. */
	uint64_t res = q << 32;
	int k = __builtin_clzll(ub);
	if (k == 0)
		k = 1; /* ub = 2^63: r < 2^63 still shifts by one */
	for (int left = 32; left > 0;) {
		int n = k < left ? k : left;
		r <<= n;
		left -= n;
		res |= (r / ub) << left;
		r %= ub;
	}
	return neg ? -(int64_t)res : (int64_t)res;
}
