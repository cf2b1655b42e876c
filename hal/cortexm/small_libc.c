/* Byte-at-a-time string routines for the board, in place of newlib's
 * word-at-a-time ones: the link compares and measures short names and
 * lines (tens of bytes), where the unrolled forms buy little and cost
 * about 1 KiB of the 48 KiB flash budget. The linker takes these before
 * the library's. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

int strcmp(const char *a, const char *b)
{
	const unsigned char *p = (const unsigned char *)a, *q = (const unsigned char *)b;
	while (*p && *p == *q)
		p++, q++;
	return (int)*p - (int)*q;
}

/* Word at a time once aligned ($help measures 34 names in one request):
 * a word holds a zero byte when (w - 0x01..) & ~w & 0x80.. is non-zero. */
size_t strlen(const char *s)
{
	const char *p = s;
	while (((uintptr_t)p & 3u) != 0) {
		if (*p == '\0')
			return (size_t)(p - s);
		p++;
	}
	const uint32_t *w = (const uint32_t *)(const void *)p;
	while (((*w - 0x01010101u) & ~*w & 0x80808080u) == 0)
		w++;
	p = (const char *)w;
	while (*p)
		p++;
	return (size_t)(p - s);
}
