/* The saved configuration's two slots (cfgstore.h says how a save stays
 * power-cut safe). */
#include "cfgstore.h"

#include <stddef.h>

/* The header's words by index (cfgstore.h gives their byte offsets). The
 * store's format is little-endian, as the unit is: the header is read and
 * built as words, where a byte-wise get and put per field took 0.1 KiB
 * more flash. */
_Static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the record's words in the unit's order");
#define W_MAGIC	   0u
#define W_SEQ	   1u
#define W_SCHEMA   2u
#define W_LEN	   3u
#define W_CRC	   4u
#define W_COMMIT   6u
#define OFF_CRC	   (4u * W_CRC)
#define OFF_COMMIT (4u * W_COMMIT)
#define CHUNK	   64u

typedef enum { SLOT_ERASED, SLOT_VALID, SLOT_GARBAGE, SLOT_IO } slot_state_t;

typedef struct {
	slot_state_t st;
	uint32_t seq, schema, len;
} slot_t;

uint32_t cfgstore_crc32(uint32_t crc, const void *data, uint32_t n)
{
	const uint8_t *p = data;
	crc = ~crc;
	for (uint32_t i = 0; i < n; i++) {
		crc ^= p[i];
		for (int b = 0; b < 8; b++)
			crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
	}
	return ~crc;
}

static uint32_t slot_bytes(const hal_store_t *s)
{
	return (s->pages / 2u) * s->page_size;
}

uint32_t cfgstore_capacity(const hal_store_t *s)
{
	if (!s || !s->read || !s->erase || !s->program || s->pages < 2u ||
	    (s->word != 4u && s->word != 8u) || s->page_size % s->word != 0u ||
	    s->page_size > 0x10000u || s->pages > 0x100u)
		return 0;
	uint32_t b = slot_bytes(s);
	return b > CFGSTORE_HEADER ? b - CFGSTORE_HEADER : 0;
}

static uint32_t slot_base(const hal_store_t *s, uint8_t slot)
{
	return slot * slot_bytes(s);
}

/* All of the slot's bytes from off on are erased. */
static slot_state_t erased_from(const hal_store_t *s, uint8_t slot, uint32_t off)
{
	uint8_t b[CHUNK];
	uint32_t end = slot_bytes(s);
	while (off < end) {
		uint32_t n = end - off < CHUNK ? end - off : CHUNK;
		if (!s->read(s->ctx, slot_base(s, slot) + off, b, n))
			return SLOT_IO;
		for (uint32_t i = 0; i < n; i++)
			if (b[i] != s->erased_byte)
				return SLOT_GARBAGE;
		off += n;
	}
	return SLOT_ERASED;
}

/* What a slot holds; with buf, a valid record's payload is read into it
 * (cap bytes; the caller checked the length). */
static slot_t slot_read(const hal_store_t *s, uint8_t slot, uint8_t *buf)
{
	slot_t r = {SLOT_GARBAGE, 0, 0, 0};
	uint32_t h[CFGSTORE_HEADER / 4u];
	uint32_t base = slot_base(s, slot);
	if (!s->read(s->ctx, base, h, sizeof h)) {
		r.st = SLOT_IO;
		return r;
	}
	r.len = h[W_LEN];
	if (h[W_COMMIT] != CFGSTORE_COMMIT || h[W_MAGIC] != CFGSTORE_MAGIC ||
	    r.len > cfgstore_capacity(s)) {
		r.st = erased_from(s, slot, 0);
		return r;
	}
	uint32_t crc = cfgstore_crc32(0, h, OFF_CRC);
	uint8_t b[CHUNK] = {0}; /* read into before it is used */
	for (uint32_t off = 0; off < r.len;) {
		uint32_t n = r.len - off < CHUNK ? r.len - off : CHUNK;
		uint8_t *p = buf ? buf + off : b;
		if (!s->read(s->ctx, base + CFGSTORE_HEADER + off, p, n)) {
			r.st = SLOT_IO;
			return r;
		}
		crc = cfgstore_crc32(crc, p, n);
		off += n;
	}
	if (crc != h[W_CRC])
		return r;
	r.st = SLOT_VALID;
	r.seq = h[W_SEQ];
	r.schema = h[W_SCHEMA];
	return r;
}

/* Which slot holds the newest record: 0 or 1, or 2 for none. */
static uint8_t newest(const slot_t sl[2])
{
	if (sl[0].st == SLOT_VALID && sl[1].st == SLOT_VALID)
		return (int32_t)(sl[1].seq - sl[0].seq) > 0 ? 1u : 0u;
	if (sl[0].st == SLOT_VALID)
		return 0;
	return sl[1].st == SLOT_VALID ? 1u : 2u;
}

