/* Byte-at-a-time string routines for the board, in place of newlib's
 * word-at-a-time ones: the link compares and measures short names and
 * lines (tens of bytes), where the unrolled forms buy nothing and cost
 * about 1 KiB of the 48 KiB flash budget. The linker takes these before
 * the library's. */
#include <stddef.h>
#include <string.h>

int strcmp(const char *a, const char *b)
{
	const unsigned char *p = (const unsigned char *)a, *q = (const unsigned char *)b;
	while (*p && *p == *q)
		p++, q++;
	return (int)*p - (int)*q;
}

size_t strlen(const char *s)
{
	const char *p = s;
	while (*p)
		p++;
	return (size_t)(p - s);
}
