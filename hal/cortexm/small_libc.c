/* Byte-at-a-time string routines for the board, in place of newlib's
 * word-at-a-time ones: the link compares and measures short names and
 * lines (tens of bytes), where the unrolled forms buy little and cost
 * about 1.5 KiB of flash. The linker takes these before
 * the library's. */
#include <stdbool.h>
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

/* memcpy, memmove and memset: a word at a time (two for memcpy, which
 * getActiveAlarm's reply leans on to answer within a period), else a byte
 * at a time; newlib's cost some 700 bytes of flash more. The attribute
 * keeps the compiler from turning the loops back into calls to
 * themselves; the word types may alias anything, and an ARMv7-M core
 * (__ARM_FEATURE_UNALIGNED) loads and stores them at any address. */
#define NO_LOOP_CALLS __attribute__((optimize("no-tree-loop-distribute-patterns")))
typedef uint32_t __attribute__((may_alias)) word_t;
typedef uint32_t __attribute__((may_alias, aligned(1))) uword_t;

NO_LOOP_CALLS void *memcpy(void *restrict dst, const void *restrict src, size_t n)
{
	unsigned char *d = dst;
	const unsigned char *s = src;
#ifndef __ARM_FEATURE_UNALIGNED
	if ((((uintptr_t)d | (uintptr_t)s) & 3u) == 0)
#endif
		for (; n >= 8; n -= 8, d += 8, s += 8) {
			uword_t *dw = (uword_t *)(void *)d;
			const uword_t *sw = (const uword_t *)(const void *)s;
			dw[0] = sw[0];
			dw[1] = sw[1];
		}
	while (n--)
		*d++ = *s++;
	return dst;
}

NO_LOOP_CALLS void *memchr(const void *p, int c, size_t n)
{
	const unsigned char *s = p;
	for (size_t i = 0; i < n; i++)
		if (s[i] == (unsigned char)c)
			return (void *)(s + i); /* memchr's contract drops const */
	return NULL;
}

int strncmp(const char *a, const char *b, size_t n)
{
	const unsigned char *p = (const unsigned char *)a, *q = (const unsigned char *)b;
	for (; n; n--, p++, q++)
		if (*p != *q || *p == '\0')
			return (int)*p - (int)*q;
	return 0;
}

size_t strnlen(const char *s, size_t max); /* POSIX: newlib declares it with _GNU_SOURCE */
size_t strnlen(const char *s, size_t max)
{
	size_t n = 0;
	while (n < max && s[n])
		n++;
	return n;
}

/* strspn and strcspn in one (newlib's strspn is 48 bytes): the length of
 * s's start whose characters are all in set (in), or none of them (!in). */
static size_t span(const char *s, const char *set, bool in)
{
	size_t n = 0;
	for (; s[n]; n++) {
		const char *r = set;
		while (*r && *r != s[n])
			r++;
		if ((*r != '\0') != in)
			break;
	}
	return n;
}

size_t strspn(const char *s, const char *accept)
{
	return span(s, accept, true);
}

size_t strcspn(const char *s, const char *reject)
{
	return span(s, reject, false);
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
	word_t w = (unsigned char)c * 0x01010101u, *dw = (word_t *)(void *)d;
	/* Four words a turn: a struct cleared on the tick (a line's plan,
	 * 0.1 KiB) costs half the instructions. */
	for (; n >= 16; n -= 16, dw += 4)
		dw[0] = dw[1] = dw[2] = dw[3] = w;
	for (; n >= 4; n -= 4)
		*dw++ = w;
	d = (unsigned char *)dw;
	while (n--)
		*d++ = (unsigned char)c;
	return dst;
}
