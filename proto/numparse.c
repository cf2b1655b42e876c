/* Strict number and boolean parsing for the console, and its number
 * formatting (see numparse.h). No libc number conversion: the same code runs
 * on the host and on the MCU, where strtod and printf's %f would cost more
 * flash than the rest of the console. */
#include "numparse.h"

#include <string.h>

#define NP_2P53 (UINT64_C(1) << 53)

/* Exponents are saturated here: far beyond any representable double or
 * integer, and small enough that digit counts added to it never overflow. */
#define NP_EXP_SAT 100000L

typedef struct {
	bool neg;
	const char *ip; /* integer digits */
	long in;
	const char *fp; /* fraction digits */
	long fn;
	long exp;
} np_dec_t;

static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

/* Validates the whole string against the grammar and splits it. */
static bool np_scan(const char *s, np_dec_t *d)
{
	const char *p = s;

	d->neg = false;
	d->exp = 0;
	if (*p == '+' || *p == '-')
		d->neg = *p++ == '-';
	d->ip = p;
	while (is_digit(*p))
		p++;
	d->in = (long)(p - d->ip);
	d->fp = p;
	d->fn = 0;
	if (*p == '.') {
		d->fp = ++p;
		while (is_digit(*p))
			p++;
		d->fn = (long)(p - d->fp);
	}
	if (d->in == 0 && d->fn == 0)
		return false;
	if (*p == 'e' || *p == 'E') {
		bool eneg = false;
		long e = 0;

		p++;
		if (*p == '+' || *p == '-')
			eneg = *p++ == '-';
		if (!is_digit(*p))
			return false;
		while (is_digit(*p)) {
			if (e < NP_EXP_SAT)
				e = e * 10 + (*p - '0');
			p++;
		}
		if (e > NP_EXP_SAT)
			e = NP_EXP_SAT;
		d->exp = eneg ? -e : e;
	}
	return *p == '\0';
}

/* Digit k of the concatenated integer and fraction digits. */
static int dec_digit(const np_dec_t *d, long k)
{
	return k < d->in ? d->ip[k] - '0' : d->fp[k - d->in] - '0';
}

/* value = *w * 10^e10: w the first (up to) 19 significant digits, e10 the
 * scale (digits after the 19th only lower the precision, not the scale);
 * returns the count of significant digits, those beyond w included. */
static long dec_value(const np_dec_t *d, uint64_t *w, long *e10)
{
	long n = d->in + d->fn, first, used;

	for (first = 0; first < n && dec_digit(d, first) == 0; first++)
		;
	used = n - first > 19 ? 19 : n - first;
	*w = 0;
	for (long k = first; k < first + used; k++)
		*w = *w * 10u + (uint64_t)dec_digit(d, k);
	*e10 = d->exp - d->fn + (n - first - used);
	return n - first;
}

