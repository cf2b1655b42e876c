/* Strict parsing of console arguments.
 *
 * Numbers: [+-] digits [. [digits]] [(e|E) [+-] digits], or with the
 * integer part omitted (".5"). Anything else is rejected: empty text,
 * hexadecimal, "nan", "inf", trailing characters. Doubles must come out
 * finite (a decimal that overflows is rejected like junk). Integers are
 * evaluated exactly from their decimal digits, so "1e3" is 1000 and "2.50"
 * is not an integer, whatever the precision of a double.
 *
 * np_parse_double is correctly rounded for up to 19 significant digits
 * (exactly representable below 2^53, in practice up to 15) with a decimal
 * exponent within +-22 after moving the point behind the last digit: every
 * console value. Beyond that it is within a few units in the last place;
 * digits after the 19th significant one are ignored.
 *
 * Formatting writes exactly what printf's "%.3f" (round to nearest, ties to
 * even on the exact binary value), "%llu" and "%lld" write, NUL-terminated,
 * and returns the length. No libc number conversion is used on either side,
 * so host and MCU share one implementation.
 */
#ifndef NUMPARSE_H
#define NUMPARSE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum {
	NP_OK = 0,
	NP_SYNTAX, /* not a decimal number, or not finite */
	NP_RANGE,  /* a number, but not an integer inside [min, max] */
} np_result_t;

np_result_t np_parse_double(const char *s, double *out);
np_result_t np_parse_int(const char *s, int64_t min, int64_t max, int64_t *out);
/* true|false|1|0|on|off, case-insensitive. */
bool np_parse_bool(const char *s, bool *out);
/* ASCII case-insensitive equality. */
bool np_streq_nocase(const char *a, const char *b);
/* strcmp ignoring ASCII case: < 0, 0 or > 0 */
int np_cmp_nocase(const char *a, const char *b);

/* Room buf needs, including the NUL: "-" + 20 digits; "-" + 309 integer
 * digits + ".000" (DBL_MAX). */
#define NP_INT_MAX    22
#define NP_FIXED3_MAX 316

size_t np_fmt_u64(uint64_t v, char *buf);
size_t np_fmt_i64(int64_t v, char *buf);
/* Three decimals; "-0.000" for negative values that round to zero, "inf",
 * "-inf", "nan", "-nan" as printf has them. */
size_t np_fmt_fixed3(double v, char *buf);

#endif
