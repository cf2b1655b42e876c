/* printf subset for the console (supported directives: fmt.h). */
#include "fmt.h"

#include <stdbool.h>
#include <stdint.h>

typedef struct {
	char *buf;
	size_t cap; /* bytes buf holds, NUL included */
	size_t n;   /* length of the whole output so far, cut or not */
} out_t;

static void put(out_t *o, char ch)
{
	if (o->n + 1 < o->cap)
		o->buf[o->n] = ch;
	o->n++;
}

static void pad(out_t *o, char ch, unsigned width, size_t len)
{
	for (; len < width; len++)
		put(o, ch);
}

/* Zero padding goes between the sign and the digits, as in printf. */
static void put_num(out_t *o, unsigned long long v, bool neg, unsigned base, unsigned width,
		    bool zero)
{
	char tmp[20]; /* 2^64 - 1 has 20 decimal digits */
	size_t k = 0;
	uint32_t w;

	/* 64-bit division is a library call on a 32-bit core (about 100
	 * instructions a digit on a Cortex-M): only for the digits above 2^32. */
	while (v > UINT32_MAX) {
		tmp[k++] = "0123456789ABCDEF"[v % base];
		v /= base;
	}
	w = (uint32_t)v;
	do {
		tmp[k++] = "0123456789ABCDEF"[w % base];
		w /= base;
	} while (w);
	if (!zero)
		pad(o, ' ', width, k + (neg ? 1u : 0u));
	if (neg)
		put(o, '-');
	if (zero)
		pad(o, '0', width, k + (neg ? 1u : 0u));
	while (k)
		put(o, tmp[--k]);
}

static void put_str(out_t *o, const char *s, int prec, unsigned width)
{
	size_t len = 0;

	if (!s)
		s = "(null)";
	/* Never reads past prec bytes: s need not be terminated there. */
	while ((prec < 0 || len < (size_t)prec) && s[len])
		len++;
	pad(o, ' ', width, len);
	for (size_t i = 0; i < len; i++)
		put(o, s[i]);
}

static bool is_digit(char ch)
{
	return ch >= '0' && ch <= '9';
}

/* Decimal digits at *p, advancing it; false when over FMT_WIDTH_MAX. */
static bool get_num(const char **p, unsigned *v)
{
	*v = 0;
	while (is_digit(**p)) {
		*v = *v * 10u + (unsigned)(**p - '0');
		if (*v > FMT_WIDTH_MAX)
			return false;
		(*p)++;
	}
	return true;
}

size_t fmt_v(char *buf, size_t cap, const char *fmt, va_list ap)
{
	out_t o = {buf, cap, 0};
	const char *p = fmt;

	while (*p) {
		const char *start = p;
		bool zero = false, has_prec = false, star = false, ok;
		unsigned width, uprec = 0, lng = 0;
		char conv;

		if (*p != '%') {
			put(&o, *p++);
			continue;
		}
		p++;
		if (*p == '%') {
			put(&o, '%');
			p++;
			continue;
		}
		if (*p == '0') {
			zero = true;
			p++;
		}
		ok = get_num(&p, &width);
		if (ok && *p == '.') {
			has_prec = true;
			p++;
			if (*p == '*') {
				star = true;
				p++;
			} else {
				ok = get_num(&p, &uprec);
			}
		}
		if (ok && *p == 'l') {
			lng = 1;
			p++;
			if (*p == 'l') {
				lng = 2;
				p++;
			}
		}
		conv = ok ? *p : '\0';
		if (conv == 's')
			ok = !zero && lng == 0;
		else
			ok = (conv == 'd' || conv == 'u' || conv == 'X') && !has_prec;
		if (!ok) {
			/* Outside the subset: the rest as it stands, no argument read. */
			for (p = start; *p; p++)
				put(&o, *p);
			break;
		}
		p++;
		if (conv == 's') {
			int prec = has_prec ? (int)uprec : -1;

			if (star) {
				prec = va_arg(ap, int);
				if (prec < 0)
					prec = -1;
			}
			put_str(&o, va_arg(ap, const char *), prec, width);
		} else if (conv == 'd') {
			long long v;
			unsigned long long m;

			if (lng == 2)
				v = va_arg(ap, long long);
			else
				v = lng ? va_arg(ap, long) : va_arg(ap, int);
			m = (unsigned long long)v;
			put_num(&o, v < 0 ? 0u - m : m, v < 0, 10, width, zero);
		} else {
			unsigned long long v;

			if (lng == 2)
				v = va_arg(ap, unsigned long long);
			else
				v = lng ? va_arg(ap, unsigned long) : va_arg(ap, unsigned);
			put_num(&o, v, false, conv == 'X' ? 16 : 10, width, zero);
		}
	}
	if (cap)
		buf[o.n < cap ? o.n : cap - 1] = '\0';
	return o.n;
}

size_t fmt_print(char *buf, size_t cap, const char *fmt, ...)
{
	va_list ap;
	size_t n;

	va_start(ap, fmt);
	n = fmt_v(buf, cap, fmt, ap);
	va_end(ap);
	return n;
}
