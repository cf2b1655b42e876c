/* The saved configuration: a record in one of two slots of a non-volatile
 * store (hal_store_t), power-cut safe.
 *
 * Each slot is half the store's pages. A record is a header and a payload
 * (the configuration's bytes, encoded above this layer):
 *
 *   0   magic "VCFG"    4  sequence       8  schema (names the table)
 *   12  payload length  16 CRC-32 of bytes 0..15 and the payload
 *   20  reserved        24 commit word     32 payload ...
 *
 * A save erases the slot that does not hold the newest record, programs the
 * payload, then the header, and last the commit word. A cut before the
 * commit word leaves that slot invalid (the commit word still erased) and
 * the other slot as it was; a cut in the commit word's own program leaves a
 * word that is neither erased nor the commit value, equally invalid. A
 * record is valid when its commit word, magic, length and CRC all hold;
 * the valid record of the higher sequence (serial arithmetic) wins. So a
 * boot after any cut finds the record before the save or the one it wrote,
 * never a mix; and once a save returned true, its record. Tested
 * exhaustively on a flash model (tests/test_cfgstore.c): a cut after every
 * word programmed and every word erased, and inside each program.
 */
#ifndef VS_CFGSTORE_H
#define VS_CFGSTORE_H

#include <stdbool.h>
#include <stdint.h>

#include "../hal/hal.h"

#define CFGSTORE_MAGIC	0x47464356u /* "VCFG" little-endian */
#define CFGSTORE_COMMIT 0x5AC3A55Au
#define CFGSTORE_HEADER 32u

typedef enum {
	CFGSTORE_OK = 0, /* a valid record was found (or written) */
	/* No record: never saved, or cleared; other_torn when one slot holds
	 * what a first save or a clear cut short left. */
	CFGSTORE_EMPTY,
	CFGSTORE_CORRUPT,  /* no valid record, and neither slot erased */
	CFGSTORE_TOO_BIG,  /* the payload does not fit a slot (or the buffer) */
	CFGSTORE_IO,	   /* the store reported an error */
	CFGSTORE_VERIFY,   /* what was programmed does not read back */
	CFGSTORE_NO_STORE, /* the platform has none, or its geometry is unusable */
} cfgstore_status_t;

typedef struct {
	uint32_t seq, schema, len;
	uint8_t slot;
	/* The other slot holds neither a record nor erased pages: a save
	 * was cut short (or the store was damaged); the next save erases it. */
	bool other_torn;
} cfgstore_info_t;

/* Bytes a payload may have in this store (0: the store is unusable). */
uint32_t cfgstore_capacity(const hal_store_t *s);

/* The newest valid record's payload into buf (cap bytes). */
cfgstore_status_t cfgstore_load(const hal_store_t *s, void *buf, uint32_t cap,
				cfgstore_info_t *info);

/* A new record after the newest (sequence + 1) in the other slot. */
cfgstore_status_t cfgstore_save(const hal_store_t *s, const void *payload, uint32_t len,
				uint32_t schema);

/* Both slots erased: the store is empty (defaults at the next boot). The
 * newer slot is erased last, so a cut leaves the newest record or none. */
cfgstore_status_t cfgstore_clear(const hal_store_t *s);

/* CRC-32 (IEEE 802.3, reflected 0xEDB88320), continuing from crc (start
 * with 0). */
uint32_t cfgstore_crc32(uint32_t crc, const void *data, uint32_t n);

#endif
