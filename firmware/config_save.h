/* The configuration as the store keeps it (cfgstore.h holds the bytes):
 * what differs from the base configuration (the vehicle file on a
 * computer, the compiled-in one on a board), each field by its name, so
 * that a firmware whose table changed still reads it: a field it no longer
 * has is dropped, a new one keeps the base's value.
 *
 *   byte 0  payload version (1)     byte 1  'D' doubles, 'Q' Q32 numbers
 *   2..3    entries (little-endian)
 *   then each entry: name length, name, element, type, size, the value's
 *   bytes as the member holds them (the platform's own order).
 *
 * The schema (vs_config_schema) is a CRC-32 over the table's names, types
 * and lengths: the record says which table wrote it. */
#ifndef VS_CONFIG_SAVE_H
#define VS_CONFIG_SAVE_H

#include <stddef.h>
#include <stdint.h>

#include "config.h"

#define VS_CFGSAVE_VERSION 1u
#ifdef VS_REAL_Q32
#define VS_CFGSAVE_FORMAT 'Q'
#else
#define VS_CFGSAVE_FORMAT 'D'
#endif

/* The largest saved form of this table (every element differs): what a
 * save needs at most. A record another table wrote may be larger. */
struct vs_cfgsave_max_bytes { /* a char array an entry's bytes */
#define VS_CFGSAVE_ROW_MAX(m, n, ...)                                                              \
	char m[(n) * (4u + sizeof(#m) - 1u + sizeof(((vs_config_t *)0)->m) / (n))];
	VS_CONFIG_FIELDS(VS_CFGSAVE_ROW_MAX)
#undef VS_CFGSAVE_ROW_MAX
};
#define VS_CFGSAVE_MAX (4u + sizeof(struct vs_cfgsave_max_bytes))

uint32_t vs_config_schema(void);
/* Bytes of one element of a row's type (vs_config_type_t). */
uint8_t vs_config_type_size(uint8_t type);

/* The fields of cur that differ from base, into buf; the bytes written, or
 * 0 when they do not fit cap. cur and base: a vs_config_t, or its rows
 * alone (each row at its offset, config_keep.h). */
size_t vs_config_encode(const void *cur, const void *base, uint8_t *buf, size_t cap);

typedef struct {
	uint16_t applied; /* entries taken */
	uint16_t dropped; /* entries for fields this table does not have (or
			     has with another type or length) */
} vs_config_decode_t;

typedef enum {
	VS_CFGSAVE_OK = 0,
	VS_CFGSAVE_MALFORMED, /* cut short, or a length that runs past the end */
	VS_CFGSAVE_FOREIGN,   /* another payload version, or another platform's numbers */
} vs_config_decode_status_t;

/* Applies the entries of buf to out (which holds the base); out is not
 * changed unless the whole payload is well formed. The caller judges the
 * result with vs_config_check. */
vs_config_decode_status_t vs_config_decode(vs_config_t *out, const uint8_t *buf, size_t len,
					   vs_config_decode_t *info);

#endif
