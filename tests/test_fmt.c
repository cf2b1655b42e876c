/* proto/fmt.c, the console's printf subset: every supported directive gives
 * C's snprintf output and return value at every buffer size (written out in
 * full for the cases below, checked against glibc for the value sweeps), and
 * an unsupported directive ends conversion: the rest of the format comes
 * out as it stands and no further argument is read (fmt.h). */
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "../proto/fmt.h"

#define BUF    700
#define UNUSED 0x7f /* fill byte: what fmt_v must not have written */

/* fmt_v at every capacity 0..len+2 against the expected text: the return is
 * always the full length, the bytes are the expected prefix and a NUL, and
 * nothing after the NUL is touched. */
static void check_caps(const char *expect, const char *fmt, va_list ap)
{
	size_t len = strlen(expect);
	char got[BUF], unused[BUF];
	va_list a;

	assert_true(len + 3 < BUF);
	memset(unused, UNUSED, sizeof(unused));
	for (size_t cap = 0; cap <= len + 2; cap++) {
		size_t k = cap ? (cap - 1 < len ? cap - 1 : len) : 0;

		memset(got, UNUSED, sizeof(got));
		va_copy(a, ap);
		assert_int_equal(fmt_v(got, cap, fmt, a), len);
		va_end(a);
		assert_memory_equal(got, expect, k);
		if (cap)
			assert_int_equal(got[k], '\0');
		k += cap ? 1 : 0;
		assert_memory_equal(got + k, unused, BUF - k);
	}
	va_copy(a, ap);
	assert_int_equal(fmt_v(NULL, 0, fmt, a), len);
	va_end(a);
}

/* A supported format: expect is the exact text; glibc must agree with it,
 * and fmt_v's buffer must equal glibc's at every capacity. */
__attribute__((format(printf, 2, 0))) static void vsame(const char *expect, const char *fmt,
							va_list ap)
{
	size_t len = strlen(expect);
	char ref[BUF], got[BUF];
	va_list a;

	va_copy(a, ap);
	assert_int_equal(vsnprintf(ref, sizeof(ref), fmt, a), (int)len);
	va_end(a);
	assert_string_equal(ref, expect);
	check_caps(expect, fmt, ap);
	for (size_t cap = 0; cap <= len + 2; cap++) {
		memset(ref, UNUSED, sizeof(ref));
		memset(got, UNUSED, sizeof(got));
		va_copy(a, ap);
		vsnprintf(ref, cap, fmt, a);
		va_end(a);
		va_copy(a, ap);
		fmt_v(got, cap, fmt, a);
		va_end(a);
		assert_memory_equal(got, ref, sizeof(got));
	}
}

__attribute__((format(printf, 2, 3))) static void same(const char *expect, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vsame(expect, fmt, ap);
	va_end(ap);
}

/* Value sweeps: glibc's text is the reference. */
__attribute__((format(printf, 1, 2))) static void as_libc(const char *fmt, ...)
{
	char ref[BUF];
	va_list ap, a;

	va_start(ap, fmt);
	va_copy(a, ap);
	assert_true(vsnprintf(ref, sizeof(ref), fmt, a) < BUF);
	va_end(a);
	vsame(ref, fmt, ap);
	va_end(ap);
}

/* No format attribute: these formats are outside the subset on purpose. */
static void literal(const char *expect, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	check_caps(expect, fmt, ap);
	va_end(ap);
}

static void test_signed(void **state)
{
	(void)state;
	same("0", "%d", 0);
	same("-1", "%d", -1);
	same("-2147483648", "%d", INT_MIN);
	same("2147483647", "%d", INT_MAX);
	same("-32768 32767", "%d %d", (int16_t)INT16_MIN, (int16_t)INT16_MAX);
	same("   42", "%5d", 42);
	same("  -42", "%5d", -42);
	same("-0042", "%05d", -42);
	same("00042", "%05d", 42);
	same("12345", "%2d", 12345);
	same("7", "%0d", 7);
	same("-2147483648", "%011d", INT_MIN);
	same("-02147483648", "%012d", INT_MIN);
	same("-9223372036854775808", "%lld", LLONG_MIN);
	same("9223372036854775807", "%lld", LLONG_MAX);
	same("-32768..32767", "%lld..%lld", (long long)INT16_MIN, (long long)INT16_MAX);
	same("0..4294967295", "%lld..%lld", (long long)0, (long long)UINT32_MAX);
	same(LONG_MIN == INT64_MIN ? "-9223372036854775808" : "-2147483648", "%ld", LONG_MIN);
	same(LONG_MAX == INT64_MAX ? "  9223372036854775807" : "  2147483647",
	     LONG_MAX == INT64_MAX ? "%21ld" : "%12ld", LONG_MAX);
}

