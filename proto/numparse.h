/* Strict parsing of console arguments.
 *
 * Numbers: [+-] digits [. [digits]] [(e|E) [+-] digits], or with the
 * integer part omitted (".5"). Anything else is rejected: empty text,
 * hexadecimal, "nan", "inf", trailing characters. Doubles must come out
 * finite (a decimal that overflows is rejected like junk). Integers are
 * evaluated exactly from their decimal digits, so "1e3" is 1000 and "2.50"
 * is not an integer, whatever the precision of a double.
 */
#ifndef NUMPARSE_H
#define NUMPARSE_H

#include <stdbool.h>
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

#endif
