/* Binary frames on the serial link (docs/protocol.md).
 *
 *   A5 | len lo | len hi | seq | op | payload[len] | crc lo | crc hi
 *
 * sync 0xA5 (a sync byte inside a console line of text belongs to that
 * line: see frame_rx_set_hold and docs/protocol.md); len = payload bytes, u16 LE; seq chosen by the
 * host, echoed in the answer; op = opcode (1..0x7F) in a request, opcode | 0x80 in a response. crc:
 * CRC-16/CCITT-FALSE (cmd_crc16 from 0xFFFF) over len..payload, LE.
 *
 * A response payload starts with a status byte (wire_status_t): 0 then the
 * wire response (result byte + outs), or a NAK reason alone. A NAK for a
 * frame whose opcode could not be trusted (bad check, oversize, truncated)
 * carries op 0x80 and the seq byte received (0 when the frame ended before
 * it). An oversize length is refused when the seq byte is in.
 *
 * The receiver takes a byte stream: bytes outside frames are handed on (to
 * the console); a candidate frame that fails (length over the maximum, bad
 * check, inter-byte timeout) is reported and the stream rescanned from the
 * byte after its sync, so a good frame hidden behind garbage is still found.
 */
#ifndef FRAME_H
#define FRAME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "wire.h"

#define FRAME_SYNC	0xA5
#define FRAME_HDR	5
#define FRAME_OVERHEAD	7 /* header + check */
#define FRAME_RESP_FLAG 0x80
/* Largest request payload the unit accepts (room beyond WIRE_REQ_MAX for
 * future operations); a longer declared length is NAKed as oversize. */
#define FRAME_REQ_PAYLOAD_MAX 64
/* Largest response payload: status byte + largest wire response. */
#define FRAME_RESP_PAYLOAD_MAX (1 + WIRE_RESP_MAX)
#define FRAME_REQ_MAX	       (FRAME_OVERHEAD + FRAME_REQ_PAYLOAD_MAX)
#define FRAME_RESP_MAX	       (FRAME_OVERHEAD + FRAME_RESP_PAYLOAD_MAX)
/* A frame not completed this long after its last byte is dropped. */
#define FRAME_RX_TIMEOUT_MS 100

/* Encodes one frame into out; returns its size, 0 when cap is too small or
 * len over 0xFFFF. */
size_t frame_encode(uint8_t *out, size_t cap, uint8_t seq, uint8_t op, const uint8_t *payload,
		    size_t len);
/* A response: status byte, then payload (none for a NAK). */
size_t frame_encode_response(uint8_t *out, size_t cap, uint8_t seq, uint8_t opcode, uint8_t status,
			     const uint8_t *payload, size_t len);

/* One received frame, or a failed candidate. */
typedef struct {
	int status;	 /* WIRE_ST_OK, or CRC / OVERSIZE / TRUNCATED */
	bool header;	 /* seq and op were received (maybe damaged if status != OK) */
	uint8_t seq, op; /* seq 0 / op 0 when the candidate ended before them */
	uint16_t crc;	 /* the frame's check value (identity of a request) */
	const uint8_t *payload;
	size_t len;
} frame_t;

typedef void (*frame_fn)(void *ctx, const frame_t *f);
typedef void (*frame_other_fn)(void *ctx, const uint8_t *data, size_t n);
/* True when a sync byte arriving now belongs to the other stream (a console
 * line of text is in progress), so it starts no frame. */
typedef bool (*frame_hold_fn)(void *ctx);

typedef struct {
	uint32_t frames; /* good frames */
	uint32_t crc_errors;
	uint32_t oversize;
	uint32_t truncated;   /* timed out, or dropped unfinished on a rescan */
	uint32_t other_bytes; /* bytes outside frames */
} frame_rx_stats_t;

typedef struct {
	uint8_t *buf;
	size_t cap; /* FRAME_OVERHEAD + max payload */
	size_t max_payload;
	size_t n;
	uint32_t last_ms;
	frame_fn on_frame;
	frame_other_fn on_other;
	void *ctx, *octx;   /* of on_frame, of on_other */
	frame_hold_fn hold; /* optional */
	void *hold_ctx;
	frame_rx_stats_t st;
} frame_rx_t;

