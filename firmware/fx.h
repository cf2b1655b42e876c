/* Fixed-point arithmetic for the motion core.
 *
 * One format serves every linear and angular quantity: Q32.32 in an int64_t
 * (value = raw / 2^32). Lengths are millimetres (_mm), angles are degrees
 * (_deg); per-tick rates carry _pt (per tick) or _pt2 (per tick squared).
 * At 1 kHz, 1 mm/s^2 is 1e-6 mm/tick^2 = 4295 raw units, so the coarsest
 * acceleration a user can set is still resolved to 0.03 %. The integer range
 * (+-2^31 mm = +-2147 km) covers any floor a base drives on.
 *
 * Trigonometry uses a 32-bit binary angle (2^32 = one turn) so wrap-around
 * is free, and returns Q30 in an int32_t.
 */
#ifndef FX_H
#define FX_H

#include <stdbool.h>
#include <stdint.h>

typedef int64_t q32_t;

#define FX_SHIFT   32
#define FX_ONE	   ((q32_t)1 << FX_SHIFT)
#define FX_Q30_ONE ((int32_t)1 << 30)
#define FX_DEG_180 ((q32_t)180 << FX_SHIFT)
#define FX_DEG_360 ((q32_t)360 << FX_SHIFT)

/* A pose in the world frame (Q32 mm and degrees). */
typedef struct {
	q32_t x_mm, y_mm, th_deg; /* th wrapped to [-180, 180) */
} fx_pose_t;

/* Body-frame velocity for one tick: mm/tick and deg/tick, Q32. */
typedef struct {
	q32_t vx_pt, vy_pt, w_pt;
} fx_twist_t;

/* Integer part to Q32. */
static inline q32_t fx_from_int(int32_t v)
{
	return (q32_t)((uint64_t)(int64_t)v << FX_SHIFT);
}

/* (a << 32) / b, rounded toward zero, saturating. */
q32_t fx_div(q32_t a, q32_t b);
/* Floor of the square root of a 64-bit unsigned value. */
uint64_t fx_isqrt64(uint64_t v);
/* n / d for 0 < d < 2^16 (fx.c: cheap where 64-bit division is a call). */
uint64_t fx_udiv64_small(uint64_t n, uint32_t d);

/* A small helper: inline for speed, but out of line where code size counts
 * (-Os, a board): on a 32-bit core each inlined copy of its 64-bit
 * arithmetic costs more flash than a call (1.7 KiB in all, docs/mcu.md). */
#ifdef __OPTIMIZE_SIZE__
#define FX_HELPER static __attribute__((noinline, unused))
#else
#define FX_HELPER static inline
#endif

/* An external function's copies inlined where it is called cost more flash
 * than the calls: out of line where code size counts. */
#ifdef __OPTIMIZE_SIZE__
#define FX_OUTLINE __attribute__((noinline))
#else
#define FX_OUTLINE
#endif

/* n / d for n >= 0, d > 0. On a 32-bit core a 64-bit division is a library
 * call of some 100 instructions; when both fit 32 bits, the core divides. */
FX_HELPER int64_t fx_div_nn(int64_t n, int64_t d)
{
#if SIZE_MAX <= UINT32_MAX
	if (((uint64_t)n | (uint64_t)d) >> 32 == 0)
		return (int64_t)((uint32_t)n / (uint32_t)d);
#endif
	return n / d;
}

/* Sine and cosine of a binary angle (2^32 per turn), Q30 result.
 * Absolute error below 2e-9 (about 2 LSB of Q30). */
int32_t fx_sin_bam(uint32_t bam);
int32_t fx_cos_bam(uint32_t bam);
/* Both at once (one reduction); identical to the two calls. */
void fx_sincos_bam(uint32_t bam, int32_t *s, int32_t *c);

/* atan2(y, x) as Q32 degrees in [-180, 180). y and x in any common scale. */
q32_t fx_atan2_deg(int64_t y, int64_t x);

/* Euclidean length of (x, y), both Q32; result Q32. */
q32_t fx_hypot(q32_t x, q32_t y);

FX_HELPER int64_t fx_abs64(int64_t v)
{
	return v < 0 ? -v : v;
}
FX_HELPER int64_t fx_min64(int64_t a, int64_t b)
{
	return a < b ? a : b;
}
FX_HELPER int64_t fx_max64(int64_t a, int64_t b)
{
	return a > b ? a : b;
}
static inline int64_t fx_clamp64(int64_t v, int64_t lo, int64_t hi)
{
	return v < lo ? lo : (v > hi ? hi : v);
}

/* The hot helpers are inline: the control tick calls them dozens of times. */

/* (a * b) >> 30 for a Q32 (or any int64) and a Q30 factor, rounded to nearest;
 * without 128-bit integers two 32x32->64 products (cheap on a Cortex-M4). */