#ifndef VS_REAL_Q32
/* 10^0 .. 10^22: every one is exactly a double. */
static const double pow10_exact[23] = {
    1e0,  1e1,	1e2,  1e3,  1e4,  1e5,	1e6,  1e7,  1e8,  1e9,	1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

static bool np_finite(double v)
{
	uint64_t b;

	memcpy(&b, &v, sizeof(b));
	return ((b >> 52) & 0x7ffu) != 0x7ffu;
}

np_result_t np_parse_double(const char *s, double *out)
{
	np_dec_t d;
	long e10, sig;
	uint64_t w;
	double v;

	if (!np_scan(s, &d))
		return NP_SYNTAX;
	sig = dec_value(&d, &w, &e10);
	if (w == 0) {
		v = 0.0;
	} else if (w <= NP_2P53 && e10 >= -22 && e10 <= 22 && sig <= 19) {
		/* Both operands exact: one correctly rounded operation. */
		v = (double)w;
		v = e10 < 0 ? v / pow10_exact[-e10] : v * pow10_exact[e10];
	} else {
		/* Outside the exact range (more than 15-16 significant digits,
		 * or |exponent| > 22): a few roundings in a row, within a few
		 * units in the last place, and rounded to zero or infinity at
		 * the ends of the range. */
		v = (double)w;
		while (e10 > 0 && np_finite(v)) {
			long step = e10 > 22 ? 22 : e10;

			v *= pow10_exact[step];
			e10 -= step;
		}
		while (e10 < 0 && v != 0.0) {
			long step = -e10 > 22 ? 22 : -e10;

			v /= pow10_exact[step];
			e10 += step;
		}
	}
	if (!np_finite(v))
		return NP_SYNTAX;
	*out = d.neg ? -v : v;
	return NP_OK;
}

#endif /* VS_REAL_Q32 */

np_result_t np_parse_int(const char *s, int64_t min, int64_t max, int64_t *out)
{
	np_dec_t d;
	long n, first, scale, keep, k;
	uint64_t mag = 0;

	if (!np_scan(s, &d))
		return NP_SYNTAX;
	/* value = digits * 10^scale, digits without leading zeros. */
	n = d.in + d.fn;
	for (first = 0; first < n && dec_digit(&d, first) == 0; first++)
		;
	scale = d.exp - d.fn;
	if (first < n) {
		keep = n - first;
		if (scale < 0) {
			/* The dropped digits must all be zero. */
			if (-scale >= keep)
				return NP_RANGE;
			for (k = n + scale; k < n; k++)
				if (dec_digit(&d, k) != 0)
					return NP_RANGE;
			keep += scale;
			n += scale;
			scale = 0;
		}
		/* 19 digits always fit in a uint64_t; anything longer is far
		 * outside every IDL integer type. */
		if (keep + scale > 19)
			return NP_RANGE;
		for (k = first; k < n; k++)
			mag = mag * 10u + (uint64_t)dec_digit(&d, k);
		for (k = 0; k < scale; k++)
			mag *= 10u;
	}
	if (d.neg) {
		if (mag > (uint64_t)INT64_MAX || -(int64_t)mag < min)
			return NP_RANGE;
		*out = -(int64_t)mag;
	} else {
		if (mag > (uint64_t)INT64_MAX || (int64_t)mag > max)
			return NP_RANGE;
		*out = (int64_t)mag;
	}
	return NP_OK;
}

static char lower(char c)
{
	return (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c;
}

int np_cmp_nocase(const char *a, const char *b)
{
	while (*a && lower(*a) == lower(*b)) {
		a++;
		b++;
	}
	return (unsigned char)lower(*a) - (unsigned char)lower(*b);
}

bool np_streq_nocase(const char *a, const char *b)
{
	return np_cmp_nocase(a, b) == 0;
}

bool np_parse_bool(const char *s, bool *out)
{
	static const char *const yes[] = {"true", "1", "on"};
	static const char *const no[] = {"false", "0", "off"};

	for (unsigned i = 0; i < 3; i++) {
		if (np_streq_nocase(s, yes[i])) {
			*out = true;
			return true;
		}
		if (np_streq_nocase(s, no[i])) {
			*out = false;
			return true;
		}
	}
	return false;
}

/* Writes v's decimal digits backwards ending at end; returns the start. */
static char *put_u64_rev(char *end, uint64_t v)
{
	do {
		*--end = (char)('0' + v % 10u);
		v /= 10u;
	} while (v);
	return end;
}

size_t np_fmt_u64(uint64_t v, char *buf)
{
	char tmp[NP_INT_MAX];
	char *p = put_u64_rev(tmp + sizeof(tmp), v);
	size_t n = (size_t)(tmp + sizeof(tmp) - p);

	memcpy(buf, p, n);
	buf[n] = '\0';
	return n;
}

size_t np_fmt_i64(int64_t v, char *buf)
{
	if (v >= 0)
		return np_fmt_u64((uint64_t)v, buf);
	buf[0] = '-';
	return 1 + np_fmt_u64(-(uint64_t)v, buf + 1);
}

#ifndef VS_REAL_Q32
/* An integer m * 2^e2 of up to 309 digits, exactly: base 10^9 limbs. */
static size_t fmt_big(uint64_t m, int e2, char *buf)
{
	uint32_t limb[35];
	size_t nl = 0, n;

	while (m) {
		limb[nl++] = (uint32_t)(m % 1000000000u);
		m /= 1000000000u;
	}
	while (e2 > 0) {
		int s = e2 > 32 ? 32 : e2;
		uint64_t carry = 0;

		for (size_t i = 0; i < nl; i++) {
			uint64_t t = ((uint64_t)limb[i] << s) + carry;

			limb[i] = (uint32_t)(t % 1000000000u);
			carry = t / 1000000000u;
		}
		while (carry) {
			limb[nl++] = (uint32_t)(carry % 1000000000u);
			carry /= 1000000000u;
		}
		e2 -= s;
	}
	n = np_fmt_u64(limb[nl - 1], buf);
	for (size_t i = nl - 1; i-- > 0;) {
		uint32_t l = limb[i];

		for (int k = 8; k >= 0; k--) {
			buf[n + (size_t)k] = (char)('0' + l % 10u);
			l /= 10u;
		}
		n += 9;
	}
	return n;
}

size_t np_fmt_fixed3(double v, char *buf)
{
	uint64_t b, m, q = 0;
	int ex, e2;
	size_t n = 0;

	memcpy(&b, &v, sizeof(b));
	ex = (int)((b >> 52) & 0x7ffu);
	m = b & (NP_2P53 / 2u - 1u);
	if (b >> 63)
		buf[n++] = '-';
	if (ex == 0x7ff) {
		memcpy(buf + n, m ? "nan" : "inf", 4);
		return n + 3;
	}
	/* v = m * 2^e2 exactly */
	if (ex)
		m |= NP_2P53 / 2u;
	e2 = (ex ? ex : 1) - 1075;
	if (e2 > 10) {
		n += fmt_big(m, e2, buf + n);
		memcpy(buf + n, ".000", 5);
		return n + 4;
	}
	if (e2 >= 0) {
		/* an integer below 2^63 */
		n += np_fmt_u64(m << e2, buf + n);
		memcpy(buf + n, ".000", 5);
		return n + 4;
	}
	if (e2 > -64) {
		/* m * 1000 < 2^63: thousandths, rounded to nearest, ties to
		 * even (the rounding of printf's "%.3f"). */
		unsigned k = (unsigned)-e2;
		uint64_t t = m * 1000u, r = t & ((UINT64_C(1) << k) - 1u);
		uint64_t half = UINT64_C(1) << (k - 1u);

		q = t >> k;
		if (r > half || (r == half && (q & 1u)))
			q++;
	}
	/* else below 2^-64 * 2^63: less than half a thousandth, q = 0 */
	n += np_fmt_u64(q / 1000u, buf + n);
	buf[n++] = '.';
	buf[n++] = (char)('0' + q / 100u % 10u);
	buf[n++] = (char)('0' + q / 10u % 10u);
	buf[n++] = (char)('0' + q % 10u);
	buf[n] = '\0';
	return n;
}
#endif /* VS_REAL_Q32 */

/* ---- Q32.32 (real.h) --------------------------------------------------- */

#define Q32_SAT INT64_MAX
#define Q32_NAN INT64_MIN

/* The first 19 significant digits of DBL_MAX (1.797...e308): a decimal
 * above it is rejected as the double parser rejects it. */
#define DBL_MAX_19 UINT64_C(1797693134862315708)

/* round(w / 10^k * 2^32), half away from zero, saturating. As
 * w * 2^(32 - k) / 5^k: 5^27 still fits 64 bits, so up to 27 decimals the
 * rounding is exact; beyond, the value is below 10^-8 and the dropped digits
 * weigh under 10^-27. */
static int64_t q32_of_ratio(uint64_t w, long k)
{
	uint64_t d = 1u, q, r, f = 0;

	for (; k > 27; k--)
		w /= 10u;
	for (long i = 0; i < k; i++)
		d *= 5u;
	q = w / d;
	r = w % d;
	if (q >> (31 + k))
		return Q32_SAT;
	/* 32 - k fraction bits by binary long division: r < d < 2^63. */
	for (long i = k; i < 32; i++) {
		r <<= 1;
		f <<= 1;
		if (r >= d) {
			r -= d;
			f |= 1u;
		}
	}
	q = (q << (32 - k)) + f;
	if (r >= d - r) /* at least half: away from zero */
		q++;
	return q >> 63 ? Q32_SAT : (int64_t)q;
}

np_result_t np_parse_q32(const char *s, int64_t *out)
{
	np_dec_t d;
	long e10, sig;
	uint64_t w, w19;
	int64_t v;

	if (!np_scan(s, &d))
		return NP_SYNTAX;
	sig = dec_value(&d, &w, &e10);
	if (w == 0) {
		*out = 0;
		return NP_OK;
	}
	/* Beyond a double's range: junk, as for np_parse_double. The
	 * magnitude is 10^(digits of w - 1 + e10). */
	long used = sig > 19 ? 19 : sig;
	long mag = used - 1 + e10;
	w19 = w;
	for (long k = used; k < 19; k++)
		w19 *= 10u;
	if (mag > 308 || (mag == 308 && w19 > DBL_MAX_19))
		return NP_SYNTAX;
	if (e10 >= 0) {
		/* An integer: 2^31 or more saturates. */
		v = Q32_SAT;
		if (e10 <= 9) {
			uint64_t x = w;

			for (long k = 0; k < e10 && x < (UINT64_C(1) << 31); k++)
				x *= 10u;
			if (x < (UINT64_C(1) << 31))
				v = (int64_t)(x << 32);
		}
	} else {
		v = q32_of_ratio(w, -e10);
	}
	*out = d.neg ? -v : v;
	return NP_OK;
}

size_t np_fmt_q32_fixed3(int64_t v, char *buf)
{
	uint64_t m = v < 0 ? 0u - (uint64_t)v : (uint64_t)v, t = (m & 0xffffffffu) * 1000u;
	uint32_t ip = (uint32_t)(m >> 32), f = (uint32_t)(t >> 32), r = (uint32_t)t;
	size_t n = 0;

	if (v == Q32_NAN) {
		memcpy(buf, "nan", 4);
		return 3;
	}
	if (v < 0)
		buf[n++] = '-';
	/* Thousandths rounded to nearest, ties to even (1000 is even: the
	 * parity is f's), as "%.3f" rounds the same value as a double. */
	if (r > 0x80000000u || (r == 0x80000000u && (f & 1u)))
		f++;
	if (f == 1000u) {
		f = 0;
		ip++; /* at most 2^31 */
	}
	n += np_fmt_u64(ip, buf + n);
	buf[n++] = '.';
	buf[n++] = (char)('0' + f / 100u);
	buf[n++] = (char)('0' + f / 10u % 10u);
	buf[n++] = (char)('0' + f % 10u);
	buf[n] = '\0';
	return n;
}

int64_t np_q32_from_ieee(uint64_t b)
{
	int ex = (int)(b >> 52) & 0x7ff;
	uint64_t m = (b & (NP_2P53 / 2u - 1u)) | (uint64_t)(ex != 0) << 52, q;
	/* value = m * 2^(ex - 1075), so Q32 = m * 2^s */
	int s = (ex ? ex : 1) - 1075 + 32;

	if (ex == 0x7ff)
		return Q32_NAN;
	if (s > 10) /* m * 2^s >= 2^63 */
		return b >> 63 ? -Q32_SAT : Q32_SAT;
	if (s >= 0)
		q = m << s;
	else if (s < -64) /* below 2^-33: rounds to zero */
		q = 0;
	else /* the last bit shifted out rounds: half away from zero */
		q = ((m >> (-s - 1)) + 1u) >> 1;
	return b >> 63 ? -(int64_t)q : (int64_t)q;
}

uint64_t np_q32_to_ieee(int64_t v)
{
	uint64_t m = v < 0 ? 0u - (uint64_t)v : (uint64_t)v, sign = (uint64_t)(v < 0) << 63;
	int p;

	if (v == 0)
		return 0;
	if (v == Q32_NAN)
		return UINT64_C(0x7ff8000000000000);
	p = 63 - __builtin_clzll(m);
	if (p > 52) {
		/* to 53 bits, ties to even, as int64 -> double rounds */
		int sh = p - 52;
		uint64_t lost = m << (64 - sh), half = UINT64_C(1) << 63;

		m >>= sh;
		if (lost > half || (lost == half && (m & 1u)))
			m++;
	} else {
		m <<= 52 - p;
	}
	/* value = v * 2^-32, exponent p - 32; m's leading bit (bit 52, or 53
	 * when the rounding carried) adds itself to the exponent field */
	return sign | (((uint64_t)(p - 32 + 1022) << 52) + m);
}