static void test_unsigned(void **state)
{
	(void)state;
	same("0", "%u", 0u);
	same("4294967295", "%u", UINT32_MAX);
	same("2147483648", "%u", (unsigned)INT_MAX + 1u);
	same("0000000042", "%010u", 42u);
	same("        42", "%10u", 42u);
	same("0", "%lu", 0ul);
	same("4294967295", "%lu", (unsigned long)UINT32_MAX);
	same(ULONG_MAX == UINT64_MAX ? "18446744073709551615" : "4294967295", "%lu", ULONG_MAX);
	same("18446744073709551615", "%llu", ULLONG_MAX);
	same("ok ticks 0 overruns 4294967295 mode idle queue 16 ref",
	     "ok ticks %lu overruns %lu mode %s queue %u ref", 0ul, (unsigned long)UINT32_MAX,
	     "idle", 16u);
}

static void test_hex(void **state)
{
	(void)state;
	same("00", "%02X", 0u);
	same("05", "%02X", 5u);
	same("7F", "%02X", 0x7fu);
	same("AB", "%02X", 0xabu);
	same("100", "%02X", 0x100u);
	same("\\x1F\\xFF", "\\x%02X\\x%02X", (unsigned char)0x1f, (unsigned char)0xff);
	same("0000", "%04X", 0u);
	same("000A", "%04X", 0xau);
	same("BEEF", "%04X", 0xbeefu);
	same("12345", "%04X", 0x12345u);
	same(" protocol 1 table 0x0C3A", " protocol %d table 0x%04X", 1, 0x0c3au);
	same("FFFFFFFF", "%X", UINT32_MAX);
	same("    BEEF", "%8X", 0xbeefu);
	same("0000BEEF", "%08X", 0xbeefu);
	same("FFFFFFFFFFFFFFFF", "%llX", ULLONG_MAX);
	same(ULONG_MAX == UINT64_MAX ? "FFFFFFFFFFFFFFFF" : "FFFFFFFF", "%lX", ULONG_MAX);
}

static void test_strings(void **state)
{
	static const char names[] = "x_,y_,theta_";
	static const char abc[3] = {'a', 'b', 'c'}; /* not terminated */

	(void)state;
	same("", "%s", "");
	same("hello", "%s", "hello");
	same("[  ab]", "[%4s]", "ab");
	same("[abcdef]", "[%4s]", "abcdef");
	same("x_", "%.*s", 2, names);
	same("x_,y_,theta_", "%.*s", (int)strlen(names), names);
	same("", "%.*s", 0, names);
	same("ab", "%.*s", 10, "ab");
	same("ab", "%.*s", -1, "ab");
	same("ab", "%.*s", INT_MIN, "ab");
	same("abc", "%.*s", 3, abc);
	same("abc", "%.3s", abc);
	same("", "%.s", "ab");
	same("", "%.0s", "ab");
	same("     a", "%6.1s", "ab");
	same("in double x_", "%s%s %s %.*s", "", "in", "double", 2, names);
	same(", out double theta", "%s%s %s %.*s", ", ", "out", "double", 5, names + 6);
	same("error 3 setSpeed takes 1 argument, got 2", "error %d %s takes %u argument%s, got %u",
	     3, "setSpeed", 1u, "", 2u);
}

static void test_percent(void **state)
{
	(void)state;
	same("%", "%%");
	same("100% 5%", "100%% %d%%", 5);
	same("%d", "%%d");
	same("%7", "%%%d", 7);
	literal("", "");
	same("no directive", "no directive");
}

/* NULL for %s is undefined in C; here it prints "(null)" like any string
 * (through literal(): gcc rejects a null %s argument at compile time). */
static void test_null_string(void **state)
{
	(void)state;
	literal("(null)", "%s", (const char *)NULL);
	literal("[  (null)]", "[%8s]", (const char *)NULL);
	literal("(nu|", "%.*s|", 3, (const char *)NULL);
	literal("(null) 5", "%s %d", (const char *)NULL, 5);
}

/* The widest supported field, and one beyond it. */
static void test_width_limit(void **state)
{
	char spaces[FMT_WIDTH_MAX + 1];

	(void)state;
	memset(spaces, ' ', sizeof(spaces));
	spaces[FMT_WIDTH_MAX - 1] = '1';
	spaces[FMT_WIDTH_MAX] = '\0';
	same(spaces, "%255d", 1);
	spaces[FMT_WIDTH_MAX - 1] = 'x';
	same(spaces, "%255s", "x");
	same("ab", "%.255s", "ab");
	literal("%256d", "%256d", 1);
	literal("%.256s", "%.256s", "ab");
	literal("%99999999999999999999999999d", "%99999999999999999999999999d", 1);
}

