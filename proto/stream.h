/* The telemetry value set (stream.def) and its two encodings: the serial
 * link's stream frames (docs/protocol.md, "Telemetry stream") and the CAN
 * status group (docs/can.md). One sample is read from the unit once and
 * encoded either way, so both links carry the same integers.
 *
 * Serial: a host subscribes with a request of opcode WIRE_OP_STREAM
 * (payload u16 group mask, u16 period in ms; mask 0 unsubscribes). The unit
 * then sends, every period, a frame of that opcode without the response
 * flag (unit-initiated: a host that reads both tells it from an answer by
 * bit 7 of op), its seq the stream's own sequence number, its payload
 * u16 mask, u32 tick (the unit's control ticks since start), then the
 * groups' fields in bit order. A set at a rate the line cannot carry with
 * STREAM_RESERVE of it left for answers is refused (NAK WIRE_ST_RATE):
 * the rule is stream_fits, the one place it is computed.
 */
#ifndef PROTO_STREAM_H
#define PROTO_STREAM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "../firmware/vehicle.h"

enum {
	STREAM_G_POSE = 0,
	STREAM_G_CMD = 1,
	STREAM_G_MEAS = 2,
	STREAM_G_STATE = 3,
	STREAM_G_ALARM = 4,
	STREAM_G_BATTERY = 5,
	STREAM_G_IO = 6,
	STREAM_G_QUEUE = 7,
	STREAM_GROUPS = 8
};
#define STREAM_MASK_ALL ((uint16_t)((1u << STREAM_GROUPS) - 1u))

typedef enum {
	STREAM_T_I16 = 0,
	STREAM_T_I32 = 1,
	STREAM_T_U8 = 2,
	STREAM_T_U16 = 3,
	STREAM_T_U32 = 4
} stream_type_t;

/* One sample, in the table's integer units. */
typedef struct {
	uint16_t state;
	uint8_t alarms;
	uint8_t counter; /* the CAN group's counter (not in serial frames) */
	uint16_t battery_cV;
	int16_t vx_mm_s, vy_mm_s, w_ddeg_s;
	int32_t x_dmm, y_dmm, theta_mdeg;
	int16_t mvx_mm_s, mvy_mm_s, mw_ddeg_s;
	uint8_t queue, alarm_type;
	uint32_t alarm_code;
	uint16_t inputs, outputs;
} stream_sample_t;

typedef struct {
	const char *name;
	uint8_t group, type, can_frame, can_offset;
	uint16_t at; /* offsetof in stream_sample_t */
} stream_field_t;

extern const stream_field_t stream_fields[];
extern const unsigned stream_field_count;
extern const char *const stream_group_names[STREAM_GROUPS];

/* Stream frame payload: u16 mask, u32 tick, then the fields. */
#define STREAM_HDR	   6
#define STREAM_VALUES_MAX  39 /* every group */
#define STREAM_PAYLOAD_MAX (STREAM_HDR + STREAM_VALUES_MAX)
#define STREAM_FRAME_MAX   (7 + STREAM_PAYLOAD_MAX) /* FRAME_OVERHEAD + payload */
#define STREAM_TEXT_MAX	   400			    /* a text line of every group, and more */
/* The subscription: request u16 mask, u16 period_ms; answer (after the
 * status byte) u16 mask, u16 period_ms, u16 frame bytes, u16 the fastest
 * period the set may have, u16 tick rate (Hz). */
#define STREAM_REQ_LEN	4
#define STREAM_RESP_LEN 10
/* The stream takes at most STREAM_SHARE_NUM / STREAM_SHARE_DEN of the line
 * (10 bits a byte, 8N1); the rest is the reserve for answers. */
#define STREAM_SHARE_NUM 3u
#define STREAM_SHARE_DEN 4u
#define STREAM_BAUD	 115200u /* a port with no line speed (a pty) counts as this */

/* CAN status group: frames A..E. */
#define STREAM_CAN_FRAMES     5
#define STREAM_CAN_COUNTER_AT 3 /* byte of frame A */