static inline int64_t fx_mul_q30(int64_t a, int32_t b_q30)
{
#ifdef __SIZEOF_INT128__
	/* The same bits as the split form below: hi b 2^32 is a multiple of 2^30. */
	return (int64_t)(((__int128)a * b_q30 + ((__int128)1 << 29)) >> 30);
#else
	/* a = hi * 2^32 + lo, lo unsigned; each partial product fits in 64 bits. */
	int64_t hi = a >> 32;
	int64_t lo = (int64_t)(uint32_t)(uint64_t)a;
	int64_t p_hi = hi * b_q30;
	int64_t p_lo = lo * b_q30;
	return p_hi * 4 + ((p_lo + ((int64_t)1 << 29)) >> 30);
#endif
}

/* (x, y) turned by the angle whose Q30 cosine and sine are c and s:
 * (x c - y s, x s + y c). Every rotation of the engine in one copy where
 * code size counts. */
FX_HELPER void fx_rot_q30(int64_t x, int64_t y, int32_t c, int32_t s, int64_t *rx, int64_t *ry)
{
	*rx = fx_mul_q30(x, c) - fx_mul_q30(y, s);
	*ry = fx_mul_q30(x, s) + fx_mul_q30(y, c);
}

/* floor(a * b / 2^32 + 1/2), saturating: the portable form, and the one a
 * build without 128-bit integers (a Cortex-M) uses out of line. */
q32_t fx_mul_portable(q32_t a, q32_t b);

/* (a * b) >> 32 for two Q32 values, rounded to nearest; saturates on overflow. */
static inline q32_t fx_mul(q32_t a, q32_t b)
{
	/* Both forms give the same bits, so a recorded run replays identically
	 * on the MCU and the host (tests/test_fx.c compares them). */
#ifdef __SIZEOF_INT128__
	__int128 p = ((__int128)a * b + ((__int128)1 << 31)) >> 32;
	if (p > INT64_MAX)
		return INT64_MAX;
	if (p < INT64_MIN)
		return INT64_MIN;
	return (q32_t)p;
#else
	return fx_mul_portable(a, b);
#endif
}

/* The high half of a 64 x 64-bit product; the portable form is what a
 * target without 128-bit arithmetic runs (tests/test_fx.c compares them). */
uint64_t fx_mulhi_u64_portable(uint64_t x, uint64_t y);
static inline uint64_t fx_mulhi_u64(uint64_t x, uint64_t y)
{
#ifdef __SIZEOF_INT128__
	return (uint64_t)(((unsigned __int128)x * y) >> 64);
#else
	return fx_mulhi_u64_portable(x, y);
#endif
}

/* fx_mul for products the caller knows to fit in 64 bits: the same bits,
 * without the saturation checks (per-tick quantities bounded by the
 * configured limits). */
static inline q32_t fx_mul_fit(q32_t a, q32_t b)
{
#ifdef __SIZEOF_INT128__
	return (q32_t)(((__int128)a * b + ((__int128)1 << 31)) >> 32);
#else
	return fx_mul_portable(a, b);
#endif
}

/* fx_wrap_deg more than a turn out of range (a division). */
q32_t fx_wrap_deg_any(q32_t deg);

/* Wrap a Q32 angle in degrees into [-180, 180). */
static inline q32_t fx_wrap_deg(q32_t deg)
{
	if (deg >= -FX_DEG_180 && deg < FX_DEG_180)
		return deg;
	/* A sum of two wrapped angles is at most a turn out: no division. */
	if (deg >= FX_DEG_180 && deg < FX_DEG_180 + FX_DEG_360)
		return deg - FX_DEG_360;
	if (deg < -FX_DEG_180 && deg >= -FX_DEG_180 - FX_DEG_360)
		return deg + FX_DEG_360;
	return fx_wrap_deg_any(deg);
}

/* Degrees (Q32) to binary angle, modulo one turn. */
static inline uint32_t fx_deg_to_bam(q32_t deg)
{
	q32_t w = fx_wrap_deg(deg);
	/* deg * 2^32 / 360 in Q32 degrees is w / 360, rounded. */
	int64_t b = (w >= 0 ? w + 180 : w - 180) / 360;
	return (uint32_t)(int32_t)b;
}

/* The last angle's sine and cosine: a heading that holds still (a straight
 * line) costs a comparison instead of an evaluation. */
typedef struct {
	uint32_t bam;
	int32_t s, c;
	bool valid;
} fx_trig_cache_t;

static inline void fx_sincos_cached(fx_trig_cache_t *tc, uint32_t bam, int32_t *s, int32_t *c)
{
	if (!tc->valid || tc->bam != bam) {
		fx_sincos_bam(bam, &tc->s, &tc->c);
		tc->bam = bam;
		tc->valid = true;
	}
	*s = tc->s;
	*c = tc->c;
}

#endif