static void test_unsupported(void **state)
{
	static const char *const fmts[] = {
	    "%f",   "%x",  "%c",   "%p",   "%o",   "%i",   "%e",  "%n",	  "%hd", "%hhu",
	    "%zu",  "%jd", "%Lf",  "%lf",  "%ls",  "%lls", "%lc", "%-5d", "%+d", "% d",
	    "%#X",  "%*d", "%.3d", "%.*u", "%.1X", "%05s", "%0s", "%lll", "%l",	 "%ll",
	    "%",    "%5",  "%.",   "%.*",  "%5%",  "%.2%", "%0",  "%l%",  "%'d", "%lllu",
	    "%1$d", "%S",  "%C",   "%D",   "%U",   "%m",   "%a",  "%G",	  "%.5",
	};

	(void)state;
	/* On its own, with no argument at all. */
	for (size_t i = 0; i < sizeof(fmts) / sizeof(fmts[0]); i++)
		literal(fmts[i], fmts[i]);
	/* Conversion stops there: the %s and %d after it read nothing (there is
	 * nothing to read). */
	literal("a %f b %s %d %%", "a %f b %s %d %%");
	literal("v=5 %x %s", "v=%d %x %s", 5);
	literal("ab%5.2f%d", "%s%5.2f%d", "ab");
	literal("100% %hd", "%u%% %hd", 100u);
	literal("tail %", "tail %");
}

/* Values across the ranges (extremes, powers of the bases and neighbours,
 * and a pseudo-random spread of magnitudes) in every supported integer form. */
static void test_sweep_integers(void **state)
{
	static const char *const ifmt[] = {"%d",    "%1d",  "%3d",   "%03d",   "%11d",
					   "%011d", "%12d", "%012d", "[%20d]", "%0d"};
	static const char *const ufmt[] = {"%u",   "%X",    "%02X", "%04X", "%08X",
					   "%10u", "%010u", "%12X", "%1u",  "%0X"};
	static const char *const lfmt[] = {"%ld", "%021ld", "%25ld", "%lu", "%022lu", "%lX"};
	static const char *const llfmt[] = {"%lld",    "%025lld", "%llu",
					    "%021llu", "%llX",	  "%018llX"};
	unsigned long long v[200];
	size_t n = 0;
	uint64_t x = 0x9e3779b97f4a7c15u;

	(void)state;
	v[n++] = 0;
	v[n++] = (unsigned long long)INT_MIN;
	v[n++] = INT_MAX;
	v[n++] = UINT32_MAX;
	v[n++] = ULONG_MAX;
	v[n++] = (unsigned long long)LLONG_MIN;
	v[n++] = LLONG_MAX;
	v[n++] = ULLONG_MAX;
	for (unsigned long long p = 1; p <= ULLONG_MAX / 10; p *= 10) {
		v[n++] = p - 1;
		v[n++] = p;
	}
	for (unsigned s = 0; s < 64; s += 4)
		v[n++] = 1ull << s;
	while (n < sizeof(v) / sizeof(v[0])) {
		x ^= x << 13;
		x ^= x >> 7;
		x ^= x << 17;
		v[n++] = x >> (x % 64);
	}
	for (size_t i = 0; i < n; i++) {
		for (size_t f = 0; f < sizeof(ifmt) / sizeof(ifmt[0]); f++) {
			as_libc(ifmt[f], (int)(unsigned)v[i]);
			as_libc(ifmt[f], -(int)(v[i] % INT_MAX));
		}
		for (size_t f = 0; f < sizeof(ufmt) / sizeof(ufmt[0]); f++)
			as_libc(ufmt[f], (unsigned)v[i]);
		for (size_t f = 0; f < sizeof(lfmt) / sizeof(lfmt[0]); f++)
			as_libc(lfmt[f], (unsigned long)v[i]);
		for (size_t f = 0; f < sizeof(llfmt) / sizeof(llfmt[0]); f++)
			as_libc(llfmt[f], v[i]);
		as_libc("%u%%%d|%04X|%lu|%lld", (unsigned)v[i], (int)v[i], (unsigned)(v[i] >> 3),
			(unsigned long)v[i], (long long)v[i]);
	}
}

static void test_sweep_strings(void **state)
{
	static const char *const strs[] = {
	    "", "a", "ab", "hello", "x_,y_,theta_", "0123456789012345678901234567890123456789"};
	static const char *const sfmt[] = {"%s",   "%1s",  "%5s",  "[%12s]", "%40s", "%41s",
					   "%.0s", "%.1s", "%.5s", "%3.2s",  "%.45s"};

	(void)state;
	for (size_t i = 0; i < sizeof(strs) / sizeof(strs[0]); i++) {
		int len = (int)strlen(strs[i]);

		for (size_t f = 0; f < sizeof(sfmt) / sizeof(sfmt[0]); f++)
			as_libc(sfmt[f], strs[i]);
		for (int p = -3; p <= len + 3; p++)
			as_libc("<%.*s>", p, strs[i]);
		as_libc("%.*s%s%.*s", 1, strs[i], strs[i], len + 1, strs[i]);
	}
}

int main(void)
{
	const struct CMUnitTest tests[] = {
	    cmocka_unit_test(test_signed),
	    cmocka_unit_test(test_unsigned),
	    cmocka_unit_test(test_hex),
	    cmocka_unit_test(test_strings),
	    cmocka_unit_test(test_percent),
	    cmocka_unit_test(test_null_string),
	    cmocka_unit_test(test_width_limit),
	    cmocka_unit_test(test_unsupported),
	    cmocka_unit_test(test_sweep_integers),
	    cmocka_unit_test(test_sweep_strings),
	};
	return cmocka_run_group_tests(tests, NULL, NULL);
}