/* buf of FRAME_OVERHEAD + max_payload bytes, owned by the caller. on_other
 * may be NULL (bytes outside frames are then only counted). */
void frame_rx_init(frame_rx_t *rx, uint8_t *buf, size_t max_payload, frame_fn on_frame,
		   frame_other_fn on_other, void *ctx);
/* Sends the bytes outside frames to on_other(ctx, ...) instead (NULL: only
 * counted). */
void frame_rx_set_other(frame_rx_t *rx, frame_other_fn on_other, void *ctx);
/* Sets the predicate that keeps a sync byte in the other stream (NULL: a
 * sync byte outside a frame always starts one). */
void frame_rx_set_hold(frame_rx_t *rx, frame_hold_fn hold, void *ctx);
/* Feeds received bytes; calls on_frame / on_other as they complete. */
void frame_rx_feed(frame_rx_t *rx, const uint8_t *data, size_t n, uint32_t now_ms);
/* Applies the inter-byte timeout: an unfinished frame older than
 * FRAME_RX_TIMEOUT_MS is reported as TRUNCATED and the rest rescanned. */
void frame_rx_poll(frame_rx_t *rx, uint32_t now_ms);
/* True while a frame is partly received. */
static inline bool frame_rx_busy(const frame_rx_t *rx)
{
	return rx->n > 0;
}

/* The unit's side: frames in, operations run through wire_dispatch, answers
 * out. A request repeating the sequence number and check value of the last
 * executed one is answered from the cache without running it again. */
typedef void (*frame_write_fn)(void *ctx, const uint8_t *data, size_t n);
/* Runs one console line (WIRE_OP_CONSOLE): false when it gets no reply
 * (blank, comment), else the reply line in reply. */
typedef bool (*frame_line_fn)(void *ctx, const char *line, char *reply, size_t cap);
/* A stream subscription (WIRE_OP_STREAM, stream.h): returns the answer's
 * length in resp, or 0 with *st the NAK. */
typedef size_t (*frame_stream_fn)(void *ctx, const uint8_t *p, size_t len, uint8_t *resp, int *st);

typedef struct {
	uint32_t executed;   /* requests run */
	uint32_t duplicates; /* answered from the cache */
	uint32_t naks;	     /* NAKs sent */
} frame_srv_stats_t;

typedef struct {
	vehicle_t *v;
	frame_rx_t rx;
	uint8_t rxbuf[FRAME_REQ_MAX];
	frame_write_fn write;
	void *wctx;
	frame_line_fn line; /* WIRE_OP_CONSOLE; NULL: NAK opcode */
	void *lctx;
	frame_stream_fn stream; /* WIRE_OP_STREAM; NULL: NAK opcode */
	void *sctx;
	bool have_last;
	uint8_t last_seq, last_op;
	uint16_t last_crc;
	uint8_t last_resp[FRAME_RESP_MAX];
	size_t last_len;
	frame_srv_stats_t st;
} frame_srv_t;

/* on_other: bytes that are not frames (the console), handed on by the
 * receiver itself; may be NULL. */
void frame_srv_init(frame_srv_t *s, vehicle_t *v, frame_write_fn write, void *wctx,
		    frame_other_fn on_other, void *octx);
/* Console lines carried in frames (WIRE_OP_CONSOLE) go to fn. */
static inline void frame_srv_set_line(frame_srv_t *s, frame_line_fn fn, void *ctx)
{
	s->line = fn;
	s->lctx = ctx;
}
/* Stream subscriptions (WIRE_OP_STREAM) go to fn. */
static inline void frame_srv_set_stream(frame_srv_t *s, frame_stream_fn fn, void *ctx)
{
	s->stream = fn;
	s->sctx = ctx;
}
static inline void frame_srv_feed(frame_srv_t *s, const uint8_t *data, size_t n, uint32_t now_ms)
{
	frame_rx_feed(&s->rx, data, n, now_ms);
}
static inline void frame_srv_poll(frame_srv_t *s, uint32_t now_ms)
{
	frame_rx_poll(&s->rx, now_ms);
}

#endif
