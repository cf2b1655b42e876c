/* Bounded printf-style formatting for the console replies, without libc's
 * printf family (several KiB of MCU flash). Freestanding: no libc call, no
 * floating point, no heap.
 *
 * Supported directives, exactly:
 *   %%                  a percent sign
 *   %[0][W][l|ll]d      int, long, long long
 *   %[0][W][l|ll]u      unsigned, unsigned long, unsigned long long
 *   %[0][W][l|ll]X      the same in upper-case hexadecimal
 *   %[W][.P|.*]s        a string, at most P bytes of it read; a negative
 *                       precision argument counts as none (as in C); a
 *                       NULL string prints as "(null)" (cut by P like any
 *                       other string)
 * W and P are decimal, at most FMT_WIDTH_MAX. The field is right-aligned,
 * padded with spaces, or with zeros after the sign with the 0 flag. Within
 * this set the output is what C's snprintf writes.
 *
 * Anything else (other flags, conversions or length modifiers, a precision
 * on an integer, the 0 flag on %s, '*' as width, a '%' ending the format)
 * is unsupported: from the first such directive on, the rest of the format
 * is copied as it stands and no further argument is read, since the
 * arguments after it can no longer be matched to directives safely.
 * gcc's format(printf) check does not know this subset (it accepts %f, for
 * one): the list above is the reference.
 */
#ifndef FMT_H
#define FMT_H

#include <stdarg.h>
#include <stddef.h>

#define FMT_WIDTH_MAX 255

/* vsnprintf's contract: writes at most cap - 1 bytes and a NUL (nothing at
 * all when cap is 0, buf may then be NULL) and returns the length the whole
 * output has, so a return >= cap means it was cut. */
__attribute__((format(printf, 3, 0))) size_t fmt_v(char *buf, size_t cap, const char *fmt,
						   va_list ap);
/* The same with the arguments inline, as snprintf. */
__attribute__((format(printf, 3, 4))) size_t fmt_print(char *buf, size_t cap, const char *fmt, ...);

#endif
