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

/* Q32.32 (firmware/real.h) for a board built with VS_REAL_Q32, where the
 * console and the wire carry the unit's numbers without floating point.
 * np_parse_q32 takes what np_parse_double takes and rounds the decimal to
 * the nearest Q32 (ties away from zero), exactly for up to 19 significant
 * digits and 27 decimals; beyond +-2^31 it saturates at
 * +-INT64_MAX. np_fmt_q32_fixed3 writes what np_fmt_fixed3 writes for the
 * same value; "nan" for INT64_MIN. np_q32_from_ieee rounds an IEEE-754
 * double to Q32 as the host's conversion does (NaN and infinities give
 * INT64_MIN, finite values beyond the range saturate); np_q32_to_ieee is
 * the host's (double)v / 2^32. */
np_result_t np_parse_q32(const char *s, int64_t *out);
size_t np_fmt_q32_fixed3(int64_t v, char *buf);
int64_t np_q32_from_ieee(uint64_t bits);
uint64_t np_q32_to_ieee(int64_t v);

/* The boundary's number (real.h) either way. */
#ifdef VS_REAL_Q32
#define np_parse_real np_parse_q32
#define np_fmt_real3  np_fmt_q32_fixed3
#else
#define np_parse_real np_parse_double
#define np_fmt_real3  np_fmt_fixed3
#endif

#endif
