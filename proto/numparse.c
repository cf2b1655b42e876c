/* Strict number and boolean parsing for the console (see numparse.h). */
#include "numparse.h"

#include <math.h>
#include <stdlib.h>

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

np_result_t np_parse_double(const char *s, double *out)
{
	np_dec_t d;
	char *end;
	double v;

	if (!np_scan(s, &d))
		return NP_SYNTAX;
	/* The grammar above is a subset of strtod's, which rounds correctly. */
	v = strtod(s, &end);
	if (*end != '\0' || !isfinite(v))
		return NP_SYNTAX;
	*out = v;
	return NP_OK;
}

/* Digit k of the concatenated integer and fraction digits. */
static int dec_digit(const np_dec_t *d, long k)
{
	return k < d->in ? d->ip[k] - '0' : d->fp[k - d->in] - '0';
}

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

bool np_streq_nocase(const char *a, const char *b)
{
	while (*a && lower(*a) == lower(*b)) {
		a++;
		b++;
	}
	return lower(*a) == lower(*b);
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