cfgstore_status_t cfgstore_load(const hal_store_t *s, void *buf, uint32_t cap,
				cfgstore_info_t *info)
{
	if (cfgstore_capacity(s) == 0)
		return CFGSTORE_NO_STORE;
	slot_t sl[2] = {slot_read(s, 0, NULL), slot_read(s, 1, NULL)};
	if (sl[0].st == SLOT_IO || sl[1].st == SLOT_IO)
		return CFGSTORE_IO;
	uint8_t k = newest(sl);
	if (k == 2) {
		/* One slot erased and the other not: the first save (or a
		 * clear) was cut short. Both not erased: damage. */
		if (info)
			*info = (cfgstore_info_t){
			    0, 0, 0, 0, sl[0].st == SLOT_GARBAGE || sl[1].st == SLOT_GARBAGE};
		return sl[0].st == SLOT_ERASED || sl[1].st == SLOT_ERASED ? CFGSTORE_EMPTY
									  : CFGSTORE_CORRUPT;
	}
	if (sl[k].len > cap)
		return CFGSTORE_TOO_BIG;
	/* Read again into buf, checked again: what is returned is what the
	 * CRC held for. */
	slot_t r = slot_read(s, k, buf);
	if (r.st != SLOT_VALID || r.seq != sl[k].seq)
		return r.st == SLOT_IO ? CFGSTORE_IO : CFGSTORE_CORRUPT;
	if (info) {
		info->seq = r.seq;
		info->schema = r.schema;
		info->len = r.len;
		info->slot = k;
		info->other_torn = sl[k ^ 1u].st == SLOT_GARBAGE;
	}
	return CFGSTORE_OK;
}

static cfgstore_status_t erase_slot(const hal_store_t *s, uint8_t slot)
{
	uint32_t per = s->pages / 2u;
	for (uint32_t p = 0; p < per; p++)
		if (!s->erase(s->ctx, slot * per + p))
			return CFGSTORE_IO;
	slot_state_t e = erased_from(s, slot, 0);
	return e == SLOT_ERASED ? CFGSTORE_OK : e == SLOT_IO ? CFGSTORE_IO : CFGSTORE_VERIFY;
}

cfgstore_status_t cfgstore_save(const hal_store_t *s, const void *payload, uint32_t len,
				uint32_t schema)
{
	uint32_t cap = cfgstore_capacity(s);
	if (cap == 0)
		return CFGSTORE_NO_STORE;
	if (len > cap)
		return CFGSTORE_TOO_BIG;
	slot_t sl[2] = {slot_read(s, 0, NULL), slot_read(s, 1, NULL)};
	if (sl[0].st == SLOT_IO || sl[1].st == SLOT_IO)
		return CFGSTORE_IO;
	uint8_t k = newest(sl);
	uint8_t slot = k == 2 ? 0u : (uint8_t)(k ^ 1u);
	uint32_t seq = k == 2 ? 1u : sl[k].seq + 1u;
	cfgstore_status_t st = erase_slot(s, slot);
	if (st != CFGSTORE_OK)
		return st;

	uint32_t base = slot_base(s, slot), w = s->word;
	/* The payload: its whole words from the caller's buffer, the last
	 * part word padded with erased bytes. */
	uint32_t whole = len - len % w;
	if (whole && !s->program(s->ctx, base + CFGSTORE_HEADER, payload, whole))
		return CFGSTORE_IO;
	if (len > whole) {
		uint8_t tail[8];
		for (uint32_t i = 0; i < w; i++)
			tail[i] = i < len - whole ? ((const uint8_t *)payload)[whole + i]
						  : s->erased_byte;
		if (!s->program(s->ctx, base + CFGSTORE_HEADER + whole, tail, w))
			return CFGSTORE_IO;
	}
	/* The header up to the commit word, then the commit word alone. */
	uint32_t h[CFGSTORE_HEADER / 4u];
	for (uint32_t i = 0; i < CFGSTORE_HEADER / 4u; i++)
		h[i] = s->erased_byte * 0x01010101u; /* the reserved words erased */
	h[W_MAGIC] = CFGSTORE_MAGIC;
	h[W_SEQ] = seq;
	h[W_SCHEMA] = schema;
	h[W_LEN] = len;
	h[W_CRC] = cfgstore_crc32(cfgstore_crc32(0, h, OFF_CRC), payload, len);
	h[W_COMMIT] = CFGSTORE_COMMIT;
	if (!s->program(s->ctx, base, h, OFF_COMMIT) ||
	    !s->program(s->ctx, base + OFF_COMMIT, &h[W_COMMIT], w))
		return CFGSTORE_IO;
	slot_t r = slot_read(s, slot, NULL);
	if (r.st == SLOT_IO)
		return CFGSTORE_IO;
	return r.st == SLOT_VALID && r.seq == seq ? CFGSTORE_OK : CFGSTORE_VERIFY;
}

cfgstore_status_t cfgstore_clear(const hal_store_t *s)
{
	if (cfgstore_capacity(s) == 0)
		return CFGSTORE_NO_STORE;
	slot_t sl[2] = {slot_read(s, 0, NULL), slot_read(s, 1, NULL)};
	uint8_t k = newest(sl);
	uint8_t first = k == 0 ? 1u : 0u;
	cfgstore_status_t st = erase_slot(s, first);
	return st != CFGSTORE_OK ? st : erase_slot(s, (uint8_t)(first ^ 1u));
}