/* Wire size of one field type. */
size_t stream_type_size(unsigned type);
/* Payload bytes of a stream frame of mask (header included). */
size_t stream_payload_len(uint16_t mask);
/* Bytes on the wire of one stream frame of mask. */
size_t stream_frame_bytes(uint16_t mask);
/* The one budget rule: frames of mask every period_ms fit the stream's
 * share of a line of baud. */
bool stream_fits(uint16_t mask, uint32_t period_ms, uint32_t baud);
/* The shortest period (ms) at which mask fits (0 for mask 0). */
uint32_t stream_min_period_ms(uint16_t mask, uint32_t baud);

/* The same rule for any line size (the console's text form), and the
 * most bytes one text line of mask takes (stream_text). */
bool stream_fits_bytes(size_t bytes, uint32_t period_ms, uint32_t baud);
uint32_t stream_min_period_bytes(size_t bytes, uint32_t baud);
size_t stream_text_bytes(uint16_t mask);

/* Reads the unit's values now (counter 0). */
void stream_read(vehicle_t *v, stream_sample_t *s);
/* A field's value, widened, and set from one. */
int64_t stream_get(const stream_sample_t *s, const stream_field_t *f);
void stream_set(stream_sample_t *s, const stream_field_t *f, int64_t val);

/* The stream frame payload of mask; returns its length (0: cap too small). */
size_t stream_encode(const stream_sample_t *s, uint16_t mask, uint32_t tick, uint8_t *out,
		     size_t cap);
/* Decodes a stream frame payload: 0, or -1 when its length does not match
 * its mask or the mask has unknown bits. Fields of groups not in the mask
 * are left as they were. */
int stream_decode(const uint8_t *p, size_t len, uint16_t *mask, uint32_t *tick, stream_sample_t *s);

/* The console's text form of a sample: "~stream SEQ TICK name value ..."
 * (the groups of mask, the table's integers) and LF; its length, 0 when
 * cap is too small. */
size_t stream_text(const stream_sample_t *s, uint16_t mask, uint8_t seq, uint32_t tick, char *out,
		   size_t cap);

/* CAN status frame `which` (0..4: A..E), 8 data bytes; and back. */
void stream_can_put(const stream_sample_t *s, unsigned which, uint8_t data[8]);
void stream_can_get(const uint8_t data[8], unsigned which, stream_sample_t *s);

/* A subscription on one serial link. */
typedef struct {
	uint16_t mask; /* 0: none */
	uint16_t period_ms;
	uint32_t period_ticks;
	uint32_t next_tick; /* the tick count at which the next frame is due */
	uint8_t seq;	    /* the next frame's sequence number */
	uint32_t baud;
	bool text;	  /* the console's text form, not frames */
	uint32_t sent;	  /* frames sent */
	uint32_t skipped; /* slots that found the last frame still unsent */
} stream_sub_t;

void stream_sub_init(stream_sub_t *ss, uint32_t baud);
/* Puts mask every period_ms in force (mask 0: none) at tick count
 * now_tick, as frames or text lines: WIRE_ST_OK, or WIRE_ST_VALUE (unknown
 * group, period 0 or not whole ticks) or WIRE_ST_RATE (over the line's
 * share), the subscription in force then unchanged. */
int stream_start(stream_sub_t *ss, uint32_t tick_hz, uint32_t now_tick, uint16_t mask,
		 uint16_t period, bool text);
/* A subscription request (payload p of len) at tick count now_tick on a
 * unit of tick_hz: fills resp (STREAM_RESP_LEN) and returns its length,
 * or 0 with *st the NAK: WIRE_ST_LENGTH, WIRE_ST_VALUE (unknown group,
 * period 0 or not whole ticks), WIRE_ST_RATE (over the line's share). */
size_t stream_subscribe(stream_sub_t *ss, uint32_t tick_hz, uint32_t now_tick, const uint8_t *p,
			size_t len, uint8_t *resp, int *st);
/* At tick count now_tick: true when a frame is due; the schedule moves on
 * (slots passed over without a poll are skipped, their sequence numbers
 * too). */
bool stream_due(stream_sub_t *ss, uint32_t now_tick);

#endif
