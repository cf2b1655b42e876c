/* Binary encoding of the command table's arguments, shared by every binary
 * link (framed serial, CAN) and by the host client library.
 *
 * Encodings, all little-endian, no padding, fields in table order:
 *   b  boolean        1 byte, 0 or 1 (anything else is WIRE_ST_VALUE)
 *   h  short          int16, 2 bytes
 *   u  unsigned long  uint32, 4 bytes
 *   d  double         IEEE-754 binary64, 8 bytes
 *   s  string         u8 length n, then n bytes (no NUL; n <= WIRE_STR_MAX)
 *   a  SeqAlarm       u8 count n (<= VS_ALARM_LIST_MAX), then per alarm:
 *                     u32 code, u8 type, string source (n < VS_ALARM_SOURCE_MAX)
 *
 * A request payload is the in arguments of the operation. A response payload
 * is the boolean result (1 byte) followed by the out arguments. Decoding is
 * exact: a payload shorter or longer than its fields is WIRE_ST_LENGTH.
 *
 * The status codes double as the NAK reasons of every link (docs/protocol.md).
 */
#ifndef WIRE_H
#define WIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cmdtab.h"

/* Longest string on the wire (the u8 length prefix). */
#define WIRE_STR_MAX 255

/* Largest request payload of any operation (3 doubles) and largest response
 * payload (getActiveAlarm with VS_ALARM_LIST_MAX alarms of the longest
 * source). Receivers size their buffers from these. */
#define WIRE_REQ_MAX	     24
#define WIRE_ALARM_MAX_BYTES (4 + 1 + 1 + (VS_ALARM_SOURCE_MAX - 1))
#define WIRE_RESP_MAX	     (1 + 2 + 1 + VS_ALARM_LIST_MAX * WIRE_ALARM_MAX_BYTES)

/* Not an operation: protocol information, answered by every binary link.
 * Request payload empty; response payload:
 *   u8 protocol version (CMD_PROTO_VERSION), u16 table checksum
 *   (cmd_table_crc), u8 number of operations (CMD_COUNT),
 *   u16 largest request payload, u16 largest response payload. */
#define WIRE_OP_INFO  0x7F
#define WIRE_INFO_LEN 8
/* Not an operation: one console line (docs/console.md) carried in a frame,
 * for the bring-up extras ($config, ...) that have no opcode. Request
 * payload: the line's bytes, 1..64, no line ending; response payload: the
 * reply line's bytes ("ok ..." or "error ..."), no newline; empty for a
 * blank line or a comment. Serial frames only (not CAN). */
#define WIRE_OP_CONSOLE 0x7E
/* Not an operation: the telemetry stream (stream.h, docs/protocol.md). A
 * request subscribes (u16 group mask, u16 period in ms; mask 0
 * unsubscribes); the unit's own stream frames carry this opcode without
 * the response flag. Serial frames only (not CAN). */
#define WIRE_OP_STREAM 0x7D

/* Status of a request: 0 accepted, else the reason it was refused (NAK). */
typedef enum {
	WIRE_ST_OK = 0,
	WIRE_ST_CRC = 1,       /* frame check failed */
	WIRE_ST_OVERSIZE = 2,  /* declared length over the receiver's maximum */
	WIRE_ST_LENGTH = 3,    /* payload size does not match the operation */
	WIRE_ST_OPCODE = 4,    /* no such operation */
	WIRE_ST_VALUE = 5,     /* malformed field (boolean not 0/1, bad string or count) */
	WIRE_ST_TRUNCATED = 6, /* frame not completed within the inter-byte timeout */
	WIRE_ST_SPACE = 7,     /* output buffer too small (a local error, never sent) */
	WIRE_ST_RATE = 8,      /* the line cannot carry the stream asked for */
	WIRE_ST_COUNT
} wire_status_t;

/* Short lowercase name of a status ("crc", "length", ...). */
const char *wire_status_name(int st);

/* Where decoded strings and alarm sequences live; one per decode, valid
 * until the next decode into the same store. */
typedef struct {
	char str[CMD_MAX_FIELDS][WIRE_STR_MAX + 1];
	vs_alarm_t alarms[VS_ALARM_LIST_MAX];
} wire_store_t;

/* Little-endian scalar helpers (also for frame and CAN headers). */
void wire_put_u16(uint8_t *p, uint16_t v);
void wire_put_u32(uint8_t *p, uint32_t v);
uint16_t wire_get_u16(const uint8_t *p);
uint32_t wire_get_u32(const uint8_t *p);

/* Encodes n values of the type codes in types. Returns WIRE_ST_OK and the
 * byte count in *len, WIRE_ST_SPACE when cap is too small, WIRE_ST_VALUE for
 * a string over WIRE_STR_MAX or an alarm sequence over VS_ALARM_LIST_MAX. */
int wire_encode(const char *types, unsigned n, const cmd_value_t v[], uint8_t *buf, size_t cap,
		size_t *len);
/* Decodes exactly len bytes into n values. Returns WIRE_ST_OK,
 * WIRE_ST_LENGTH (short or trailing bytes) or WIRE_ST_VALUE. Strings are
 * NUL-terminated copies in st; an embedded NUL is WIRE_ST_VALUE. st may be
 * NULL: then a string or alarm field is WIRE_ST_VALUE. */
int wire_decode(const char *types, unsigned n, const uint8_t *buf, size_t len, cmd_value_t v[],
		wire_store_t *st);

/* Request = in arguments; response = result byte + out arguments. */
int wire_encode_request(const cmd_def_t *d, const cmd_value_t in[], uint8_t *buf, size_t cap,
			size_t *len);
int wire_decode_request(const cmd_def_t *d, const uint8_t *buf, size_t len, cmd_value_t in[],
			wire_store_t *st);
int wire_encode_response(const cmd_def_t *d, bool result, const cmd_value_t out[], uint8_t *buf,
			 size_t cap, size_t *len);
int wire_decode_response(const cmd_def_t *d, const uint8_t *buf, size_t len, bool *result,
			 cmd_value_t out[], wire_store_t *st);

/* The WIRE_OP_INFO response payload (buf has room for WIRE_INFO_LEN). */
size_t wire_info(uint8_t *buf);

#endif
