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

/* memmove and memset: a word at a time once aligned, else a byte at a
 * time; newlib's cost some 400 bytes of flash more. memcpy stays newlib's:
 * the requests that copy most (getActiveAlarm) need its speed to answer
 * within a period. The attribute keeps the
 * compiler from turning the loops back into calls to themselves. */
#define NO_LOOP_CALLS __attribute__((optimize("no-tree-loop-distribute-patterns")))

NO_LOOP_CALLS void *memmove(void *dst, const void *src, size_t n)
{
	unsigned char *d = dst;
	const unsigned char *s = src;
	if (d <= s || d >= s + n)
		return memcpy(dst, src, n); /* forward copying is safe */
	while (n--)
		d[n] = s[n];
	return dst;
}

NO_LOOP_CALLS void *memset(void *dst, int c, size_t n)
{
	unsigned char *d = dst;
	for (; n && ((uintptr_t)d & 3u); n--)
		*d++ = (unsigned char)c;
	uint32_t w = (unsigned char)c * 0x01010101u, *dw = (uint32_t *)(void *)d;
	for (; n >= 4; n -= 4)
		*dw++ = w;
	d = (unsigned char *)dw;
	while (n--)
		*d++ = (unsigned char)c;
	return dst;
}
