/* Fuzz target: the saved configuration's reader (firmware/cfgstore.c) on
 * any bytes in the store's pages. Byte 0 picks the geometry; the rest are
 * the pages. Every input gets a verdict and never a crash; a record
 * returned is within the store and its CRC holds; and a save on top always
 * works and is read back. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../../firmware/cfgstore.h"
#include "../../firmware/config_save.h"

#define MEM 1024

static uint8_t mem[MEM];
static hal_store_t hs;

static bool r(void *ctx, uint32_t off, void *buf, uint32_t n)
{
	(void)ctx;
	if (off + n > hs.pages * hs.page_size)
		return false;
	memcpy(buf, mem + off, n);
	return true;
}

static bool e(void *ctx, uint32_t page)
{
	(void)ctx;
	if (page >= hs.pages)
		return false;
	memset(mem + page * hs.page_size, 0xFF, hs.page_size);
	return true;
}

static bool p(void *ctx, uint32_t off, const void *buf, uint32_t n)
{
	(void)ctx;
	if (off % hs.word || n % hs.word || off + n > hs.pages * hs.page_size)
		return false;
	for (uint32_t i = 0; i < n; i++)
		if (mem[off + i] != 0xFF)
			abort(); /* a program of a word not erased */
	memcpy(mem + off, buf, n);
	return true;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	static const uint32_t geo[4][3] = {{256, 2, 4}, {128, 4, 8}, {512, 2, 8}, {64, 2, 4}};
	if (size == 0)
		return 0;
	const uint32_t *g = geo[data[0] & 3];
	hs = (hal_store_t){g[0], g[1], g[2], 0xFF, r, e, p, NULL};
	memset(mem, 0xFF, sizeof mem);
	size_t n = size - 1 < MEM ? size - 1 : MEM;
	memcpy(mem, data + 1, n);

	static uint8_t buf[MEM];
	cfgstore_info_t info;
	cfgstore_status_t st = cfgstore_load(&hs, buf, sizeof buf, &info);
	if (st == CFGSTORE_OK) {
		if (info.len > cfgstore_capacity(&hs) || info.slot > 1)
			abort();
		/* The header's CRC over what came back (the header is in the
		 * pages): recomputed, it must hold. */
		const uint8_t *h = mem + info.slot * (hs.pages / 2) * hs.page_size;
		uint32_t crc = cfgstore_crc32(cfgstore_crc32(0, h, 16), buf, info.len);
		uint32_t want = (uint32_t)h[16] | (uint32_t)h[17] << 8 | (uint32_t)h[18] << 16 |
				(uint32_t)h[19] << 24;
		if (crc != want)
			abort();
		/* The payload's reader: a verdict; a well-formed one changes
		 * only the table's fields. */
		static vs_config_t base, out;
		vs_config_defaults(&base);
		out = base;
		vs_config_decode_t di;
		vs_config_decode_status_t ds = vs_config_decode(&out, buf, info.len, &di);
		if (ds != VS_CFGSAVE_OK && memcmp(&out, &base, sizeof out) != 0)
			abort(); /* a rejected payload changed the configuration */
		if (memcmp(out.io, base.io, sizeof out.io) != 0)
			abort();
	} else if (st != CFGSTORE_EMPTY && st != CFGSTORE_CORRUPT) {
		abort();
	}
	/* Whatever was there, a save works and wins. */
	static const uint8_t rec[] = "tick_hz 500";
	if (cfgstore_save(&hs, rec, sizeof rec, 42) != CFGSTORE_OK)
		abort();
	if (cfgstore_load(&hs, buf, sizeof buf, &info) != CFGSTORE_OK || info.len != sizeof rec ||
	    memcmp(buf, rec, sizeof rec) != 0 || info.schema != 42)
		abort();
	return 0;
}
