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

/* memcpy, memmove and memset: a word at a time once aligned (memcpy when
 * both ends share the offset, as the firmware's structs and strings do),
 * else a byte at a time. newlib's ones cost 720 bytes of flash, these
 * about 250. The attribute keeps the
 * compiler from turning the loops back into calls to themselves. */
#define NO_LOOP_CALLS __attribute__((optimize("no-tree-loop-distribute-patterns")))

NO_LOOP_CALLS void *memcpy(void *restrict dst, const void *restrict src, size_t n)
{
	unsigned char *d = dst;
	const unsigned char *s = src;
	if ((((uintptr_t)d ^ (uintptr_t)s) & 3u) == 0) {
		/* Same offset in a word: bytes up to the boundary, then words,
		 * four at a time while they last. */
		for (; n && ((uintptr_t)d & 3u); n--)
			*d++ = *s++;
		uint32_t *dw = (uint32_t *)(void *)d;
		const uint32_t *sw = (const uint32_t *)(const void *)s;
		for (; n >= 16; n -= 16, dw += 4, sw += 4) {
			dw[0] = sw[0];
			dw[1] = sw[1];
			dw[2] = sw[2];
			dw[3] = sw[3];
		}
		for (; n >= 4; n -= 4)
			*dw++ = *sw++;
		d = (unsigned char *)dw;
		s = (const unsigned char *)sw;
	}
	while (n--)
		*d++ = *s++;
	return dst;
}

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
